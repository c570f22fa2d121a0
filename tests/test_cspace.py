"""Forbidden-values maps (armguard.cspace): certified, compact, lazily loaded, resumable, identical on Dask.

The map is built once per module at a coarse resolution (6°, joint-3 quantum 6°) so the whole
file runs in well under a minute; the certification argument does not depend on the resolution.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

import armguard
from armguard import ForbiddenMapError
from armguard.cspace import (
    CombinedChecker,
    CombinedStatus,
    DetectorClearance,
    ExactnessStatus,
    ForbiddenMap,
    Lookup,
    MapGrid,
    check_exactness,
    map_links,
    random_configurations,
)
from armguard.cspace._certify import certify_substructure, decode_intervals, encode_mask
from armguard.cspace._clearance import link_obstacle_scene
from armguard.models import builtin_path

REF = yaml.safe_load((Path(__file__).resolve().parent.parent / "reference" / "seeds" / "hermes_forbidden_map.yaml").read_text())
RES = math.radians(6.0)
DEPTH = 3
SD = REF["stopping_distance"]["worst_m"]  # the paper's worst stopping distance, 0.1 m
KW = dict(resolution=RES, stopping_distance=SD, max_depth=DEPTH)


@pytest.fixture(scope="module")
def scene():
    return armguard.load_scene("hermes")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("cspace") / "hermes6.agmap"
    fmap = ForbiddenMap.build("hermes", out=out, **KW)
    return fmap


def test_grid_matches_the_papers_substructures():
    lo = np.radians([REF["joint_ranges_deg"]["joint1"][0], REF["joint_ranges_deg"]["joint2"][0], -160.0])
    hi = np.radians([REF["joint_ranges_deg"]["joint1"][1], REF["joint_ranges_deg"]["joint2"][1], 160.0])
    g = MapGrid.create(lo, hi, math.radians(REF["full_structure_1deg"]["resolution_deg"]), math.radians(1.0),
                       np.radians(REF["substructures"]["extent_deg"]))
    assert g.n_substructures == REF["substructures"]["count"]  # 864
    assert tuple(g.per_sub) == (10, 10) and g.n_cells == 360 * 240


def test_a_substructure_larger_than_the_grid_is_the_whole_grid():
    """``--cell 1e300deg`` made INT64_MIN cells per substructure: a map written over ``--out`` that did not load."""
    g = MapGrid.create([-1.0, -1.0, -1.0], [1.0, 2.0, 1.0], math.radians(30), math.radians(30), math.radians(1e300))
    assert tuple(g.per_sub) == tuple(g.counts[:2]) and g.n_substructures == 1
    assert g.sub_cells(0) == (0, int(g.counts[0]), 0, int(g.counts[1]))


def test_default_links_and_irrelevant_joints(scene):
    ml = map_links(scene, "hera")
    assert ml.links == ("link1", "link2", "link3")
    assert ml.joints == ("shoulder_yaw", "shoulder_pitch", "elbow")
    with pytest.raises(ForbiddenMapError, match="also moved by"):
        map_links(scene, "hera", links=("link2", "link4"))
    # joints 4-6 do not move links 1-3: the clearance is the same whatever they are
    det = armguard.Detector(link_obstacle_scene(scene, "hera", ml.links), threshold=0.0)
    rng = np.random.default_rng(1)
    Q = random_configurations(scene, 2000, seed=2)
    Q2 = Q.copy()
    hera = scene.robots["hera"]
    Q2[:, 3:6] = rng.uniform(hera.lower[3:6], hera.upper[3:6], size=(len(Q), 3))
    d1 = det.check_many(Q).min_distance.min(axis=1)
    d2 = det.check_many(Q2).min_distance.min(axis=1)
    assert np.array_equal(d1, d2)
    assert np.array_equal(d1, DetectorClearance(scene, ml)(Q[:, :3]))


def test_no_allowed_configuration_collides(built, scene):
    rep = check_exactness(built, scene, n=20_000, seed=3)
    print(f"\n6° map: truly colliding {rep.colliding / rep.n:.3f}; false-forbidden share {rep.false_forbidden_share:.3f} "
          f"({rep.false_forbidden_of_free:.3f} of the free configurations)")
    assert rep.status is ExactnessStatus.CONSERVATIVE and rep.allowed_but_colliding == 0
    assert rep.colliding > 0 and rep.n - rep.colliding - rep.false_forbidden > 0.2 * rep.n  # a useful map, not all forbidden


def test_allowed_boxes_are_clear_at_corners_and_centre(built, scene):
    """Beyond random samples: the 8 corners and the centre of 400 allowed cell × bin boxes are clear."""
    g = built.grid
    mask = built.mask()
    rng = np.random.default_rng(4)
    idx = np.argwhere(~mask)
    pick = idx[rng.choice(len(idx), size=400, replace=False)]
    corners = np.array([[a, b, c] for a in (0, 1) for b in (0, 1) for c in (0, 1)] + [[0.5, 0.5, 0.5]])
    Q = (g.lower + (pick[:, None, :] + corners[None, :, :]) * g.step).reshape(-1, 3)
    Q = np.minimum(Q, g.upper)
    d = DetectorClearance(scene, map_links(scene, "hera"))(Q)
    assert np.all(d > SD)


def test_round_trip_and_certify_agree(built, scene):
    ml = map_links(scene, "hera")
    hook = DetectorClearance(scene, ml)
    g = built.grid
    for s in (0, g.n_substructures // 2, g.n_substructures - 1):
        r = certify_substructure(g, s, hook, ml.lever, SD, armguard.DEFAULT_TOLERANCES.cspace_contact, DEPTH)
        ptr, iv = built.substructure(s)
        assert np.array_equal(ptr, r.pointers) and np.array_equal(iv, r.intervals)
    again = ForbiddenMap.load(built.path)
    assert np.array_equal(again.mask(), built.mask())
    assert again.header["grid"] == built.header["grid"] and again.stopping_distance == SD
    rng = np.random.default_rng(5)
    m = rng.random((4, 7, 50)) < 0.4
    assert np.array_equal(decode_intervals(*encode_mask(m), m.shape), m)
    info = built.info()
    assert info.size_bytes == built.path.stat().st_size and info.n_substructures == g.n_substructures
    assert 0.0 < info.forbidden_fraction < 1.0


def test_lookups_match_the_mask_and_limits(built):
    g = built.grid
    mask = built.mask()
    rng = np.random.default_rng(6)
    Q = rng.uniform(g.lower, g.upper, size=(50_000, 3))
    idx = np.minimum(np.floor((Q - g.lower) / g.step).astype(int), g.counts - 1)
    expect = ~mask[idx[:, 0], idx[:, 1], idx[:, 2]]
    assert np.array_equal(built.allowed_many(Q), expect)
    full = np.zeros((len(Q), 6))
    full[:, :3] = Q
    assert np.array_equal(built.allowed_many(full), expect)  # robot joint vectors work too
    out = np.array([[g.lower[0] - 0.01, 0.5, 0.0], [1.0, g.upper[1] + 0.01, 0.0], [np.nan, 0.5, 0.0]])
    assert list(built.lookup_many(out)) == [Lookup.OUTSIDE_LIMITS] * 3 and not built.allowed(out[0])
    assert built.allowed_many(np.array([g.upper])).shape == (1,)  # the upper limits are inside the last cell


def test_neighbourhood_equals_full_loading(built):
    g = built.grid
    rng = np.random.default_rng(7)
    sizes = np.diff(built._dir)
    for q in rng.uniform(g.lower, g.upper, size=(6, 3)).tolist() + [list(g.lower), list(g.upper)]:
        nb = built.neighbourhood(q)
        (a1, b1), (a2, b2) = nb.substructures
        assert (b1 - a1) <= 3 and (b2 - a2) <= 3
        lo = g.lower + np.array([a1 * g.per_sub[0], a2 * g.per_sub[1], 0]) * g.step
        hi = np.minimum(g.lower + np.array([b1 * g.per_sub[0], b2 * g.per_sub[1], g.counts[2]]) * g.step, g.upper)
        Q = rng.uniform(lo, hi, size=(5000, 3))
        assert np.array_equal(nb.allowed_many(Q), built.allowed_many(Q))
        subs = [k1 * g.n_sub[1] + k2 for k1 in range(a1, b1) for k2 in range(a2, b2)]
        assert nb.nbytes == int(sizes[subs].sum())
    nb = built.neighbourhood([0.01, g.lower[1] + 0.01, 0.0])
    with pytest.raises(ForbiddenMapError, match="outside the loaded neighbourhood"):
        nb.allowed([g.upper[0] - 0.01, g.upper[1] - 0.01, 0.0])


def test_another_model_file_is_refused(built, tmp_path):
    with pytest.raises(ForbiddenMapError, match="built for other model files"):
        ForbiddenMap.load(built.path, model="ranger")
    ForbiddenMap.load(built.path, model="hermes")  # the same file: fine
    # a map built from a copy of the scene file refuses once that file changes
    src = tmp_path / "hermes_copy.yaml"
    shutil.copy(builtin_path("hermes"), src)
    fmap = ForbiddenMap.build(str(src), out=tmp_path / "c.agmap", resolution=math.radians(30), stopping_distance=SD,
                              max_depth=0)
    ForbiddenMap.load(fmap.path)
    src.write_text(src.read_text() + "\n# edited\n")
    with pytest.raises(ForbiddenMapError, match="built for other model files"):
        ForbiddenMap.load(fmap.path)
    with pytest.raises(ForbiddenMapError, match="built for other model files"):
        CombinedChecker(ForbiddenMap.load(built.path), "ranger")


def test_a_map_is_checked_against_its_own_files_from_any_working_directory(tmp_path, monkeypatch):
    """A map recorded its model as given (``h.yaml``): ``cspace info`` run in another folder sampled that
    folder's ``h.yaml`` (another model) and could call a map that is not conservative conservative."""
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    shutil.copy(builtin_path("hermes"), a / "h.yaml")
    (b / "h.yaml").write_text((a / "h.yaml").read_text() + "\n# another model's file\n")
    monkeypatch.chdir(a)
    fmap = ForbiddenMap.build("h.yaml", out=tmp_path / "c.agmap", resolution=math.radians(30), stopping_distance=SD,
                              max_depth=0)
    assert fmap.header["model"] == str((a / "h.yaml").resolve())
    monkeypatch.chdir(b)
    assert check_exactness(ForbiddenMap.load(tmp_path / "c.agmap"), n=50).n == 50  # its own files, not b's
    fmap.header["model"] = "h.yaml"  # as maps recorded it before: the file found there is checked first
    with pytest.raises(ForbiddenMapError, match="built for other model files"):
        check_exactness(fmap, n=50)


