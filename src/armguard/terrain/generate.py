"""Synthetic terrains and stereo-like point clouds of them, seeded and reproducible.

* :func:`fractal_heights`: a fractal (fBm) height field by spectral synthesis -- white Gaussian
  noise shaped in the Fourier domain by an amplitude ``|f| ** (-beta / 2)`` (a power spectrum
  ``|f| ** -beta``; ``beta = 2 (H + 1)`` for Hurst exponent ``H``; natural terrain ~ 2-2.5),
  scaled to a given standard deviation.
* :func:`add_rocks`: half-ellipsoid rocks (random centres, radii, heights) merged by max.
* :func:`make_terrain`: both, as an :class:`ElevationMap` (the ground truth).
* :func:`render_depth`: a pinhole depth image of the terrain from a camera pose, by ray marching
  the bilinear surface through the cell centres; pixels that see nothing within range are holes.
* :func:`stereo_points`: that depth image made stereo-like -- Gaussian depth noise growing with
  the square of the range (stereo: ``sigma_z = sigma_1 * z**2`` with ``sigma_1`` the error at 1 m),
  holes at grazing incidence (the surface seen at less than ``min_grazing`` rad: no texture to
  match) besides the occlusion shadows the ray casting leaves behind rocks, and a few outliers
  (pixels given a uniformly random depth) -- back-projected to W.

Everything draws from ``numpy.random.default_rng(seed)``; the same call gives the same terrain
(``reference/terrain/README.md`` lists the calls that made the shipped terrains).
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import TerrainError
from ._io import depth_to_points
from ._map import ElevationMap

__all__ = ["fractal_heights", "add_rocks", "make_terrain", "look_at", "render_depth", "stereo_points", "REFERENCE",
           "reference_terrain"]


def fractal_heights(n: int, *, beta: float = 2.2, sigma: float = 0.05, seed: int = 0) -> np.ndarray:
    """``(n, n) float64, m``: a zero-mean fractal height field with standard deviation ``sigma``
    (m) and spectral exponent ``beta`` (see the module docstring)."""
    if n < 2:
        raise TerrainError(f"fractal_heights: n must be >= 2, got {n}")
    rng = np.random.default_rng(seed)
    white = rng.standard_normal((n, n))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n), indexing="ij"))
    f[0, 0] = np.inf  # no mean
    h = np.fft.ifft2(np.fft.fft2(white) * f ** (-beta / 2.0)).real
    return (h - h.mean()) * (sigma / h.std())


def add_rocks(heights, cell: float, *, count: int = 6, radius=(0.05, 0.2), height=(0.05, 0.25),
              seed: int = 0) -> np.ndarray:
    """``heights (ny, nx) m`` with ``count`` half-ellipsoid rocks added (max of surface and rock):
    horizontal radius uniform in ``radius`` (m), height above the local surface uniform in
    ``height`` (m), centres uniform over the grid."""
    h = np.array(heights, dtype=np.float64)
    ny, nx = h.shape
    rng = np.random.default_rng(seed)
    y, x = (np.indices(h.shape) + 0.5) * cell
    for _ in range(count):
        cx, cy = rng.uniform(0, nx * cell), rng.uniform(0, ny * cell)
        r, t = rng.uniform(*radius), rng.uniform(*height)
        iy, ix = min(ny - 1, int(cy / cell)), min(nx - 1, int(cx / cell))
        q = 1.0 - ((x - cx) ** 2 + (y - cy) ** 2) / r**2
        rock = np.where(q > 0.0, h[iy, ix] + t * np.sqrt(np.clip(q, 0.0, None)), -np.inf)
        h = np.maximum(h, rock)
    return h


def make_terrain(n: int = 64, cell: float = 0.05, *, beta: float = 2.2, sigma: float = 0.05, rocks: int = 6,
                 seed: int = 0, origin=(0.0, 0.0)) -> ElevationMap:
    """The ground-truth map of a generated terrain: :func:`fractal_heights` (seed ``seed``) plus
    :func:`add_rocks` (seed ``seed + 1``), ``n x n`` cells of ``cell`` m from ``origin`` (m, W)."""
    h = add_rocks(fractal_heights(n, beta=beta, sigma=sigma, seed=seed), cell, count=rocks, seed=seed + 1)
    return ElevationMap.from_heights(h, cell, origin)


def look_at(eye_W, target_W) -> np.ndarray:
    """``(4, 4)`` pose X_WC of a camera at ``eye_W`` (m) looking at ``target_W`` (m), image rows
    downward (C: x right, y down, z forward; W's z up)."""
    eye, tgt = np.asarray(eye_W, np.float64), np.asarray(target_W, np.float64)
    z = tgt - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    if np.linalg.norm(x) == 0.0:
        raise TerrainError("look_at: the camera looks straight up or down; give another target")
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, :3] = np.stack([x, np.cross(z, x), z], axis=1)
    X[:3, 3] = eye
    return X


