"""The time line of :class:`~._state.ConsoleState`: a canned run's or a trajectory's playback, its ticks and
the run's state (running, done, back at the start, stopped, stopped by detection), and the operator taking
an arm over from it."""

from __future__ import annotations

import numpy as np

from ._parse import ConsoleInputError

__all__ = ["PlaybackMixin"]


class PlaybackMixin:
    """Playback commands; mixed into ConsoleState (uses its lock, player, arms and checks)."""

    def _taken_over(self, robot: str) -> str:
        """The operator moved ``robot``: a run or trajectory playing on it is paused (its next tick overwrote
        the typed joints without a word); returns the note saying so, or ``""``."""
        p = self._player
        if p is None or p.robot != robot or not p.timeline.playing:
            return ""
        p.timeline.pause()
        when = f"at t = {p.timeline.t:.2f} s"
        if p.kind in ("run", "avoid") and self._run_state == "running":
            self._run_state, self._run_detail = "stopped", f"{when} ({robot} moved by hand)"
        return f"{p.name}: paused {when}: {robot} moved by hand"

    # ------------------------------------------------------------------ time line
    def _cancel_filtering(self, why: str) -> None:
        """Drop a run with avoidance still being filtered: it would play over what was done since (test7's Setup)."""
        if self._run_state == "filtering" and getattr(self, "_filtering", None) is not None:
            self._filtering, self._run_state, self._run_detail = None, "stopped", f"{why} while the motion was filtered"

    def _stop_player(self) -> None:
        self._cancel_filtering("replaced")
        p = self._player
        if p is not None:
            p.timeline.pause()
            if p.kind in ("run", "avoid") and self._run_state == "running":  # the Tests tab said running on
                self._run_state, self._run_detail = "stopped", f"at t = {p.timeline.t:.2f} s (replaced)"
        self._player = None

    def stop(self) -> None:
        """Drop the current run or trajectory (the arms stay where they are)."""
        with self._lock:
            p = self._player
            was_running = p is not None and p.kind in ("run", "avoid") and self._run_state == "running"
            self._stop_player()
            if self._run_state == "filtering":  # a run with avoidance still being filtered: it must not start
                self._filtering = None
                self._run_state, self._run_detail = "stopped", "while the motion was filtered"
                self._changed("stopped by the operator while the motion was filtered")
            elif was_running:
                self._run_state = "stopped"
                self._run_detail = f"at t = {p.timeline.t:.2f} s"
                self._changed(f"{p.name}: stopped by the operator")
            else:
                self._changed()

    def _apply_player_time(self, t: float) -> None:
        p = self._player
        q = np.asarray(p.trajectory.at(float(t)), dtype=np.float64)
        self._q[p.robot] = np.clip(q, *self.joint_limits(p.robot))

    def timeline_command(self, command: str, value=None) -> None:
        """Drive the time line: ``play``, ``pause``, ``toggle``, ``faster``, ``slower``, ``reverse``,
        ``forward``, ``backward`` or ``seek`` (``value`` in s)."""
        with self._lock:
            p = self._player
            if p is None:
                raise ConsoleInputError("time line: nothing loaded (load a trajectory or run a canned test)")
            tl = p.timeline
            simple = {"play": tl.play, "pause": tl.pause, "toggle": tl.toggle, "faster": tl.faster,
                      "slower": tl.slower, "reverse": tl.reverse,
                      "forward": lambda: tl.set_direction(True), "backward": lambda: tl.set_direction(False)}
            if command == "seek":
                tl.seek(value)
            elif command in simple:
                simple[command]()
            else:
                raise ConsoleInputError(f"time line: unknown command {command!r}; expected seek or one of {list(simple)}")
            self._apply_player_time(tl.t)
            self._changed(self._message)

    def tick(self, dt_wall: float) -> bool:
        """Advance the player by ``dt_wall`` s of wall-clock time; returns whether anything changed.

        During a canned run with detection on and a stopping distance set (> 0), a nearest
        distance within the stopping distance halts the motion (Ranger's collision avoidance with
        a stand-off distance); with no stopping distance the run plays to its end, through a
        collision if its motion makes one.
        """
        with self._lock:
            p = self._player
            if p is None or not p.timeline.playing:
                return False
            t = p.timeline.advance(dt_wall)
            self._apply_player_time(t)
            self._evaluate()
            r = self._readout
            if p.kind == "avoid":  # the filter keeps the stand-off: no stop by detection
                return self._tick_avoid(p, t)
            if p.kind != "run":
                return True
            if self._detection and self._stopping > 0.0 and r.distance <= self._stopping:
                p.timeline.pause()
                self._run_state = "stopped by detection"
                self._run_detail = (f"at t = {t:.2f} s, {r.link} within the stopping distance "
                                    f"{self._stopping * 1000:.0f} mm: {r.distance * 1000:.1f} mm of {r.obstacle}")
                self._message_is_error = True
                self._message = f"{p.name}: stopped by detection {self._run_detail}"
            elif self._back_or_again(p, t):
                pass
            elif not p.timeline.playing or t >= p.timeline.duration:
                p.timeline.pause()
                self._run_state = "done"
                self._run_detail = f"at t = {t:.2f} s"
                self._message_is_error = False
                self._message = f"{p.name}: done {self._run_detail}"
            return True

    def _back_or_again(self, p, t: float) -> bool:
        """A canned run (with avoidance or not) played backwards to its start says "back at the start" (it said
        "done", or with avoidance stayed "running" and kept the other arms from being chosen): True.  Played again
        after it ended or was halted, it says "running" again (False)."""
        if not p.timeline.playing and t <= 0.0 and p.timeline.rate < 0.0:
            self._run_state, self._run_detail = "back at the start", f"at t = {t:.2f} s"
            self._message_is_error = False
            self._message = f"{p.name}: back at the start {self._run_detail}"
            return True
        if p.timeline.playing and self._run_state != "running":
            self._run_state, self._run_detail = "running", ""
            self._message_is_error = False
            self._message = f"{p.name}: running from t = {t:.2f} s"
        return False

