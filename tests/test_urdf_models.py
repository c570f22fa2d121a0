"""The models in urdf/ (docs/models.md): Pinocchio loads every one, with every collision element,
and each has the same kinematics, geometry, limits and checked pairs as the built-in YAML scene it
was written from by tools/dh_to_urdf (armguard.model.export)."""

from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

pin = pytest.importorskip("pinocchio")
coal = pytest.importorskip("coal")

from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere  # noqa: E402
from armguard.kinematics import Coupling, DHRow, Robot  # noqa: E402
from armguard.harness import seed_data  # noqa: E402
from armguard.model.export import export_scene  # noqa: E402
from armguard.models import builtin_path  # noqa: E402
from armguard.scene import Scene, load_scene_file  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
URDF_DIR = ROOT / "urdf"
SYSTEMS = ("ranger", "hermes", "puma560", "gmf_s480", "rover")
URDF_FILES = sorted(URDF_DIR.glob("**/*.urdf"))
TOL = 1e-9
_CACHE: dict = {}


def _load(path: Path):
    key = str(path)
    if key not in _CACHE:
        model = pin.buildModelFromUrdf(key, mimic=True)
        geom = pin.buildGeomFromUrdf(model, key, pin.COLLISION, package_dirs=[str(path.parent), str(URDF_DIR)])
        _CACHE[key] = (model, geom)
    return _CACHE[key]


def _system(name: str):
    """Today's built-in YAML scene (the reference) and the URDF written from it."""
    if name not in _CACHE:
        _CACHE[name] = load_scene_file(builtin_path(name))
    return _CACHE[name], URDF_DIR / name / f"{name}.urdf"


def _link(owner: str) -> str:
    return owner.replace("/", "_")  # docs/models.md: R/link <-> R_link; bodies and payloads by name


def _pin_q(model, scene, q: dict) -> np.ndarray:
    out = pin.neutral(model)
    for r, robot in scene.robots.items():
        for j, v in zip(robot.joint_names, q[r]):
            jid = model.getJointId(f"{r}_{j}")
            assert jid < model.njoints, f"no URDF joint {r}_{j}"
            out[model.idx_qs[jid]] = v
    return out


def _random_q(scene, rng) -> dict:
    return {r: rng.uniform(robot.lower, robot.upper) for r, robot in scene.robots.items()}


def _placed(model, geom, q):
    data, gdata = model.createData(), pin.GeometryData(geom)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    pin.updateGeometryPlacements(model, data, geom, gdata)
    return data, {go.name: (go.geometry, gdata.oMg[k], go.meshPath) for k, go in enumerate(geom.geometryObjects)}


def _obj_vertices(path) -> np.ndarray:
    rows = [ln.split()[1:4] for ln in Path(path).read_text().splitlines() if ln.startswith("v ")]
    return np.array(rows, dtype=np.float64)


def _points(g, M) -> np.ndarray:
    R, t = M.rotation, M.translation
    if isinstance(g, coal.Box):
        h = np.asarray(g.halfSide)
        signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)
        return t + (signs * h) @ R.T
    pts = np.asarray(g.points() if callable(g.points) else g.points, dtype=np.float64).reshape(-1, 3)
    return pts @ R.T + t


def _same_set(a: np.ndarray, b: np.ndarray) -> bool:
    if len(a) != len(b):
        return False
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return d.min(axis=1).max() < TOL and d.min(axis=0).max() < TOL


def _compare_shape(shape, g, M, mesh_path, where: str) -> None:
    R, t = M.rotation, M.translation
    if isinstance(shape, Capsule):
        assert isinstance(g, coal.Capsule), where
        h = float(g.halfLength)
        ends = np.array([t - h * R[:, 2], t + h * R[:, 2]])
        assert _same_set(ends, np.array([shape.p0, shape.p1])), where
        assert abs(g.radius - shape.radius) < TOL, where
    elif isinstance(shape, Sphere):
        assert isinstance(g, coal.Sphere), where
        assert np.linalg.norm(t - shape.center) < TOL and abs(g.radius - shape.radius) < TOL, where
    elif isinstance(shape, Box):
        assert isinstance(g, coal.Box), where
        assert np.linalg.norm(t - shape.center) < TOL, where
        assert _same_set(_points(g, M), shape.vertices), where
    else:
        assert isinstance(shape, (Prism, ConvexPolyhedron, Polygon)), where
        assert isinstance(g, coal.Convex), where
        # The OBJ keeps the exact vertices (17 digits); Pinocchio reads meshes through assimp in
        # single precision, so coal's Convex holds them rounded to float32 (docs/models.md).
        local = _obj_vertices(mesh_path)
        assert _same_set(local @ R.T + t, np.asarray(shape.core_points)), where
        stored = np.asarray(g.points() if callable(g.points) else g.points, dtype=np.float64).reshape(-1, 3)
        assert _same_set(stored, local.astype(np.float32).astype(np.float64)), where
        assert np.abs(_points(g, M) - (stored @ R.T + t)).max() < TOL


