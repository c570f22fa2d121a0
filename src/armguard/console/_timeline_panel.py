"""The console's *Time line* tab on viser: what is loaded, the trajectory to verify, play, the plot.

The tab shows only what is on the time line now (the state's player): with nothing loaded the
time slider is disabled at 0 and a line says so (the play buttons, which viser cannot disable,
answer that nothing is loaded) (a stopped canned run left
the slider where it stopped, with no plot or report); the slider's end is the loaded motion's
duration rounded to :data:`SLIDER_STEP` (an unrounded ``18.346304`` was its label), and dragged
there it goes to the very end. The *trajectory* dropdown names what is loaded: the scene's
trajectory verified, or an entry for a program run from the Tasks tab (:func:`program_entry`),
which "verify and load" does not verify again. :func:`timeline_view` decides all of it from the
player alone; :class:`TimelinePanel` puts it on the widgets.
"""

from __future__ import annotations

import html
from dataclasses import dataclass

import numpy as np

from ._parse import ConsoleInputError
from ._plot import ClearancePlot, MarkerFeed

__all__ = ["TimelinePanel", "TimelineView", "timeline_view", "slider_end", "slider_time", "program_entry",
           "SLIDER_STEP", "NOTHING_LOADED"]

SLIDER_STEP = 0.01
"""Step of the time slider and rounding of its end label (s)."""

NOTHING_LOADED = "nothing loaded: verify and load a trajectory, run a canned test (Tests) or a program (Tasks)"
"""The tab's line with nothing on the time line."""


def slider_end(duration: float) -> float:
    """The slider's maximum for a motion of ``duration`` s: rounded to :data:`SLIDER_STEP`, at least one step."""
    return max(SLIDER_STEP, round(round(float(duration) / SLIDER_STEP) * SLIDER_STEP, 2))


def slider_time(value: float, duration: float) -> float:
    """The time (s) a slider position ``value`` asks for: the slider's end (rounded) is the motion's end."""
    v = float(value)
    return float(duration) if v >= slider_end(duration) - 1e-9 else v


def program_entry(name: str) -> str:
    """The dropdown's entry for a program run from the Tasks tab (not a scene trajectory)."""
    return f"program {name} (run from Tasks)"


@dataclass(frozen=True)
class TimelineView:
    """What the tab shows: ``loaded`` (its line), the slider's ``end`` and ``value`` (s), whether the
    slider is ``enabled``, the dropdown's ``options`` and ``selected`` entry
    (None: keep the operator's choice)."""

    loaded: str
    end: float
    value: float
    enabled: bool
    options: tuple
    selected: str | None


def timeline_view(player, trajectories) -> TimelineView:
    """The :class:`TimelineView` of the state's ``player`` (None: nothing loaded) with the scene's
    ``trajectories`` (names)."""
    trajs = tuple(trajectories) or ("(none)",)
    if player is None:
        return TimelineView(NOTHING_LOADED, 1.0, 0.0, False, trajs, None)
    tl = player.timeline
    end = slider_end(tl.duration)
    t = tl.t
    value = end if t >= tl.duration else float(min(t, end))  # at the motion's end: at the slider's
    what = {"run": "canned test", "avoid": "canned test (with avoidance)"}.get(player.kind)
    if what is not None:
        return TimelineView(f"loaded: {what} {player.name} (run from Tests)", end, value, True, trajs, None)
    if player.name in trajectories:
        return TimelineView(f"loaded: trajectory {player.name}, verified", end, value, True, trajs, player.name)
    entry = program_entry(player.name)
    return TimelineView(f"loaded: {entry}", end, value, True, (entry,) + trajs, entry)


