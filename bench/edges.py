"""A planner's edges on public robots: certified (``Verifier.check_edges``) against sampling at 0.05 and 0.01 rad.

Sampling planners check each straight joint-space edge: OMPL's ``DiscreteMotionValidator`` and
MoveIt at a fraction of the space's extent, Drake at 0.05 rad (``DRAKE_JOINT_STEP``).  Here, on
random in-limit edges of each public arm (no joint moving more than ``MAX_STEP`` rad):

* **certified**: ``Verifier.check_edges(Q0, Q1)`` (every configuration of the edge; the covering of
  ``armguard.verify._edges``), thread CPU time per edge, the evaluations per edge (median, p90);
* **one edge through ``Verifier.verify``** (a two-knot ``Trajectory``, its report and profile);
* **sampled**: the edge's samples at ``step`` (both ends and ``ceil(max |dq| / step)`` pieces), all of
  them in one ``collides(Q)`` of the coal reference backend and of the analytic backend (a planner's
  validator stops at the first sample in contact; every sample of a free edge is checked either way);
* **missed**: edges the certified check finds in collision that the sampled check passes (a sample
  spacing steps over the contact); **false clear**: edges certified CLEAR with a sample coal finds in
  contact (must be 0).
"""

from __future__ import annotations

import json
import math
import os
import sys

from bench.timing import json_of_process

TITLE = "Edges of a planner: certified against sampled"
ROBOTS = ("ur5", "panda", "kuka_iiwa", "xarm7", "z1", "so101", "panda+wires")
WIRES = [((0.5, -0.6, z), (0.5, 0.6, z)) for z in (0.2, 0.45, 0.7)] + [((-0.5, -0.6, 0.3), (-0.5, 0.6, 0.3))]
"""``panda+wires``: four 2 mm wires (capsules, radius 2 mm, 1.2 m long) across the Panda's workspace."""
MAX_STEP = 0.5  # rad: the largest joint move of an edge
STEPS = (0.05, 0.01)


def _edges(model, n: int, seed: int, free=None):
    """``n`` random edges, both ends in limits (and apart for the checker ``free`` when given)."""
    import numpy as np

    Q0, Q1 = [], []
    i = 0
    while len(Q0) < n:
        Q = model.random_q(2, seed + i)
        i += 1
        if free is not None and free.collides(Q).any():
            continue
        Q = model.scene_q(Q)
        d = Q[1] - Q[0]
        Q[1] = Q[0] + d * min(1.0, MAX_STEP / float(np.max(np.abs(d))))
        Q0.append(Q[0])
        Q1.append(Q[1])
    return np.array(Q0), np.array(Q1)


def measure(name: str, n: int) -> dict:
    import warnings

    import numpy as np

    import armguard
    from armguard.kinematics import Trajectory
    from armguard.verify import Verifier
    from bench.timing import interleaved_thread_seconds

    warnings.simplefilter("ignore")
    model = armguard.load_model(name.removesuffix("+wires"))
    if name.endswith("+wires"):
        from armguard.geometry import Capsule

        model = model.with_body("wires", [Capsule(a, b, 0.002) for a, b in WIRES])
    robot = next(iter(model.scene.robots))
    names = model.scene.robots[robot].joint_names
    v = Verifier(model.scene)
    Q0, Q1 = _edges(model, n, 7000, free=armguard.checker(model, "coal") if name.endswith("+wires") else None)
    res = v.check_edges(Q0, Q1)
    coal = armguard.checker(model, "coal", {"threads": 1})
    ana = armguard.checker(model, "analytic")
    samples = {}
    for step in STEPS:
        per = []
        for q0, q1 in zip(Q0, Q1):
            k = max(1, math.ceil(float(np.max(np.abs(q1 - q0))) / step))
            s = np.linspace(0.0, 1.0, k + 1)[:, None]
            per.append(model.pin_q(q0 + s * (q1 - q0)))
        samples[step] = per
    out = {"name": name, "edges": n, "pairs": len(v.model.owner_a), **res.counts()}
    collision = res.code == 1
    for step in STEPS:
        hit_coal = np.array([bool(coal.collides(Q).any()) for Q in samples[step]])
        out[f"missed_{step}"] = int(np.sum(collision & ~hit_coal))
        out[f"false_clear_{step}"] = int(np.sum(res.clear & hit_coal))
        out[f"samples_{step}"] = float(np.mean([len(Q) for Q in samples[step]]))
    few = min(n, 30)
    traj = [Trajectory(robot, names, [0.0, 1.0], np.stack([Q0[i], Q1[i]])) for i in range(few)]
    fns = {
        "certified": lambda: v.check_edges(Q0, Q1),
        "certified_each": lambda: [v.check_edges(Q0[i:i + 1], Q1[i:i + 1]) for i in range(n)],
        "coal_0.05": lambda: [coal.collides(Q) for Q in samples[0.05]],
        "analytic_0.05": lambda: [ana.collides(Q) for Q in samples[0.05]],
        "coal_0.01": lambda: [coal.collides(Q) for Q in samples[0.01]],
        "analytic_0.01": lambda: [ana.collides(Q) for Q in samples[0.01]],
    }
    t = interleaved_thread_seconds(fns, repeat=5)
    for k, sec in t.items():
        out[f"us_{k}"] = sec / n * 1e6
    out["us_verify"] = interleaved_thread_seconds({"v": lambda: [v.verify(tr) for tr in traj]}, repeat=3)["v"] / few * 1e6
    ev = res.evaluations
    out["evals_median"] = float(np.median(ev))
    out["evals_p90"] = float(np.percentile(ev, 90))
    return out