def _compare_scene(scene, path: Path, n_configs: int, seed: int = 0) -> None:
    """Pinocchio's FK and geometry placements equal ``scene.shapes_at(q)`` and the tool frames."""
    model, geom = _load(path)
    srdf = _srdf(path.with_suffix(".srdf"))
    assert model.nq == len(scene.joint_names)
    rng = np.random.default_rng(seed)
    configs = [scene.default_q()] + [_random_q(scene, rng) for _ in range(n_configs)]
    for q in configs:
        data, placed = _placed(model, geom, _pin_q(model, scene, q))
        items = scene.shapes_at(q)
        count: dict = {}
        for item in items:
            k = count.get(item.owner, 0)
            count[item.owner] = k + 1
            name = f"{_link(item.owner)}_{k}"
            assert name in placed, f"{path.name}: no geometry {name}"
            _compare_shape(item.shape, *placed[name], f"{path.name} {name}")
        assert len(items) == len(placed)
        for r, robot in scene.robots.items():
            tip = srdf["chains"][r][1]
            X_WT = robot.forward_kinematics(q[r])[robot.link_index(robot.tool_link)]
            M = data.oMf[model.getFrameId(tip)]
            assert np.abs(M.homogeneous - X_WT).max() < TOL, f"{path.name}: {tip} vs {r}/{robot.tool_link}"


def _srdf(path: Path) -> dict:
    root = ET.parse(path).getroot()
    groups = {g.get("name"): g for g in root.iter("group")}
    chains = {n: (g.find("chain").get("base_link"), g.find("chain").get("tip_link"))
              for n, g in groups.items() if g.find("chain") is not None}
    members = {n: [ln.get("name") for ln in g.findall("link")] for n, g in groups.items()}
    disabled = [(e.get("link1"), e.get("link2"), e.get("reason")) for e in root.iter("disable_collisions")]
    states = {(s.get("name"), s.get("group")): {j.get("name"): float(j.get("value")) for j in s.findall("joint")}
              for s in root.iter("group_state")}
    return {"chains": chains, "members": members, "disabled": disabled, "states": states}


def _collisions(path: Path):
    """``[(link, collision name, geometry tag, mark or None)]`` in file order, from the XML."""
    out = []
    for link in ET.parse(path).getroot().findall("link"):
        marks = {el.get("name"): el.tag for cc in link.findall("collision_checking") for el in cc}
        for c in link.findall("collision"):
            tag = list(c.find("geometry"))[0].tag
            out.append((link.get("name"), c.get("name"), tag, marks.get(c.get("name"))))
        assert set(marks) <= {c.get("name") for c in link.findall("collision")}, f"{path.name}: a mark names nothing"
    return out


# ------------------------------------------------------------------ every file in urdf/
def test_the_five_systems_are_there():
    for s in SYSTEMS:
        for ext in ("urdf", "srdf", "yaml"):
            assert (URDF_DIR / s / f"{s}.{ext}").is_file()


@pytest.mark.parametrize("path", URDF_FILES, ids=lambda p: str(p.relative_to(URDF_DIR)))
def test_every_collision_element_reaches_pinocchio(path):
    model, geom = _load(path)
    xml = _collisions(path)
    assert len(xml) == geom.ngeoms > 0
    per_link: dict = {}
    for go in geom.geometryObjects:
        per_link.setdefault(model.frames[go.parentFrame].name, []).append(go)
    expected = {"capsule": coal.Capsule, "convex": coal.Convex}
    plain = {"box": coal.Box, "sphere": coal.Sphere, "cylinder": coal.Cylinder, "mesh": coal.BVHModelBase}
    seen: dict = {}
    for link, cname, tag, mark in xml:
        i = seen.get(link, 0)
        seen[link] = i + 1
        go = per_link[link][i]
        assert go.name == f"{link}_{i}"
        assert isinstance(go.geometry, expected.get(mark) or plain[tag]), f"{path.name} {cname}: {type(go.geometry)}"
        if mark == "capsule":
            assert tag == "cylinder"
        if mark == "convex":
            assert tag == "mesh"


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # trimesh's, inside yourdfpy
@pytest.mark.parametrize("path", URDF_FILES, ids=lambda p: str(p.relative_to(URDF_DIR)))
def test_yourdfpy_loads_every_file(path):
    yourdfpy = pytest.importorskip("yourdfpy")
    u = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                           build_collision_scene_graph=True, load_collision_meshes=True)
    assert u.validate() and u.collision_scene is not None
    n = sum(len(link.collisions) for link in u.robot.links)
    assert n == len(_collisions(path))
    for link in u.robot.links:
        for c in link.collisions:
            if c.geometry.mesh is not None:
                assert (path.parent / c.geometry.mesh.filename).is_file()


