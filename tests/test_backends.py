"""The backend plugins against each other: analytic vs the coal reference (and python-fcl) on every model.

Tolerances, in one place: ``armguard.Tolerances``' ``differential_*`` fields (``src/armguard/harness/_tolerances.py``,
shared with ``tests/test_reference.py`` and ``armguard compare``):

* ``CONTACT_BAND``: a verdict may differ only where the reference distance is within this of 0;
* ``DISTANCE_TOL``: separated distances agree within this (both backends exact up to round-off;
  coal's GJK on mesh hulls stops within ``HULL_TOL``, measured 3.6e-6 m on the Panda's hulls);
* ``WITNESS_TOL``: the analytic backend's witness relation ``| |p_WA - p_WB| - |d| |``;
* ``FCL_TOL``: python-fcl's separated distances run long (GJK stopped early: up to 0.39 m on
  Hermes in 10^4 configurations, never short of the exact distance); it is held to that
  one-sided bound and to verdicts outside this band.
* coal's witness points are checked on separated pairs only: on penetrating mesh-hull pairs its
  points were seen not to keep ``|p_WA - p_WB| == |d|``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard import BackendError, SceneFileError
from armguard.backends import available, resolve
from armguard import DEFAULT_TOLERANCES as TOL

CONTACT_BAND = TOL.differential_contact_band
DISTANCE_TOL = TOL.differential_distance
HULL_TOL = TOL.differential_hull
WITNESS_TOL = TOL.differential_witness
FCL_TOL = TOL.differential_fcl
N_DISTANCE = 2000  # 10^4 per model: `armguard compare` (docs/backends.md)
N_VERDICT = 10_000

import sysconfig

# example-robot-data ships data only: its files lie in site-packages' cmeel prefix
ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
MODELS = ["ranger", "hermes", "puma560", "gmf_s480", "rover", "panda", "ur5", "iiwa_world20"]
WORLD20 = Path(__file__).resolve().parents[1] / "bench" / "data" / "world20.json"


def iiwa_world20_yaml(folder: Path) -> Path:
    """A scene file: pybullet's KUKA iiwa (its URDF's mesh hulls) among the 20 boxes of bench/data/world20.json."""
    import json

    import pybullet_data
    import yaml

    urdf = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
    boxes = json.loads(WORLD20.read_text())["boxes"]
    data = {"armguard_scene": 1, "name": "iiwa_world20", "robots": [{"name": "iiwa", "urdf": str(urdf)}],
            "bodies": [{"name": f"box{i}", "shapes": [{"type": "box", "size": [2 * h for h in b["half_extents"]],
                                                         "xyz": b["center"], "rpy": [0.0, 0.0, b["yaw"]]}]}
                       for i, b in enumerate(boxes)]}
    path = folder / "iiwa_world20.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _load(name: str, tmp_factory=None):
    if name == "panda":
        return armguard.load_model(ROBOTS / "panda_description/urdf/panda.urdf",
                                   srdf=ROBOTS / "panda_description/srdf/panda.srdf")
    if name == "ur5":
        return armguard.load_model(ROBOTS / "ur_description/urdf/ur5_robot.urdf",
                                   srdf=ROBOTS / "ur_description/srdf/ur5.srdf")
    if name == "iiwa_world20":  # a plain scene file: its Pinocchio side is written as URDF first
        return armguard.load_model(iiwa_world20_yaml(tmp_factory.mktemp("iiwa")))
    return armguard.load_model(name)


def _kind(model, name: str) -> str:
    if name == "workspace":
        return "workspace"
    return type(model.collision_model.geometryObjects[model.geometry_index(name)].geometry).__name__


def _axis(model, name: str, q):
    """A capsule's axis direction in W at q (None for a sphere)."""
    import pinocchio as pin

    go = model.collision_model.geometryObjects[model.geometry_index(name)]
    if type(go.geometry).__name__ != "Capsule":
        return None
    data = model.pin_model.createData()
    pin.framesForwardKinematics(model.pin_model, data, q)
    return (data.oMi[go.parentJoint] * go.placement).rotation[:, 2]


@pytest.fixture(scope="module")
def checkers(tmp_path_factory):
    cache = {}

    def get(name):
        if name not in cache:
            m = _load(name, tmp_path_factory)
            cache[name] = (m, armguard.checker(m, "analytic"), armguard.checker(m, "coal"))
        return cache[name]

    return get


def test_bundled_backends_are_installed():
    assert {"analytic", "coal", "fcl"} <= set(available())