def test_a_worker_that_loads_another_model_is_refused():
    """``cspace build --scheduler``: a worker whose copy of the model files differs built its part of the map on
    them (a non-conservative map, recorded with the client's files)."""
    from armguard.cspace._build import _WORKER_CACHE, _task

    scene = armguard.load_model("hermes").scene_for()
    ml = map_links(scene, "hera")
    _WORKER_CACHE.clear()
    with pytest.raises(ForbiddenMapError, match="loaded 'hermes' as another model"):
        _task("t1", "hermes", ml.robot, ml.joints, ml.links, armguard.DEFAULT_TOLERANCES, None, ("analytic", {}),
              {"geometry": "0" * 64}, [])
    _WORKER_CACHE.clear()


class _Stop(Exception):
    pass


def test_interrupted_build_resumes(built, tmp_path):
    out = tmp_path / "r.agmap"
    k = 40

    def stop_after(done, total):
        if done >= k:
            raise _Stop

    with pytest.raises(_Stop):
        ForbiddenMap.build("hermes", out=out, progress=stop_after, **KW)
    assert not out.exists() and (tmp_path / "r.agmap.partial").exists()
    fmap = ForbiddenMap.build("hermes", out=out, **KW)
    r = fmap.build_report
    assert r.status.value == "resumed" and r.reused == k and r.computed == built.grid.n_substructures - k
    assert out.read_bytes() == built.path.read_bytes()
    assert not (tmp_path / "r.agmap.partial").exists()


