"""Uncertain relations (Smith & Cheeseman): compound and merge cost per call, 2-D and 3-D, beside
pytransform3d's uncertainty module in the same run.

Times are medians of per-thread CPU time (``time.thread_time``) over repeated runs of many calls.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

TITLE = "Uncertain relations: compound and merge (µs per call)"


def median_seconds(fn, *, repeat: int = 7, number: int = 1) -> float:
    """Median over ``repeat`` runs of the thread CPU time per call of ``fn`` (``number`` calls a run)."""
    fn()
    samples = []
    for _ in range(repeat):
        t0 = time.thread_time()
        for _ in range(number):
            fn()
        samples.append((time.thread_time() - t0) / number)
    return statistics.median(samples)


def run(quick: bool) -> str:
    from armguard.uncertainty import UncertainPose2, UncertainPose3, se2, se3

    rep = 3 if quick else 7
    num = 2_000 if quick else 20_000
    rng = np.random.default_rng(0)
    a2 = UncertainPose2([1.0, 0.5, 0.3], np.diag([1e-4, 2e-4, 3e-4]))
    b2 = UncertainPose2([0.8, -0.2, 1.1], np.diag([2e-4, 1e-4, 1e-4]))
    c3 = np.diag([1e-4] * 3 + [3e-4] * 3)
    a3 = UncertainPose3.from_exp_coords(rng.normal(size=6), c3)
    b3 = UncertainPose3.from_exp_coords(rng.normal(size=6), c3 * 2)
    b3m = UncertainPose3(se3.exp(rng.normal(size=6) * 1e-2) @ a3.mean, c3 * 2)
    ours = {
        ("2-D", "compound"): (median_seconds(lambda: a2.compound(b2), repeat=rep, number=num),
                              median_seconds(lambda: se2.compound(a2.mean, a2.cov, b2.mean, b2.cov), repeat=rep, number=num)),
        ("2-D", "merge"): (median_seconds(lambda: a2.merge(b2), repeat=rep, number=num),
                           median_seconds(lambda: se2.merge(a2.mean, a2.cov, b2.mean, b2.cov), repeat=rep, number=num)),
        ("2-D", "reverse"): (median_seconds(lambda: a2.reverse(), repeat=rep, number=num),
                             median_seconds(lambda: se2.reverse(a2.mean, a2.cov), repeat=rep, number=num)),
        ("3-D", "compound"): (median_seconds(lambda: a3.compound(b3), repeat=rep, number=num),
                              median_seconds(lambda: se3.compound(a3.mean, a3.cov, b3.mean, b3.cov), repeat=rep, number=num)),
        ("3-D", "merge"): (median_seconds(lambda: a3.merge(b3m), repeat=rep, number=num // 4),
                           median_seconds(lambda: se3.merge(a3.mean, a3.cov, b3m.mean, b3m.cov), repeat=rep, number=num // 4)),
        ("3-D", "inverse"): (median_seconds(lambda: a3.inverse(), repeat=rep, number=num),
                             median_seconds(lambda: se3.inverse(a3.mean, a3.cov), repeat=rep, number=num)),
    }
    peer: dict = {}
    note = "pytransform3d not installed: no peer column."
    try:
        import pytransform3d
        import pytransform3d.uncertainty as pu

        ta, ca = a3.to_pytransform3d()
        tb, cb = b3.to_pytransform3d()
        tbm, cbm = b3m.to_pytransform3d()
        concat = getattr(pu, "compound_poses", None) or pu.concat_globally_uncertain_transforms
        name = concat.__name__
        peer[("3-D", "compound")] = (median_seconds(lambda: concat(tb, cb, ta, ca), repeat=rep, number=num // 4),
                                     f"`{name}` (with its 4th-order terms)")
        peer[("3-D", "merge")] = (median_seconds(lambda: pu.pose_fusion([ta, tbm], [ca, cbm]), repeat=rep, number=max(20, num // 200)),
                                  "`pose_fusion` (20 Gauss-Newton iterations)")
        peer[("3-D", "inverse")] = (median_seconds(lambda: pu.invert_uncertain_transform(ta, ca), repeat=rep, number=num // 4),
                                    "`invert_uncertain_transform`")
        note = (f"pytransform3d {pytransform3d.__version__}: it has no 2-D uncertainty functions. Its "
                "`concat_globally_uncertain_transforms` (formerly `compound_poses`) uses the same left "
                "perturbation as armguard's `UncertainPose3` and adds Barfoot & Furgale's fourth-order "
                "covariance terms; `pose_fusion` iterates to the maximum-a-posteriori pose, armguard's merge "
                "is the paper's one-step Kalman update (Eqns. 5-7) in the tangent space.")
    except ImportError:  # pragma: no cover - optional peer
        pass

    def us(t):
        return f"{t * 1e6:.2f}"

    lines = [
        "Per call from Python. *Class*: the `UncertainPose2`/`UncertainPose3` method (inputs validated once, "
        "at construction); *validated array function*: `armguard.uncertainty.se2`/`se3` on raw arrays, which "
        "checks finiteness and symmetric-PSD covariances (an eigenvalue solve per covariance) on every call.",
        "",
        "| relation | operation | class (µs) | validated array function (µs) | pytransform3d (µs) | peer / class |",
        "|---|---|---|---|---|---|",
    ]
    for (dim, op), (t_cls, t_fn) in ours.items():
        p = peer.get((dim, op))
        cell = f"{us(p[0])} — {p[1]}" if p else "—"
        ratio = f"{p[0] / t_cls:.1f}×" if p else "—"
        lines.append(f"| {dim} | {op} | {us(t_cls)} | {us(t_fn)} | {cell} | {ratio} |")
    load = os.getloadavg()
    lines += ["", note, "", f"Machine load while measuring (1/5/15-minute load average on {os.cpu_count()} cores): "
              f"{load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}."]
    return "\n".join(lines)
