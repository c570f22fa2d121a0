"""The hull cache: a second load reads each mesh's hull from ``$ARMGUARD_CACHE_DIR/hulls`` and
gets exactly the shapes a first load computed; a damaged, edited or another mesh's entry is
recomputed with a warning; a changed mesh file (or a glTF's buffer) is a new entry; a mesh replaced
while it is hulled is never stored under the old bytes' key; ``ARMGUARD_HULL_CACHE=0`` reads and
writes nothing."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armguard
from armguard import ArmguardWarning
from armguard.model._hull_cache import _arrays_sha256, hull_cache_dir

URDF = ('<robot name="r"><link name="base"><collision><geometry><mesh filename="flat.stl"/></geometry></collision></link>'
        '<link name="l1"><collision><geometry><mesh filename="ball.stl" scale="0.5 0.5 0.5"/></geometry></collision>'
        '<collision><origin xyz="0.1 0 0.2" rpy="0.3 0 0"/><geometry><mesh filename="ball.stl" scale="0.5 0.5 0.5"/>'
        '</geometry></collision><collision><geometry><mesh filename="box.stl"/></geometry></collision></link>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>')


@pytest.fixture
def robot(tmp_path, monkeypatch):
    """A URDF with a dense ball (used twice), a box and a flat square; the cache in tmp_path/cache."""
    import trimesh

    monkeypatch.setenv("ARMGUARD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("ARMGUARD_HULL_CACHE", raising=False)
    trimesh.creation.icosphere(subdivisions=3, radius=0.1).export(tmp_path / "ball.stl")
    trimesh.creation.box([0.1, 0.2, 0.05]).export(tmp_path / "box.stl")
    flat = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]], [[0, 1, 2], [0, 2, 3]], process=False)
    flat.export(tmp_path / "flat.stl")
    (tmp_path / "r.urdf").write_text(URDF, encoding="utf-8")
    return tmp_path / "r.urdf"


def _shapes(model) -> list:
    robot = model.scene.robots["r"]
    return [s for ln in sorted(robot.link_shapes) for s in robot.link_shapes[ln]] + \
        [s for b in model.scene.bodies.values() for s in b.shapes]


def _assert_identical(m1, m2) -> None:
    s1, s2 = _shapes(m1), _shapes(m2)
    assert [type(s) for s in s1] == [type(s) for s in s2] and len(s1) >= 4
    for a, b in zip(s1, s2):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        if hasattr(a, "faces"):
            assert len(a.faces) == len(b.faces)
            for fa, fb in zip(a.faces, b.faces):
                np.testing.assert_array_equal(fa, fb)
            np.testing.assert_array_equal(a.planes, b.planes)
            np.testing.assert_array_equal(a.edges, b.edges)
        for x, y in zip(a._pbuf, b._pbuf):  # every kernel buffer, the vertex graph included
            np.testing.assert_array_equal(x, y)
    for g1, g2 in zip(m1.collision_model.geometryObjects, m2.collision_model.geometryObjects):
        np.testing.assert_array_equal(np.asarray(g1.geometry.points()), np.asarray(g2.geometry.points()))
        assert g1.geometry.num_polygons == g2.geometry.num_polygons


def test_a_cache_hit_gives_the_computed_shapes(robot):
    m1 = armguard.load_model(robot, srdf=False)
    assert dict(m1.hull_cache) == {"folder": str(hull_cache_dir()), "computed": 3, "stored": 3}  # ball.stl once for its two uses
    entries = sorted(hull_cache_dir().glob("*.npz"))
    assert len(entries) == 3
    m2 = armguard.load_model(robot, srdf=False)
    assert dict(m2.hull_cache) == {"folder": str(hull_cache_dir()), "hits": 3}
    _assert_identical(m1, m2)
    assert m1.sha256 == m2.sha256 and len(m1.sha256) == 4  # the URDF and its three meshes


def _rewrite(target, edit, *, keep_checksum: bool) -> None:
    """Rewrite entry ``target`` with ``edit(parts)`` applied; its arrays' SHA-256 made to match
    them again (a consistent edit, caught by the hull checks) unless ``keep_checksum``."""
    with np.load(target) as z:
        parts = dict(z)
    edit(parts)
    if not keep_checksum:
        parts["sha256"] = np.array(_arrays_sha256(parts))
    with open(target, "wb") as f:
        np.savez(f, **parts)


def _bad_index(parts):
    parts["triangles"] = parts["triangles"] + len(parts["vertices"])
    if not len(parts["triangles"]):  # the flat square: a face loop out of range instead
        parts["face_lengths"] = np.array([3], dtype=np.int64)
        parts["face_loops"] = np.array([0, 1, 99], dtype=np.int64)


@pytest.mark.parametrize("damage", ["garbage", "truncated", "bad index", "shrunk", "another mesh's"])
def test_a_damaged_entry_is_recomputed_with_a_warning(robot, damage):
    m1 = armguard.load_model(robot, srdf=False)
    entries = sorted(hull_cache_dir().glob("*.npz"))
    target = entries[0]
    if damage == "garbage":
        target.write_bytes(b"not a hull")
    elif damage == "truncated":
        target.write_bytes(target.read_bytes()[:200])
    elif damage == "bad index":  # a readable archive whose triangles name a vertex that is not there
        _rewrite(target, _bad_index, keep_checksum=False)
    elif damage == "shrunk":  # a hand edit: every vertex and plane offset scaled, the checksum left as written
        def shrink(parts):
            parts["vertices"] = parts["vertices"] * 0.3
            parts["planes"] = parts["planes"] * np.array([1.0, 1.0, 1.0, 0.3])
        _rewrite(target, shrink, keep_checksum=True)
    else:  # a copy of another mesh's entry under this one's name
        target.write_bytes(entries[1].read_bytes())
    why = {"garbage": "", "truncated": "", "bad index": "do not make a hull", "shrunk": "was edited",
           "another mesh's": "another mesh or scale"}[damage]
    with pytest.warns(ArmguardWarning, match=f"hull cache entry {target}.*{why}"):
        m2 = armguard.load_model(robot, srdf=False)
    assert m2.hull_cache["computed"] == 1 and m2.hull_cache["hits"] == 2
    _assert_identical(m1, m2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)  # rewritten: read back without a warning
        m3 = armguard.load_model(robot, srdf=False)
    assert m3.hull_cache["hits"] == 3


def test_a_changed_mesh_is_a_new_entry(robot):
    import trimesh

    m1 = armguard.load_model(robot, srdf=False)
    trimesh.creation.box([0.1, 0.2, 0.5]).export(robot.parent / "box.stl")  # taller
    m2 = armguard.load_model(robot, srdf=False)
    assert m2.hull_cache["computed"] == 1 and m2.hull_cache["hits"] == 2
    assert len(list(hull_cache_dir().glob("*.npz"))) == 4
    z1 = [np.ptp(s.vertices[:, 2]) for s in _shapes(m1)]
    z2 = [np.ptp(s.vertices[:, 2]) for s in _shapes(m2)]
    assert max(z2) == pytest.approx(0.5, abs=1e-7) and max(z1) < 0.2  # the new box, not the cached one


def test_a_gltf_buffer_edited_is_a_new_entry_and_one_of_the_files(tmp_path, monkeypatch):
    """A glTF keeps its vertices in its ``.bin`` buffer: an edit of the buffer alone (the ``.gltf``
    byte for byte the same) is a new entry, and the buffer is one of ``Model.files``."""
    import trimesh

    monkeypatch.setenv("ARMGUARD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("ARMGUARD_HULL_CACHE", raising=False)

    def export(size):
        files = trimesh.creation.box([size] * 3).export(file_type="gltf")
        for name, data in files.items():
            (tmp_path / ("box.gltf" if name.endswith(".gltf") else name)).write_bytes(data)
        return sorted(n for n in files if not n.endswith(".gltf"))

    buffers = export(0.2)
    assert buffers  # the vertices live outside the .gltf
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>'
        '<link name="arm"><collision><geometry><mesh filename="box.gltf"/></geometry></collision></link>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.5"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>', encoding="utf-8")
    m1 = armguard.load_model(tmp_path / "r.urdf", srdf=False)
    gltf = (tmp_path / "box.gltf").read_bytes()
    assert export(0.6) == buffers
    (tmp_path / "box.gltf").write_bytes(gltf)  # only the buffer changed (its bounds in the .gltf kept)
    m2 = armguard.load_model(tmp_path / "r.urdf", srdf=False)
    assert m2.hull_cache["computed"] == 1 and not m2.hull_cache.get("hits")
    size = [np.ptp(m.hulls[next(iter(m.hulls))].vertices, axis=0) for m in (m1, m2)]
    np.testing.assert_allclose(size[0], 0.2, atol=1e-6)
    np.testing.assert_allclose(size[1], 0.6, atol=1e-6)  # the edited buffer's box, not the cached 0.2 m one
    paths = [str((tmp_path / b).resolve()) for b in buffers]
    assert set(paths) <= set(map(str, m2.files))
    assert any(m1.sha256[p] != m2.sha256[p] for p in paths)  # the vertex buffer's edit is on record


def test_a_mesh_replaced_while_hulled_is_not_stored_under_the_old_bytes(robot, monkeypatch):
    """A checkout that replaces box.stl between the cache's hash of it and its reading: the hull
    made is the new file's, stored under the new bytes' key; loading the old file again (restored)
    gives the old box, never the new one from the cache."""
    import trimesh

    from armguard.model import _urdf

    old = (robot.parent / "box.stl").read_bytes()
    tall = trimesh.creation.box([0.1, 0.2, 0.5]).export(file_type="stl")
    read = _urdf._mesh_vertices

    def replaced_first(path, scale):
        if str(path).endswith("box.stl"):
            (robot.parent / "box.stl").write_bytes(tall)  # replaced after the hash, before the read
        return read(path, scale)

    monkeypatch.setattr(_urdf, "_mesh_vertices", replaced_first)
    m1 = armguard.load_model(robot, srdf=False)
    monkeypatch.setattr(_urdf, "_mesh_vertices", read)
    (robot.parent / "box.stl").write_bytes(old)
    m2 = armguard.load_model(robot, srdf=False)
    z1 = max(np.ptp(s.vertices[:, 2]) for s in _shapes(m1))
    z2 = max(np.ptp(s.vertices[:, 2]) for s in _shapes(m2))
    assert z1 == pytest.approx(0.5, abs=1e-7)  # the file as it was when read
    assert z2 < 0.2  # the old box again: its key holds no tall hull


def test_the_cache_can_be_turned_off(robot, monkeypatch):
    monkeypatch.setenv("ARMGUARD_HULL_CACHE", "0")
    assert hull_cache_dir() is None
    m1 = armguard.load_model(robot, srdf=False)
    m2 = armguard.load_model(robot, srdf=False)
    assert dict(m2.hull_cache) == {"folder": None, "computed": 3}
    assert not (robot.parent / "cache").exists()
    _assert_identical(m1, m2)


def test_an_unwritable_cache_folder_warns_and_loads(robot, monkeypatch):
    (robot.parent / "file").write_text("a file, not a folder")
    monkeypatch.setenv("ARMGUARD_CACHE_DIR", str(robot.parent / "file"))
    with pytest.warns(ArmguardWarning, match="could not be written") as got:
        m = armguard.load_model(robot, srdf=False)
    assert m.hull_cache["computed"] == 3
    assert len([w for w in got if issubclass(w.category, ArmguardWarning)]) == 1  # once per load, not per mesh