def test_precedence_argument_env_file_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMGUARD_BACKEND", raising=False)
    monkeypatch.delenv("ARMGUARD_CONFIG", raising=False)
    assert resolve()[0] == "analytic"
    (tmp_path / "armguard.toml").write_text('[backend]\nname = "fcl"\n')
    assert resolve()[0] == "fcl"
    monkeypatch.setenv("ARMGUARD_BACKEND", "coal")
    assert resolve()[0] == "coal"
    assert resolve("analytic")[0] == "analytic"
    (tmp_path / "armguard.toml").write_text('[backend]\nname = "coal"\nthreads = 1\n')
    assert resolve() == ("coal", {"threads": 1})


def test_unknown_backend_lists_the_installed_ones(monkeypatch):
    with pytest.raises(BackendError, match="installed backends are .*analytic.*coal"):
        armguard.checker("hermes", "nonesuch")


@pytest.mark.parametrize("name", MODELS, ids=MODELS)
def test_analytic_matches_coal(checkers, name):
    model, a, c = checkers(name)
    assert a.pair_distances(model.neutral()).pairs.shape == (len(model.pairs), 2)
    hull = np.array([any(type(model.collision_model.geometryObjects[model.geometry_index(n)].geometry).__name__ == "Convex"
                         for n in pair if n != "workspace") for pair in model.pairs.names])
    tol = np.where(hull, HULL_TOL, DISTANCE_TOL)
    kinds = [[_kind(model, n) for n in pair] for pair in model.pairs.names]
    unique_witness = np.array([all(k in ("Capsule", "Sphere") for k in pk) for pk in kinds])
    Q = model.random_q(N_DISTANCE, 11)
    worst = 0.0
    for q in Q:
        ra, rc = a.pair_distances(q), c.pair_distances(q)
        assert np.array_equal(ra.pairs, rc.pairs)
        sep = (ra.distance > CONTACT_BAND) & (rc.distance > CONTACT_BAND)
        err = np.abs(ra.distance - rc.distance)
        assert np.all(err[sep] <= tol[sep]), (name, q.tolist(), ra.pairs[sep][np.argmax(err[sep] - tol[sep])])
        worst = max(worst, float(err[sep].max(initial=0.0)))
        gap = np.linalg.norm(ra.p_WA - ra.p_WB, axis=1)
        assert np.all(np.abs(gap - np.abs(ra.distance)) <= WITNESS_TOL)
        # each backend's witness points keep the contract on their own; where they are unique (two
        # capsules with non-parallel axes, a sphere), both backends name the same points
        gap_c = np.linalg.norm(rc.p_WA - rc.p_WB, axis=1)
        assert np.all(np.abs(gap_c - np.abs(rc.distance))[sep] <= tol[sep])
        for k in np.flatnonzero(unique_witness & (ra.distance > TOL.differential_unique_min_distance)):
            da, db = _axis(model, ra.pairs[k, 0], q), _axis(model, ra.pairs[k, 1], q)
            if da is None or db is None or np.linalg.norm(np.cross(da, db)) > TOL.differential_parallel:
                np.testing.assert_allclose(ra.p_WA[k], rc.p_WA[k], atol=TOL.differential_unique_point)
                np.testing.assert_allclose(ra.p_WB[k], rc.p_WB[k], atol=TOL.differential_unique_point)
    Qv = model.random_q(N_VERDICT, 12)
    va, vc = a.collides(Qv), c.collides(Qv)
    differ = np.flatnonzero(va != vc)
    if differ.size:  # only inside the contact band
        dmin = np.array([c.pair_distances(q).distance.min() for q in Qv[differ]])
        assert np.all(np.abs(dmin) <= CONTACT_BAND), (name, Qv[differ][0].tolist())


@pytest.mark.parametrize("name", ["hermes", "ranger", "puma560"], ids=["hermes", "ranger", "puma560"])
def test_fcl_never_reports_less_than_the_exact_distance(checkers, name):
    """python-fcl stops GJK early (its distances ran up to 0.39 m long on Hermes over 10^4
    configurations): an early stop gives a feasible pair of points, so a separated distance is
    never below the exact one, and verdicts agree outside its band."""
    model, a, _ = checkers(name)
    f = armguard.checker(model, "fcl")
    for q in model.random_q(300, 13):
        ra, rf = a.pair_distances(q), f.pair_distances(q)
        assert np.array_equal(ra.pairs, rf.pairs)
        sep = (ra.distance > CONTACT_BAND) & (rf.distance > CONTACT_BAND)
        assert np.all(rf.distance[sep] >= ra.distance[sep] - DISTANCE_TOL), name
        far = np.abs(ra.distance) > FCL_TOL
        assert np.array_equal(ra.distance[far] > 0, rf.distance[far] > 0)


