"""The console's avoidance widgets: on/off and the stand-off in the Control tab, and on the time line
a plot of the commanded against the filtered motion of a canned run with avoidance on.

Bound to :class:`~._avoid.AvoidMixin`'s commands through the app's own guarded helpers, so a bad
stand-off is refused as every typed field is (the message in the panel, the state unchanged, the
box put back).
"""

from __future__ import annotations

import math

import numpy as np

from ._avoid import MAX_STAND_OFF
from ._plot import MarkedPlot, MarkerFeed

__all__ = ["AvoidPanel", "AvoidPlot"]

_JOINT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                  "#bcbd22", "#17becf")


def _fmt(x: float) -> str:
    x = float(x)
    return f"{0.0 if x == 0.0 else x:.6g}"


class AvoidPlot(MarkedPlot):
    """A canned run with avoidance (an :class:`~._avoid.AvoidedRun`) against time: above, the least
    distance (mm) of the commanded motion (dashed) and of the filtered one (solid) with the
    stand-off; below, each joint commanded (dashed) and filtered (solid), deg for revolute joints
    (``units``) and m for prismatic ones.  Rendered once; :meth:`image_at` marks the time ``t``."""

    def __init__(self, run, units, *, width_px: int = 480, height_px: int = 360) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        t = np.asarray(run.times, dtype=np.float64)
        self.t0, self.t1 = float(t[0]), float(t[-1]) if t[-1] > t[0] else float(t[0]) + 1.0
        dpi = 100
        fig = Figure(figsize=(width_px / dpi, height_px / dpi), dpi=dpi)
        canvas = FigureCanvasAgg(fig)
        ax_d = fig.add_axes((0.13, 0.58, 0.84, 0.36))
        ax_q = fig.add_axes((0.13, 0.12, 0.84, 0.36), sharex=ax_d)
        ax_d.plot(t, np.asarray(run.distance_cmd) * 1000.0, color="#666666", ls="--", lw=1.2, label="commanded")
        ax_d.plot(t, np.asarray(run.distance) * 1000.0, color="#2e9e44", lw=1.5, label="filtered")
        ax_d.axhline(run.stand_off * 1000.0, color="#f2a000", ls=":", lw=1.2, label="stand-off")
        ax_d.axhline(0.0, color="#d62828", lw=1)
        ax_d.set_ylabel("least d (mm)", fontsize=8)
        ax_d.legend(fontsize=6, loc="best", framealpha=0.7)
        scale = np.array([180.0 / math.pi if u == "deg" else 1.0 for u in units])
        for j in range(run.q.shape[1]):
            c = _JOINT_COLOURS[j % len(_JOINT_COLOURS)]
            ax_q.plot(t, run.q_cmd[:, j] * scale[j], color=c, ls="--", lw=0.9)
            ax_q.plot(t, run.q[:, j] * scale[j], color=c, lw=1.3)
        ax_q.set_ylabel("joints (deg, m)" if "m" in units else "joints (deg)", fontsize=8)
        ax_q.set_xlabel("t (s)   dashed: commanded, solid: filtered", fontsize=8)
        for ax in (ax_d, ax_q):
            ax.set_xlim(self.t0, self.t1)
            ax.tick_params(labelsize=7)
            ax.grid(True, alpha=0.3)
        canvas.draw()
        self._base = np.asarray(canvas.buffer_rgba())[:, :, :3].copy()
        H = self._base.shape[0]
        top, bottom = ax_d.get_window_extent(), ax_q.get_window_extent()  # display pixels, origin bottom-left
        self._x0, self._x1 = float(bottom.x0), float(bottom.x1)
        self._y0, self._y1 = int(round(H - top.y1)), int(round(H - bottom.y0))



class AvoidPanel:
    """The avoidance widgets of a :class:`~._app.ConsoleApp` (built by it; see the module docstring)."""

    def __init__(self, app) -> None:
        self.app = app
        self._plot: AvoidPlot | None = None
        self._player = None
        self._feed = MarkerFeed()

    def build_control(self, order: float) -> "AvoidPanel":
        """The "avoidance" folder (checkbox, stand-off field) at ``order`` in the current tab."""
        app, gui, st = self.app, self.app.server.gui, self.app.state
        on, stand_off = st.avoidance_settings()
        with gui.add_folder("avoidance", order=order):
            self.checkbox = gui.add_checkbox(
                "avoidance", on, hint="canned runs go through the velocity-damper filter: they slide along or "
                "stop short at the stand-off instead of stopping by detection")
            self.field = app._field("stand-off (m)", _fmt(stand_off), st.set_stand_off,
                                    f"0 to {MAX_STAND_OFF:g} m; applies on Enter or on leaving the field")
        self.checkbox.on_update(app._from_client(lambda v: st.set_avoidance(v)))
        return self

    def build_timeline(self) -> None:
        """The commanded-against-filtered plot in the current tab (hidden until a run with avoidance)."""
        self.image = self.app.server.gui.add_image(np.full((20, 40, 3), 255, dtype=np.uint8), format="png",
                                                   visible=False)

    def sync(self) -> None:
        """Show the state's settings (after a refusal, or a change from another tab)."""
        on, stand_off = self.app.state.avoidance_settings()
        if self.checkbox.value != on:
            self.checkbox.value = on
        self.field.show(_fmt(stand_off))

    def refresh(self, snap) -> None:
        """The plot of the player's run with avoidance, marked at its time; hidden for anything else."""
        p = snap.player
        if p is None or p.kind != "avoid":
            if self._player is not None:
                self.image.visible = False
                self._player = None
            return
        if p is not self._player:
            self._plot = AvoidPlot(p.report, self.app.state.joint_units(p.robot))
            self._player = p
            self.image.visible = True
            self._feed.reset()
        tl = p.timeline.state
        state = "playing" if tl.playing else "paused"
        caption = (f"t = {tl.t:.2f} / {tl.duration:.2f} s · {state} {tl.direction} · "
                   f"speed ×{abs(tl.rate):g} · with avoidance")
        self._feed.push(self._plot, tl.t, tl.playing, caption, self.image, self.app._timeline.w_rate)
