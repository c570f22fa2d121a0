"""DH couplings a Model can hold, refused at their place in the scene file otherwise.

A coupling's URDF form is one mimic joint per term, each of a commanded joint earlier in the chain (``model.export``):
a coupling on a later joint loaded with ``load_scene`` and then failed in ``load_model`` naming a deleted temporary
URDF; a drive coupling whose own term was not 1 likewise; a dependent joint's own limits were read and dropped.
"""

from __future__ import annotations

import pytest

import armguard

HEAD = """armguard_scene: 1
name: cell
units: {length: m, angle: deg}
robots:
  - name: arm
    convention: standard
    joints:
      - {name: j1, a: 0.3, alpha: 0, d: 0.2, limits: [-90, 90]}
      - {name: j2, a: 0.3, alpha: 0, d: 0.0, limits: [-90, 90]}
      - {name: j3, a: 0.2, alpha: 0, d: 0.0JLIM}
      - {name: j4, a: 0.1, alpha: 0, d: 0.0, limits: [-90, 90]}
    couplings:
      - COUPLING
"""


def _scene(tmp_path, coupling: str, jlim: str = ""):
    f = tmp_path / "cell.yaml"
    f.write_text(HEAD.replace("COUPLING", coupling).replace("JLIM", jlim))
    return f


@pytest.mark.parametrize("coupling, said", [
    ("{joint: j3, terms: {j1: 0.5, j4: -2.0}}", "'j4' comes after 'j3' in the chain"),
    ("{joint: j4, terms: {j4: 2.0, j1: -1.0}}", "a drive coupling's own term must be 1"),
])
def test_a_coupling_without_a_urdf_form_is_refused_at_its_place(tmp_path, coupling, said):
    f = _scene(tmp_path, coupling)
    with pytest.raises(armguard.SceneFileError) as err:
        armguard.load_scene(str(f))
    msg = str(err.value)
    assert msg.startswith(str(f)) and "robots[0].couplings[0].terms" in msg and said in msg, msg


def test_a_dependent_joints_own_limits_are_refused_not_dropped(tmp_path):
    f = _scene(tmp_path, "{joint: j3, terms: {j1: 0.5, j2: -2.0}}", ", limits: [-1, 1]")
    with pytest.raises(armguard.SceneFileError) as err:
        armguard.load_scene(str(f))
    assert "robots[0].joints[2].limits" in str(err.value) and "follows a coupling" in str(err.value)


@pytest.mark.parametrize("coupling", ["{joint: j3, terms: {j1: 0.5, j2: -2.0}, offset: 7}",
                                      "{joint: j4, terms: {j4: 1.0, j1: -1.0}}"])
def test_couplings_with_a_urdf_form_load_as_models(tmp_path, coupling):
    f = _scene(tmp_path, coupling)
    scene = armguard.load_scene(str(f))
    model = armguard.load_model(str(f))
    assert model.pin_model.nq >= 3 and "arm" in scene.robots