# ------------------------------------------------------------------ the same model as today's scenes
@pytest.mark.parametrize("system", SYSTEMS)
def test_same_kinematics_and_geometry_as_the_scene(system):
    scene, path = _system(system)
    _compare_scene(scene, path, n_configs=50)


@pytest.mark.parametrize("system", SYSTEMS)
def test_joint_limits_and_velocities(system):
    scene, path = _system(system)
    model, _ = _load(path)
    for r, robot in scene.robots.items():
        for k, j in enumerate(robot.joint_names):
            jid = model.getJointId(f"{r}_{j}")
            iq, iv = model.idx_qs[jid], model.idx_vs[jid]
            assert model.lowerPositionLimit[iq] == pytest.approx(robot.lower[k], abs=1e-12)
            assert model.upperPositionLimit[iq] == pytest.approx(robot.upper[k], abs=1e-12)
            assert model.velocityLimit[iv] == pytest.approx(robot.max_velocity[k], abs=1e-12)


@pytest.mark.parametrize("system", SYSTEMS)
def test_srdf_reproduces_the_checked_pairs_groups_and_home(system):
    scene, path = _system(system)
    srdf = _srdf(path.with_suffix(".srdf"))
    geometric = sorted({_link(o) for o in scene.owners()})
    disabled = {frozenset((a, b)) for a, b, _ in srdf["disabled"]}
    assert len(disabled) == len(srdf["disabled"])
    checked = {frozenset((a, b)) for i, a in enumerate(geometric) for b in geometric[i + 1:]} - disabled
    assert checked == {frozenset((_link(p.a), _link(p.b))) for p in scene.allowed_pairs()}
    assert set(srdf["chains"]) == set(scene.robots)
    for r, robot in scene.robots.items():
        assert srdf["chains"][r][0] == f"{r}_{robot.root_link}"
        home = srdf["states"][("home", r)]
        assert home == {f"{r}_{j}": pytest.approx(v, abs=1e-15) for j, v in zip(robot.joint_names, scene.home(r))}
    vehicle = [b.name for b in scene.bodies.values() if b.category == "vehicle"]
    assert srdf["members"].get("vehicle", []) == vehicle
    assert srdf["members"].get("payload", []) == list(scene.payloads)


def test_hermes_self_pairs_and_seed_rules_in_the_srdf():
    scene, path = _system("hermes")
    srdf = _srdf(path.with_suffix(".srdf"))
    off = {frozenset((a, b)): reason for a, b, reason in srdf["disabled"]}
    links = [f"hera_link{i}" for i in (1, 2, 3, 4, 6)]
    listed = {(1, 3), (1, 4), (1, 6), (2, 4), (2, 6), (3, 6)}
    for i, a in enumerate(links):
        for b in links[i + 1:]:
            pair = (int(a[-1]), int(b[-1]))
            assert (frozenset((a, b)) in off) == (pair not in listed), pair
    for body in scene.bodies:
        assert off[frozenset(("hera_link1", body))] == "Seed"
    # the seed's payload-link module examines "the first four links"; its "last three links" would drop
    # link 4: the conservative reading checks it
    assert frozenset(("payload", "hera_link4")) not in off
    assert frozenset(("payload", "hera_link6")) in off


def test_hermes_polyhedra_faces_and_vertices():
    _, path = _system("hermes")
    model, geom = _load(path)
    _, placed = _placed(model, geom, pin.neutral(model))
    polys = [ConvexPolyhedron(_points(g, M)) for name, (g, M, _) in placed.items()
             if isinstance(g, (coal.Box, coal.Convex)) and not name.startswith(("hera_", "payload"))]
    hermes = seed_data("hermes")["model"]  # reference/seeds/hermes.yaml
    assert len(polys) == hermes["polyhedra"]
    assert sum(len(p.faces) for p in polys) == hermes["faces"]
    assert sum(len(p.vertices) for p in polys) == hermes["vertices"]


