"""The differential tolerances: one place for what "the backends agree" means.

``tests/test_backends.py``, ``tests/test_reference.py`` and the harness (``armguard compare``)
all read :data:`DIFFERENTIAL` (a :class:`DifferentialTolerances`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["DifferentialTolerances", "DIFFERENTIAL", "pair_kinds", "pair_distance_tolerance", "unique_witness_kinds"]


@dataclass(frozen=True)
class DifferentialTolerances:
    """How closely two backends (or a backend and ``reference/``) must agree.

    Attributes
    ----------
    contact_band : float, m
        A verdict (collides or not) may differ between backends only where the reference
        distance is within this of 0.
    distance : float, m
        Separated distances agree within this (both backends exact up to round-off).
    hull : float, m
        ... within this where a side is a ``coal.Convex`` hull (coal's GJK on mesh hulls stops
        within it; measured 3.6e-6 m on the Panda's hulls).
    witness : float, m
        The analytic backend's witness relation ``| |p_WA - p_WB| - |d| |`` holds within this.
    fcl : float, m
        python-fcl's distances were measured up to 5.3e-2 m off the exact ones (its capsule and
        GJK paths); it is held to verdicts outside this band (not on Ranger, where it is off by
        0.32 m on some pairs).
    unique_min_distance : float, m
        Witness points are compared between backends only on pairs where they are unique: both
        sides capsules or spheres, the reference distance above this, ...
    parallel : float, dimensionless
        ... and, for two capsules, ``|sin(angle between the axes)|`` above this.
    unique_point : float, m
        Unique witness points agree within this.
    """

    contact_band: float = 1e-6
    distance: float = 1e-6
    hull: float = 1e-5
    witness: float = 1e-9
    fcl: float = 6e-2
    unique_min_distance: float = 1e-3
    parallel: float = 1e-3
    unique_point: float = 1e-6

    def to_dict(self) -> dict:
        return asdict(self)


DIFFERENTIAL = DifferentialTolerances()

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


def pair_distance_tolerance(model, tol: DifferentialTolerances = DIFFERENTIAL) -> np.ndarray:
    """``(n,) float64, m``: ``tol.hull`` for pairs with a Convex side, else ``tol.distance``."""
    hull = (pair_kinds(model) == "Convex").any(axis=1)
    return np.where(hull, tol.hull, tol.distance)
