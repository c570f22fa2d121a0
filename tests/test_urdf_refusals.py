"""A URDF armguard refuses names the file, the element and the attribute; nothing that would give a
wrong shape loads.

Pinocchio's parser refuses a duplicate link, a NaN limit or a revolute joint without limits with
"the file does not contain a valid URDF model" (no place); a capsule with a negative length loaded
with its ends swapped (analytic and coal then disagreed by 77 mm); a mesh with a NaN vertex gave a
raw ``LinAlgError``, a collinear or zero-scale mesh a raw ``QhullError``.
"""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard import ArmguardError, SceneFileError
from armguard.geometry import Polygon

LINK1 = '<link name="l1"><collision{cname}><origin xyz="0 0 0.2"/><geometry>{geom}</geometry></collision>{extra}</link>'
CAPSULE = '<collision_checking><capsule name="c"/></collision_checking>'
JOINT1 = ('<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/>'
          '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>')


def _urdf(geom='<sphere radius="0.05"/>', extra="", joint=JOINT1, more=""):
    """Line 1 <robot>, 2 link base, 3 link l1 (a capsule named "c" when ``extra`` is CAPSULE), 4 joint j1, 5 ``more``."""
    cname = ' name="c"' if extra == CAPSULE else ""
    return (f'<robot name="r">\n<link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry>'
            f'</collision></link>\n{LINK1.format(geom=geom, extra=extra, cname=cname)}\n{joint}\n{more}\n</robot>\n')


def _refused(tmp_path, text: str) -> SceneFileError:
    path = tmp_path / "r.urdf"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneFileError) as err:
        armguard.load_model(path)
    assert err.value.file == str(path)
    return err.value


def _joint(**kw) -> str:
    return JOINT1.replace('type="revolute"', f'type="{kw.get("type", "revolute")}"').replace(
        '<limit lower="-1" upper="1" velocity="1" effort="1"/>', kw.get("limit", '<limit lower="-1" upper="1" velocity="1" effort="1"/>')
    ).replace('<origin xyz="0 0 0.1"/>', kw.get("origin", '<origin xyz="0 0 0.1"/>'))


