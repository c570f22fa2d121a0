"""Trajectories seen in finer pieces: a stopping distance looked up per piece, not per segment."""

from __future__ import annotations

import numpy as np

__all__ = ["Subdivided"]


class Subdivided:
    """A trajectory seen as ``n`` pieces per segment (the same path and time law, finer intervals)."""

    def __init__(self, trajectory, n: int = 8) -> None:
        if int(n) != n or n < 1:
            from .._errors import VerificationError

            raise VerificationError(f"Subdivided: expected an integer number of pieces >= 1, got {n!r}")
        self._t = trajectory
        self.n = int(n)
        self.robot_name = trajectory.robot_name
        self.joint_names = trajectory.joint_names
        self.duration = trajectory.duration
        self.name = getattr(trajectory, "name", None)

    def at(self, t):
        return self._t.at(t)

    def velocity(self, t):
        return self._t.velocity(t)

    def sample(self, *args, **kwargs):
        return self._t.sample(*args, **kwargs)

    def segments(self):
        for t0, t1, _q0, _q1 in self._t.segments():
            ts = np.linspace(float(t0), float(t1), self.n + 1)
            qs = np.asarray(self._t.at(ts), dtype=np.float64)
            for k in range(self.n):
                yield ts[k], ts[k + 1], qs[k], qs[k + 1]
