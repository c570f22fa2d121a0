"""Grasp error from a wrist force/torque sensor (WORKMATE §III.C): how well weighing finds where a held
object sits, by sensor noise and number of hand orientations.

Emulated: a 1.2 kg box held 3 cm off its nominal grasp point and turned 10 degrees; the hand is
weighed at N random orientations (at rest), then turned about random axes with known accelerations (about 20 rad/s^2).
Prints the median position and orientation errors over 200 trials per cell of the table.

    .venv/bin/python examples/grasp_error.py
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from armguard.program import grasp_orientation, object_wrench, weigh

MASS = 1.2
P_NOMINAL = np.array([0.0, 0.0, 0.12])
P_TRUE = P_NOMINAL + np.array([0.02, -0.015, 0.015])  # 3 cm off
R_NOMINAL = np.eye(3)
R_TRUE = Rotation.from_rotvec(np.radians(10.0) * np.array([0.6, 0.8, 0.0])).as_matrix()
I_O = np.diag([0.004, 0.006, 0.009])  # a 1.2 kg box, about 0.24 x 0.18 x 0.10 m
B_F, B_TAU = np.array([0.3, -0.2, 0.5]), np.array([0.02, 0.01, -0.03])


def trial(rng, n: int, sigma_f: float, sigma_tau: float) -> tuple[float, float]:
    """(position error m, orientation error rad) of one emulated weighing + rotation."""
    I_C_S = R_TRUE @ I_O @ R_TRUE.T
    R = Rotation.random(n, random_state=rng).as_matrix()
    f, tau = object_wrench(R, MASS, P_TRUE, I_C_S, b_f=B_F, b_tau=B_TAU)
    f = f + rng.normal(0.0, sigma_f, f.shape)
    tau = tau + rng.normal(0.0, sigma_tau, tau.shape)
    w8 = weigh(R, f, tau, sigma_f=sigma_f, sigma_tau=sigma_tau)
    m = max(n, 6)
    R2 = Rotation.random(m, random_state=rng).as_matrix()
    w = rng.normal(0.0, 2.0, (m, 3))
    a = rng.normal(0.0, 20.0, (m, 3))  # rad/s^2: a wrist's controlled acceleration
    _, tau2 = object_wrench(R2, MASS, P_TRUE, I_C_S, w_S=w, a_S=a, b_f=B_F, b_tau=B_TAU)
    tau2 = tau2 + rng.normal(0.0, sigma_tau, tau2.shape)
    go = grasp_orientation(w8, R2, w, a, tau2, I_O, R_NOMINAL)
    ang = float(np.linalg.norm(Rotation.from_matrix(go.R_SO @ R_TRUE.T).as_rotvec()))
    return float(np.linalg.norm(w8.p_SC - P_TRUE)), ang


def table(noise=((0.05, 0.005), (0.2, 0.02), (0.5, 0.05)), poses=(4, 8, 16, 32), trials: int = 200, seed: int = 0) -> str:
    rows = ["| sensor noise (N, N m) | " + " | ".join(f"N = {n}" for n in poses) + " |",
            "|---|" + "---|" * len(poses)]
    for sf, st in noise:
        cells = []
        for n in poses:
            rng = np.random.default_rng(seed)
            e = np.array([trial(rng, n, sf, st) for _ in range(trials)])
            cells.append(f"{1000 * np.median(e[:, 0]):.2f} mm, {np.degrees(np.median(e[:, 1])):.2f}°")
        rows.append(f"| {sf:g}, {st:g} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


if __name__ == "__main__":
    print(table())