def run(quick: bool) -> str:
    n = 60 if quick else 300
    rows = ["| robot | link pairs | edges: clear / collision / incomplete | certified `check_edges`, all edges in one call "
            "| certified, one call per edge | evaluations / edge (p90) "
            "| `Verifier.verify`, one edge | coal sampled 0.05 rad (samples) | analytic sampled 0.05 rad "
            "| coal sampled 0.01 rad (samples) | analytic sampled 0.01 rad | coal 0.05 / certified (one call per edge) "
            "| coal 0.01 / certified (one call per edge) | missed at 0.05 / 0.01 rad | false clear |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    for name in ROBOTS:
        r = json_of_process([sys.executable, "-m", "bench.edges", name, str(n)], cwd=here, timeout=1800)
        if "error" in r:
            rows.append(f"| {name} | error: {r['error']} |||||||||||||")
            continue
        print(f"  {name}: {r}", file=sys.stderr, flush=True)
        rows.append(
            f"| {name} | {r['pairs']} | {r['clear']} / {r['collision']} / {r['incomplete']} | {r['us_certified']:.0f} µs "
            f"| {r['us_certified_each']:.0f} µs | {r['evals_median']:g} ({r['evals_p90']:g}) | {r['us_verify']:.0f} µs "
            f"| {r['us_coal_0.05']:.0f} µs ({r['samples_0.05']:.1f}) | {r['us_analytic_0.05']:.0f} µs "
            f"| {r['us_coal_0.01']:.0f} µs ({r['samples_0.01']:.1f}) | {r['us_analytic_0.01']:.0f} µs "
            f"| {r['us_coal_0.05'] / r['us_certified_each']:.1f}× | {r['us_coal_0.01'] / r['us_certified_each']:.1f}× "
            f"| {r['missed_0.05']} / {r['missed_0.01']} | {r['false_clear_0.05'] + r['false_clear_0.01']} |")
    note = (f"\n\n{n} random in-limit edges per robot (seeded), no joint moving more than {MAX_STEP} rad; each robot in "
            "its own process. *panda+wires*: the Panda with four 2 mm wires across its workspace (capsules of radius 2 mm, "
            "`Model.with_body`), its edges between configurations apart (for coal) at both ends. Times are thread CPU time per edge, medians of 5 interleaved runs over all the edges "
            "(`Verifier.verify`: 30 edges, 3 runs). *certified*: `Verifier.check_edges(Q0, Q1)` on the analytic "
            "backend, every configuration of the edge proven at least 0 m clear (CLEAR) or a configuration in contact "
            "found (COLLISION); all the edges in one call (a planner that batches its edges), or one call per edge as "
            "the sampled checks are made (the ratios: a planner checking its edges one at a time). `Verifier.verify` "
            "checks one edge as a trajectory and builds its report and clearance profile: slower than sampling "
            "with coal at 0.05 rad. *sampled*: the edge's samples at the step in one `collides(Q)` call per edge (coal "
            "with `threads=1`; the sample configurations made beforehand, not timed). *missed*: edges in collision "
            "(certified) that the sampled check, with coal, passes. *false clear*: edges certified CLEAR with a "
            "sample coal finds in contact (a certified check's error: 0 expected). `bench/edges.py`.")
    return "\n".join(rows) + note


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]))))
