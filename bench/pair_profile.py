"""Where the analytic ``pair_distances(q)`` spends its time, and how much work GJK does per pair.

Each robot is measured in a fresh process (``python -m bench.pair_profile NAME N``, one JSON line),
all times ``time.thread_time`` medians over 5 runs of ``N / 5`` calls (the runs of the four figures below interleaved), ``q`` cycling over 200
random in-limit configurations (``Model.random_q``, seeded):

* **call**: ``checker.pair_distances(q)``, every pair (as ``bench robots``);
* **kernel**: the same call's compiled entry point alone (``_Fast.entry``, preallocated outputs);
* **Python wrapper**: the call with that entry point swapped for a Python function that returns at
  once, less that function's call (argument checks, three output arrays, the result object;
  :func:`bench.backends._wrapper_seconds`);
* **fixed**: the entry point with no pair selected: unboxing its 15 arguments, the kernel's views,
  the joint limits and forward kinematics; *(kernel - fixed) / pairs* is the mean cost of a pair;
* **same q**: ``pair_distances`` at one configuration over and over: the same work with the
  branch predictor trained on it (the gap to *call* is mostly mispredicted branches, as the
  caches hold the hulls either way);
* **GJK work** per polytope pair (hull or box against hull or box, the pairs checked in their link
  frames, ``_narrow.narrow_rel``), counted by replaying ``_pair_gjk._gjk_body`` in Python (``py_func``)
  on 20 configurations: support evaluations of the Minkowski difference (GJK iterations, the
  first and the final verifying one included), hill climbs on the hulls' vertex graphs (one per
  hull side per iteration, ``_pair_gjk._climb``) and the supports' dot products (the climbs'
  neighbours; a box side scans its 8 corners), over the pairs GJK finds apart GJK starts as the kernel does,
  from the pair's seed table where it has one (``armguard_analytic._engine._seeds.seed_row``; a
  seed's vertices are no support evaluations); *from a cold start* counts the iterations without it,
  and *along the answer* those of a cold start whose first direction is the pair's final one: what no
  better first direction can save (a far pair, with no seed table, cannot get below it by its direction);
* **by pair kind** (:func:`_by_kind`): each pair alone, its configuration repeated (hot), grouped into
  apart with a seed table, apart without, and overlapping (EPA); the whole kernel with each
  configuration repeated; each pair alone with the configurations in turn.  Against *kernel - fixed*
  this tells how much of a call goes to the pairs' own work and how much to what changes from one
  configuration to the next, and that the latter is no matter of the caches' capacity (a pair alone
  pays it too).
"""

from __future__ import annotations

import json
import math
import os
import sys

from bench.timing import json_of_process

TITLE = "Analytic pair_distances: where the time goes"
ROBOTS = ("ur3", "kinova", "kuka_iiwa", "z1", "so101")


