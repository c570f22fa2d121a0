"""The exact right circular cylinder (URDF's ``<cylinder>``), a shape whose core is curved.

Its core is the solid cylinder itself (radius 0 swept around it); no finite point set has it as
its hull, so the kernels reach it through its support function (``_pair_cylinder``: GJK and EPA
on support functions, van den Bergen, *Collision Detection in Interactive 3D Environments*
§4.3): with ``c`` the centre, ``a`` the unit axis, ``r`` the radius and ``h`` the half length,

    s(d) = c + h sign(a . d) a + r (d - (a . d) a) / |d - (a . d) a|

(the radial term dropped when ``d`` is along the axis: a cap is a face, any of its points is a
support; ``a . d = 0``: a side segment is an edge, its ``+h`` end is returned).  The radial part
is evaluated in the cylinder's frame, ``d - (a . d) a = u x_C + v y_C`` with ``u = x_C . d``,
``v = y_C . d``: orthogonal to the axis by construction, where the subtraction would lose it to
cancellation for ``d`` near the axis (and with it the support value, by up to ``r``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .._errors import GeometryError
from ._check import check_nonnegative, check_point, check_pose, check_rotation
from ._pack import attach_packed
from ._shapes import CoreKind, Shape, Sphere, _apply, _readonly

__all__ = ["Cylinder", "CYLINDER_HULL_SIDES"]

CYLINDER_HULL_SIDES = 16
"""Sides of the circumscribed prism whose vertices are a Cylinder's ``core_points`` (a hull that
contains it, for callers that bound a shape by its core points; every distance is exact)."""


@dataclass(frozen=True, eq=False)
class Cylinder(Shape):
    """A solid right circular cylinder.

    ``center`` (3,) m in W; ``rotation`` R_WC (3, 3) whose third column is the axis (the first
    two columns are the reference directions of the cross-section, used only for ``core_points``);
    ``radius`` (m, > 0); ``half_length`` (m, > 0) half the axial length.  URDF's ``<cylinder
    radius length>`` with its ``<origin>`` as ``(center, rotation)`` and ``length = 2
    half_length``; coal's ``Cylinder(radius, 2 half_length)``.
    """

    center: np.ndarray
    rotation: np.ndarray
    radius: float
    half_length: float
    core_kind: ClassVar[int] = CoreKind.CYLINDER

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check_point(self.center, "Cylinder.center"))
        object.__setattr__(self, "rotation", check_rotation(self.rotation, "Cylinder.rotation"))
        r = check_nonnegative(self.radius, "Cylinder.radius")
        h = check_nonnegative(self.half_length, "Cylinder.half_length")
        if r <= 0.0 or h <= 0.0:
            raise GeometryError("Cylinder: radius and half_length must be > 0 (a cylinder with volume)")
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "half_length", h)
        attach_packed(self)

    @property
    def axis(self) -> np.ndarray:
        """``(3,) float64``: the unit axis in W (``rotation[:, 2]``)."""
        return _readonly(self.rotation[:, 2])

    @property
    def p0(self) -> np.ndarray:
        """``(3,) float64, m``: centre of the cap at ``-half_length`` along the axis."""
        return _readonly(self.center - self.half_length * self.rotation[:, 2])

    @property
    def p1(self) -> np.ndarray:
        """``(3,) float64, m``: centre of the cap at ``+half_length`` along the axis."""
        return _readonly(self.center + self.half_length * self.rotation[:, 2])

    @property
    def length(self) -> float:
        """Axial length (m), ``2 half_length``."""
        return 2.0 * self.half_length

    @property
    def core_points(self) -> np.ndarray:
        """``(32, 3) float64, m``: vertices of the circumscribed ``CYLINDER_HULL_SIDES``-sided prism
        (apothem = radius): a hull containing the cylinder, for bounds only -- the cylinder's core is
        curved; :meth:`support` and every distance kernel use the exact cylinder."""
        n = CYLINDER_HULL_SIDES
        rc = self.radius / math.cos(math.pi / n)
        ang = (np.arange(n) + 0.5) * (2.0 * math.pi / n)
        ring = np.stack([rc * np.cos(ang), rc * np.sin(ang), np.zeros(n)], axis=1)
        local = np.vstack([ring + [0, 0, -self.half_length], ring + [0, 0, self.half_length]])
        return _readonly(self.center + local @ self.rotation.T)

    def support(self, direction) -> np.ndarray:
        """``(3,) float64, m``: a point of the cylinder farthest along ``direction`` (exact, see the
        module docstring)."""
        d = np.asarray(direction, dtype=np.float64)
        u, v, s = self.rotation.T @ d  # d in the cylinder's frame: the radial part is exactly orthogonal
        R = self.rotation
        p = self.center + (self.half_length if s >= 0.0 else -self.half_length) * R[:, 2]
        n = math.hypot(u, v)
        if n > 0.0:
            p = p + (self.radius / n) * (u * R[:, 0] + v * R[:, 1])
        return p

    def aabb(self) -> tuple[np.ndarray, np.ndarray]:
        """The exact axis-aligned bounding box in W: along axis ``k`` the extent is
        ``h |a_k| + r sqrt(1 - a_k^2)`` about the centre."""
        a = self.rotation[:, 2]
        e = self.half_length * np.abs(a) + self.radius * np.sqrt(np.maximum(0.0, 1.0 - a * a))
        return self.center - e, self.center + e

    def circumscribed_sphere(self) -> Sphere:
        """The smallest sphere containing the cylinder (centre, radius ``hypot(r, h)``)."""
        return Sphere(self.center, math.hypot(self.radius, self.half_length))

    def inscribed_sphere(self) -> Sphere:
        """The largest sphere inside the cylinder (centre, radius ``min(r, h)``)."""
        return Sphere(self.center, min(self.radius, self.half_length))

    def transformed(self, X_AW) -> "Cylinder":
        X = check_pose(X_AW, "X_AW")
        return Cylinder(_apply(X, self.center), X[:3, :3] @ self.rotation, self.radius, self.half_length)
