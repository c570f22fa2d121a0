"""Seeded random shapes for the geometry tests (shared by tests/test_geometry*.py)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere

KINDS = ["sphere", "capsule", "box", "prism", "polyhedron", "polygon"]


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    return Rotation.random(random_state=rng.integers(2**31)).as_matrix()


def random_shape(kind: str, rng: np.random.Generator, spread: float = 1.0):
    """A random shape of ``kind`` near the origin (size ~0.2-0.6 m, centre within ``spread``)."""
    c = rng.uniform(-spread, spread, 3)
    if kind == "sphere":
        return Sphere(c, rng.uniform(0.05, 0.5))
    if kind == "capsule":
        d = rng.normal(size=3)
        d *= rng.uniform(0.1, 0.8) / np.linalg.norm(d)
        return Capsule(c - d / 2, c + d / 2, rng.uniform(0.0, 0.3))
    if kind == "box":
        return Box(c, rng.uniform(0.05, 0.5, 3), random_rotation(rng))
    if kind == "prism":
        return Prism(c, random_rotation(rng), rng.uniform(0.05, 0.4), rng.uniform(0.05, 0.4), int(rng.integers(3, 9)))
    if kind == "polyhedron":
        v = rng.normal(size=(int(rng.integers(4, 13)), 3))
        return ConvexPolyhedron(c + v * rng.uniform(0.1, 0.4))
    if kind == "polygon":
        n = int(rng.integers(3, 8))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        ang = np.linspace(0, 2 * np.pi, n, endpoint=False) + rng.uniform(0, 0.3, n)
        rad = rng.uniform(0.1, 0.5)
        pts = np.stack([rad * np.cos(ang), rad * np.sin(ang), np.zeros(n)], 1)
        return Polygon(c + pts @ random_rotation(rng).T)
    raise ValueError(kind)