def _gjk_work(model, ana, n_q: int) -> dict:
    """Mean and 90th percentile of GJK iterations, climbs and climb dot products per polytope pair."""
    import numpy as np

    from armguard.geometry import _pair_gjk as G
    from armguard_analytic._engine._layout import K

    count = {"it": 0, "climb": 0, "dot": 0}

    def climb(pb, adj, i, dx, dy, dz):  # _pair_gjk._climb, counted
        count["climb"] += 1
        best = pb[i, 0] * dx + pb[i, 1] * dy + pb[i, 2] * dz
        k, e = adj[G.ADJ_HEAD + i], adj[G.ADJ_HEAD + i + 1]
        while k < e:
            j = adj[k]
            count["dot"] += 1
            s = pb[j, 0] * dx + pb[j, 1] * dy + pb[j, 2] * dz
            if s > best:
                best, i, k, e = s, j, adj[G.ADJ_HEAD + j], adj[G.ADJ_HEAD + j + 1]
            else:
                k += 1
        return i

    m_support_py = G._m_support.py_func

    def m_support(*a):
        count["it"] += 1
        return m_support_py(*a)

    scan_py = G._scan.py_func

    def scan(pb, dx, dy, dz):  # _pair_gjk._scan, counted
        count["dot"] += pb.shape[0]
        return scan_py(pb, dx, dy, dz)

    from numba.core.registry import CPUDispatcher

    for nm, fn in list(vars(G).items()):  # every compiled helper GJK's body calls, as Python
        if isinstance(fn, CPUDispatcher):
            setattr(G, nm, fn.py_func)
    G._climb, G._m_support, G._scan = climb, m_support, scan  # this process ends after the replay

    f = ana._plan()
    H, MF, MI, prm, iprm = f.args

    def seg(buf, k, w=0):
        a = buf[H[2 * k]:H[2 * k] + H[2 * k + 1] * max(w, 1)]
        return a.reshape(-1, w) if w else a

    core, vst, glink = seg(MI, K["core"]), seg(MI, K["vstart"]), seg(MI, K["glink"])
    gadj, gadjs, gdir, gdirs = seg(MI, K["gadj"]), seg(MI, K["gadjs"]), seg(MI, K["gdir"]), seg(MI, K["gdirs"])
    vL, pair_a, pair_b = seg(MF, K["verts_L"], 3), seg(MI, K["pair_a"]), seg(MI, K["pair_b"])
    from armguard_analytic._engine._seeds import seed_row

    spair, sgrid, sdt = seg(MI, K["spair"], 6), seg(MF, K["sgrid"], 6), seg(MI, K["sdt"], 7)
    rows, cold, by = [], [], {}  # by: the table's joint count (0: no table) -> [(seeded, cold) iterations]
    for q in model.random_q(n_q, 11):
        ana.pair_distances(q)
        Xs = seg(f.tls.s[0], K["Xs"], 16).reshape(-1, 4, 4)
        q_engine = seg(f.tls.s[0], K["fk_q"]).copy()
        for p in range(len(pair_a)):
            a, b = int(pair_a[p]), int(pair_b[p])
            if b < 0 or core[a] not in (2, 3) or core[b] not in (2, 3):
                continue
            X = np.linalg.inv(Xs[glink[a]] if glink[a] >= 0 else np.eye(4)) @ (Xs[glink[b]] if glink[b] >= 0 else np.eye(4))
            rot = np.ascontiguousarray(X[:3, :3]).ravel()
            pa, pb = vL[vst[a]:vst[a + 1]], vL[vst[b]:vst[b + 1]]
            adja, adjb = gadj[gadjs[a]:gadjs[a + 1]], gadj[gadjs[b]:gadjs[b + 1]]
            taba, tabb = gdir[gdirs[a]:gdirs[a + 1]], gdir[gdirs[b]:gdirs[b + 1]]
            d0 = np.array(G._inner_point(pa, adja)) - (X[:3, :3] @ np.array(G._inner_point(pb, adjb)) + X[:3, 3])
            e = G._b_dir(rot, *d0)
            sa, sb = G.table_start(taba, *(-d0)), G.table_start(tabb, *e)
            its, answer = [], None
            for out, seed in ((cold, None), (rows, seed_row(spair, sgrid, sdt, p, q_engine))):
                for k in count:
                    count[k] = 0
                r = G._gjk_body(pa, adja, pb, adjb, rot, X[0, 3], X[1, 3], X[2, 3], *d0, prm[2], prm[4], iprm[2],
                                np.zeros(9), np.inf, sa, sb, taba, tabb, seed)
                if r[0] == G.GJK_SEPARATED:
                    out.append((count["it"], count["climb"], count["dot"]))
                    its.append(count["it"])
                    answer = np.array(r[2:5]) - np.array(r[5:8])  # the witnesses' difference: the answer's direction
            if len(its) == 2:
                # a cold start along the answer's own direction (climbs from the tables' entries for it): the
                # iterations no better first direction can save
                e = G._b_dir(rot, *answer)
                for k in count:
                    count[k] = 0
                G._gjk_body(pa, adja, pb, adjb, rot, X[0, 3], X[1, 3], X[2, 3], *answer, prm[2], prm[4], iprm[2],
                            np.zeros(9), np.inf, G.table_start(taba, *(-answer)), G.table_start(tabb, *e), taba, tabb)
                by.setdefault(int(spair[p, 2] & 3) if spair[p, 0] >= 0 else 0, []).append((its[1], its[0], count["it"]))
    r = np.array(rows, dtype=float).reshape(-1, 3)
    out = {"gjk_pairs": len(r), "it_cold": float(np.mean([c[0] for c in cold])) if cold else float("nan"),
           "by_joints": {str(k): [float(np.mean([v[j] for v in b])) for j in range(3)] for k, b in sorted(by.items())}}
    for j, k in enumerate(("it", "climb", "dot")):
        out[k] = float(r[:, j].mean()) if len(r) else float("nan")
        out[k + "_p90"] = float(np.percentile(r[:, j], 90)) if len(r) else float("nan")
    return out