@pytest.mark.parametrize("name", ["ranger", "hermes"])  # ranger: workspace rows (six wall boxes each)
def test_fcl_collides_stops_at_the_first_pair_within_the_margin(checkers, name, monkeypatch):
    """python-fcl's ``collides`` takes its verdicts from the same distances as ``pair_distances``
    (equal at every margin), computing the pairs in order only up to the first within the margin."""
    import fcl

    model, _, _ = checkers(name)
    f = armguard.checker(model, "fcl")
    Q = model.random_q(60, 5)
    D = np.array([f.pair_distances(q).distance for q in Q])
    for margin in (0.0, 0.02, 0.2):
        assert np.array_equal(f.collides(Q, margin=margin), D.min(axis=1) <= margin), margin
    hit = D <= 0.2
    m = next(i for i in range(len(Q)) if hit[i].any() and np.argmax(hit[i]) < D.shape[1] - 1)
    first = int(np.argmax(hit[m]))
    calls, real = [], fcl.distance
    monkeypatch.setattr(fcl, "distance", lambda *a: calls.append(1) or real(*a))
    assert f.collides(Q[m:m + 1], margin=0.2)[0]
    walls = [k for k in range(first) if model.pairs.b[k] == armguard.model.WORKSPACE]
    # every pair before the first hit answered whole (a workspace row: its six walls), the hit's own
    # row up to its nearest wall within the margin, nothing after it
    assert (first - len(walls)) + 6 * len(walls) < len(calls) <= (first - len(walls)) + 6 * len(walls) + 6
    assert len(calls) < sum(6 if b == armguard.model.WORKSPACE else 1 for b in model.pairs.b)


def test_panda_at_its_srdf_home_is_clear(checkers):
    model, a, c = checkers("panda")
    q = model.neutral()
    assert a.pair_distances(q).distance.min() > 0 and not a.collides(q[None])[0] and not c.collides(q[None])[0]


def test_q_is_in_pin_model_order(checkers):
    model, a, _ = checkers("ranger")
    q = model.random_q(1, 3)[0]
    assert q.shape == (model.pin_model.nq,)
    with pytest.raises(BackendError, match="expected shape"):
        a.pair_distances(q[:-1])
    with pytest.raises(BackendError, match="NaN"):
        a.pair_distances(np.full(model.nq, np.nan))


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_a_q_of_joint_angles_on_continuous_joints_is_told_what_to_do(checkers, backend):
    """kinova: six joint angles where Pinocchio's q has nine values (three continuous joints, a
    ``(cos, sin)`` each): the error says so, names each position, and points to ``Model.pin_q``, whose
    answer is then taken."""
    model, a, c = checkers("kinova")
    chk = a if backend == "analytic" else c
    angles = np.array([1.57, 2.6, 4.7, 3.14, 2.6, 0.0])
    with pytest.raises(BackendError, match=r"\(cos, sin\).*Model\.pin_q\(angles\)"):
        chk.pair_distances(angles)
    assert np.isfinite(chk.pair_distances(model.pin_q(angles)).distance).all()


@pytest.mark.parametrize("name", ["gmf_s480", "ranger", "kinova"])  # q in the scene's order; gathered; converted
def test_analytic_collides_a_row_at_a_time_as_in_one_batch(checkers, name):
    """``collides`` on a few rows runs inline on the thread's batch scratch (reused from call to
    call): every row alone answers as the rows in one batch, the batch again after other calls as
    before, and as the fused Detector's ``collides_many`` and coal's distances (clear of contact)."""
    model, a, c = checkers(name)
    Q = model.random_q(300, 17)
    Q[::7] = model.random_q(len(Q[::7]), 18)  # more rows, some in contact
    whole = a.collides(Q)
    assert whole.dtype == bool and whole.shape == (len(Q),) and whole.any() and not whole.all()
    rows = np.array([a.collides(Q[m:m + 1])[0] for m in range(len(Q))])
    np.testing.assert_array_equal(rows, whole)
    hit, clear = int(np.argmax(whole)), int(np.argmin(whole))  # one row: a new verdict array each call
    v = a.collides(Q[hit:hit + 1])
    assert a.collides(Q[clear:clear + 1])[0] == whole[clear] and v[0] and v.dtype == bool and v.shape == (1,)
    a.collides(model.random_q(5, 19))
    np.testing.assert_array_equal(a.collides(Q), whole)
    np.testing.assert_array_equal(a.detector().collides_many(model.scene_q(Q)), whole)
    d = np.array([c.pair_distances(q).distance.min() for q in Q[:60]])
    far = np.abs(d) > CONTACT_BAND
    np.testing.assert_array_equal(whole[:60][far], d[far] <= 0.0)
    with pytest.raises(BackendError, match="NaN"):
        a.collides(np.full((1, model.nq), np.nan))