@pytest.mark.parametrize("system", SYSTEMS)
def test_sidecar_keeps_what_urdf_cannot_say(system):
    scene, path = _system(system)
    side = yaml.safe_load(path.with_suffix(".yaml").read_text())
    source = yaml.safe_load(builtin_path(system).read_text())
    assert side["armguard_scene"] == 1 and side["name"] == system
    assert side["units"] == {"angle": "deg", "length": "m"} == source["units"]
    assert side["model"] == {"urdf": f"{system}.urdf", "srdf": f"{system}.srdf"}
    assert side["description"] == scene.description
    for key in ("workspace", "trajectories", "canned_tests"):
        assert side.get(key) == source.get(key), key
    acc = {f"{r}/{j}": math.degrees(a) for r, robot in scene.robots.items()
           for j, a in zip(robot.joint_names, robot.max_acceleration)}
    assert {k: v["max_acceleration"] for k, v in side["joints"].items()} == pytest.approx(acc, rel=1e-12)
    text = path.with_suffix(".yaml").read_text()
    assert text.count("# assumed") == builtin_path(system).read_text().count("# assumed") - _assumed_outside(system)


def _assumed_outside(system: str) -> int:
    """``# assumed`` notes of the source outside the sidecar's sections (they go to the URDF/SRDF)."""
    text = builtin_path(system).read_text()
    keep = ("workspace", "trajectories", "canned_tests")
    n, section = 0, None
    for ln in text.splitlines():
        if ln[:1].isalpha():
            section = ln.split(":")[0]
        if "# assumed" in ln and section not in keep and not ln.startswith("#"):
            n += 1
    return n


@pytest.mark.parametrize("system", SYSTEMS)
def test_assumed_notes_reach_the_urdf_and_srdf(system):
    _, path = _system(system)
    text = path.read_text() + path.with_suffix(".srdf").read_text()
    assert text.count("# assumed") >= _assumed_outside(system) > 0
    header = builtin_path(system).read_text().split("armguard_scene:")[0]
    assert header.splitlines()[0].lstrip("# ") in path.read_text()


# ------------------------------------------------------------------ export_scene on a scene made here
def _small_scene() -> Scene:
    rows = [DHRow(0.1, math.pi / 2, 0.4, 0.2), DHRow(0.5, 0.0, 0.0), DHRow(0.4, 0.0, 0.0, -0.3),
            DHRow(0.0, -math.pi / 2, 0.1, 0.0, "prismatic"), DHRow(0.0, math.pi / 2, 0.0), DHRow(0.05, 0.0, 0.15)]
    couplings = [Coupling("j3", {"j3": 1.0, "j2": -1.0}),           # a drive coupling: j3 commanded from j2's link
                 Coupling("j5", {"j2": 0.5, "j1": -0.25}, offset=0.1)]  # a dependent joint with an offset
    robot = Robot.from_dh(
        "arm", rows, joint_names=[f"j{i}" for i in range(1, 7)], lower=[-2.0, -1.0, -2.5, 0.0, -1.5], upper=[2.0, 1.5, 2.5, 0.2, 1.5],
        max_velocity=[1.0, 1.1, 1.2, 0.3, 1.4], max_acceleration=[2.0, 2.0, 2.0, 0.5, 3.0], couplings=couplings,
        X_WB=np.array([[0.0, -1, 0, 0.3], [1, 0, 0, -0.2], [0, 0, 1, 0.1], [0, 0, 0, 1]]),
        link_shapes={"link0": [Sphere([0, 0, 0.1], 0.15)], "link1": [Capsule([0, 0, -0.3], [0.1, 0, 0], 0.08)],
                     "link2": [Capsule([-0.5, 0, 0], [0, 0, 0], 0.06)],
                     "link3": [Prism([-0.2, 0, 0], np.eye(3), 0.04, 0.15, 6)],
                     "link6": [Box([0, 0, -0.05], [0.03, 0.04, 0.05])]},
    )
    scene = Scene("small")
    scene.add_body("wall", [Box([1.5, 0, 0.5], [0.05, 1, 0.5]), Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0.2]])],
                   category="vehicle")
    scene.add_body("post", ConvexPolyhedron(np.random.default_rng(3).normal(size=(12, 3)) * 0.1 + [0.8, 0.8, 0.3]))
    scene.add_robot(robot, home=[0.1, 0.2, -0.3, 0.05, 0.0])
    scene.attach_payload("part", "arm", "link6", [Capsule([0, 0, 0], [0, 0.1, 0.05], 0.03)],
                         np.array([[1.0, 0, 0, 0], [0, 0, -1, 0.02], [0, 1, 0, 0.03], [0, 0, 0, 1]]))
    scene.disable_pair("arm/link1", "wall")
    scene.set_workspace([-2, -2, -1], [2, 2, 2])
    return scene


