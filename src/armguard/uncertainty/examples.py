"""The paper's example situations as data, and the Monte Carlo agreement table of
``docs/uncertainty.md``.

The paper gives no numbers for its Fig. 1 robot or its Fig. 3 simulation, so the chains here
are of its kind: a mobile robot's moves, each uncertain relative to the last position
(wheel-counter errors of centimetres and degrees), a loop that ends near its start (Fig. 1),
two approximately perpendicular motions (Section 5.3), and a large angular error followed by
a long colinear move — the case Section 6 names as where the estimates and the simulation
diverge.

Reproduce the table: ``python -m armguard.uncertainty.examples [--samples N] [--seed S]
[--plot PATH]``.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from .montecarlo import agreement, monte_carlo_chain, monte_carlo_chain3, path_length
from .pose2 import UncertainPose2
from .pose3 import UncertainPose3

__all__ = ["move", "figure1_chain", "perpendicular_chain", "colinear_chain", "chain3", "agreement_rows",
           "agreement_table"]


def move(x: float, y: float, theta_deg: float, sd_xy: float, sd_theta_deg: float) -> UncertainPose2:
    """One robot move ``(x m, y m, θ deg)`` with independent errors ``sd_xy`` (m, each of x and
    y) and ``sd_theta_deg`` (deg), relative to the last position."""
    return UncertainPose2([x, y, math.radians(theta_deg)],
                          np.diag([sd_xy**2, sd_xy**2, math.radians(sd_theta_deg) ** 2]))


def figure1_chain() -> list[UncertainPose2]:
    """Fig. 1: four moves that bring the robot back near its start (3.8 m of path)."""
    return [move(1.0, 0.0, 90, 0.02, 2), move(1.0, 0.0, 90, 0.02, 2), move(1.0, 0.0, 90, 0.02, 2),
            move(0.8, 0.0, 60, 0.02, 2)]


def perpendicular_chain() -> list[UncertainPose2]:
    """Section 5.3: the final position formed from two approximately perpendicular motions."""
    return [move(1.0, 0.0, 90, 0.05, 3), move(1.0, 0.0, 0, 0.05, 3)]


def colinear_chain(sd_theta_deg: float) -> list[UncertainPose2]:
    """Section 6's failure case: a short move with angular error ``sd_theta_deg`` (deg), then a
    long colinear move (2 m) — the angle error is large compared with the displacement error."""
    return [move(0.2, 0.0, 0, 0.01, sd_theta_deg), move(2.0, 0.0, 0, 0.01, 0.5)]


def chain3() -> list[UncertainPose3]:
    """A 6-DOF chain of three relations (1 cm, 1° errors) with rotations about all three axes."""
    rng = np.random.default_rng(7)
    out = []
    for axis in (np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])):
        xi = np.concatenate((rng.uniform(-1.0, 1.0, 3), axis * math.radians(70)))
        cov = np.diag([0.01**2] * 3 + [math.radians(1) ** 2] * 3)
        out.append(UncertainPose3.from_exp_coords(xi, cov))
    return out


def agreement_rows(n: int = 100_000, seed: int = 0, *, moment_match: bool = False) -> list[dict]:
    """Linearised vs Monte Carlo for the example chains; one dict per chain.

    Keys: ``name``, ``sd_theta_deg`` (the largest input angular sd), ``mean_position``,
    ``mean_sigma``, ``cov`` (see :class:`Agreement`) and ``inside90`` (share of samples in the
    linearised 90 % ellipse; NaN in 3-D).
    """
    cases = [("Fig. 1 loop, 4 moves", figure1_chain(), 2.0), ("two perpendicular moves", perpendicular_chain(), 3.0)]
    cases += [(f"colinear, σθ = {s:g}°", colinear_chain(s), s) for s in (1, 5, 10, 20, 35)]
    rows = []
    for i, (name, chain, sdt) in enumerate(cases):
        rng = np.random.default_rng([seed, i])
        lin = UncertainPose2.chain(*chain)
        mc = monte_carlo_chain(chain, n, rng, moment_match=moment_match)
        a = agreement(lin.mean, lin.cov, mc, length_scale=path_length(chain))
        inside = float(np.mean(lin.ellipse(0.9).contains(mc.samples[:, :2])))
        rows.append(dict(name=name, sd_theta_deg=sdt, mean_position=a.mean_position, mean_sigma=a.mean_sigma,
                         cov=a.cov, inside90=inside))
    c3 = chain3()
    lin3 = UncertainPose3.chain(*c3)
    mc3 = monte_carlo_chain3(c3, n, np.random.default_rng([seed, len(cases)]), moment_match=moment_match)
    a3 = agreement(np.zeros(6), lin3.cov, mc3, length_scale=path_length(c3), position=slice(0, 3), angle_index=())
    rows.append(dict(name="SE(3), 3 relations", sd_theta_deg=1.0, mean_position=a3.mean_position,
                     mean_sigma=a3.mean_sigma, cov=a3.cov, inside90=math.nan))
    return rows


def agreement_table(n: int = 100_000, seed: int = 0) -> str:
    """The Markdown table of :func:`agreement_rows`, plain and moment-matched sampling."""
    plain = agreement_rows(n, seed)
    matched = agreement_rows(n, seed, moment_match=True)
    lines = [
        "| chain | largest σθ | mean error / path | mean error / σ | cov error (plain) | cov error (moment-matched) "
        "| samples in 90 % ellipse |",
        "|---|---|---|---|---|---|---|",
    ]
    for p, m in zip(plain, matched):
        inside = "—" if math.isnan(p["inside90"]) else f"{p['inside90']:.1%}"
        lines.append(f"| {p['name']} | {p['sd_theta_deg']:g}° | {p['mean_position']:.2%} | {p['mean_sigma']:.3f} "
                     f"| {p['cov']:.2%} | {m['cov']:.2%} | {inside} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m armguard.uncertainty.examples")
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plot", help="also write a PNG of the Fig. 1 chain's samples and ellipses")
    args = ap.parse_args(argv)
    if args.samples < 2:  # a usage error (exit 2), not a traceback from the Monte Carlo
        ap.error(f"--samples: expected an integer >= 2, got {args.samples}")
    print(agreement_table(args.samples, args.seed))
    if args.plot:
        from .plot import plot_monte_carlo

        chain = figure1_chain()
        prefixes = [UncertainPose2.chain(*chain[: i + 1]) for i in range(len(chain))]
        mc = monte_carlo_chain(chain, args.samples, np.random.default_rng(args.seed))
        print(plot_monte_carlo(args.plot, mc.samples, prefixes[-1], chain=prefixes[:-1],
                               title="Fig. 1 chain: samples and linearised ellipses"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
