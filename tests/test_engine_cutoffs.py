"""The exact and min modes' cut-offs on penetrating pairs and the ordered moving-static GJK pairs.

Two rules skip work without changing a per-category result:

* EPA with a cap (:func:`armguard.geometry._pair_epa.epa_depth`, ``cap``): once a support value
  proves the depth below the cap, EPA stops with that bound; the kernel passes
  ``cap = -(cut-off + radii)``, so a pair that cannot be deeper than its category's best so far
  gets no exact depth (``_narrow.narrow_rel`` returns ``BOUNDED``).
* The moving-static GJK pairs seeded, collected and evaluated in increasing key
  (``_engine._static_gjk``), each skipped only when a lower bound exceeds its category's cut-off.

Oracles: EPA without a cap, and the brute-force reference (:func:`armguard.detect.check_reference`)
and the all-pairs path (``check_many_bruteforce``) on a scene where arms penetrate several
obstacles at once.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard.geometry._pack import hull_graph, support_table
from armguard.geometry._pair_epa import EPA_WORK_SIZE, epa_depth
from armguard.geometry._pair_gjk import gjk_dir_rel


sys.path.insert(0, str(Path(__file__).parent))
from _engine_world import random_cloud as _cloud, random_rotation as _rotation  # noqa: E402


def _epa(pa, ga, ta, pb, gb, tb, R_AB, t_AB, cap=None):
    """GJK then EPA (capped when ``cap`` is given) in A's frame; None when GJK leaves no tetrahedron."""
    work = np.zeros(EPA_WORK_SIZE)
    d0 = pa.mean(axis=0) - (R_AB @ pb.mean(axis=0) + t_AB)
    rot = np.ascontiguousarray(R_AB.ravel())
    gjk_dir_rel(pa, ga, ta, pb, gb, tb, rot, *t_AB, *d0, 1e-12, 1e-12, 128, work[0:9], np.inf, np.zeros(0, np.int64))
    if work[0] != 1.0:
        return None
    if cap is None:
        return epa_depth(pa, ga, pb, gb, work, 1e-12, rot, *t_AB)
    return epa_depth(pa, ga, pb, gb, work, 1e-12, rot, *t_AB, cap=cap)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), factor=st.floats(0.0, 2.0))
def test_capped_epa_is_the_uncapped_depth_or_a_bound_below_the_cap(seed, factor):
    """With ``cap`` at ``factor`` times the exact depth: at or below the depth EPA runs as without a
    cap (the same result, bit for bit); above it, what EPA returns is below the cap and at least the
    depth (an upper bound on it, the stopping rule: ``depth <= h`` for every support value ``h``)."""
    rng = np.random.default_rng(seed)
    pa, pb = _cloud(rng, int(rng.integers(60, 300))), _cloud(rng, int(rng.integers(60, 300)))
    ga, gb = hull_graph(pa)[0], hull_graph(pb)[0]
    ta, tb = support_table(pa), support_table(pb)
    R_AB = _rotation(rng)
    t_AB = 0.15 * rng.normal(size=3)  # overlapping clouds (sizes 0.05-0.4 m)
    ref = _epa(pa, ga, ta, pb, gb, tb, R_AB, t_AB)
    if ref is None or not ref[0]:
        return  # not overlapping, or EPA did not settle it (the SAT's case): no depth to cap
    depth = ref[1]
    cap = factor * depth
    got = _epa(pa, ga, ta, pb, gb, tb, R_AB, t_AB, cap)
    if cap <= depth:
        assert got == ref
    elif cap >= depth + 1e-9:  # (between: EPA's own tolerance)
        assert got[0]
        assert got[1] < cap
        assert got[1] >= depth - 1e-12


def test_capped_epa_stops_early_on_a_shallow_pair():
    """The rule is exercised: among overlapping pairs, some capped EPA returns a bound that is not
    the converged depth (stopped before convergence)."""
    rng = np.random.default_rng(3)
    early = 0
    for _ in range(40):
        pa, pb = _cloud(rng, 200), _cloud(rng, 200)
        ga, gb = hull_graph(pa)[0], hull_graph(pb)[0]
        ta, tb = support_table(pa), support_table(pb)
        R_AB, t_AB = _rotation(rng), 0.15 * rng.normal(size=3)
        ref = _epa(pa, ga, ta, pb, gb, tb, R_AB, t_AB)
        if ref is None or not ref[0]:
            continue
        got = _epa(pa, ga, ta, pb, gb, tb, R_AB, t_AB, 4.0 * ref[1])
        early += got[1] != ref[1]
    assert early > 0


def _crowded_panda(n_boxes: int = 8):
    """The built-in panda (mesh hulls) among ``n_boxes`` boxes within its reach: random
    configurations often penetrate two or more boxes at once, and the arm itself.  Up to 32 static
    elements ``_static_gjk`` tests every pair; beyond, it walks the BVH."""
    from armguard.geometry import Box
    from armguard.scene import load_scene

    scene = load_scene("panda")
    rng = np.random.default_rng(11)
    size = 0.1 * np.sqrt(8 / n_boxes)
    for k in range(n_boxes):
        a = 2 * np.pi * k / n_boxes
        r = rng.uniform(0.3, 0.6)
        c = [r * np.cos(a), r * np.sin(a), rng.uniform(0.15, 0.8)]
        scene.add_body(f"box{k}", [Box(c, rng.uniform(0.5, 1.5, size=3) * size)])
    return scene


