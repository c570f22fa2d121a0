"""The analytic engine's W path, for tests: every element moved to W, and one pair's distance by the
generic per-pair kernel (``_narrow.pair_distance``) on the detector's buffers; random point clouds
and rotations for the link-frame kernel tests."""

from __future__ import annotations

import numpy as np
from numba import njit


def move_all(det) -> None:
    """Move every moving element of ``det``'s last check to W (the calling thread's scratch)."""
    from armguard_analytic._engine._step import move_element

    @njit(cache=False)
    def run(ids, H, MF, MI, SF):
        for g in ids:
            move_element(g, H, MF, MI, SF)

    run(det._model.mov_ids, det._H, det._MF, det._MI, det._SF)


def world_pair_distance(det, a: int, b: int) -> tuple:
    """``(distance, error)`` of elements ``a``, ``b`` by the generic kernel on the W data."""
    from armguard.geometry._pair_cylinder import SUPPORT_WORK_SIZE
    from armguard.geometry._pair_epa import EPA_WORK_SIZE
    from armguard_analytic._engine._calls import addresses
    from armguard_analytic._engine._narrow import pair_distance

    L, tol = det._layout, det._tol
    V = lambda buf, k: L.view(buf, k)  # noqa: E731
    out, work = np.zeros(9), np.zeros(max(EPA_WORK_SIZE, SUPPORT_WORK_SIZE))
    return pair_distance(a, b, V(det._MI, "core"), V(det._MF, "radius"), V(det._SF, "vW"), V(det._MI, "vstart"),
                         V(det._SF, "boxW"), V(det._SF, "fnW"), V(det._MI, "pstart"), V(det._SF, "edW"),
                         V(det._MI, "estart"), V(det._MI, "gadj"), V(det._MI, "gadjs"), V(det._MI, "gtri"),
                         V(det._MI, "gtris"), out, work, tol.length, tol.parallel, tol.gjk_epsilon,
                         tol.gjk_max_iterations, tol.penetration_witness_offset, -np.inf, addresses())


def random_rotation(rng) -> np.ndarray:
    """A uniformly random rotation (3, 3), from a random unit quaternion."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def random_cloud(rng, n: int) -> np.ndarray:
    """``n`` points on a random ellipsoid (semi-axes 0.05-0.4 m): every one a hull vertex."""
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return np.ascontiguousarray(p * rng.uniform(0.05, 0.4, size=3))
