"""Plot Monte Carlo samples with the linearised confidence ellipses (the paper's Figs. 1 and 3)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from .._errors import UncertaintyError
from .pose2 import UncertainPose2

__all__ = ["plot_monte_carlo"]


def plot_monte_carlo(path, samples, estimate: UncertainPose2, *, confidences: Sequence[float] = (0.5, 0.9),
                     chain: Sequence[UncertainPose2] = (), max_points: int = 20_000,
                     title: str | None = None, rng: np.random.Generator | None = None) -> Path:
    """Write a PNG of sampled positions and the linearised confidence ellipses.

    Parameters
    ----------
    path : str or Path — the PNG to write (parent folders are created).
    samples : (n, >= 2) float64, m — sampled positions (x, y first), e.g.
        ``monte_carlo_chain(...).samples``.
    estimate : UncertainPose2 — the linearised estimate; its ellipses are drawn solid, with
        the share of samples inside each in the legend.
    confidences : probabilities of the ellipses to draw (Appendix A's k²).
    chain : the intermediate relations with respect to the first frame (Fig. 1's solid
        ellipses), drawn dashed at the largest confidence with their means joined.
    max_points : at most this many samples are scattered (a random subset, drawn with ``rng``).
    title : str, optional
    rng : numpy.random.Generator, optional — for the subset (default seed 0).

    Returns
    -------
    Path — the written file.
    """
    s = np.asarray(samples, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] < 2 or s.shape[0] < 1 or not np.all(np.isfinite(s[:, :2])):
        raise UncertaintyError(f"samples: expected a finite (n, >= 2) array, got shape {s.shape}")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rng = rng if rng is not None else np.random.default_rng(0)
    shown = s if s.shape[0] <= max_points else s[rng.choice(s.shape[0], max_points, replace=False)]
    fig = Figure(figsize=(6.4, 6.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.scatter(shown[:, 0], shown[:, 1], s=1.0, alpha=0.25, color="tab:blue", label=f"{s.shape[0]} samples")
    colors = ("tab:red", "tab:orange", "tab:green", "tab:purple")
    for i, p in enumerate(confidences):
        e = estimate.ellipse(p)
        pts = e.points(256)
        inside = float(np.mean(e.contains(s[:, :2])))
        ax.plot(*np.vstack((pts, pts[:1])).T, color=colors[i % len(colors)], lw=1.5,
                label=f"{p:.0%} ellipse (k² = {e.k2:.3f}): {inside:.1%} of samples inside")
    if chain:
        means = np.array([[0.0, 0.0]] + [c.mean[:2] for c in chain] + [estimate.mean[:2]])
        ax.plot(means[:, 0], means[:, 1], "k.-", lw=0.8, label="chain means")
        for c in chain:
            pts = c.ellipse(max(confidences)).points(128)
            ax.plot(*np.vstack((pts, pts[:1])).T, "k--", lw=0.6)
    ax.plot(*estimate.mean[:2], "k+", ms=12)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize=7)
    from .._io import save_figure

    return save_figure(fig, Path(path), parents=True)  # whole or not at all, in the format of its suffix