@pytest.fixture(scope="module", params=[8, 48], ids=["8-boxes-flat", "48-boxes-bvh"])
def crowded(request):
    from armguard.detect import Detector

    scene = _crowded_panda(request.param)
    robot = next(iter(scene.robots.values()))
    Q = np.random.default_rng(5).uniform(robot.lower, robot.upper, size=(120, len(robot.lower)))
    return scene, robot, Q, Detector(scene, threshold=0.05)


def test_the_crowded_scene_has_several_penetrating_pairs_per_category(crowded):
    """The scene exercises the rules: configurations with two or more penetrating pairs in one
    category (the capped EPA's case) and with collisions in two categories at once."""
    _, _, Q, det = crowded
    several = both = 0
    for q in Q:
        pd = det.pair_distances(q)
        neg = [int(np.sum((pd.distance < 0) & (pd.category == c))) for c in range(4)]
        several += max(neg) >= 2
        both += sum(n > 0 for n in neg) >= 2
    assert several >= 10
    assert both >= 1


def test_the_two_scenes_take_the_two_collection_paths(crowded):
    """8 boxes: every pair tested (``n_st <= _FLAT``); 48: the BVH walk."""
    from armguard_analytic._engine._layout import SC
    from armguard_analytic._engine._static_gjk import _FLAT

    scene, _, _, det = crowded
    n_st = int(det._H[SC["n_st"]])
    n_boxes = sum(1 for name in scene.bodies if name.startswith("box"))
    assert n_st >= n_boxes
    assert (n_st <= _FLAT) == (n_boxes == 8)


@pytest.mark.parametrize("threshold", [0.0, 0.05, 0.3])
def test_check_and_check_many_equal_the_brute_force_reference_among_penetrations(crowded, threshold):
    """``check`` (exact mode: cut-off ``max(threshold, best)``) and ``check_many`` (min mode: the best
    alone) give the reference's per-category nearest distances and status at every configuration;
    ``check`` also every pair within the threshold."""
    from armguard.detect import CATEGORIES, Status, check_reference

    status_of_code = {0: Status.CLEAR, 1: Status.WARNING, 2: Status.COLLISION}
    scene, _, Q, det = crowded
    det.set_threshold(threshold)
    batch = det.check_many(Q)
    for m, q in enumerate(Q):
        ref = check_reference(scene, q, threshold)
        fin = np.isfinite(ref.min_distance)
        rep = det.check(q)
        got = np.array([rep.by_category[c].distance if c in rep.by_category else np.inf for c in CATEGORIES])
        for row in (got, batch.min_distance[m]):
            assert np.array_equal(np.isfinite(row), fin)
            assert np.allclose(row[fin], ref.min_distance[fin], atol=1e-9)
        assert status_of_code[ref.status] is rep.status
        assert int(batch.status[m]) == ref.status
        assert len(rep.within_threshold) == int(np.sum(det.pair_distances(q).distance <= threshold))


@settings(max_examples=15, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31))
def test_check_many_equals_the_all_pairs_path(crowded, seed):
    """The batch (cut-offs, capped EPA, ordered static pairs) against the all-pairs path (every pair
    evaluated, same narrow phase), on a random batch: equal minima and statuses."""
    _, robot, _, det = crowded
    det.set_threshold(0.05)
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, size=(300, len(robot.lower)))
    a, b = det.check_many(Q), det.check_many_bruteforce(Q)
    fin = np.isfinite(b.min_distance)
    assert np.array_equal(np.isfinite(a.min_distance), fin)
    assert np.allclose(a.min_distance[fin], b.min_distance[fin], atol=1e-9)
    assert np.array_equal(a.status, b.status)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), offset=st.floats(0.0, 0.6))
def test_the_boxes_face_separation_bounds_the_signed_distance_of_any_sign(seed, offset):
    """``_static_gjk`` skips a pair when its key exceeds a negative cut-off: the face-axis separation
    of a box containing the element and the obstacle box bounds their signed distance from below,
    penetrating or not (oracle: :func:`armguard.geometry.distance`, EPA / SAT)."""
    from armguard.geometry import Box, ConvexPolyhedron, distance
    from armguard_analytic._engine._cull import _face_sep

    rng = np.random.default_rng(seed)
    R_WA = _rotation(rng)
    p = _cloud(rng, 80) @ R_WA.T + rng.normal(size=3) * 0.1
    # a box containing the hull: its points' extent along their principal axes
    c0 = p.mean(axis=0)
    axes = np.linalg.svd(p - c0)[2].T  # columns
    u = (p - c0) @ axes
    lo, hi = u.min(axis=0), u.max(axis=0)
    cA = c0 + axes @ (0.5 * (lo + hi))
    A = (*cA, *(0.5 * (hi - lo)), *axes.ravel())
    R_WB = _rotation(rng)
    h_B = rng.uniform(0.05, 0.3, size=3)
    c_B = cA + offset * rng.normal(size=3)
    B = np.concatenate([c_B, h_B, R_WB.ravel()])
    s = _face_sep(tuple(float(x) for x in A), B, 0)
    d = distance(ConvexPolyhedron(p), Box(c_B, h_B, R_WB)).distance
    assert s <= d + 1e-9


@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), n=st.integers(0, 40))
def test_insertion_sort_order_matches_stable_argsort(seed, n):
    """``_cull._argsort_small`` (insertion up to 32 keys, the heap beyond) orders as a stable argsort."""
    from armguard_analytic._engine._cull import _argsort_small

    rng = np.random.default_rng(seed)
    key = np.round(rng.normal(size=n), 1)  # ties on purpose
    key[: n // 5] = -np.inf
    order = np.full(max(n, 1), -1, dtype=np.int64)
    _argsort_small(key, order, n)
    np.testing.assert_array_equal(order[:n], np.argsort(key, kind="stable"))
