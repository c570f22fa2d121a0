"""A URDF whose collision geometry is invalid: the error names the file, the link and the element.

Found in review: a negative sphere radius or a zero box edge in ``<collision>`` gave
"FILE: Sphere.radius: must be >= 0" with no place in the file (a mesh that was missing did
name ``link[l1].collision[0]``).
"""

from __future__ import annotations

import pytest

import armguard
from armguard import SceneFileError

URDF = """<robot name="r2">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l1">
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0 0 0.2"/><geometry>{geom}</geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
</robot>
"""


@pytest.mark.parametrize(
    "geom, what",
    [('<sphere radius="-0.05"/>', "radius"), ('<box size="0 0.1 0.1"/>', "<box size='0 0.1 0.1'>: each edge must be > 0"),
     ('<cylinder radius="0.0" length="0.4"/>', "<cylinder radius='0.0'>: the radius must be > 0")],
    ids=["negative-radius", "zero-box", "zero-cylinder"],
)
def test_bad_collision_geometry_is_located(tmp_path, geom, what):
    path = tmp_path / "r2.urdf"
    path.write_text(URDF.format(geom=geom), encoding="utf-8")
    with pytest.raises(SceneFileError) as err:
        armguard.load_scene(path)
    assert err.value.file == str(path)
    assert err.value.where == "link[l1].collision[1]"
    assert what in err.value.message


def test_valid_collision_geometry_loads(tmp_path):
    path = tmp_path / "r2.urdf"
    path.write_text(URDF.format(geom='<cylinder radius="0.05" length="0.4"/>'), encoding="utf-8")
    robot = armguard.load_scene(path).robots["r2"]
    assert [type(s).__name__ for s in robot.link_shapes["l1"]] == ["Sphere", "Cylinder"]