def _surface(m: ElevationMap, x, y):
    """Bilinear height (m) of the surface through the cell centres at W points ``(x, y)`` (beyond the
    outer centres, the edge's heights)."""
    ny, nx = m.shape
    u = np.clip((x - m.origin[0]) / m.cell - 0.5, 0.0, nx - 1.0)
    v = np.clip((y - m.origin[1]) / m.cell - 0.5, 0.0, ny - 1.0)
    i0, j0 = np.minimum(v.astype(np.int64), max(ny - 2, 0)), np.minimum(u.astype(np.int64), max(nx - 2, 0))
    i1, j1 = np.minimum(i0 + 1, ny - 1), np.minimum(j0 + 1, nx - 1)
    a, b = v - i0, u - j0
    H = m.heights
    return (H[i0, j0] * (1 - a) * (1 - b) + H[i0, j1] * (1 - a) * b + H[i1, j0] * a * (1 - b) + H[i1, j1] * a * b)


def render_depth(m: ElevationMap, X_WC, *, width: int = 80, height: int = 60, fov: float = 1.0,
                 max_range: float = 6.0, step: float | None = None):
    """Ray-cast depth image of the terrain.

    Returns ``(depth (height, width) float64 m, along C's z; NaN where the ray meets no ground
    within the range), (fx, fy, cx, cy) px, normals_W (height, width, 3))``.  Beyond the map the
    ground goes on at its edge's heights (:func:`_surface` clamps): a world that ended at the map's
    edge would show the camera a cliff there, its face seen from below.  ``fov`` (rad) is the
    horizontal field of view; ``step`` (m) the marching step (default half a cell), refined by
    bisection to a hundredth of it."""
    X = np.asarray(X_WC, np.float64)
    fx = fy = 0.5 * width / math.tan(0.5 * fov)
    cx, cy = 0.5 * (width - 1), 0.5 * (height - 1)
    v, u = np.indices((height, width), dtype=np.float64)
    d_C = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=-1).reshape(-1, 3)
    d_W = d_C @ X[:3, :3].T  # per unit of depth along C's z
    o = X[:3, 3]
    ds = 0.5 * m.cell if step is None else float(step)
    seg = np.linalg.norm(d_W, axis=1)
    n_ray = len(d_W)
    z_prev = np.zeros(n_ray)
    hit = np.full(n_ray, np.nan)
    alive = np.ones(n_ray, bool)
    n_steps = int(math.ceil(max_range / ds))
    for s in range(1, n_steps + 1):
        idx = np.flatnonzero(alive)
        if len(idx) == 0:
            break
        zc = np.full(len(idx), s * ds) / seg[idx]  # depth along C's z after s steps of length ds
        p = o + d_W[idx] * zc[:, None]
        below = p[:, 2] <= _surface(m, p[:, 0], p[:, 1])
        if below.any():
            j = idx[below]
            lo, hi = z_prev[j], zc[below]
            for _ in range(7):  # bisection: 2**-7 of a step
                mid = 0.5 * (lo + hi)
                q = o + d_W[j] * mid[:, None]
                under = q[:, 2] <= _surface(m, q[:, 0], q[:, 1])
                hi, lo = np.where(under, mid, hi), np.where(under, lo, mid)
            hit[j] = hi
            alive[j] = False
        z_prev[idx] = zc
    depth = hit.reshape(height, width)
    # surface normals at the hits (finite differences of the bilinear surface)
    p = o + d_W * np.nan_to_num(hit)[:, None]
    e = 0.5 * m.cell
    gx = (_surface(m, p[:, 0] + e, p[:, 1]) - _surface(m, p[:, 0] - e, p[:, 1])) / (2 * e)
    gy = (_surface(m, p[:, 0], p[:, 1] + e) - _surface(m, p[:, 0], p[:, 1] - e)) / (2 * e)
    nrm = np.stack([-gx, -gy, np.ones_like(gx)], axis=1)
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    return depth, (fx, fy, cx, cy), nrm.reshape(height, width, 3)


