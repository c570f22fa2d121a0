"""The robot's non-arm parts as a hierarchy of bounding volumes, tested top-down (the JPL brief, seed ``002``).

"Similar tests for collisions are performed with a similarly hierarchical model of the
non-manipulator parts of the robot (body, cameras, sensors, suspension, and wheels)."
(Leger, NPO-30356.)  :meth:`BodyHierarchy.from_model` builds it from the URDF: the root holds the
group (the SRDF's ``vehicle`` group by default); below it the group's links, nested as the
link tree of ``model.pin_model``'s frames nests them (a link fixed to another link is its child);
below each link its collision shapes, split in two recursively at the widest gap between their
centres along a world axis (the rover's six wheels split left | right — its two suspension
sides — then by axle; its mast into the pole and the camera head).  A leaf is one shape, its
volume the shape's OBP or OBB (:func:`~armguard.terrain.link_volume`); every inner volume is
the OBB of its children's volumes, so it contains them, and a test that misses a node cannot
miss anything below it.

:meth:`BodyHierarchy.check` tests link volumes top-down with the division-free OBB test
(:func:`armguard.geometry.batch.box_box_overlap`; an OBP is the union of its boxes), descending
only into the children of nodes hit; exact mode confirms the leaves with the exact distance.
:meth:`check_flat` tests every leaf (the reference) and :meth:`check_terrain` the body against a
terrain pyramid the same way.  The hierarchy is static in W (the rover's W is body-fixed).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .._errors import TerrainError
from ..geometry import Shape, distance
from ..geometry.batch import _box_box_overlap
from ._pyramid import TerrainPyramid
from ._volumes import grown, link_volume, union_box, volume_boxes

__all__ = ["BodyHierarchy", "BodyNode", "BodyResult"]


@dataclass(frozen=True)
class BodyNode:
    """One node: ``name``, ``volume`` (Box / Prism in W), ``children`` (node indices), ``shape``
    (leaf: index into :attr:`BodyHierarchy.shapes`, else -1), ``depth`` (root 0)."""

    name: str
    volume: Shape = field(repr=False)
    children: tuple[int, ...]
    shape: int
    depth: int


@dataclass(frozen=True)
class BodyResult:
    """The outcome of a hierarchical (or flat) body check.

    ``hit`` whether any leaf was reached (exact mode: within ``clearance``); ``level`` the deepest
    depth tested; ``nodes_tested`` nodes whose volume was tested, ``tests`` volume–volume tests;
    ``hits`` sorted ``(link, leaf name)`` pairs (exact mode: those within ``clearance``);
    ``min_distance`` (exact mode) the least exact distance among the leaves reached (``inf`` if
    none) and ``nearest`` its ``(link, leaf name)``.
    """

    hit: bool
    level: int
    nodes_tested: int
    tests: int
    hits: tuple[tuple[int, str], ...]
    min_distance: float | None = None
    nearest: tuple[int, str] | None = None


def _split(idx: list[int], centres: np.ndarray) -> tuple[list[int], list[int], str] | None:
    """``idx`` in two at the widest gap between centres along x, y or z (None: fewer than two)."""
    if len(idx) < 2:
        return None
    best = None
    for ax in range(3):
        v = centres[idx, ax]
        order = np.argsort(v, kind="stable")
        gaps = np.diff(v[order])
        j = int(np.argmax(gaps))
        if best is None or gaps[j] > best[0] + 1e-12:
            best = (float(gaps[j]), ax, order, j)
    _, ax, order, j = best
    lo = [idx[i] for i in order[:j + 1]]
    hi = [idx[i] for i in order[j + 1:]]
    return lo, hi, "xyz"[ax]


class BodyHierarchy:
    """A tree of bounding volumes over static shapes (see the module docstring).

    Attributes
    ----------
    nodes : list[BodyNode]
        ``nodes[0]`` the root; parents before children.
    shapes : list[Shape]
        The leaves' exact shapes in W; ``names`` their names (GeometryObject names from a Model).
    depth : int
        The deepest node's depth.
    """

    def __init__(self, groups: Sequence[tuple[str, Sequence[tuple[str, Shape]], Sequence]], *, name: str = "body"):
        """``groups``: the tree below the root as ``(link name, [(shape name, shape)], [child groups])``."""
        self.nodes: list[BodyNode] = []
        self.shapes: list[Shape] = []
        self.names: list[str] = []
        self._leaf_vol: list[Shape] = []
        self._add(name, None, list(groups), 0)
        if not self.shapes:
            raise TerrainError("BodyHierarchy: no shapes")
        self.depth = max(n.depth for n in self.nodes)

    # -------------------------------------------------------------------------- building
    def _add(self, name, shapes, groups, depth) -> int:
        """Add the node for ``shapes`` (a list of (name, shape), split further) and ``groups``; returns its index."""
        me = len(self.nodes)
        self.nodes.append(None)  # placeholder: children come first in the volume computation
        kids = []
        if shapes is not None and len(shapes) == 1 and not groups:
            nm, s = shapes[0]
            self.shapes.append(s)
            self.names.append(nm)
            vol = link_volume(s)
            self.nodes[me] = BodyNode(nm, vol, (), len(self.shapes) - 1, depth)
            return me
        if shapes:
            if groups or len(shapes) == 1:
                kids += [self._add(nm, [(nm, s)], [], depth + 1) for nm, s in shapes]
            else:
                centres = np.array([0.5 * np.add(*s.aabb()) for _, s in shapes])
                lo, hi, ax = _split(list(range(len(shapes))), centres)
                for side, part in (("-", lo), ("+", hi)):
                    sub = [shapes[i] for i in part]
                    kids.append(self._add(sub[0][0] if len(sub) == 1 else f"{name}:{ax}{side}", sub, [], depth + 1))
        for gname, gshapes, gkids in groups:
            kids.append(self._add(gname, list(gshapes), list(gkids), depth + 1))
        vols = [self.nodes[k].volume for k in kids]
        pts = [np.asarray(b.vertices) for v in vols for b in volume_boxes(v)]
        from ..geometry import ConvexPolyhedron

        self.nodes[me] = BodyNode(name, union_box([ConvexPolyhedron(np.concatenate(pts))]), tuple(kids), -1, depth)
        return me

    @classmethod
    def from_model(cls, model, *, group: str = "vehicle") -> "BodyHierarchy":
        """The hierarchy of the bodies in SRDF group ``group`` (scene category) of ``model`` (an
        :class:`armguard.Model`), nested as ``model.pin_model``'s link frames nest them."""
        scene = model.scene_for()  # the Model as made
        owners = [n for n, b in scene.bodies.items() if getattr(b, "category", None) == group]
        if not owners:
            raise TerrainError(f"BodyHierarchy: model {model.name!r} has no body in group {group!r}")
        pm = model.pin_model
        frames = {f.name: i for i, f in enumerate(pm.frames)}

        def parent_link(name: str) -> str | None:
            i = frames.get(name)
            while i is not None and i > 0:
                i = int(pm.frames[i].parentFrame)
                f = pm.frames[i]
                if str(f.type).endswith("BODY") and f.name in owners:
                    return f.name
                if i == 0:
                    break
            return None

        parent = {o: parent_link(o) for o in owners}

        def group_of(o: str):
            shapes = [(model.geometry_name(o, i), s) for i, s in enumerate(scene.bodies[o].shapes)]
            return (o, shapes, [group_of(c) for c in owners if parent[c] == o])

        return cls([group_of(o) for o in owners if parent[o] is None], name=group)

    @classmethod
    def from_scene(cls, scene, owners: Sequence[str] | None = None, *, name: str = "body") -> "BodyHierarchy":
        """The hierarchy of ``owners`` (default: every body) of a Scene, one node per body."""
        owners = list(scene.bodies) if owners is None else list(owners)
        return cls([(o, [(f"{o}_{i}", s) for i, s in enumerate(scene.bodies[o].shapes)], []) for o in owners],
                   name=name)

    def __repr__(self) -> str:
        return f"BodyHierarchy({self.nodes[0].name!r}, {len(self.nodes)} nodes, {len(self.shapes)} leaves, depth {self.depth})"

    def tree(self) -> str:
        """The tree as indented text (one node a line)."""
        return "\n".join("  " * n.depth + n.name for n in self._preorder())

    def _preorder(self):
        stack = [0]
        while stack:
            i = stack.pop()
            yield self.nodes[i]
            stack.extend(reversed(self.nodes[i].children))

    # -------------------------------------------------------------------------- queries
    @staticmethod
    def _boxes(vol) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        bs = volume_boxes(vol)
        return (np.array([b.center for b in bs]), np.array([b.half_extents for b in bs]),
                np.array([b.rotation for b in bs]))

    def _overlap(self, a, b) -> bool:
        (ca, ha, Ra), (cb, hb, Rb) = a, b
        return bool(np.any(_box_box_overlap(ca[:, None], ha[:, None], Ra[:, None], cb[None], hb[None], Rb[None])))

    def _node_boxes(self):
        nb = getattr(self, "_nb", None)
        if nb is None:
            nb = self._nb = [self._boxes(n.volume) for n in self.nodes]
        return nb

    def check(self, volumes: Sequence[Shape], *, shapes: Sequence[Shape] | None = None, exact: bool = False,
              clearance: float = 0.0) -> BodyResult:
        """Top-down check of link ``volumes`` (Box / Prism in W) against the hierarchy: a node's
        children are tested against a link only where the node's volume overlaps the link's volume
        grown by ``clearance`` (m).  ``exact``: confirm the leaves with the exact distance between
        ``shapes[k]`` (default the volumes) and the leaf's shape (HIT: within ``clearance``)."""
        return self._run(volumes, shapes, exact, clearance, flat=False)

    def check_flat(self, volumes: Sequence[Shape], *, shapes: Sequence[Shape] | None = None, exact: bool = False,
                   clearance: float = 0.0) -> BodyResult:
        """The reference: every leaf against every link volume (no hierarchy)."""
        return self._run(volumes, shapes, exact, clearance, flat=True)

    def _run(self, volumes, shapes, exact, clearance, flat):
        vols = list(volumes)
        if not vols:
            raise TerrainError("BodyHierarchy.check: no link volumes")
        if not (np.isfinite(clearance) and clearance >= 0.0):
            raise TerrainError(f"clearance must be finite and >= 0, got {clearance!r}")
        ex = vols if shapes is None else list(shapes)
        lb = [self._boxes(grown(v, clearance)) for v in vols]
        nb = self._node_boxes()
        reached, tests, tested, level = [], 0, 0, 0
        for k in range(len(vols)):
            stack = [i for i, n in enumerate(self.nodes) if n.shape >= 0] if flat else [0]
            while stack:
                i = stack.pop()
                tested += 1
                tests += 1
                level = max(level, self.nodes[i].depth)
                if not self._overlap(lb[k], nb[i]):
                    continue
                n = self.nodes[i]
                if n.shape >= 0:
                    reached.append((k, n.shape))
                else:
                    stack.extend(n.children)
        if not exact:
            hits = tuple(sorted((k, self.names[s]) for k, s in reached))
            return BodyResult(bool(hits), level, tested, tests, hits)
        best, nearest, hits = np.inf, None, []
        for k, s in reached:
            d = distance(ex[k], self.shapes[s]).distance
            if d <= clearance:
                hits.append((k, self.names[s]))
            if d < best:
                best, nearest = float(d), (k, self.names[s])
        return BodyResult(bool(hits), level, tested, tests, tuple(sorted(hits)), best, nearest)

    def check_terrain(self, pyramid: TerrainPyramid, *, clearance: float = 0.0, exact: bool = True) -> BodyResult:
        """The body against a terrain pyramid, top-down: a node's volume is tested coarse-to-fine
        against the pyramid (``first=True``), its children only where it touches; the leaves in
        exact mode (their exact shapes against the cell columns).  ``hits`` are ``(0, leaf name)``."""
        reached, tested, level, stack = [], 0, 0, [0]
        boxes = 0
        while stack:
            i = stack.pop()
            n = self.nodes[i]
            tested += 1
            level = max(level, n.depth)
            r = pyramid.check([n.volume], clearance=clearance, first=True)
            boxes += r.boxes_tested
            if r.cells_hit.size:
                if n.shape >= 0:
                    reached.append(n.shape)
                else:
                    stack.extend(n.children)
        hits, best, nearest = [], np.inf, None
        for s in reached:
            if not exact:
                hits.append((0, self.names[s]))
                continue
            r = pyramid.check([self.nodes[self._leaf(s)].volume], shapes=[self.shapes[s]], exact=True,
                              clearance=clearance)
            boxes += r.boxes_tested
            if r.status.value == "hit":
                hits.append((0, self.names[s]))
            if r.min_distance < best:
                best, nearest = float(r.min_distance), (0, self.names[s])
        return BodyResult(bool(hits), level, tested, boxes, tuple(sorted(hits)), best if exact else None,
                          nearest)

    def _leaf(self, s: int) -> int:
        return next(i for i, n in enumerate(self.nodes) if n.shape == s)