class TimelinePanel:
    """The Time line tab of a :class:`~._app.ConsoleApp` (built inside the tab; module docstring)."""

    def __init__(self, app) -> None:
        gui, st = app.server.gui, app.state
        self.app = app
        trajs = st.trajectories()
        self.w_loaded = gui.add_markdown(self._loaded_md(NOTHING_LOADED))
        self.w_traj = gui.add_dropdown("trajectory", trajs or ("(none)",))
        self.b_load = gui.add_button("verify and load", disabled=not trajs)
        self.w_transport = gui.add_button_group("play", ("◀ back", "pause", "play ▶", "slower", "faster"))
        self.w_time = gui.add_slider("time (s)", min=0.0, max=1.0, step=SLIDER_STEP, initial_value=0.0,
                                     disabled=True)
        self.w_rate = gui.add_markdown("")
        self.w_plot = gui.add_image(np.full((20, 40, 3), 255, dtype=np.uint8), format="png", visible=False)
        self.w_report = gui.add_html("")
        app._avoid.build_timeline()
        self._plot: ClearancePlot | None = None
        self._plot_player = None
        self._plot_threshold = None
        self._feed = MarkerFeed()
        self._shown_player = False  # no player shown yet (None is a player state: nothing loaded)
        self.w_time.on_update(app._from_client(self._seek))
        self.w_transport.on_click(app._from_client(self._transport))
        self.w_traj.on_update(lambda e: self._choice_changed())
        self.b_load.on_click(app._guard(lambda _e: self.load()))

    @staticmethod
    def _loaded_md(text: str) -> str:
        return f"*{html.escape(text)}*"

    # ------------------------------------------------------------------ commands
    def load(self):
        """"verify and load" with the dropdown's entry: a scene trajectory verified and put on the time line."""
        name = str(self.w_traj.value)
        if name not in self.app.state.trajectories():
            raise ConsoleInputError(f"verify and load: {name!r} is already on the time line, not a trajectory of "
                                    "the scene to verify; pick one of the scene's trajectories")
        return self.app.state.load_trajectory(name)

    def _seek(self, value) -> None:
        p = self.app.state.snapshot().player
        self.app.state.timeline_command("seek", value if p is None else slider_time(value, p.timeline.duration))

    def _transport(self, label: str) -> None:
        cmd = {"◀ back": "backward", "pause": "pause", "play ▶": "forward", "slower": "slower", "faster": "faster"}[label]
        self.app.state.timeline_command(cmd)
        if cmd in ("backward", "forward"):
            self.app.state.timeline_command("play")

    def _choice_changed(self) -> None:
        trajs = self.app.state.trajectories()
        self.b_load.disabled = str(self.w_traj.value) not in trajs

    # ------------------------------------------------------------------ showing
    def model_reloaded(self) -> None:
        """After a model reload: the dropdown offers the new model's trajectories."""
        self._shown_player = False
        self.sync(self.app.state.snapshot())

    def sync(self, snap) -> None:
        """The line, the dropdown (when the player changed) and the slider, from the snapshot."""
        p = snap.player
        view = timeline_view(p, self.app.state.trajectories())
        if self.w_loaded.content != self._loaded_md(view.loaded):
            self.w_loaded.content = self._loaded_md(view.loaded)
        if self._shown_player is False or p is not self._shown_player:  # a new player: the dropdown says what
            self._shown_player = p
            keep = str(self.w_traj.value)
            self.w_traj.options = view.options
            self.w_traj.value = view.selected or (keep if keep in view.options else view.options[0])
            self._choice_changed()
        if self.w_time.disabled == view.enabled:  # (viser's button groups cannot be disabled: they say why)
            self.w_time.disabled = not view.enabled
        if self.w_time.max != view.end:
            self.w_time.max = view.end
        if abs(self.w_time.value - view.value) > 1e-9:
            self.w_time.value = view.value

    def refresh(self, snap) -> None:
        """The clearance plot, its caption and the report of a verified motion; cleared otherwise."""
        p = snap.player
        if p is None or p.kind != "verified":
            if self._plot_player is not None:
                self.w_plot.visible = False
                self.w_report.content = ""
                self._plot_player = None
            if (p is None or p.kind == "run") and self.w_rate.content:  # no stale caption of what was loaded
                self.w_rate.content = ""
                self._feed.reset()
            return
        if p is not self._plot_player or snap.threshold != self._plot_threshold:  # the dashed line: the threshold now
            from ._app import report_html

            rep = p.report
            fc = getattr(rep, "first_collision", None)
            self._plot = ClearancePlot(p.times, p.clearance, threshold=snap.threshold,
                                       first_collision=None if fc is None else float(fc.time))
            self._plot_player, self._plot_threshold = p, snap.threshold
            summary = rep.summary() if hasattr(rep, "summary") else str(rep)
            self.w_report.content = report_html(summary)
            self.w_plot.visible = True
            self._feed.reset()
        tl = p.timeline.state
        state = "playing" if tl.playing else "paused"
        caption = f"t = {tl.t:.2f} / {tl.duration:.2f} s · {state} {tl.direction} · speed ×{abs(tl.rate):g}"
        self._feed.push(self._plot, tl.t, tl.playing, caption, self.w_plot, self.w_rate)