def stereo_points(m: ElevationMap, X_WC, *, width: int = 80, height: int = 60, fov: float = 1.0,
                  max_range: float = 6.0, sigma_1m: float = 0.002, min_grazing: float = 0.1,
                  outliers: float = 0.002, seed: int = 0):
    """A stereo-like point cloud of the terrain seen from ``X_WC (4, 4)``.

    Returns ``(points_W (N, 3) float64 m, depth (height, width) float64 m with NaN holes,
    intrinsics (fx, fy, cx, cy) px)``: :func:`render_depth`, then depth noise
    ``N(0, (sigma_1m * z**2)**2)`` (m, ``z`` the depth in m), holes where the ray meets the surface
    at a grazing angle below ``min_grazing`` (rad), and a fraction ``outliers`` of the valid pixels
    replaced by a depth uniform in ``(0.3 z, 1.5 z)``; back-projected with :func:`depth_to_points`."""
    rng = np.random.default_rng(seed)
    depth, (fx, fy, cx, cy), nrm = render_depth(m, X_WC, width=width, height=height, fov=fov, max_range=max_range)
    X = np.asarray(X_WC, np.float64)
    v, u = np.indices(depth.shape, dtype=np.float64)
    ray = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=-1) @ X[:3, :3].T
    ray /= np.linalg.norm(ray, axis=-1, keepdims=True)
    sin_graze = np.abs(np.sum(ray * nrm, axis=-1))  # sine of the angle between ray and surface
    d = depth.copy()
    d[sin_graze < math.sin(min_grazing)] = np.nan
    ok = np.isfinite(d)
    d[ok] += rng.standard_normal(int(ok.sum())) * sigma_1m * d[ok] ** 2
    flat = np.flatnonzero(ok)
    n_out = int(round(outliers * len(flat)))
    pick = rng.choice(flat, size=n_out, replace=False) if n_out else np.zeros(0, np.int64)
    d.flat[pick] = d.flat[pick] * rng.uniform(0.3, 1.5, size=n_out)
    return depth_to_points(d, fx, fy, cx, cy, X), d, (fx, fy, cx, cy)


# The shipped terrains (reference/terrain/<name>.npz): the make_terrain call, the camera on the
# mast (eye and target, m, W) and the stereo_points call.  `python -m armguard.terrain.generate`
# rewrites them.
REFERENCE = {
    "gentle": {"terrain": {"n": 64, "cell": 0.05, "beta": 2.4, "sigma": 0.03, "rocks": 3, "seed": 11},
               "eye": (1.6, -0.8, 1.5), "target": (1.6, 1.6, 0.0), "stereo": {"width": 80, "height": 60, "seed": 12}},
    "rocky": {"terrain": {"n": 64, "cell": 0.05, "beta": 2.2, "sigma": 0.05, "rocks": 12, "seed": 21},
              "eye": (1.6, -0.8, 1.5), "target": (1.6, 1.6, 0.0), "stereo": {"width": 80, "height": 60, "seed": 22}},
    "rough": {"terrain": {"n": 64, "cell": 0.05, "beta": 1.8, "sigma": 0.06, "rocks": 6, "seed": 31},
              "eye": (-0.6, -0.6, 1.4), "target": (1.8, 1.8, 0.0), "stereo": {"width": 80, "height": 60, "seed": 32}},
}


def reference_terrain(name: str) -> dict:
    """Regenerate shipped terrain ``name`` (a key of :data:`REFERENCE`): a dict with ``heights
    (n, n) m`` (ground truth), ``cell`` (m), ``X_WC (4, 4)``, ``points_W (N, 3) m`` and ``depth
    (H, W) m`` (NaN holes)."""
    if name not in REFERENCE:
        raise TerrainError(f"reference_terrain: unknown terrain {name!r}; known: {sorted(REFERENCE)}")
    spec = REFERENCE[name]
    m = make_terrain(**spec["terrain"])
    X = look_at(spec["eye"], spec["target"])
    pts, depth, _ = stereo_points(m, X, **spec["stereo"])
    return {"heights": m.heights, "cell": m.cell, "X_WC": X, "points_W": pts, "depth": depth}


def _write_reference(folder) -> None:  # pragma: no cover - run by hand
    from pathlib import Path

    from .._io import atomic_write, make_folder

    folder = make_folder(Path(folder))
    for name in REFERENCE:
        r = reference_terrain(name)
        arrays = dict(heights=r["heights"].astype(np.float32), cell=r["cell"], X_WC=r["X_WC"],
                      points_W=r["points_W"].astype(np.float32))
        # whole or not at all: the shipped file is the default target (a full disk left it cut short)
        atomic_write(folder / f"{name}.npz", lambda f, a=arrays: np.savez_compressed(f, **a))
        print(name, r["points_W"].shape, (folder / f"{name}.npz").stat().st_size, "bytes")


if __name__ == "__main__":  # pragma: no cover
    import sys

    _write_reference(sys.argv[1] if len(sys.argv) > 1 else "reference/terrain")
