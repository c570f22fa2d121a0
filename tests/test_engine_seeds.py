"""Seed tables: GJK started from another configuration's simplex (``armguard_analytic._engine._seeds``).

A seed changes where GJK starts, never its answer: a property test starts GJK from random simplices
(any support index pairs are points of the Minkowski difference) and compares with the cold start; on
public robots the engine's answers with its tables equal its answers with them switched off, and
coal's.  EPA leaves the facet it ends on for the tables, and that facet lies at the depth EPA returns.
Along a path, GJK starting from each pair's simplex at the previous configuration gives the answers of
a checker that sees the same configurations in another order.
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armguard
from armguard.geometry._pack import hull_graph, support_table
from armguard.geometry._pair_epa import EPA_WORK_SIZE, epa_depth
from armguard.geometry._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, gjk_dir_rel
from armguard.model import known_models

sys.path.insert(0, str(Path(__file__).parent))
from _engine_world import random_cloud as _cloud, random_rotation as _rotation  # noqa: E402

_NO_SEED = np.zeros(0, np.int64)


def _pair(seed: int, gap: float):
    rng = np.random.default_rng(seed)
    pa, pb = _cloud(rng, int(rng.integers(20, 300))), _cloud(rng, int(rng.integers(20, 300)))
    R_AB = _rotation(rng)
    t_AB = (0.6 + gap) * rng.normal(size=3) / np.sqrt(3)
    d0 = pa.mean(axis=0) - (R_AB @ pb.mean(axis=0) + t_AB)
    return rng, pa, pb, np.ascontiguousarray(R_AB.ravel()), t_AB, d0


def _gjk(pa, pb, rot, t_AB, d0, seed_row, work):
    ga, gb = hull_graph(pa)[0], hull_graph(pb)[0]
    ta, tb = support_table(pa), support_table(pb)
    return gjk_dir_rel(pa, ga, ta, pb, gb, tb, rot, *t_AB, *d0, 1e-12, 1e-12, 128, work, np.inf, seed_row)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), gap=st.floats(-0.3, 0.8), n=st.integers(0, 3))
def test_gjk_from_any_seed_gives_the_cold_answer(seed, gap, n):
    """Any simplex of support index pairs (repeats included) as the start: the same status and the same
    distance to 1e-9 m as GJK from a cold start; and the final simplex a separated run leaves in
    ``simp[9:16]`` is a seed that brings the distance back."""
    rng, pa, pb, rot, t_AB, d0 = _pair(seed, gap)
    row = np.zeros(7, np.int64)
    row[0] = n
    row[1::2] = rng.integers(0, len(pa), size=3)
    row[2::2] = rng.integers(0, len(pb), size=3)
    w0, w1 = np.zeros(16), np.zeros(16)
    ref = _gjk(pa, pb, rot, t_AB, d0, _NO_SEED, w0)
    got = _gjk(pa, pb, rot, t_AB, d0, row, w1)
    assert ref[0] != GJK_NOT_CONVERGED and got[0] != GJK_NOT_CONVERGED
    if ref[0] == GJK_SEPARATED and ref[1] > 1e-9:
        assert got[0] == GJK_SEPARATED
        assert abs(got[1] - ref[1]) <= 1e-9
        again = _gjk(pa, pb, rot, t_AB, d0, w0[9:16].astype(np.int64), np.zeros(16))
        assert 1 <= w0[9] <= 3 and again[0] == GJK_SEPARATED and abs(again[1] - ref[1]) <= 1e-9
    elif ref[0] == GJK_INTERSECTING:
        assert got[0] == GJK_INTERSECTING or got[1] <= 1e-9
        assert w0[9] == 0  # no seed from an overlapping run's simplex


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), shift=st.floats(0.0, 0.05))
def test_epa_leaves_the_facet_it_ends_on(seed, shift):
    """Two ellipsoid hulls about the same centre (offset at most 5 cm): after a settled depth,
    ``work[0] == 2`` and ``work[1:4]``, ``work[5:8]`` index three vertices of the Minkowski difference
    on the plane ``n . w = depth``."""
    rng, pa, pb, rot, t_AB, d0 = _pair(seed, -0.6)
    t_AB = shift * rng.normal(size=3) / np.sqrt(3)  # the centres within ~5 cm: the hulls overlap
    d0 = pa.mean(axis=0) - (rot.reshape(3, 3) @ pb.mean(axis=0) + t_AB)
    ga, gb = hull_graph(pa)[0], hull_graph(pb)[0]
    ta, tb = support_table(pa), support_table(pb)
    work = np.zeros(EPA_WORK_SIZE)
    st_ = gjk_dir_rel(pa, ga, ta, pb, gb, tb, rot, *t_AB, *d0, 1e-12, 1e-12, 128, work[0:9], np.inf, _NO_SEED)
    assert st_[0] == GJK_INTERSECTING and work[0] == 1.0  # the origin inside GJK's tetrahedron
    ok, d, nx, ny, nz = epa_depth(pa, ga, pb, gb, work, 1e-12, rot, *t_AB, ta, tb, -math.inf)[:5]
    assert ok and d > 0.0 and work[0] == 2.0
    R = rot.reshape(3, 3)
    for k in range(3):
        w = pa[int(work[1 + k])] - (R @ pb[int(work[5 + k])] + t_AB)
        assert abs(np.dot((nx, ny, nz), w) - d) <= 1e-9


def _seg(f, name, w=0):
    from armguard_analytic._engine._layout import K

    H, MI = f.args[0], f.args[2]
    buf = f.args[1] if name == "sgrid" else MI
    a = buf[H[2 * K[name]]:H[2 * K[name]] + H[2 * K[name] + 1] * max(w, 1)]
    return a.reshape(-1, w) if w else a


@pytest.mark.parametrize("name", ["kuka_iiwa", "ur3"])
def test_seed_tables_change_no_answer(name):
    """kuka_iiwa and ur3 (hull pairs apart and overlapping at random configurations): every pair whose
    pose depends on one to three joints has a table (the iiwa's links two joints apart on exactly
    two), and the distances and witnesses with the tables equal those with every table switched off
    to 1e-9 m, and coal's verdicts."""
    if name not in {m.name for m in known_models() if m.available}:
        pytest.skip(f"{name}'s package is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model(name)
    ana = armguard.checker(model, "analytic")
    coal = armguard.checker(model, "coal")
    Q = model.random_q(60, 3)
    ana.pair_distances(Q[0])
    f = ana._plan()
    spair = _seg(f, "spair", 6)
    seeded = spair[:, 0] >= 0
    assert seeded.sum() >= 11 and set(spair[seeded, 2] & 3) <= {1, 2, 3}
    if name == "kuka_iiwa":  # limits under a turn: plain grids
        assert np.count_nonzero(spair[:, 2] == 2) == 6
    else:  # ur3's joints turn +-2 pi: periodic grids, a value and the same angle a turn away share a node
        from armguard_analytic._engine._seeds import seed_row

        periodic = seeded & (spair[:, 2] >= 4)
        assert periodic.sum() >= 11
        sgrid, sdt = _seg(f, "sgrid", 6), _seg(f, "sdt", 7)
        for q in Q[:10]:
            for p in np.nonzero(periodic)[0]:
                for k in range(spair[p, 2] & 3):
                    if (spair[p, 2] >> (2 + k)) & 1:
                        q2 = q.copy()
                        q2[spair[p, 3 + k]] += 2 * np.pi * (1 if q2[spair[p, 3 + k]] < 0 else -1)
                        assert np.array_equal(seed_row(spair, sgrid, sdt, p, q), seed_row(spair, sgrid, sdt, p, q2))
    on = spair[:, 0].copy()
    with_tables = [ana.pair_distances(q) for q in Q]
    try:
        spair[:, 0] = -1  # every pair starts cold
        cold = [ana.pair_distances(q) for q in Q]
    finally:
        spair[:, 0] = on
    overlapping = 0
    for q, a, b in zip(Q, with_tables, cold):
        np.testing.assert_allclose(a.distance, b.distance, atol=1e-9, rtol=0)
        apart = a.distance > 1e-6  # where the nearest points are unique enough to compare
        np.testing.assert_allclose(a.p_WA[apart], b.p_WA[apart], atol=1e-6, rtol=0)
        ref = np.asarray(coal.pair_distances(q).distance)
        clear = np.abs(ref) > 1e-6
        assert np.array_equal(a.distance[clear] < 0, ref[clear] < 0)
        overlapping += int(np.count_nonzero(a.distance < 0))
    assert overlapping > 0 or name == "kuka_iiwa"  # ur3's random configurations overlap: EPA's facets seed


def test_seed_tables_are_made_once_per_process():
    """A second checker on the same model makes no table again (the process cache, keyed by content),
    and gets the same tables."""
    if "kuka_iiwa" not in {m.name for m in known_models() if m.available}:
        pytest.skip("kuka_iiwa's package is not installed")
    from armguard_analytic._engine import _seeds

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("kuka_iiwa")
    q = model.random_q(1, 5)[0]
    first = armguard.checker(model, "analytic")
    first.pair_distances(q)
    made = []
    real = _seeds.gjk_dir_rel

    def counted(*args):
        made.append(1)
        return real(*args)

    _seeds.gjk_dir_rel = counted
    try:
        second = armguard.checker(model, "analytic")
        second.pair_distances(q)
    finally:
        _seeds.gjk_dir_rel = real
    assert not made
    assert np.array_equal(_seg(first._plan(), "sdt", 7), _seg(second._plan(), "sdt", 7))
    assert len(_seg(first._plan(), "sdt", 7)) == 6 * 32**2 + 5 * 16**3


def _path(model, step: float, seed: int):
    """Configurations along straight joint-space segments between 5 random waypoints, no joint moving
    more than ``step`` between consecutive ones."""
    import pinocchio as pin

    W = model.random_q(5, seed)
    out = []
    for a, b in zip(W[:-1], W[1:]):
        k = max(1, int(np.ceil(np.max(np.abs(pin.difference(model.pin_model, a, b))) / step)))
        out += [pin.interpolate(model.pin_model, a, b, i / k) for i in range(k)]
    return np.array(out)


@pytest.mark.parametrize("name", ["kuka_iiwa", "ur3"])
def test_the_previous_simplex_changes_no_answer(name):
    """Option ``warm_start``: along a path (joint steps of 0.01 rad, within ``COHERENT_STEP``) each
    link-frame GJK starts from the simplex that pair ended with at the thread's previous check: the
    thread's scratch says so (the flag set, final simplices kept for pairs apart), and every distance
    equals the same configuration's from a second warm-started checker that sees the path's
    configurations in shuffled order (its flag set on at most a tenth of them) and from a checker
    without the option (its flag never set) to 1e-9 m, its witnesses to 1e-6 m where the pair is
    apart, and coal's verdicts."""
    if name not in {m.name for m in known_models() if m.available}:
        pytest.skip(f"{name}'s package is not installed")
    from armguard_analytic._engine._layout import COHERENT_STEP, K

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model(name)
    T = _path(model, 0.01, 4)
    assert 0.01 < COHERENT_STEP and len(T) > 300
    rng = np.random.default_rng(0)
    pick = set(rng.choice(len(T), size=120, replace=False).tolist())  # the configurations compared
    walk, fresh = (armguard.checker(model, "analytic", {"warm_start": True}) for _ in range(2))
    plain = armguard.checker(model, "analytic")
    coal = armguard.checker(model, "coal")
    on_path, coherent, kept = {}, 0, 0
    for k, q in enumerate(T):
        r = walk.pair_distances(q)
        if k in pick:
            on_path[k] = r
        f = walk._plan()
        H, SF = f.args[0], f.tls.s[0]
        coherent += int(SF[H[2 * K["coh"]] + 1] == 1.0)
        lseed = SF[H[2 * K["lseed"]]:H[2 * K["lseed"]] + 7 * H[2 * K["lseed"] + 1]].view(np.int64).reshape(-1, 7)
        kept = max(kept, int(np.count_nonzero(lseed[:, 0] > 0)))
    assert coherent == len(T) - 1  # every check after the first
    assert kept >= 10
    control_coherent = 0
    for k in rng.permutation(sorted(pick)):
        a, b = on_path[k], fresh.pair_distances(T[k])
        f = fresh._plan()
        control_coherent += int(f.tls.s[0][f.args[0][2 * K["coh"]] + 1] == 1.0)
        c = plain.pair_distances(T[k])
        f = plain._plan()
        assert f.tls.s[0][f.args[0][2 * K["coh"]] + 1] == 0.0
        for other in (b, c):
            np.testing.assert_allclose(a.distance, other.distance, atol=1e-9, rtol=0)
            apart = a.distance > 1e-6
            np.testing.assert_allclose(a.p_WA[apart], other.p_WA[apart], atol=1e-6, rtol=0)
            np.testing.assert_allclose(a.p_WB[apart], other.p_WB[apart], atol=1e-6, rtol=0)
        ref = np.asarray(coal.pair_distances(T[k]).distance)
        clear = np.abs(ref) > 1e-6
        assert np.array_equal(a.distance[clear] < 0, ref[clear] < 0)
    assert control_coherent <= len(pick) // 10  # the control starts from tables or cold, not the walk's simplices


def test_a_warm_started_detector_reports_as_a_plain_one():
    """``armguard.Detector(model, backend_options={"warm_start": True})`` (Ranger's cycle, the analytic
    fast path): along a path its thread's checks start from the previous simplices (the flag set on
    every check after the first), and each report has the plain detector's status, pairs within the
    threshold and their distances to 1e-9 m; a value other than True or False is refused."""
    if "kuka_iiwa" not in {m.name for m in known_models() if m.available}:
        pytest.skip("kuka_iiwa's package is not installed")
    from armguard_analytic._engine._layout import K

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("kuka_iiwa")
    warm = armguard.Detector(model, threshold=0.05, backend="analytic", backend_options={"warm_start": True})
    plain = armguard.Detector(model, threshold=0.05, backend="analytic")
    T = model.scene_q(_path(model, 0.01, 6))
    coherent = 0
    for q in T:
        a, b = warm.check(q), plain.check(q)
        coherent += int(warm._scratch().SF[warm._b.H[2 * K["coh"]] + 1] == 1.0)
        assert plain._scratch().SF[plain._b.H[2 * K["coh"]] + 1] == 0.0
        assert a.status is b.status
        assert [(r.a, r.b) for r in a.within_threshold] == [(r.a, r.b) for r in b.within_threshold]
        np.testing.assert_allclose([r.distance for r in a.within_threshold], [r.distance for r in b.within_threshold],
                                   atol=1e-9, rtol=0)
    assert coherent == len(T) - 1
    with pytest.raises(ValueError, match="warm_start"):
        armguard.Detector(model, backend="analytic", backend_options={"warm_start": "yes"})


def test_building_the_tables_compiles_no_kernel_of_its_own():
    """The tables' GJK and EPA calls use the argument types the fused kernel's narrow phase passes
    (writeable hulls, ``._calls.NATIVE``), so a first run compiles each of those kernels once: with the
    model's read-only hull arrays numba compiled a second gjk_dir_rel and epa_depth for them, 11 s and
    7 s of ``make run`` on a fresh checkout.  A fresh process builds puma560's tables (from numba's cache,
    or compiling) and lists the overloads it made."""
    import subprocess

    code = (
        "import json, armguard\n"
        "from numba import types\n"
        "from armguard.geometry._pair_gjk import gjk_dir_rel\n"
        "from armguard.geometry._pair_epa import epa_depth\n"
        "from armguard_analytic._engine import _seeds\n"
        "before = {k: set(f.overloads) for k, f in (('gjk', gjk_dir_rel), ('epa', epa_depth))}\n"
        "_seeds._cache.clear()\n"
        "c = armguard.checker(armguard.load_model('puma560'), 'analytic')\n"
        "c.pair_distances(c.model.random_q(1, 0)[0])\n"
        "new = {k: [str(s) for s in set(f.overloads) - before[k]] for k, f in (('gjk', gjk_dir_rel), ('epa', epa_depth))}\n"
        "print(json.dumps({'sdt': int(c._plan().b.layout.view(c._plan().b.MI, 'sdt').size), 'new': new,\n"
        "                  'readonly': [str(s) for f in (gjk_dir_rel, epa_depth) for s in f.overloads\n"
        "                               if any(isinstance(a, types.Array) and not a.mutable for a in s)]}))\n"
    )
    import json

    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["sdt"] > 7  # puma560 has seed tables (more than the one empty row)
    assert out["readonly"] == [], out["readonly"]  # no overload for read-only arrays


def test_hull_graphs_and_support_tables_are_remembered_by_their_points():
    """An edited Model rebuilds the engine of the links it did not touch: the hull graph and support table of
    the same points are the remembered ones (fresh copies: a caller's write reaches neither the memo nor the
    next caller), equal to what a computation anew gives; other points get their own."""
    import armguard.geometry._pack as pack

    rng = np.random.default_rng(3)
    v = rng.normal(size=(400, 3))
    pack._MEMO.clear()
    adj, tri = hull_graph(v)
    tab = support_table(v)
    assert len(pack._MEMO) == 2
    adj[:] = -1
    tab[:] = -1
    again_adj, again_tri = hull_graph(v.copy())
    assert len(pack._MEMO) == 2 and again_adj.flags.writeable
    from scipy.spatial import ConvexHull

    fresh_tri = ConvexHull(v).simplices
    fresh_adj = pack._graph(v, [fresh_tri[:, [0, 1]], fresh_tri[:, [1, 2]], fresh_tri[:, [2, 0]]])
    assert np.array_equal(again_adj, fresh_adj) and np.array_equal(again_tri, fresh_tri)
    assert np.array_equal(support_table(v), pack._support_table(v, 16))
    assert not np.array_equal(support_table(v + 1e-9), -np.ones_like(tab)) and len(pack._MEMO) == 3
    old = pack._MEMO_BYTES
    try:
        pack._MEMO_BYTES = 1  # the oldest entries go first, the newest stays
        hull_graph(v * 2.0)
        assert len(pack._MEMO) == 1
    finally:
        pack._MEMO_BYTES = old
