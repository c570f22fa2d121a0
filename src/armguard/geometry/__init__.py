"""Shapes and exact pairwise proximity queries (signed distance, witness points, overlap)."""

from ._proximity import Proximity
from ._shapes import Box, Capsule, ConvexPolyhedron, CoreKind, Polygon, Prism, Shape, Sphere

__all__ = [
    "Shape",
    "Sphere",
    "Capsule",
    "Box",
    "Prism",
    "ConvexPolyhedron",
    "Polygon",
    "CoreKind",
    "Proximity",
]
