"""Distance Jacobians and collision avoidance: what ``jacobian=True`` adds, and one damper step.

* Jacobians for every pair vs distances alone, analytic and coal(+Pinocchio) in the same run
  (median thread-CPU µs per call over random in-limit configurations);
* one avoidance step (``armguard.avoidance.avoid_step``: the arm's distances and Jacobians, the
  damper rows of the pairs within the influence distance, the DAQP solve) for Ranger's left arm
  (74 pairs), thread CPU and wall clock, and its parts: the distance call, the compiled filter
  and its NumPy reference (``avoid``);
* every Ranger canned test run with avoidance on (``armguard.avoidance.run_canned_all``), at a
  5 cm and a 20 cm stand-off: contact, least distance, how far each got (``canned_table``).
"""

from __future__ import annotations

import os
import time

import numpy as np

TITLE = "Distance Jacobians and collision avoidance"
MODELS = ["ranger", "hermes", "puma560", "panda", "z1", "kinova", "so101"]  # the last three: mesh hulls of 1,500-6,900 vertices


def _median_us(fn, args_list, reps: int, clock=time.thread_time) -> float:
    """Median µs per call of ``fn(a)`` over ``args_list`` (``reps`` rounds): thread CPU time by
    default (what one core spends; less sensitive to the shared machine's load), or wall clock."""
    times = []
    for _ in range(reps):
        for a in args_list:
            t = clock()
            fn(a)
            times.append(clock() - t)
    return 1e6 * float(np.median(times))


def _load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def run(quick: bool = False) -> str:
    import armguard
    from armguard.avoidance import Damper, avoid, avoid_step
    from armguard.avoidance._fast import filter_velocity

    reps = 3 if quick else 20
    load0 = _load()
    lines = ["| model | pairs | nv | analytic d (µs) | analytic d+J (µs) | ratio | coal d (µs) | coal d+J (µs) | ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name in MODELS:
        m = armguard.load_model(name)
        Q = list(m.random_q(10, rng=1))
        row = [name, str(len(m.pairs)), str(m.pin_model.nv)]
        for be in ("analytic", "coal"):
            c = armguard.checker(m, be)
            c.pair_distances(Q[0], jacobian=True)  # warm
            t0 = _median_us(lambda q: c.pair_distances(q), Q, reps)
            t1 = _median_us(lambda q: c.pair_distances(q, jacobian=True), Q, reps)
            row += [f"{t0:.1f}", f"{t1:.1f}", f"{t1 / t0:.2f}"]
        lines.append("| " + " | ".join(row) + " |")

    m = armguard.load_model("ranger")
    c = armguard.checker(m, "analytic")
    p = m.pairs
    rows = np.array([k for k, (a, b) in enumerate(zip(p.owner_a, p.owner_b))
                     if a.startswith("left_arm/") or b.startswith("left_arm/")])
    pm = m.pin_model
    cols = [pm.joints[j].idx_v for j in range(1, pm.njoints) if pm.names[j].startswith("left_arm_")]
    assert len(cols) == 7, cols
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    rng = np.random.default_rng(3)
    cases = []
    for q in m.random_q(40, rng=rng):
        v = np.zeros(pm.nv)
        v[cols] = rng.normal(size=len(cols))
        cases.append((q, v))
    # and 40 where the damper binds: a configuration with a pair between the stand-off and the
    # influence distance, commanded at the velocity limits straight towards that pair
    near = 0
    for q in m.random_q(4000, rng=rng):
        if near == 40:
            break
        r = c.pair_distances(q, pairs=rows, jacobian=True)
        k = int(np.argmin(r.distance))
        if not damper.stand_off + 0.01 < r.distance[k] < damper.stand_off + 0.1:
            continue
        v = np.zeros(pm.nv)
        v[cols] = -np.sign(r.jacobian[k, cols]) * damper.velocity_limit
        cases.append((q, v))
        near += 1
    avoid_step(c, *cases[0], damper, pairs=rows)
    step = lambda a: avoid_step(c, a[0], a[1], damper, pairs=rows)  # noqa: E731
    t_step = _median_us(step, cases, reps)
    t_wall = _median_us(step, cases, reps, clock=time.perf_counter)
    t_bind = _median_us(step, cases[40:], reps) if near else float("nan")
    t_dj = _median_us(lambda a: c.pair_distances(a[0], pairs=rows, jacobian=True), cases, reps)
    outs = [avoid_step(c, q, v, damper, pairs=rows) for q, v in cases]
    subs = []
    for (q, v), o in zip(cases, outs):
        r = c.pair_distances(q, pairs=rows[np.isin(rows, o.rows)] if len(o.rows) else rows[:0], jacobian=True)
        subs.append((v, r))
    t_qp = _median_us(lambda a: avoid(a[0], a[1], damper), subs, reps)
    tol, lim = m.tol, damper.limits(pm.nv)
    t_fast = _median_us(lambda a: filter_velocity(a[0], a[1].distance, a[1].jacobian, -lim, lim, damper, tol), subs,
                        reps)
    n_con = np.array([len(o.rows) for o in outs])
    status = {s: sum(o.status.value == s for o in outs) for s in ("free", "slowed", "stopped")}
    body = (f"Thread CPU time medians (`time.thread_time`; load average {load0} at the start, {_load()} at the "
            "end of this part).\n\n" + "\n".join(lines))
    body += (
        "\n\nOne avoidance step, Ranger's left arm (7 joints, "
        f"{len(rows)} pairs; stand-off {damper.stand_off} m, influence {damper.influence} m; 40 random configurations "
        f"with random commands on the arm's joints, and {near} with a pair 1-10 cm beyond the stand-off commanded at the "
        f"velocity limits straight towards it): **{t_step:.0f} µs median** thread time for the whole step "
        f"({t_wall:.0f} µs wall clock): the distances and Jacobians of the {len(rows)} pairs in one call "
        f"({t_dj:.0f} µs), the {int(np.median(n_con))} (median; max {n_con.max()}) pairs within influence as damper rows, "
        f"the QP; the compiled rows-QP-checks alone (`avoidance._fast.filter_velocity`) {t_fast:.0f} µs, its NumPy "
        f"reference (`avoid`) {t_qp:.0f} µs; the commands towards a pair alone: {t_bind:.0f} µs median; "
        f"statuses {status}.\n"
    )
    return body + "\n" + canned_table()


def canned_table() -> str:
    """Every Ranger canned test with avoidance on, at two stand-off distances (100 Hz, 1 rad/s)."""
    import armguard
    from armguard.avoidance import Damper, run_canned_all

    m = armguard.load_model("ranger")
    lines = ["| canned test | stand-off (m) | start d (m) | least d (m) | contact | holds | progress | free / slowed / stopped |",
             "|---|---|---|---|---|---|---|---|"]
    for so in (0.05, 0.2):
        damper = Damper(stand_off=so, influence=so + 0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
        for r in run_canned_all(m, damper):
            st = r.statuses
            lines.append(f"| {r.name} | {so} | {r.start_distance:.3f} | {r.min_distance:.3f} | {'yes' if r.contact else 'no'} "
                         f"| {'yes' if r.holds(so) else 'NO'} | {100 * r.progress:.1f} % "
                         f"| {st['free']} / {st['slowed']} / {st['stopped']} |")
    return ("Ranger's canned tests with avoidance on (influence = stand-off + 0.15 m, approach speed 0.3 m/s, "
            "1 rad/s, 100 Hz; 'holds': no contact and least distance >= min(stand-off, start) - 1 mm; "
            "progress: fraction of the joint-space way to the goal):\n\n" + "\n".join(lines) + "\n")