KINDS = ("apart, seed table", "apart, no table", "overlapping")


def _by_kind(ana, f, Q, Q_turn) -> tuple:
    """Each pair alone, hot: the kernel's entry point on that one pair (``f.subset``), the same
    configuration 15 times (the best time, so the pair's data in L1 and its branches learnt), less
    the same for no pair; per configuration of ``Q`` and pair, grouped by what the pair is there:
    apart with a seed table, apart without, overlapping (EPA's depth).  Returns that, the whole kernel's
    time with each configuration of ``Q`` repeated (µs, the fixed part less), and the sum over the pairs
    of each pair alone with the configurations of ``Q_turn`` in turn (µs)."""
    import time

    import numpy as np

    from armguard_analytic._engine._layout import K

    H, MF, MI, prm, iprm = f.args
    SF, SI, q1 = f.tls.s
    spair = MI[H[2 * K["spair"]]:H[2 * K["spair"]] + 6 * H[2 * K["spair"] + 1]].reshape(-1, 6)
    tabled = spair[:, 0] >= 0 if len(spair) else np.zeros(f.n, bool)
    g_one = [f.subset(np.array([p], np.int64)) for p in range(f.n)]
    g0, e = f.subset(np.zeros(0, np.int64)), np.empty(0)
    d1, a1, b1 = np.empty(1), np.empty((1, 3)), np.empty((1, 3))

    def best(q, g, d, a, b):
        t_best = math.inf
        for _ in range(15):
            t = time.perf_counter()
            f.entry(f.fn, q, 0, 1, g, H, MF, MI, SF, SI, prm, iprm, q1, d, a, b)
            t_best = min(t_best, time.perf_counter() - t)
        return t_best

    sums = {k: [0, 0.0] for k in KINDS}
    again = []  # every pair at once, the configuration repeated: the call with its data and branches warm
    d, pa, pb = np.empty(f.n), np.empty((f.n, 3)), np.empty((f.n, 3))
    for q in Q:
        dist = ana.pair_distances(q).distance
        t0 = best(q, g0, e, e.reshape(0, 3), e.reshape(0, 3))
        again.append(best(q, f.gmap, d, pa, pb) - t0)
        for p in range(f.n):
            kind = KINDS[2] if dist[p] < 0.0 else (KINDS[0] if tabled[p] else KINDS[1])
            sums[kind][0] += 1
            sums[kind][1] += max(best(q, g_one[p], d1, a1, b1) - t0, 0.0)
    out = {k: [c / len(Q), (t / c * 1e9) if c else float("nan")] for k, (c, t) in sums.items()}

    def cycling(g, d, a, b):  # the configurations of Q_turn in turn, 5 passes after one: seconds a call
        for q in Q_turn:
            f.entry(f.fn, q, 0, 1, g, H, MF, MI, SF, SI, prm, iprm, q1, d, a, b)
        t = time.perf_counter()
        for _ in range(5):
            for q in Q_turn:
                f.entry(f.fn, q, 0, 1, g, H, MF, MI, SF, SI, prm, iprm, q1, d, a, b)
        return (time.perf_counter() - t) / (5 * len(Q_turn))

    # each pair alone again, the configurations in turn: only its own two elements in the caches, its
    # branches trained on the previous configuration
    t0 = cycling(g0, e, e.reshape(0, 3), e.reshape(0, 3))
    alone_cycling = sum(max(cycling(g_one[p], d1, a1, b1) - t0, 0.0) for p in range(f.n))
    return out, float(np.mean(again)) * 1e6, alone_cycling * 1e6


