"""WORKMATE's emulation time line (Smith 1986, seed ``004`` section 4 "Emulation").

"The time increment is under control of the user ... time can be speeded up, slowed down, or
stopped at any arbitrary point in the simulation" and, as the paper foresaw, run backwards.
A :class:`Timeline` is the clock only: a time ``t`` in ``[0, duration]`` s, a signed ``rate``
(simulated seconds per wall-clock second; negative plays backwards) and a playing flag.  The
console samples the trajectory at ``t`` after each :meth:`advance`.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

from ._parse import ConsoleInputError, parse_number

__all__ = ["Timeline", "TimelineState", "RATE_STEP", "MIN_RATE", "MAX_RATE"]

RATE_STEP = 2.0
"""``faster`` multiplies and ``slower`` divides the speed by this factor."""
MIN_RATE = 1.0 / 16.0
"""Slowest speed offered (|rate|): 1/16 real time."""
MAX_RATE = 16.0
"""Fastest speed offered (|rate|): 16x real time."""


@dataclass(frozen=True)
class TimelineState:
    """A snapshot of a :class:`Timeline`: ``t`` s, ``duration`` s, signed ``rate``, ``playing``."""

    t: float
    duration: float
    rate: float
    playing: bool

    @property
    def direction(self) -> str:
        """``"forward"`` or ``"backward"``."""
        return "forward" if self.rate >= 0.0 else "backward"


class Timeline:
    """A play / pause / faster / slower / backwards / scrub clock over ``[0, duration]`` s.

    Thread-safe: the console's player thread calls :meth:`advance` while GUI callbacks call the
    other methods.  Reaching either end stops playback there (the end is shown, not skipped).
    """

    def __init__(self, duration: float, *, rate: float = 1.0) -> None:
        d = parse_number(duration, "timeline duration", lo=0.0, unit="s")
        r = parse_number(rate, "timeline rate", lo=-MAX_RATE, hi=MAX_RATE)
        if abs(r) < MIN_RATE:
            raise ConsoleInputError(f"timeline rate: |rate| must be at least {MIN_RATE:g}, got {r:g}")
        self._lock = threading.Lock()
        self._duration = d
        self._t = 0.0
        self._rate = r
        self._playing = False

    # -- reading -------------------------------------------------------------------------
    @property
    def state(self) -> TimelineState:
        with self._lock:
            return TimelineState(self._t, self._duration, self._rate, self._playing)

    @property
    def t(self) -> float:
        """Current time (s)."""
        return self.state.t

    @property
    def duration(self) -> float:
        """Length of the time line (s)."""
        return self._duration

    @property
    def rate(self) -> float:
        """Signed speed: simulated s per wall-clock s (negative: backwards)."""
        return self.state.rate

    @property
    def playing(self) -> bool:
        return self.state.playing

    # -- commands ------------------------------------------------------------------------
    def play(self) -> None:
        """Start playing in the current direction; from an end, restart from the other end."""
        with self._lock:
            if self._rate > 0.0 and self._t >= self._duration:
                self._t = 0.0
            elif self._rate < 0.0 and self._t <= 0.0:
                self._t = self._duration
            self._playing = self._duration > 0.0

    def pause(self) -> None:
        with self._lock:
            self._playing = False

    def toggle(self) -> None:
        """Play if paused, pause if playing."""
        if self.playing:
            self.pause()
        else:
            self.play()

    def faster(self) -> float:
        """Multiply the speed by :data:`RATE_STEP` (at most :data:`MAX_RATE`); returns the new rate."""
        with self._lock:
            self._rate = math.copysign(min(MAX_RATE, abs(self._rate) * RATE_STEP), self._rate)
            return self._rate

    def slower(self) -> float:
        """Divide the speed by :data:`RATE_STEP` (at least :data:`MIN_RATE`); returns the new rate."""
        with self._lock:
            self._rate = math.copysign(max(MIN_RATE, abs(self._rate) / RATE_STEP), self._rate)
            return self._rate

    def reverse(self) -> float:
        """Flip the direction of play (backwards <-> forwards); returns the new rate."""
        with self._lock:
            self._rate = -self._rate
            return self._rate

    def set_direction(self, forward: bool) -> None:
        with self._lock:
            self._rate = abs(self._rate) if forward else -abs(self._rate)

    def seek(self, t) -> float:
        """Scrub to time ``t`` (s, a number or its text), clamped to ``[0, duration]``; returns it.

        A non-number or non-finite ``t`` raises ConsoleInputError and leaves the time unchanged.
        """
        x = parse_number(t, "time", unit="s")
        with self._lock:
            self._t = min(max(x, 0.0), self._duration)
            return self._t

    def seek_fraction(self, fraction) -> float:
        """Scrub to ``fraction`` (0..1) of the duration; returns the new time (s)."""
        f = parse_number(fraction, "time line position", lo=0.0, hi=1.0)
        with self._lock:
            self._t = f * self._duration
            return self._t

    def advance(self, dt_wall: float) -> float:
        """Move the clock by ``rate * dt_wall`` if playing (``dt_wall`` s >= 0); returns ``t``.

        Stops at ``0`` or ``duration``.
        """
        dt = parse_number(dt_wall, "wall-clock step", lo=0.0, unit="s")
        with self._lock:
            if self._playing:
                t = self._t + self._rate * dt
                if t >= self._duration:
                    t, self._playing = self._duration, False
                elif t <= 0.0:
                    t, self._playing = 0.0, False
                self._t = t
            return self._t