_BAD = """<robot name="bad"><link name="base"/><link name="l1">
  <collision name="c"><geometry>{geom}</geometry></collision></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="0" velocity="1"/></joint></robot>"""


@pytest.mark.parametrize("geom, where", [
    ('<capsule radius="0.1" length="0.5"/>', "link[l1].collision[0]"),
    ('<mesh filename="nowhere.stl"/>', "link[l1].collision[0]"),
], ids=["plain-capsule-tag", "missing-mesh"])
def test_a_collision_element_pinocchio_would_drop_is_an_error(tmp_path, geom, where):
    p = tmp_path / "bad.urdf"
    p.write_text(_BAD.format(geom=geom))
    with pytest.raises(SceneFileError) as info:
        armguard.load_model(p)
    assert info.value.file == str(p.resolve()) and info.value.where == where


def test_a_malformed_urdf_is_an_error_not_an_empty_model(tmp_path):
    p = tmp_path / "broken.urdf"
    p.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(SceneFileError, match="not well-formed"):
        armguard.load_model(p)


def test_an_srdf_naming_a_missing_link_is_an_error(tmp_path):
    p = tmp_path / "ok.urdf"
    p.write_text(_BAD.format(geom='<sphere radius="0.1"/>'))
    (tmp_path / "ok.srdf").write_text('<robot name="bad"><disable_collisions link1="l1" link2="nope" reason="x"/></robot>')
    with pytest.raises(SceneFileError, match="nope"):
        armguard.load_model(p)


def test_entry_points_are_discovered_once_per_path_and_refreshed_on_request(monkeypatch, tmp_path):
    """``get_backend`` runs on every Detector's construction: the entry points are scanned once (by
    one thread, the others waiting for its result), again when ``sys.path`` changes, and on
    ``available(refresh=True)`` / ``refresh()``; a package installed into a folder already on the
    path shows up only then."""
    import sys
    import threading
    from importlib import metadata

    from armguard import backends

    scans = []
    real = metadata.entry_points

    def counting(**kw):
        scans.append(threading.get_ident())
        return real(**kw)

    monkeypatch.setattr(backends.metadata, "entry_points", counting)
    first = backends.available(refresh=True)
    assert len(scans) == 1 and {"analytic", "coal"} <= set(first)
    for _ in range(5):
        assert backends.available() == first
        backends.get_backend("analytic")
    assert len(scans) == 1
    scans.clear()
    monkeypatch.setattr(backends, "_EP_CACHE", ((), None))  # as before the first call: threads race to it
    go = threading.Barrier(8)
    seen = []

    def worker():
        go.wait()
        seen.append(backends.available())

    threads = [threading.Thread(target=worker) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(scans) == 1 and seen == [first] * 8
    # a package on a folder prepended to sys.path: seen without a refresh (the path changed)
    info = tmp_path / "armguard_fake-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: armguard-fake\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text("[armguard.backends]\nfake = armguard_fake:Backend\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "fake" in backends.available() and len(scans) == 2
    # a second package installed into that folder while the process runs: seen after a refresh
    info2 = tmp_path / "armguard_fake2-0.1.0.dist-info"
    info2.mkdir()
    (info2 / "METADATA").write_text("Metadata-Version: 2.1\nName: armguard-fake2\nVersion: 0.1.0\n")
    (info2 / "entry_points.txt").write_text("[armguard.backends]\nfake2 = armguard_fake2:Backend\n")
    assert "fake2" not in backends.available()
    assert "fake2" in backends.refresh() and "fake2" in backends.available() and len(scans) == 3
    with pytest.raises(BackendError, match="fake2"):  # the listing of installed backends names it
        backends.get_backend("no_such_backend")
    monkeypatch.undo()
    assert "fake" not in backends.available() and sys.path[0] != str(tmp_path)


def test_coal_yes_no_agrees_with_its_distances_just_above_contact():
    """puma560's tool 1e-6 m above the table: coal's collision requests kept coal's GJK tolerance 1e-6 (the distance
    requests were tightened to 1e-9) and ``collides`` said collision there, on one row and on its 64-row pool, where
    its own distance, the analytic backend and ``check`` say apart."""
    model = armguard.load_model("puma560")
    q = np.array([2.497641659227946, 2.5627451813342916, -0.1846978379996368,
                  0.5763358132833984, -0.566416407672864, -0.36291853231111804])
    c = armguard.checker(model, "coal")
    d = c.pair_distances(q).distance.min()
    assert 0.0 < d < 2e-6
    assert not c.collides(q[None])[0] and not c.collides(np.repeat(q[None], 64, axis=0)).any()
    assert not armguard.checker(model, "analytic").collides(q[None])[0]