def measure(name: str, n: int) -> dict:
    """One robot's row (see the module docstring); run in a fresh process."""
    import numpy as np

    import armguard

    model = armguard.load_model(name)
    ana = armguard.checker(model, "analytic")
    Q = [np.ascontiguousarray(q) for q in model.random_q(200, 7)]
    ana.pair_distances(Q[0])
    f = ana._plan()
    H, MF, MI, prm, iprm = f.args
    SF, SI, q1 = f.tls.s
    it = iter(range(10**9))
    d, pA, pB = np.empty(f.n), np.empty((f.n, 3)), np.empty((f.n, 3))
    g0, e = f.subset(np.zeros(0, np.int64)), np.empty(0)
    from .backends import _wrapper_seconds
    from .timing import interleaved_thread_seconds

    E3 = e.reshape(0, 3)
    t = interleaved_thread_seconds({
        "call": lambda: ana.pair_distances(Q[next(it) % 200]),
        "kernel": lambda: f.entry(f.fn, Q[next(it) % 200], 0, 1, f.gmap, H, MF, MI, SF, SI, prm, iprm, q1, d, pA, pB),
        "fixed": lambda: f.entry(f.fn, Q[next(it) % 200], 0, 1, g0, H, MF, MI, SF, SI, prm, iprm, q1, e, E3, E3),
        "same": lambda: ana.pair_distances(Q[0])}, repeat=5, number=n // 5)
    t_call, t_kernel, t_fixed, t_same = t["call"], t["kernel"], t["fixed"], t["same"]
    t_wrap = _wrapper_seconds(ana, f, Q[0])
    from armguard_analytic._engine._layout import K

    core = MI[H[2 * K["core"]]:H[2 * K["core"]] + H[2 * K["core"] + 1]]
    pa = MI[H[2 * K["pair_a"]]:H[2 * K["pair_a"]] + H[2 * K["pair_a"] + 1]]
    pb = MI[H[2 * K["pair_b"]]:H[2 * K["pair_b"]] + H[2 * K["pair_b"] + 1]]
    poly = int(sum(1 for a, b in zip(pa, pb) if b >= 0 and core[a] in (2, 3) and core[b] in (2, 3)))
    row = {"name": name, "pairs": f.n, "poly_pairs": poly, "us_call": t_call * 1e6, "us_kernel": t_kernel * 1e6,
           "us_fixed": t_fixed * 1e6, "us_same": t_same * 1e6, "us_wrap": t_wrap * 1e6}
    row["by_kind"], row["us_again"], row["us_alone_cycling"] = _by_kind(ana, f, Q[:40], Q)  # before the replay below swaps GJK's helpers for Python
    row.update(_gjk_work(model, ana, 20))
    return row


def run(quick: bool) -> str:
    n = 2000 if quick else 10000
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    rows = ["| robot | pairs (polytope) | call | Python wrapper | fixed (unboxing, views, FK) | per pair | same q "
            "| GJK iterations / pair (p90) | from a cold start | seeded / cold / along the answer, by the joints of the pair's table "
            "| climbs / pair (p90) | support dot products / pair (p90) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    kinds = ["| robot | " + " | ".join(f"{k}: pairs / configuration, ns each" for k in KINDS)
             + " | the pairs alone | all at once, the configuration again | the pairs alone, the configurations in turn "
             "| kernel - fixed | the rest |", "|---|---|---|---|---|---|---|---|---|"]
    for name in ROBOTS:
        r = json_of_process([sys.executable, "-m", "bench.pair_profile", name, str(n)], cwd=root, env=env)
        if "error" in r:
            rows.append(f"| {name} | error: {r['error']} |||||||||||")
            continue
        print(f"  {name}: {r}", file=sys.stderr, flush=True)
        per = (r["us_kernel"] - r["us_fixed"]) / max(r["pairs"], 1)
        by = ", ".join(f"{'no table' if k == '0' else k}: {s:.1f} / {c:.1f} / {a:.1f}" for k, (s, c, a) in r["by_joints"].items())
        work = (f"| {r['it']:.1f} ({r['it_p90']:.0f}) | {r['it_cold']:.1f} | {by} | {r['climb']:.1f} ({r['climb_p90']:.0f}) "
                f"| {r['dot']:.0f} ({r['dot_p90']:.0f}) |") if r["gjk_pairs"] else "| — | — | — | — | — |"
        rows.append(
            f"| {name} | {r['pairs']} ({r['poly_pairs']}) | {r['us_call']:.1f} µs | {r['us_wrap']:.1f} µs "
            f"| {r['us_fixed']:.1f} µs | {per:.2f} µs | {r['us_same']:.1f} µs " + work)
        alone = sum(c * t for c, t in r["by_kind"].values() if c) / 1e3
        rest = r["us_kernel"] - r["us_fixed"] - alone
        kinds.append(f"| {name} | " + " | ".join(f"{c:.2f}, {t:.0f} ns" if c else "—" for c, t in r["by_kind"].values())
                     + f" | {alone:.1f} µs | {r['us_again']:.1f} µs | {r['us_alone_cycling']:.1f} µs "
                     f"| {r['us_kernel'] - r['us_fixed']:.1f} µs | {rest:.1f} µs "
                     f"({rest / max(r['us_kernel'] - r['us_fixed'], 1e-9):.0%}) |")
    note = (f"\n\nThread-time medians, {n} calls per figure, `q` cycling over 200 random in-limit configurations; "
            "GJK work over the separated polytope pairs of 20 configurations (`bench/pair_profile.py`). *per pair* "
            "is (kernel - fixed) / pairs; *Python wrapper* is the best of 21 interleaved runs (as `bench backends`); *same q* repeats one configuration (forward kinematics skipped, branch "
            "predictor trained). *by the joints of the pair's table*: the mean GJK iterations of the pairs whose "
            "pose depends on 1, 2 or 3 joint values (their seed tables, `armguard_analytic._engine._seeds`), and of "
            "those without a table; *along the answer*: a cold start whose first direction is the pair's own final one (the witnesses' difference; "
            "the climbs starting from the support tables' entries for it), the iterations that no better first direction saves. z1's pairs all have a cylinder side (GJK and EPA on support functions, "
            "`_pair_cylinder.support_pair_graph`): not counted.")
    note2 = ("\n\nThe same kernel, pair by pair (`_by_kind`): each pair of 40 of those configurations alone, "
             "its configuration repeated 15 times and the best time kept (its hulls in L1, its branches learnt), "
             "less the same call with no pair; grouped by what the pair is at that configuration: apart with a seed "
             "table, apart without one (a cold start), overlapping (GJK, then EPA's depth). *the pairs alone*: their "
             "sum per configuration; *all at once, the configuration again*: the whole kernel, less the same "
             "fixed part, each of the 40 configurations repeated 15 times (best kept); *the pairs alone, the "
             "configurations in turn*: each pair alone over the 200 configurations one after the other (5 passes), "
             "summed over the pairs; *the rest*: what the same pairs cost more in *kernel - fixed*, which cycles over "
             "200 configurations. A pair alone with the configurations in turn has only its own two elements to "
             "keep in the caches, yet costs about what it costs within the whole call: the rest is not the caches' "
             "capacity but what changes with the configuration (the climbs' and tests' branches taken another way, "
             "other vertices).")
    return "\n".join(rows) + note + "\n\n" + "\n".join(kinds) + note2


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 2000)))
