"""Shapes and exact pairwise proximity queries (signed distance, witness points, overlap).

``distance(a, b)`` answers every pair of the seven shapes through one dispatch table
(``_dispatch``); ``armguard.geometry.batch`` has the batched kernels over arrays of pairs and
``armguard.geometry.kernels`` the njit-callable per-pair kernels for other compiled code.
"""

from ._cylinder import Cylinder
from ._dispatch import distance, intersects, kernel_name
from ._feature import Feature, FeatureKind, feature_at
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
    "Cylinder",
    "CoreKind",
    "Proximity",
    "distance",
    "intersects",
    "kernel_name",
    "Feature",
    "FeatureKind",
    "feature_at",
]