def test_distributed_build_is_identical(built, tmp_path):
    fmap = ForbiddenMap.build("hermes", out=tmp_path / "d.agmap", workers=2, **KW)
    assert fmap.build_report.workers == 2
    assert fmap.path.read_bytes() == built.path.read_bytes()


def test_combined_check_never_misses_a_collision(built, scene):
    comb = CombinedChecker(built, scene).prepare()
    full = armguard.Detector(scene, threshold=0.0, stopping_distance=SD)
    Q = random_configurations(scene, 10_000, seed=8)
    batch = comb.check_many(Q)
    truth = full.collides_many(Q)
    assert not np.any(truth & ~batch.collision)
    assert np.array_equal(comb.collides_many(Q), batch.collision)
    assert np.any(batch.status == CombinedStatus.FREE) and np.any(batch.status == CombinedStatus.COLLISION)


def test_combined_check_refuses_a_nan_in_any_joint(built, scene):
    """A NaN in joints 1-3 read as a map bin gave MAP_FORBIDDEN (a verdict from a NaN); in 4-6 the
    backend refused it: now every column is refused, naming the row and the joint."""
    comb = CombinedChecker(built, scene).prepare()
    Q = random_configurations(scene, 3, seed=4)
    for k in range(Q.shape[1]):
        bad = Q.copy()
        bad[1, k] = np.nan if k % 2 else np.inf
        with pytest.raises(ForbiddenMapError, match=f"Q row 1: joint '{scene.joint_names[k]}' = (nan|inf)"):
            comb.check_many(bad)