def test_export_round_trip(tmp_path):
    scene = _small_scene()
    paths = export_scene(scene, tmp_path / "small")
    assert {k for k in paths} == {"urdf", "srdf", "yaml", "meshes"} and len(paths["meshes"]) == 3
    model, geom = _load(paths["urdf"])
    assert model.nq == 5 and geom.ngeoms == len(_collisions(paths["urdf"])) == 9
    _compare_scene(scene, paths["urdf"], n_configs=30, seed=1)
    srdf = _srdf(paths["srdf"])
    geometric = sorted({_link(o) for o in scene.owners()})
    disabled = {frozenset((a, b)) for a, b, _ in srdf["disabled"]}
    checked = {frozenset((a, b)) for i, a in enumerate(geometric) for b in geometric[i + 1:]} - disabled
    assert checked == {frozenset((_link(p.a), _link(p.b))) for p in scene.allowed_pairs()}
    side = yaml.safe_load(paths["yaml"].read_text())
    assert side["workspace"] == {"lo": [-2.0, -2.0, -1.0], "hi": [2.0, 2.0, 2.0]}
    assert side["joints"]["arm/j4"]["max_acceleration"] == pytest.approx(0.5)  # prismatic: m/s^2


def test_tool_frame_folds_into_an_existing_tool_link(tmp_path):
    robot = Robot.from_dh("r", [DHRow(0.3, math.pi / 2, 0.2), DHRow(0.4, 0.0, 0.0)], lower=[-1, -1], upper=[1, 1],
                          max_velocity=[1, 1], max_acceleration=[1, 1],
                          X_LT=np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.2], [0, 0, 0, 1]]))
    scene = Scene("t")
    scene.add_robot(robot)
    paths = export_scene(scene, tmp_path)
    root = ET.parse(paths["urdf"]).getroot()
    assert [ln.get("name") for ln in root.findall("link")].count("r_tool") == 1
    assert _srdf(paths["srdf"])["chains"]["r"] == ("r_link0", "r_tool")
    model, _ = _load(paths["urdf"])
    data = model.createData()
    for q in np.random.default_rng(2).uniform(-1, 1, (10, 2)):
        pin.framesForwardKinematics(model, data, q)
        X = data.oMf[model.getFrameId("r_tool")].homogeneous
        assert np.abs(X - robot.forward_kinematics(q)[robot.link_index("tool")]).max() < TOL


def test_command_line_tool(tmp_path):
    out = tmp_path / "gmf"
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "dh_to_urdf.py"), "gmf_s480", "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    model, geom = _load(out / "gmf_s480.urdf")
    assert model.nq == 4 and geom.ngeoms == 7
    # a file that is no scene file (WORKMATE's cell file): its located error, exit 3, not a traceback
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "dh_to_urdf.py"), str(ROOT / "examples" / "workmate" / "cell.yaml"),
                        "--out", str(tmp_path / "cell")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 3 and r.stderr.startswith("error: ") and "Traceback" not in r.stderr, r.stderr
    assert "armguard_scene: required key is missing" in r.stderr


def test_the_sidecar_keeps_each_arms_ik(tmp_path):
    """A scene whose arms name their inverse kinematics writes them into the sidecar (it dropped the
    ``ik:`` line, so an arm rebuilt from the files warned on its first IK that it had no routine)."""
    import armguard
    from armguard.model.export import export_scene

    for name, line in (("puma560", "ik: {puma560: puma560}"), ("hermes", "ik: {hera: numeric}")):
        paths = export_scene(armguard.load_scene(name), tmp_path / name)
        text = paths["yaml"].read_text()
        assert line in text, text
        assert {r: rb.ik for r, rb in armguard.load_scene(str(paths["yaml"])).robots.items()} == \
            {r: rb.ik for r, rb in armguard.load_scene(name).robots.items()}


