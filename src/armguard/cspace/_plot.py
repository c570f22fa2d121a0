"""A joint-1 × joint-3 slice of a map as an image (matplotlib, Agg)."""

from __future__ import annotations

import math

import numpy as np

from .._errors import ForbiddenMapError
from .._io import figure_format, save_figure

__all__ = ["plot_slice"]


def plot_slice(fmap, q2: float, out, *, q=None, dpi: int = 120) -> None:
    """Write a plot of the cells at joint 2 = ``q2`` (rad): joint 1 across, joint 3 up, forbidden bins red
    (a PNG, or the format ``out``'s suffix names: ``armguard._io.figure_format``).

    ``q``: a configuration ``(3,)`` rad (joints 1–3) to mark, or None; finite, with its joint 2 in the
    slice's cell (a marker on another slice would show that slice's verdict where it does not hold).
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure  # no pyplot: the caller's backend and figures are left alone

    figure_format(out)
    g = fmap.grid
    cell = g.cell_of([g.lower[0], q2, g.lower[2]])
    if cell is None:
        d = math.degrees  # the command line's unit beside the library's
        raise ForbiddenMapError(f"q2 = {q2:.10g} rad ({d(q2):.10g} deg) is outside joint 2's limits [{g.lower[1]:.10g}, "
                                f"{g.upper[1]:.10g}] rad ([{d(g.lower[1]):.10g}, {d(g.upper[1]):.10g}] deg)")
    i2 = cell[1]
    lo2 = g.lower[1] + i2 * g.step[1]
    hi2 = min(lo2 + g.step[1], g.upper[1])
    if q is not None:
        q = np.asarray(q, dtype=np.float64).reshape(-1)
        if q.shape != (3,) or not np.all(np.isfinite(q)):
            raise ForbiddenMapError(f"q: expected 3 finite joint values (rad), got {q.tolist()}")
        for k in (0, 2):  # the marker on a configuration the map has no bin for would read as its verdict
            if not g.lower[k] - 1e-12 <= q[k] <= g.upper[k] + 1e-12:
                raise ForbiddenMapError(f"q: its joint {k + 1} ({math.degrees(q[k]):.10g}°) is outside the map's limits "
                                        f"[{math.degrees(g.lower[k]):.10g}°, {math.degrees(g.upper[k]):.10g}°]")
        if not lo2 - 1e-12 <= q[1] <= hi2 + 1e-12:
            raise ForbiddenMapError(f"q: its joint 2 ({math.degrees(q[1]):.10g}°) is not in the slice's cell "
                                    f"[{math.degrees(lo2):.10g}°, {math.degrees(hi2):.10g}°] at q2: plot the slice at its joint 2")
    img = np.zeros((int(g.counts[2]), int(g.counts[0])), dtype=np.int8)
    for k1 in range(int(g.n_sub[0])):
        s = k1 * int(g.n_sub[1]) + i2 // int(g.per_sub[1])
        i1a, i1b, i2a, _ = g.sub_cells(s)
        img[:, i1a:i1b] = fmap.substructure_mask(s)[:, i2 - i2a, :].T
    deg = math.degrees
    x1 = min(g.lower[0] + g.counts[0] * g.step[0], g.upper[0])
    x3 = min(g.lower[2] + g.counts[2] * g.step[2], g.upper[2])
    fig = Figure(figsize=(8, 5))
    ax = fig.subplots()
    ax.imshow(img, origin="lower", aspect="auto", interpolation="nearest", cmap=ListedColormap(["#f4f4f4", "#d62728"]),
              vmin=0, vmax=1, extent=(deg(g.lower[0]), deg(x1), deg(g.lower[2]), deg(x3)))
    if q is not None:
        ok = fmap.allowed(q)
        ax.plot([deg(q[0])], [deg(q[2])], marker="x" if not ok else "o", color="k", markersize=9, mew=2,
                label=f"q ({'allowed' if ok else 'forbidden'})")
        ax.legend(loc="upper right")
    ax.set_xlabel(f"{fmap.joints[0]} (deg)")
    ax.set_ylabel(f"{fmap.joints[2]} (deg)")
    ax.set_title(f"forbidden (red): {fmap.robot} links {', '.join(fmap.links)}; {fmap.joints[1]} in "
                 f"[{deg(lo2):.3g}°, {deg(hi2):.3g}°], stopping distance "
                 f"{fmap.stopping_distance} m", fontsize=9)
    fig.tight_layout()
    save_figure(fig, out, dpi=dpi, parents=True)  # a missing folder made, as every plot's