def test_batched_lookup_equals_one_at_a_time(built):
    """``allowed_many`` (the batched numba lookup; its speed is measured in bench/cspace.py) answers
    exactly what ``allowed`` answers configuration by configuration."""
    g = built.grid
    Q = np.random.default_rng(9).uniform(g.lower, g.upper, size=(2000, 3))
    many = built.allowed_many(Q)
    assert many.dtype == bool and many.shape == (len(Q),)
    assert np.array_equal(many, np.array([built.allowed(q) for q in Q]))
    assert 0 < many.sum() < len(Q)  # the sample sees both allowed and forbidden configurations


def test_bad_requests(tmp_path):
    with pytest.raises(ForbiddenMapError, match="workers"):
        ForbiddenMap.build("hermes", out=tmp_path / "x.agmap", workers=0)
    with pytest.raises(ForbiddenMapError, match="stopping_distance"):
        ForbiddenMap.build("hermes", out=tmp_path / "x.agmap", stopping_distance=-1.0)
    with pytest.raises(ForbiddenMapError, match="model_files"):
        ForbiddenMap.build(armguard.load_scene("hermes"), out=tmp_path / "x.agmap")
    (tmp_path / "bad.agmap").write_bytes(b"not a map")
    with pytest.raises(ForbiddenMapError, match="not a forbidden-values map"):
        ForbiddenMap.load(tmp_path / "bad.agmap")


def test_largest_neighbourhood_is_what_loading_holds(built):
    """``MapInfo.neighbourhood_bytes_max`` (the figure bench/cspace.py sets beside Hermes's central-memory
    table) is the largest block ``neighbourhood(q)`` actually loads, over a q at the centre of every substructure."""
    g = built.grid
    loaded = []
    for s in range(int(g.n_substructures)):
        i1a, i1b, i2a, i2b = g.sub_cells(s)
        q = g.lower + np.array([(i1a + i1b) / 2 * g.step[0], (i2a + i2b) / 2 * g.step[1], 0.0])
        loaded.append(built.neighbourhood(np.minimum(q, g.upper)).nbytes)
    assert built.info().neighbourhood_bytes_max == max(loaded)


def test_a_scene_the_map_was_not_built_on_is_refused(built):
    """``CombinedChecker(fmap, scene)`` took a Scene as given: a sphere added on Hermes's link 3, or the arm's
    base moved, was answered by the map that never saw it (FREE where the exact check said -0.68 m).  The
    map records the digest of its pairs' geometry (the mapped links, every static body) and refuses another."""
    from armguard.geometry import Sphere

    same = armguard.load_scene("hermes")
    CombinedChecker(built, same)  # the scene it was built on
    edited = armguard.load_scene("hermes")
    edited.add_body("ball", Sphere((0.0, 0.0, 2.0), 0.5))
    with pytest.raises(ForbiddenMapError, match="other geometry than this model's \\(bodies added: ball\\)"):
        CombinedChecker(built, edited)
    moved = armguard.load_scene("hermes")
    robot = next(iter(moved.robots))
    X = np.eye(4)
    X[:3, 3] = (0.0, 0.0, 0.05)
    moved.set_robot_base(robot, X @ moved.robots[robot].X_WB)
    with pytest.raises(ForbiddenMapError, match="other geometry.*base or its links"):
        CombinedChecker(built, moved)



def test_a_wholly_forbidden_map_forbids_at_most_the_whole_box():
    """The forbidden share sums every cell's volume: a full map read 1.000000000000004 (``cspace info``)."""
    import math

    from armguard.cspace._grid import MapGrid
    from armguard.cspace._map import forbidden_share

    g = MapGrid.create([-2.2739233746429086, -1.5395734275277406, -1.0819470478723894],
                       [1.0330552710570582, 2.626540478400545, 2.8255111545554437],
                       math.radians(6), math.radians(6), math.radians(30))  # its cells sum to 1 + 1e-15

    def full(s):
        i1a, i1b, i2a, i2b = g.sub_cells(s)
        return np.ones((i1b - i1a, i2b - i2a, int(g.counts[2])), dtype=bool)

    assert forbidden_share(g, full) == 1.0
    assert forbidden_share(g, lambda s: np.zeros_like(full(s))) == 0.0
