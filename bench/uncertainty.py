"""Uncertain relations (Smith & Cheeseman): compound and merge cost per call, 2-D and 3-D, beside
pytransform3d's uncertainty module in the same run.

Times are medians of per-thread CPU time (``time.thread_time``) over repeated runs of many calls.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from bench.timing import median_thread_seconds

TITLE = "Uncertain relations: compound and merge (µs per call)"


def _wall(fn, *, repeat: int) -> float:
    """Median wall time of ``fn`` over ``repeat`` runs (after one warm-up run)."""
    fn()
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples)


def _checks_rows(quick: bool) -> list[str]:
    """Uncertain placements in the checks: clearance_sigmas and verify_with_confidence on puma560."""
    import math

    import armguard
    from armguard.uncertainty import UncertainPlacement, UncertainPose2, UncertainPose3, clearance_sigmas, verify_with_confidence

    rep = 3 if quick else 5
    scene = armguard.load_scene("puma560")
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    traj = scene.trajectories["pick_and_place"]
    T = np.eye(4)
    T[:3, 3] = [0.55, 0.15, 0.6]
    body = UncertainPlacement("cylinder_a", UncertainPose3(T, np.diag([1e-4] * 3 + [math.radians(1) ** 2] * 3)))
    base = UncertainPlacement("puma560", UncertainPose2([0.0, 0.0, 0.0], np.diag([1e-4, 1e-4, math.radians(0.5) ** 2])))
    n_mc = 1000
    rows = [
        "**Uncertain placements in the checks** (puma560 cell at home; `clearance_sigmas` through the "
        "Detector's pair distances, wall time per call):",
        "",
        "| call | placement | pairs moved | ms per call |",
        "|---|---|---|---|",
    ]
    for label, pl in (("cylinder_a, SE(3), σ = 1 cm, 1°", body), ("robot base, planar, σ = 1 cm, 0.5°", base)):
        n_pairs = len(clearance_sigmas(det, q, pl, samples=0).pairs)
        t0 = _wall(lambda p=pl: clearance_sigmas(det, q, p, samples=0), repeat=rep)
        t1 = _wall(lambda p=pl: clearance_sigmas(det, q, p, samples=n_mc), repeat=max(1, rep // 2))
        rows.append(f"| `clearance_sigmas` (sigmas and the χ² bound) | {label} | {n_pairs} | {t0 * 1e3:.2f} |")
        rows.append(f"| the same with a {n_mc}-draw Monte Carlo estimate | {label} | {n_pairs} | {t1 * 1e3:.1f} |")
    t_nom = _wall(lambda: armguard.verify(scene, traj), repeat=rep)
    t_conf = _wall(lambda: verify_with_confidence(scene, traj, [body]), repeat=rep)
    t_base = _wall(lambda: verify_with_confidence(scene, traj, [base]), repeat=rep)
    rows += [
        f"| `armguard.verify` (nominal, certified) | — | — | {t_nom * 1e3:.1f} |",
        f"| `verify_with_confidence` (99.9 %: grow, copy, verify) | {'cylinder_a, SE(3), σ = 1 cm, 1°'} | — | {t_conf * 1e3:.1f} |",
        f"| `verify_with_confidence` (99.9 %) | robot base, planar, σ = 1 cm, 0.5° | — | {t_base * 1e3:.1f} |",
    ]
    return rows


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
        ("2-D", "compound"): (median_thread_seconds(lambda: a2.compound(b2), repeat=rep, number=num),
                              median_thread_seconds(lambda: se2.compound(a2.mean, a2.cov, b2.mean, b2.cov), repeat=rep, number=num)),
        ("2-D", "merge"): (median_thread_seconds(lambda: a2.merge(b2), repeat=rep, number=num),
                           median_thread_seconds(lambda: se2.merge(a2.mean, a2.cov, b2.mean, b2.cov), repeat=rep, number=num)),
        ("2-D", "reverse"): (median_thread_seconds(lambda: a2.reverse(), repeat=rep, number=num),
                             median_thread_seconds(lambda: se2.reverse(a2.mean, a2.cov), repeat=rep, number=num)),
        ("3-D", "compound"): (median_thread_seconds(lambda: a3.compound(b3), repeat=rep, number=num),
                              median_thread_seconds(lambda: se3.compound(a3.mean, a3.cov, b3.mean, b3.cov), repeat=rep, number=num)),
        ("3-D", "merge"): (median_thread_seconds(lambda: a3.merge(b3m), repeat=rep, number=num // 4),
                           median_thread_seconds(lambda: se3.merge(a3.mean, a3.cov, b3m.mean, b3m.cov), repeat=rep, number=num // 4)),
        ("3-D", "inverse"): (median_thread_seconds(lambda: a3.inverse(), repeat=rep, number=num),
                             median_thread_seconds(lambda: se3.inverse(a3.mean, a3.cov), repeat=rep, number=num)),
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
        peer[("3-D", "compound")] = (median_thread_seconds(lambda: concat(tb, cb, ta, ca), repeat=rep, number=num // 4),
                                     f"`{name}` (with its 4th-order terms)")
        peer[("3-D", "merge")] = (median_thread_seconds(lambda: pu.pose_fusion([ta, tbm], [ca, cbm]), repeat=rep, number=max(20, num // 200)),
                                  "`pose_fusion` (20 Gauss-Newton iterations)")
        peer[("3-D", "inverse")] = (median_thread_seconds(lambda: pu.invert_uncertain_transform(ta, ca), repeat=rep, number=num // 4),
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
    lines += ["", *_checks_rows(quick)]
    load = os.getloadavg()
    lines += ["", note, "", f"Machine load while measuring (1/5/15-minute load average on {os.cpu_count()} cores): "
              f"{load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}."]
    return "\n".join(lines)