CASES = {
    "duplicate-link": (_urdf(more='<link name="l1"/>'), "link[l1]", "a second <link> named 'l1'"),
    "duplicate-joint": (_urdf(more='<link name="l2"/>' + JOINT1.replace('<child link="l1"/>', '<child link="l2"/>')),
                        "joint[j1]", "a second <joint> named 'j1'"),
    "nan-joint-origin": (_urdf(joint=_joint(origin='<origin xyz="0 nan 0.1"/>')), "joint[j1].origin", "xyz='0 nan 0.1'"),
    "inf-collision-origin": (_urdf().replace('<origin xyz="0 0 0.2"/>', '<origin xyz="0 0 0.2" rpy="0 inf 0"/>'),
                             "link[l1].collision[0].origin", "rpy='0 inf 0'"),
    "nan-limit": (_urdf(joint=_joint(limit='<limit lower="nan" upper="1" velocity="1" effort="1"/>')),
                  "joint[j1].limit", "lower='nan'"),
    "reversed-limit": (_urdf(joint=_joint(limit='<limit lower="1" upper="-1" velocity="1" effort="1"/>')),
                       "joint[j1].limit", "lower='1' > upper='-1'"),
    "limit-without-effort": (_urdf(joint=_joint(limit='<limit lower="-1" upper="1" velocity="1"/>')), "joint[j1].limit",
                             "expected attribute 'effort'"),
    "nan-calibration": (_urdf(joint=JOINT1.replace("</joint>", '<calibration rising="nan"/></joint>')), "joint[j1].calibration",
                        "rising='nan': every number must be finite"),
    "revolute-without-limit": (_urdf(joint=_joint(limit="")), "joint[j1]", "a revolute joint needs <limit"),
    "prismatic-without-limit": (_urdf(joint=_joint(type="prismatic", limit="")), "joint[j1]", "a prismatic joint needs <limit"),
    "zero-axis": (_urdf(joint=JOINT1.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>')), "joint[j1].axis", "length 0"),
    "missing-child": (_urdf(joint=JOINT1.replace('<child link="l1"/>', '<child link="l9"/>')), "joint[j1].child",
                      "link='l9': no <link>"),
    "mimic-missing-joint": (_urdf(more='<link name="l2"/><joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>'
                                  '<limit lower="-1" upper="1" velocity="1" effort="1"/><mimic joint="j7"/></joint>'),
                            "joint[j2].mimic", "joint='j7': no joint of that name"),
    "zero-box": (_urdf('<box size="0 0.1 0.1"/>'), "link[l1].collision[0]", "<box size='0 0.1 0.1'>: each edge must be > 0"),
    "negative-sphere": (_urdf('<sphere radius="-0.05"/>'), "link[l1].collision[0]", "<sphere radius='-0.05'>: the radius must be > 0"),
    "zero-sphere": (_urdf('<sphere radius="0"/>'), "link[l1].collision[0]", "radius must be > 0"),
    "nan-sphere": (_urdf('<sphere radius="nan"/>'), "link[l1].collision[0]", "radius='nan': every number must be finite"),
    "zero-cylinder-radius": (_urdf('<cylinder radius="0" length="0.3"/>'), "link[l1].collision[0]", "<cylinder radius='0'>"),
    "zero-cylinder-length": (_urdf('<cylinder radius="0.05" length="0"/>'), "link[l1].collision[0]", "<cylinder length='0'>"),
    "negative-capsule-length": (_urdf('<cylinder radius="0.05" length="-0.3"/>', extra=CAPSULE), "link[l1].collision[0]",
                                "a capsule's length must be >= 0"),
    "zero-mesh-scale": (_urdf('<mesh filename="cube.stl" scale="0.1 0 0.1"/>'), "link[l1].collision[0]",
                        "<mesh scale='0.1 0 0.1'>: a zero scale"),
    "malformed-number": (_urdf('<box size="0.1 0.1 abc"/>'), "link[l1].collision[0]", "size='0.1 0.1 abc': expected 3 numbers"),
    # urdfdom and Pinocchio named neither element nor line for these three
    "negative-velocity": (_urdf(joint=_joint(limit='<limit lower="-1" upper="1" velocity="-1" effort="1"/>')),
                          "joint[j1].limit", "velocity='-1': must be >= 0"),
    "huge-limit": (_urdf(joint=_joint(limit='<limit lower="-1e308" upper="1" velocity="1" effort="1"/>')),
                   "joint[j1].limit", "lower='-1e308': beyond 1e+09"),
    "two-root-links": (_urdf(more='<link name="l2"/>'), "link[l2]", "2 root links ('base', 'l2'): no joint joins link 'l2'"),
    "child-of-two-joints": (_urdf(more='<link name="l2"/>' + JOINT1.replace('name="j1"', 'name="j2"').replace(
                                '<parent link="base"/>', '<parent link="l2"/>')),
                            "joint[j2].child", "link='l1' is already the child of joint 'j1' (line 4): a URDF is a tree"),
}
_LINE_5 = ("duplicate-link", "duplicate-joint", "mimic-missing-joint", "two-root-links", "child-of-two-joints")


@pytest.mark.parametrize("case", list(CASES))
def test_a_refused_urdf_names_the_element_and_attribute(tmp_path, case):
    import trimesh

    trimesh.creation.box(extents=(1, 1, 1)).export(tmp_path / "cube.stl")
    text, where, what = CASES[case]
    err = _refused(tmp_path, text)
    assert err.where == where, err
    assert what in err.message, err
    line = 5 if case in _LINE_5 else 3 if where.startswith("link[l1]") else 4
    assert err.line == line, err  # the line of the element named


def test_several_problems_are_listed_together(tmp_path):
    err = _refused(tmp_path, _urdf('<sphere radius="-1"/>', joint=_joint(limit='<limit lower="nan" upper="1" velocity="1" effort="1"/>')))
    assert err.where == "link[l1].collision[0]"
    assert "1 more problem" in err.message and "joint[j1].limit (line 4): lower='nan'" in err.message  # each its line


def test_a_zero_length_capsule_is_a_sphere_and_loads(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text(_urdf('<cylinder radius="0.05" length="0"/>', extra=CAPSULE), encoding="utf-8")
    (cap,) = armguard.load_model(path).scene.robots["r"].link_shapes["l1"]
    assert cap.length == 0.0 and cap.radius == 0.05


def _mesh_urdf(tmp_path, vertices, faces, scale="1 1 1"):
    import trimesh

    trimesh.Trimesh(np.asarray(vertices, dtype=np.float64), np.asarray(faces), process=False).export(tmp_path / "m.stl")
    path = tmp_path / "r.urdf"
    path.write_text(_urdf(f'<mesh filename="m.stl" scale="{scale}"/>'), encoding="utf-8")
    return path


_TET = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]
_TET_F = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


@pytest.mark.parametrize(
    "vertices, what",
    [([[0, 0, 0], [0.1, 0, 0], [np.nan, 0.1, 0], [0, 0, 0.1]], "not finite (NaN or inf), the first is vertex"),
     ([[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0.3, 0, 0]], "the vertices lie on a line"),
     ([[0.1, 0.1, 0.1]] * 4, "no area and no volume"),
     ([[1e20, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]], "is beyond 1e+09 m"),  # (STL: float32) was a hull of 1e20 m
     ],
    ids=["nan-vertex", "collinear", "one-point", "huge-vertex"],
)
def test_a_bad_mesh_names_the_file_link_and_mesh(tmp_path, vertices, what):
    path = _mesh_urdf(tmp_path, vertices, _TET_F)
    with pytest.raises(ArmguardError) as err:
        armguard.load_model(path)
    assert isinstance(err.value, SceneFileError) and err.value.file == str(path)
    assert err.value.where == "link[l1].collision[0]"
    assert str(tmp_path / "m.stl") in err.value.message and what in err.value.message, err.value


def test_a_flat_mesh_is_a_polygon(tmp_path):
    square = [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0], [0.05, 0.05, 0]]
    path = _mesh_urdf(tmp_path, square, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    (poly,) = armguard.load_model(path).scene.robots["r"].link_shapes["l1"]
    assert isinstance(poly, Polygon) and len(poly.vertices) == 4  # the centre point is not a corner
    assert np.allclose(sorted(map(tuple, poly.vertices - [0, 0, 0.2])), sorted(map(tuple, np.array(square[:4], float))))


def test_a_mirrored_mesh_is_the_mirrored_hull(tmp_path):
    path = _mesh_urdf(tmp_path, _TET, _TET_F, scale="-2 1 1")
    (poly,) = armguard.load_model(path).scene.robots["r"].link_shapes["l1"]
    want = np.array(_TET) * [-2, 1, 1] + [0, 0, 0.2]
    got = poly.vertices[np.lexsort(poly.vertices.T)]
    assert np.allclose(got, want[np.lexsort(want.T)], rtol=0, atol=1e-7)  # STL keeps single precision


@pytest.mark.parametrize("name,content,said", [("m.obj", b"", "the file is empty (0 bytes)"),
                                               ("m.stl", b"garbage!", "Failed to determine STL storage representation")])
def test_an_unreadable_mesh_file_says_why_without_a_folder_hint(tmp_path, name, content, said):
    """A mesh file that exists but holds no mesh: the loaders' reason, not coal's "Hint: the mesh directory
    may be wrong" (the file was found)."""
    (tmp_path / name).write_bytes(content)
    err = _refused(tmp_path, _urdf(f'<mesh filename="{name}"/>'))
    assert err.where == "link[l1].collision[0]" and said in err.message and "Hint" not in err.message, err


def _tet_obj(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n", encoding="utf-8")


@pytest.mark.parametrize("filename", ["collision/m.obj", "package://nopkg/m.obj", "package://nopkg/collision/m.obj"])
def test_a_missing_mesh_is_named_never_another_file_of_its_name(tmp_path, filename):
    """``collision/m.obj`` missing beside the URDF: a mesh ``m.obj`` one or two folders up was read in its place
    (the path's leading folders dropped until a file turned up): a different model, without a word."""
    _tet_obj(tmp_path / "m.obj")
    _tet_obj(tmp_path / "deep" / "m.obj")
    deep = tmp_path / "deep" / "robot"
    deep.mkdir(parents=True)
    text = _urdf(f'<mesh filename="{filename}"/>')
    err = _refused(deep, text)
    line = text[:text.index("<mesh ")].count("\n") + 1  # the <mesh> element's line, as every refusal gives it
    assert err.where == "link[l1].collision[0]" and err.line == line and f"collision[0] (line {line}): mesh" in str(err), err
    assert "mesh file not found" in err.message and filename in err.message, err


def test_package_meshes_resolve_by_the_package_folder_or_its_parent(tmp_path):
    """``package://pkg/meshes/m.obj``: under a folder holding ``pkg`` (package_dirs, or above the URDF, as a
    description package lays itself out), or under ``pkg`` itself given as a package folder."""
    _tet_obj(tmp_path / "share" / "pkg" / "meshes" / "m.obj")
    urdf_dir = tmp_path / "share" / "pkg" / "urdf"
    urdf_dir.mkdir(parents=True)
    path = urdf_dir / "r.urdf"
    path.write_text(_urdf('<mesh filename="package://pkg/meshes/m.obj"/>'), encoding="utf-8")
    want = str(tmp_path / "share" / "pkg" / "meshes" / "m.obj")
    for kw in ({}, {"package_dirs": [tmp_path / "share"]}, {"package_dirs": [tmp_path / "share" / "pkg"]}):
        m = armguard.load_model(path, **kw)
        assert want in {str(p) for p in m.files}, kw
    other = tmp_path / "elsewhere"
    other.mkdir()
    moved = other / "r.urdf"  # the URDF away from its package: found through package_dirs only
    moved.write_text(path.read_text(encoding="utf-8"), encoding="utf-8")
    assert want in {str(p) for p in armguard.load_model(moved, package_dirs=tmp_path / "share").files}
    with pytest.raises(SceneFileError, match="mesh file not found"):
        armguard.load_model(moved)


def test_a_package_named_otherwise_than_its_folder_and_model_uris(tmp_path):
    """ROS finds a package by its package.xml's name: a download or clone named otherwise
    (``ur_description-main``) resolves ``package://ur_description/...`` as before; so does a package folder
    given in package_dirs, and ``model://`` as Pinocchio reads it.  A relative mesh missing beside the URDF
    is not looked up in the folders above it (``shared/meshes/m.obj`` for ``robots/r2/meshes/m.obj``)."""
    pkg = tmp_path / "ur_description-main"
    _tet_obj(pkg / "meshes" / "m.obj")
    (pkg / "package.xml").write_text("<package><name>ur_description</name></package>", encoding="utf-8")
    (pkg / "urdf").mkdir()
    path = pkg / "urdf" / "r.urdf"
    path.write_text(_urdf('<mesh filename="package://ur_description/meshes/m.obj"/>'), encoding="utf-8")
    assert str(pkg / "meshes" / "m.obj") in {str(p) for p in armguard.load_model(path).files}
    (pkg / "package.xml").unlink()
    with pytest.raises(SceneFileError, match="mesh file not found"):
        armguard.load_model(path)
    assert str(pkg / "meshes" / "m.obj") in {str(p) for p in armguard.load_model(path, package_dirs=pkg).files}
    path.write_text(_urdf('<mesh filename="model://ur_description-main/meshes/m.obj"/>'), encoding="utf-8")
    assert str(pkg / "meshes" / "m.obj") in {str(p) for p in armguard.load_model(path).files}
    _tet_obj(tmp_path / "shared" / "meshes" / "m.obj")
    r2 = tmp_path / "shared" / "robots" / "r2"
    r2.mkdir(parents=True)
    err = _refused(r2, _urdf('<mesh filename="meshes/m.obj"/>'))
    assert "mesh file not found: 'meshes/m.obj'" in err.message


def test_an_unclosed_element_is_named_with_its_line(tmp_path):
    """expat reports a mismatched tag at the closing tag that does not match (``</joint>``): the element left
    open (``<parent>``, written without its ``/``) is named, with its own line; so in an SRDF."""
    from armguard.model import models_dir

    text = (models_dir() / "puma560" / "puma560.urdf").read_text()
    bad = text.replace('<parent link="puma560_link5"/>', '<parent link="puma560_link5">', 1)
    line = bad[:bad.index('<parent link="puma560_link5">')].count("\n") + 1
    p = tmp_path / "p.urdf"
    p.write_text(bad)
    with pytest.raises(SceneFileError) as err:
        armguard.load_model(p, srdf=False)
    assert err.value.message == (f"not well-formed XML: mismatched tag: <parent> opened at line {line} is not closed "
                                 "(or not written <parent .../>)"), err.value
    s = tmp_path / "x.srdf"
    s.write_text('<robot name="x">\n<group name="a">\n<chain base_link="b" tip_link="c">\n</group>\n</robot>\n')
    with pytest.raises(SceneFileError, match=r"x.srdf: line 4, column 3: not well-formed XML: mismatched tag: <chain> "
                                             r"opened at line 3 is not closed"):
        armguard.load_model("puma560", srdf=s)


def test_a_huge_origin_and_a_deep_nesting_are_refused_with_their_place(tmp_path):
    """``<origin xyz="1e300 ...">`` loaded (coal's distances then came back infinite, naming no file); elements
    nested 1000 deep were an internal error (RecursionError).  Both are now refused where they are."""
    err = _refused(tmp_path, _urdf(joint=JOINT1.replace('<origin xyz="0 0 0.1"/>', '<origin xyz="1e300 0 0.1"/>')))
    assert "joint[j1].origin" in err.where and "beyond 1e+09" in err.message, err
    deep = "<x>" * 1000 + "</x>" * 1000
    err = _refused(tmp_path, _urdf(more=f'<link name="extra">{deep}</link>'))
    assert "nested more than 64 deep" in err.message and err.line == 5, err


def test_a_non_ascii_name_in_a_latin1_file_is_refused_a_latin1_comment_is_not(tmp_path):
    """An ISO-8859-1 URDF naming a link ``lién`` was an internal error (Pinocchio hands back the Latin-1 bytes as a
    frame name, not UTF-8: UnicodeDecodeError); a Latin-1 comment alone loads."""
    text = _urdf().replace('<link name="base">', '<!-- r\xe9f\xe9rence --><link name="base">')
    head = '<?xml version="1.0" encoding="ISO-8859-1"?>\n'
    p = tmp_path / "r.urdf"
    p.write_bytes((head + text).encode("latin-1"))
    armguard.load_model(p)
    p.write_bytes((head + text.replace('"l1"', '"li\xe9n"')).encode("latin-1"))
    with pytest.raises(SceneFileError, match="a non-ASCII value in a file that is not UTF-8") as err:
        armguard.load_model(p)
    assert "li\xe9n" in err.value.where and err.value.line is not None


def test_a_robot_without_a_name_and_a_utf16_file_are_refused_by_name(tmp_path):
    """Both passed armguard's own checks and failed in urdfdom: "does not contain a valid URDF model", no place,
    and C++ log lines on stderr."""
    err = _refused(tmp_path, _urdf().replace('<robot name="r">', "<robot>"))
    assert err.where == "robot" and "needs a name" in err.message and err.line == 1
    p = tmp_path / "r16.urdf"
    p.write_bytes(_urdf().encode("utf-16"))
    with pytest.raises(SceneFileError, match="UTF-16 text"):
        armguard.load_model(p)