def test_an_export_over_a_model_with_a_folder_at_one_name_writes_nothing(tmp_path):
    """A folder at one mesh's name: the URDF, SRDF, sidecar and earlier meshes were already new, the new URDF
    naming a mesh that was not written.  Every name is checked before one file is written."""
    from armguard import OutputError

    scene = load_scene_file(builtin_path("hermes"))
    paths = export_scene(scene, tmp_path, source=builtin_path("hermes"))
    assert paths["meshes"]
    victim = paths["meshes"][-1]
    victim.unlink()
    victim.mkdir()
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    edited = tmp_path.parent / "hermes_edited.yaml"  # its header comment goes into the URDF: another URDF text
    edited.write_text("# edited\n" + builtin_path("hermes").read_text(encoding="utf-8"))
    with pytest.raises(OutputError, match=f"{victim.name}: it exists and is a folder"):
        export_scene(scene, tmp_path, source=edited, name="hermes")
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_an_export_that_fails_part_way_replaces_nothing(tmp_path, monkeypatch):
    """A full disk while the second export writes: the first export's URDF, SRDF, sidecar and meshes are
    all as they were (the meshes were written one by one into place before, so a failure after them left
    the old URDF naming new meshes: another model), and no staging folder is left behind."""
    import errno

    from armguard import OutputError
    from armguard import _io

    scene = _small_scene()
    export_scene(scene, tmp_path)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    scene.remove_body("post")  # the same mesh name, other points
    scene.add_body("post", ConvexPolyhedron(np.random.default_rng(4).normal(size=(12, 3)) * 0.1 + [0.8, 0.8, 0.3]))
    real, calls = _io._write_file, []

    def write(path, blob):
        calls.append(path)
        if len(calls) == 4:  # the three meshes are written, then the disk is full
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(path, blob)

    monkeypatch.setattr(_io, "_write_file", write)
    with pytest.raises(OutputError, match="No space left"):
        export_scene(scene, tmp_path)
    assert len(calls) == 4
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".armguard-")]
    monkeypatch.setattr(_io, "_write_file", real)
    paths = export_scene(scene, tmp_path)  # and the whole new set when it can be written
    post = next(p for p in paths["meshes"] if p.name.startswith("post"))
    assert post.read_bytes() != before[post]
    _compare_scene(scene, paths["urdf"], n_configs=10, seed=2)


def test_an_export_keeps_permissions_follows_a_linked_meshes_folder_and_refuses_a_name_with_a_folder(tmp_path):
    """Writing the export as one set: a private URDF and mesh (0600) came back 0644; ``meshes/`` a link to a
    folder on another file system was refused (the files were each written in place before); a name with a
    folder part (``sub/cell``) was reported at ``out/sub/cell.urdf`` while written at ``out/cell.urdf``, and
    ``model_from_scene`` of a scene named so failed.  Now: permissions kept, the linked folder written, the
    name refused as such (its URDF would not find its meshes), and the scene's Model made."""
    import os
    import shutil
    import tempfile

    from armguard import OutputError
    from armguard.model._load import model_from_scene

    scene = _small_scene()
    paths = export_scene(scene, tmp_path / "a")
    os.chmod(paths["urdf"], 0o600)
    os.chmod(paths["meshes"][0], 0o600)
    again = export_scene(scene, tmp_path / "a")
    assert os.stat(again["urdf"]).st_mode & 0o777 == 0o600 and os.stat(again["meshes"][0]).st_mode & 0o777 == 0o600

    with pytest.raises(OutputError, match="'sub/cell' is not a plain file name"):
        export_scene(scene, tmp_path / "b", name="sub/cell")
    assert not (tmp_path / "b").exists()
    n_pairs = len(model_from_scene(scene).pairs.a)
    scene.name = "cells/small"
    assert len(model_from_scene(scene).pairs.a) == n_pairs > 0

    other = Path(tempfile.mkdtemp(dir="/dev/shm")) if Path("/dev/shm").is_dir() else None
    if other is None or os.stat(other).st_dev == os.stat(tmp_path).st_dev:
        if other is not None:
            shutil.rmtree(other, ignore_errors=True)
        return  # no second file system here: the rest is held by tests/test_io_outputs.py's own
    try:
        (tmp_path / "c").mkdir()
        (tmp_path / "c" / "meshes").symlink_to(other)
        linked = export_scene(scene, tmp_path / "c", name="small")
        assert sorted(p.name for p in other.iterdir()) == sorted(p.name for p in linked["meshes"])
        _compare_scene(scene, linked["urdf"], n_configs=5, seed=3)
    finally:
        shutil.rmtree(other, ignore_errors=True)
