"""What "the backends agree" means, per pair: the ``differential_*`` fields of
:class:`armguard.Tolerances` (the one tolerance dataclass), which ``tests/test_backends.py``,
``tests/test_reference.py`` and the harness (``armguard compare``) all read.
"""

from __future__ import annotations

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["pair_kinds", "pair_distance_tolerance", "unique_witness_kinds"]


unique_witness_kinds = frozenset({"Capsule", "Sphere"})
"""Shape kinds (coal class names) whose nearest points are unique when separated (capsules: unless parallel)."""


def pair_kinds(model) -> np.ndarray:
    """``(n, 2)`` object: the coal class name of each side of each active pair (``"workspace"`` for the walls)."""
    out = np.empty((len(model.pairs), 2), dtype=object)
    cm = model.collision_model
    for k, pair in enumerate(model.pairs.names):
        for s, name in enumerate(pair):
            out[k, s] = "workspace" if name == "workspace" else type(cm.geometryObjects[model.geometry_index(name)].geometry).__name__
    return out


def pair_distance_tolerance(model, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
    """``(n,) float64, m``: ``tol.differential_hull`` for pairs with a Convex side, else ``tol.differential_distance``."""
    hull = (pair_kinds(model) == "Convex").any(axis=1)
    return np.where(hull, tol.differential_hull, tol.differential_distance)
