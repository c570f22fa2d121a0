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

    def piece_peak_joint_speeds(self):
        """``(pieces, n_joints)``: each piece's peak ``|q̇|`` per joint, exact for a :class:`Trajectory`'s
        trapezoid time law (its path speed is piecewise linear in time: the peak over a piece is at one of
        its ends, or the plateau where the piece meets it), else None.  Sampling inside the pieces missed
        an accelerating piece's peak at its end (2.9 % low in 2 pieces of a triangle profile, enough for a
        speed step of Hermes's stopping-distance table to be skipped)."""
        from ..kinematics import Trajectory
        from ..kinematics._profile import path_ds

        t = self._t
        if type(t).velocity is not Trajectory.velocity:
            return None
        times = np.asarray(t.times, dtype=np.float64)
        T, tb = np.diff(times), np.asarray(t.blend_times, dtype=np.float64)
        W = np.asarray(t.waypoints, dtype=np.float64)
        u = np.arange(self.n + 1) / self.n
        out = []
        for k in range(len(T)):
            a, b = u[:-1] * T[k], u[1:] * T[k]
            ds = np.maximum(path_ds(a, T[k], tb[k]), path_ds(b, T[k], tb[k]))
            plateau = (b >= tb[k]) & (a <= T[k] - tb[k])  # the piece meets the constant-speed part
            ds = np.where(plateau, path_ds(np.full_like(a, 0.5 * T[k]), T[k], tb[k]), ds)
            out.append(ds[:, None] * np.abs(W[k + 1] - W[k])[None, :])
        return np.concatenate(out, axis=0)

    def segments(self):
        for t0, t1, _q0, _q1 in self._t.segments():
            ts = np.linspace(float(t0), float(t1), self.n + 1)
            qs = np.asarray(self._t.at(ts), dtype=np.float64)
            for k in range(self.n):
                yield ts[k], ts[k + 1], qs[k], qs[k + 1]
