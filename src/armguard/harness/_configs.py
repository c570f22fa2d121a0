"""The configurations every backend answers: seeded random in-limit ones plus trajectory samples."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .._errors import ArmguardError
from .._values import number, whole_number

__all__ = ["ConfigSet", "build_configs", "trajectory_q"]


@dataclass(frozen=True)
class ConfigSet:
    """Configurations in ``pin_model``'s order.

    Q : (M, nq) float64, rad or m
    source : (M,) object — ``"random"`` or ``"<trajectory>@<t>s"``
    seed : int — of the random ones (``model.random_q(n_random, seed)``)
    n_random : int
    trajectories : dict[str, int] — samples per trajectory, in order after the random ones
    rows : (M,) int64 or None — each configuration's number in the set drawn (None: ``0..M-1``; fewer
        after the configurations a backend refused were dropped, :meth:`dropping`)
    """

    Q: np.ndarray
    source: np.ndarray
    seed: int
    n_random: int
    trajectories: dict
    rows: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.Q.shape[0])

    def number(self, i: int) -> int:
        """Configuration ``i``'s number in the set drawn (what ``config`` in a report says)."""
        return int(i) if self.rows is None else int(self.rows[i])

    def dropping(self, numbers) -> "ConfigSet":
        """This set without the configurations numbered ``numbers`` (in the set drawn)."""
        rows = np.arange(len(self)) if self.rows is None else self.rows
        keep = ~np.isin(rows, np.asarray(list(numbers), dtype=np.int64))
        return replace(self, Q=self.Q[keep], source=self.source[keep], rows=rows[keep])


def trajectory_q(model, trajectory, frequency: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t (M,) s, Q (M, nq))``: ``trajectory`` sampled at ``frequency`` (Hz), the other robots at home."""
    scene = model.scene
    t, q = trajectory.sample(frequency=frequency)
    flat = np.tile(scene.flat_q(scene.default_q()), (len(t), 1))
    index = {n: k for k, n in enumerate(scene.joint_names)}
    for j, jn in enumerate(trajectory.joint_names):
        key = f"{trajectory.robot_name}/{jn}"
        if key not in index:
            raise ArmguardError(f"trajectory joint {key!r} is not a joint of model {model.name!r}")
        flat[:, index[key]] = q[:, j]
    return t, model.pin_q(flat)


def build_configs(model, n_random: int, seed: int = 0, trajectories="all", frequency: float = 1.0) -> ConfigSet:
    """``n_random`` seeded random in-limit configurations, then the samples of ``trajectories``.

    ``trajectories``: ``"all"`` (every canned trajectory of the model), ``None``/``"none"``, a
    name, or a sequence of names; each is sampled at ``frequency`` Hz.
    """
    n_random = whole_number(n_random, "n_random", ArmguardError)
    seed = whole_number(seed, "seed", ArmguardError)
    names = _names(model, trajectories)
    if names:  # 0 Hz divided by zero; NaN was refused deep inside, as the trajectory's time step
        frequency = number(frequency, "frequency", ArmguardError, low=0.0, low_open=True, unit=" (Hz)")
    Qs = [model.random_q(n_random, seed)]
    src = ["random"] * n_random
    counts = {}
    for name in names:
        t, Q = trajectory_q(model, model.scene.trajectories[name], frequency)
        Qs.append(Q)
        src.extend(f"{name}@{ti:.3f}s" for ti in t)
        counts[name] = len(t)
    return ConfigSet(np.ascontiguousarray(np.concatenate(Qs)), np.asarray(src, dtype=object), int(seed), int(n_random), counts)


def _names(model, trajectories) -> list:
    known = list(model.scene.trajectories)
    if trajectories is None or trajectories == "none":
        return []
    if trajectories == "all":
        return known
    names = [trajectories] if isinstance(trajectories, str) else list(dict.fromkeys(trajectories))  # each sampled once
    for n in names:
        if n not in known:
            raise ArmguardError(f"trajectory {n!r}: model {model.name!r} has {known or 'no canned trajectories'} (or 'all')")
    return names
