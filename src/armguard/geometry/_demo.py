"""The shape pairs of the ``armguard distance`` demo (the table is printed by :mod:`armguard.cli._distance`)."""

from __future__ import annotations

import numpy as np

from ._shapes import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere

__all__ = ["example_pairs"]


def example_pairs():
    """``[(label, A, B)]``: a few pairs covering every kernel family, apart and penetrating."""
    link = Capsule([0.0, 0.0, 0.0], [0.6, 0.0, 0.0], 0.05)
    return [
        ("link / link (apart)", link, Capsule([0.3, 0.4, -0.3], [0.3, 0.4, 0.3], 0.05)),
        ("link / link (crossing)", link, Capsule([0.3, 0.02, -0.3], [0.3, 0.02, 0.3], 0.05)),
        ("sphere / sphere", Sphere([0, 0, 0], 0.1), Sphere([0.25, 0, 0], 0.1)),
        ("link / box (apart)", link, Box([0.3, 0.0, 0.5], [0.2, 0.2, 0.2])),
        ("link / box (penetrating)", link, Box([0.3, 0.0, 0.2], [0.2, 0.2, 0.2])),
        ("link / prism (OBP)", link, Prism([0.3, 0.6, 0.0], np.eye(3), 0.1, 0.3, 8)),
        ("box / box", Box([0, 0, 0], [0.2, 0.2, 0.2]), Box([0.35, 0.1, 0.0], [0.2, 0.2, 0.2])),
        ("link / polyhedron", link, ConvexPolyhedron([[1, 0, 0], [1.2, 0, 0], [1, 0.2, 0], [1, 0, 0.2]])),
        ("link / face (Ranger)", link, Polygon([[0.0, -0.2, 0.2], [0.6, -0.2, 0.2], [0.6, 0.2, 0.2], [0.0, 0.2, 0.2]])),
    ]
