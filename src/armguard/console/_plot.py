"""The clearance plot under the time line: minimum distance along a trajectory, the current time marked.

Rendered once with matplotlib (Agg) into an RGB array; :meth:`ClearancePlot.image_at` then draws
the current-time marker by writing one pixel column band into a copy, so the marker can follow
the play head at the display rate without re-rendering the figure.
"""

from __future__ import annotations

import math
import time

import numpy as np

__all__ = ["ClearancePlot", "MarkerFeed", "MARKER_RGB", "PLOT_PERIOD", "Y_MARGIN", "clearance_ylim"]

PLOT_PERIOD = 0.2
"""Least time (s) between two marker images sent while the time line plays (at most 5 a second)."""

MARKER_RGB = (30, 90, 220)
"""Colour of the current-time marker (RGB 0..255)."""


class MarkedPlot:
    """A rendered time plot (``_base``, ``(H, W, 3) uint8``) whose axes span pixel columns
    ``_x0``..``_x1`` and rows ``_y0``..``_y1`` for times ``t0``..``t1``; a marker shows the time now."""

    t0: float
    t1: float
    _base: np.ndarray
    _x0: float
    _x1: float
    _y0: int
    _y1: int

    @property
    def shape(self) -> tuple[int, int, int]:
        return self._base.shape

    def column_of(self, t: float) -> int:
        """Pixel column of time ``t`` (s), clamped to the axes."""
        f = (min(max(float(t), self.t0), self.t1) - self.t0) / (self.t1 - self.t0)
        return int(round(self._x0 + f * (self._x1 - self._x0)))

    def image_at(self, t: float) -> np.ndarray:
        """The plot with a 2-pixel vertical marker at time ``t`` (s) through the axes: ``(H, W, 3) uint8``."""
        img = self._base.copy()
        x = self.column_of(t)
        img[self._y0 : self._y1, max(0, x - 1) : min(img.shape[1], x + 1)] = MARKER_RGB
        return img


class MarkerFeed:
    """What of a marked plot goes to the browser, and when.

    Each image is a PNG of tens of kB that the browser decodes; sent on every frame (30 a second)
    it kept a loaded machine's browser behind the run. While the time line plays, the feed sends
    at most one image every ``period`` s, and only when the marker has moved a pixel column. When
    the time line is paused or stopped, the feed sends at once, so the last image shows where the
    run stopped. The caption goes out only when its text changes.
    """

    def __init__(self, period: float = PLOT_PERIOD) -> None:
        self.period = float(period)
        self.reset()

    def reset(self) -> None:
        """A new plot: its first image and caption go out on the next :meth:`push`."""
        self._sent_at = -math.inf
        self._column: int | None = None
        self._caption: str | None = None

    def push(self, plot: MarkedPlot, t: float, playing: bool, caption: str, image_widget, caption_widget) -> bool:
        """Send ``plot`` marked at ``t`` (s) to ``image_widget.image`` and ``caption`` to
        ``caption_widget.content`` if due (see the class docstring); returns whether anything was sent."""
        now = time.perf_counter()
        if playing and now - self._sent_at < self.period:
            return False
        self._sent_at = now
        sent = False
        column = plot.column_of(t)
        if column != self._column:
            image_widget.image = plot.image_at(t)
            self._column, sent = column, True
        if caption != self._caption:
            caption_widget.content = caption
            self._caption, sent = caption, True
        return sent


Y_MARGIN = 0.12
"""Room above and below the clearance plot's lines, as a fraction of the span they cover (a constant
clearance sat on the axes' top edge)."""


def clearance_ylim(shown_mm, threshold_mm: float) -> tuple[float, float]:
    """The clearance plot's y range (mm): the clearance ``shown_mm`` (NaN where unknown), the threshold
    and the zero line, with :data:`Y_MARGIN` of their span (at least 1 mm) above and below."""
    v = np.asarray(shown_mm, dtype=np.float64)
    v = v[np.isfinite(v)]
    lo = min(0.0, float(threshold_mm), float(v.min()) if len(v) else 0.0)
    hi = max(0.0, float(threshold_mm), float(v.max()) if len(v) else 0.0)
    pad = Y_MARGIN * max(hi - lo, 1.0)
    return lo - pad, hi + pad


class ClearancePlot(MarkedPlot):
    """Clearance ``clearance`` (N,) m against ``times`` (N,) s, the threshold dashed, collisions shaded.

    ``first_collision`` (s) or None is marked with a red dot.  ``image_at(t)`` -> (H, W, 3) uint8.
    """

    def __init__(self, times, clearance, *, threshold: float, first_collision: float | None = None,
                 width_px: int = 480, height_px: int = 200) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        t = np.asarray(times, dtype=np.float64)
        c = np.asarray(clearance, dtype=np.float64)
        self.t0 = float(t[0])
        self.t1 = float(t[-1]) if t[-1] > t[0] else float(t[0]) + 1.0
        dpi = 100
        fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
        canvas = FigureCanvasAgg(fig)
        ax = fig.add_axes((0.12, 0.22, 0.85, 0.7))
        shown = np.where(np.isfinite(c), c, np.nan) * 1000.0
        ax.plot(t, shown, color="#2e9e44", lw=1.5)
        ax.axhline(threshold * 1000.0, color="#f2a000", ls="--", lw=1)
        ax.axhline(0.0, color="#d62828", lw=1)
        bad = c <= 0.0
        if np.any(bad):
            ax.fill_between(t, 0, 1, where=bad, color="#d62828", alpha=0.25, transform=ax.get_xaxis_transform())
        if first_collision is not None and math.isfinite(first_collision):
            ax.plot([first_collision], [0.0], "o", color="#d62828")
        ax.set_xlim(self.t0, self.t1)
        ax.set_ylim(*clearance_ylim(shown, threshold * 1000.0))
        ax.set_xlabel("t (s)", fontsize=8)
        ax.set_ylabel("clearance (mm)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, alpha=0.3)
        canvas.draw()
        self._base = np.asarray(canvas.buffer_rgba())[:, :, :3].copy()
        H = self._base.shape[0]
        bbox = ax.get_window_extent()  # display pixels, origin bottom-left
        self._x0, self._x1 = float(bbox.x0), float(bbox.x1)
        self._y0 = int(round(H - bbox.y1))
        self._y1 = int(round(H - bbox.y0))

