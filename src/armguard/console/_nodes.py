"""The view's scene nodes: one mesh a shape, built once, then only moved; the shapes at a
configuration, transformed only where asked.

A :class:`ShapeNode` remembers the shape as it was drawn (``shape0``, at the configuration the
view was built at) and that configuration's frame; :class:`PosedItems` gives, for a new
configuration, each node's motion ``T = X(q) X(q_built)⁻¹`` from forward kinematics alone
(:func:`~._meshes.item_frames`) and the shape itself (``shape0`` moved by ``T``) only for the few
nodes a test needs -- those whose bounding sphere comes near a segment (:meth:`PosedItems.near`).
Display only: nothing here feeds a distance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._meshes import item_frames

__all__ = ["ShapeNode", "PosedItems", "segment_point_distance"]


@dataclass(eq=False)
class ShapeNode:
    """One shape's mesh: ``c0`` (3,) m the mesh's origin in W when built, ``bound`` m the radius
    of a sphere about it holding the whole shape, ``X0_inv`` the inverse of the frame it was
    built at (:func:`~._meshes.item_frames`), ``handle`` the viser mesh, ``color`` its own colour;
    ``shown_*`` what was last sent (so an unchanged value is never sent again)."""

    owner: str
    kind: str
    robot: str | None
    shape0: object
    c0: np.ndarray
    bound: float
    X0_inv: np.ndarray
    handle: object
    color: tuple
    shown_color: tuple | None = None
    shown_opacity: float | None = field(default=None)

    def _fields(self) -> tuple:
        return (self.owner, self.kind, np.asarray(self.shape0.core_points), self.c0, self.handle, self.color,
                self.shown_color, self.shown_opacity)

    def __iter__(self):
        """Also read as ``(owner, kind, P0, c0, handle, color, shown_color, shown_opacity)``."""
        return iter(self._fields())

    def __getitem__(self, i):
        return self._fields()[i]


def segment_point_distance(a, b, P) -> np.ndarray:
    """Distance (m) of each point of ``P`` (n, 3) to the segment ``a``-``b``."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    d = b - a
    dd = float(d @ d)
    t = np.zeros(len(P)) if dd == 0.0 else np.clip((P - a) @ d / dd, 0.0, 1.0)
    return np.linalg.norm(P - (a + t[:, None] * d), axis=1)


class PosedItems:
    """The nodes' shapes at configuration ``q`` (a mapping robot -> joints) of ``scene``."""

    def __init__(self, nodes, scene, q) -> None:
        self.nodes = list(nodes)
        frames = item_frames(scene, q)
        if len(frames) != len(self.nodes):
            raise ValueError(f"the view has {len(self.nodes)} shapes, the scene {len(frames)}: rebuild the view")
        self.T = [F @ n.X0_inv for n, F in zip(self.nodes, frames)]
        self.centers = np.array([T[:3, :3] @ n.c0 + T[:3, 3] for n, T in zip(self.nodes, self.T)]).reshape(-1, 3)
        self.bounds = np.array([n.bound for n in self.nodes], dtype=np.float64)
        self._shapes: dict[int, object] = {}

    def __len__(self) -> int:
        return len(self.nodes)

    def shape(self, k: int):
        """Node ``k``'s shape at ``q`` (in W)."""
        s = self._shapes.get(k)
        if s is None:
            n, T = self.nodes[k], self.T[k]
            s = n.shape0 if np.allclose(T, np.eye(4), atol=1e-15) else n.shape0.transformed(T)
            self._shapes[k] = s
        return s

    def near(self, a, b, pad: float = 0.0) -> list[int]:
        """Nodes whose bounding sphere comes within ``pad`` m of the segment ``a``-``b``."""
        if not len(self.nodes):
            return []
        d = segment_point_distance(a, b, self.centers)
        return [int(k) for k in np.flatnonzero(d <= self.bounds + pad)]
