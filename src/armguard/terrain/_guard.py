"""The terrain category of a robot system: its moving links posed at ``q`` and checked against the pyramid.

:class:`TerrainGuard` composes a Scene (or a Model: its ``.scene``) with a
:class:`~armguard.terrain.TerrainPyramid`: for a configuration it poses each moving link's shapes
and their low-resolution volumes (an OBP where the shape is one: :func:`link_volume`), runs the
pyramid's coarse-to-fine check in exact mode and returns a :class:`TerrainReport` — the
``terrain`` category beside the Detector's ``environment`` and ``arm`` categories, with the same
status rules.  Nothing of the Detector's kernel is involved: :func:`check_with_terrain` and
``Detector(..., terrain=...)`` merge the two reports.

**Unknown terrain.**  A filled (unseen) cell is a column at the map's conservative fill, and the
ground beyond the map's edge is unknown too: four slabs around the map from the floor to the
map's highest cell.  A link within ``level + unknown_margin`` of an unknown column is "over
unknown terrain": the check says INCOMPLETE there (never CLEAR by omission) unless a known
cell already gives COLLISION.  ``unknown_margin`` is the tolerance granted to the fill.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from .._errors import TerrainError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number
from ..geometry import Box, distance
from ..model import kinematics_of, scene_of
from ._exact import column_distances
from ._map import ElevationMap
from ._pyramid import TerrainPyramid
from ._volumes import link_volume, local_obbs, pack_obbs

__all__ = ["TERRAIN", "TerrainCell", "TerrainGuard", "TerrainReport"]

TERRAIN = "terrain"
"""The category name (``by_category`` key) and the obstacle name of the terrain."""

_OUTSIDE = 1.0e3  # m: how far the unknown slabs around the map reach


def _inv(X: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = X[:3, :3].T
    out[:3, 3] = -X[:3, :3].T @ X[:3, 3]
    return out


def _length(x, name: str) -> float:
    return number(x, name, TerrainError, low=0.0, unit=" (m)")


@dataclass(frozen=True)
class TerrainCell:
    """The terrain feature of a link–terrain pair: cell ``(row, col)`` of the map (``-1, -1``: the
    ground beyond the map's edge), ``known`` whether it was seen; ``kind`` ("cell", "unseen cell" or
    "off the map") and ``index`` (``row * nx + col``, -1 off the map) as for a polytope feature."""

    row: int
    col: int
    known: bool
    index: int = -1

    @property
    def kind(self) -> str:
        return "off the map" if self.row < 0 else ("cell" if self.known else "unseen cell")

    def __str__(self) -> str:
        return self.kind if self.row < 0 else f"{self.kind} ({self.row}, {self.col})"

    def to_dict(self) -> dict:
        return {"kind": self.kind, "row": self.row, "col": self.col, "known": self.known, "index": self.index}


@dataclass(frozen=True)
class TerrainReport:
    """The terrain category at one configuration (:meth:`TerrainGuard.check`).

    Attributes
    ----------
    status : armguard.Status
        COLLISION: a known cell's column within the collision level (``max(Tolerances.length,
        stopping_distance)``); INCOMPLETE: otherwise an unknown column (a filled cell, or off the
        map) within ``threshold + unknown_margin``; WARNING: a known column within ``threshold``;
        CLEAR: every link farther than the threshold from every column.
    distance : float, m
        The exact signed distance of the pair ``link``, ``cell`` and the witnesses name: for a COLLISION
        the nearest known column (the contact, though an unknown column may be deeper), else the nearest
        of all (``min(known_distance, unknown_distance)``); ``inf`` when every link is farther than
        ``reach`` (then it is only known to be more than ``reach``).
    known_distance, unknown_distance : float, m
        The same over the known columns only / over the unknown columns and the off-map slabs.
    link : str | None
        Owner name of that pair's link (``"arm/link3"``).
    cell : (int, int) | None
        ``(row, col)`` of that pair's column (None off the map or beyond ``reach``).
    unknown : bool
        That column is unknown (filled, or off the map).
    p_WA, p_WB : (3,) float64, m, or None
        Witness points on the link and on the column.
    link_distance : dict[str, float], m
        Per moving owner, its least distance (``inf`` beyond ``reach``).
    level, boxes_tested, tests : int
        From the pyramid's descent: the level that decided, boxes visited, box–volume tests.
    threshold, stopping_distance, reach, unknown_margin : float, m
    elapsed_us : float, µs
    """

    status: object
    distance: float
    known_distance: float
    unknown_distance: float
    link: str | None
    cell: tuple[int, int] | None
    unknown: bool
    p_WA: np.ndarray | None = field(repr=False)
    p_WB: np.ndarray | None = field(repr=False)
    link_distance: dict = field(repr=False)
    level: int
    boxes_tested: int
    tests: int
    threshold: float
    stopping_distance: float
    reach: float
    unknown_margin: float
    elapsed_us: float
    nx: int = field(default=0, repr=False)

    def pair(self):
        """The link–terrain pair the report names (``distance``: a COLLISION's known column, else the nearest)
        as an :class:`armguard.PairResult` of category ``"terrain"`` (None when every
        link is beyond ``reach``)."""
        from ..detect import PairResult

        if self.link is None or self.p_WA is None:
            return None
        nx = self.nx
        cell = (TerrainCell(-1, -1, False) if self.cell is None else
                TerrainCell(self.cell[0], self.cell[1], not self.unknown, self.cell[0] * nx + self.cell[1]))
        return PairResult(self.distance, self.p_WA, self.p_WB, self.link, TERRAIN, TERRAIN, self.link, TERRAIN, cell)

    def to_dict(self) -> dict:
        """JSON-ready dictionary (``inf`` as the string ``"inf"``)."""
        f = lambda x: float(x) if math.isfinite(x) else ("inf" if x > 0 else "-inf")  # noqa: E731
        return {
            "status": self.status.value, "distance": f(self.distance), "known_distance": f(self.known_distance),
            "unknown_distance": f(self.unknown_distance), "link": self.link,
            "cell": None if self.cell is None else list(self.cell), "unknown": self.unknown,
            "p_WA": None if self.p_WA is None else [float(x) for x in self.p_WA],
            "p_WB": None if self.p_WB is None else [float(x) for x in self.p_WB],
            "link_distance": {k: f(v) for k, v in self.link_distance.items()},
            "level": self.level, "boxes_tested": self.boxes_tested, "tests": self.tests,
            "threshold": self.threshold, "stopping_distance": self.stopping_distance, "reach": self.reach,
            "unknown_margin": self.unknown_margin, "elapsed_us": self.elapsed_us,
        }


class TerrainGuard:
    """The moving links of ``model_or_scene`` against a terrain pyramid (see the module docstring).

    Parameters
    ----------
    model_or_scene : armguard.Model or armguard.Scene
    terrain : TerrainPyramid or ElevationMap
        The terrain in W (an ElevationMap is made into its pyramid).
    robot : str | None
        Only this robot's links (and the payloads it carries); None: every robot.
    threshold, stopping_distance : float, m
        As the Detector's: WARNING within ``threshold``; COLLISION within the stopping distance
        (or contact, ``Tolerances.length``, when it is 0).
    reach : float, m
        Exact distances are computed for every column within this of a link (it is raised to
        ``max(threshold, stopping_distance) + unknown_margin``); farther ones are reported as
        ``inf`` ("more than ``reach``").
    unknown_margin : float, m
        See the module docstring.
    tol : Tolerances

    Attributes
    ----------
    pyramid : TerrainPyramid
    owners : tuple[str, ...]
        Owner of each moving shape (``"arm/link2"``, a payload's name), in the scene's order.
    lever : (K, n_q) float64, m/rad
        Per moving shape, the verifier's configuration-independent lever-arm bound
        (:func:`armguard.verify._motion.chain_bounds`): any of its points moves at most
        ``|dq| . lever[k]`` when the flat configuration moves by ``dq`` along a straight line.
    """

    def __init__(self, model_or_scene, terrain, *, robot: str | None = None, threshold: float = 0.05,
                 stopping_distance: float = 0.0, reach: float = 0.0, unknown_margin: float = 0.05,
                 tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        from ..verify._motion import chain_bounds, shape_radius_about

        scene = scene_of(model_or_scene, "Guard")
        self._kin = kinematics_of(model_or_scene)  # the links move by the Model's pin_model
        if isinstance(terrain, ElevationMap):
            terrain = TerrainPyramid(terrain, tol=tol)
        if not isinstance(terrain, TerrainPyramid):
            raise TerrainError(f"TerrainGuard: expected a TerrainPyramid or an ElevationMap, got {type(terrain).__name__}")
        if robot is not None and robot not in scene.robots:
            raise TerrainError(f"TerrainGuard: unknown robot {robot!r}; robots are {list(scene.robots)}")
        self.scene, self.pyramid, self.robot, self.tol = scene, terrain, robot, tol
        self.threshold = _length(threshold, "threshold")
        self.stopping_distance = _length(stopping_distance, "stopping_distance")
        self.unknown_margin = _length(unknown_margin, "unknown_margin")
        self.reach = _length(reach, "reach")
        q0 = scene.flat_q(scene.default_q())
        poses = self._kin.link_poses(q0) if self._kin is not None else {}
        offsets, k = {}, 0
        for name, rob in scene.robots.items():
            offsets[name] = k
            k += len(rob.joint_names)
        self.n_q = k
        chains = {}
        owners, items, lever = [], [], []
        for it in scene.shapes_at(q0, poses=poses):
            if it.kind not in ("link", "payload") or (robot is not None and it.robot != robot):
                continue
            rob = scene.robots[it.robot]
            li = rob.link_index(it.link)
            X_WL = poses[it.robot][li]
            X_LW = _inv(X_WL)
            items.append((it.robot, li, it.shape.transformed(X_LW), link_volume(it.shape).transformed(X_LW)))
            owners.append(it.owner)
            ch = chains.get(it.robot) or chains.setdefault(
                it.robot, chain_bounds(rob, tol, fk=functools.partial(self._kin.robot_link_poses, it.robot)))
            row = np.zeros(self.n_q)
            k0 = offsets[it.robot]
            row[k0:k0 + len(rob.joint_names)] = ch.lever(it.link, shape_radius_about([it.shape], X_WL[:3, 3]))
            lever.append(row)
        if not items:
            raise TerrainError("TerrainGuard: no moving shape to check (no link with collision geometry)")
        self.owners = tuple(owners)
        self._items = items
        self._prepare_arrays()
        self.lever = np.array(lever)
        self.lever.flags.writeable = False
        m = terrain.map
        ny, nx = m.shape
        (x0, y0), c = m.origin, m.cell
        x1, y1 = x0 + nx * c, y0 + ny * c
        self._map_xy = (x0, y0, x1, y1)
        top = float(np.max(m.heights))
        zc, zh = 0.5 * (m.floor + top), max(0.5 * (top - m.floor), tol.length)
        O = _OUTSIDE
        self._slabs = tuple(Box([cx, cy, zc], [hx, hy, zh]) for cx, cy, hx, hy in (
            (0.5 * (x0 + x1), y0 - 0.5 * O, 0.5 * (x1 - x0) + O, 0.5 * O),  # south (y < y0), corners included
            (0.5 * (x0 + x1), y1 + 0.5 * O, 0.5 * (x1 - x0) + O, 0.5 * O),  # north
            (x0 - 0.5 * O, 0.5 * (y0 + y1), 0.5 * O, 0.5 * (y1 - y0)),      # west
            (x1 + 0.5 * O, 0.5 * (y0 + y1), 0.5 * O, 0.5 * (y1 - y0))))     # east

    def __repr__(self) -> str:
        return f"TerrainGuard({getattr(self.scene, 'name', 'scene')!r}, {len(self.owners)} moving shapes, {self.pyramid!r})"

    # ------------------------------------------------------------------ posing
    def flat_q(self, q) -> np.ndarray:
        """``q`` (a mapping robot -> joints, or flat over ``scene.joint_names``) as ``(n_q,) float64``."""
        flat = self.scene.flat_q(q) if isinstance(q, Mapping) else np.asarray(q, dtype=np.float64)
        if flat.shape != (self.n_q,):
            raise TerrainError(f"q: expected {self.n_q} joint values (scene.joint_names), got shape {flat.shape}")
        if not np.all(np.isfinite(flat)):
            raise TerrainError("q: contains NaN or infinite values")
        return flat

    def _prepare_arrays(self) -> None:
        """Each moving shape's hull (vertices, face normals, edge directions, radius) and its
        volume's OBBs in its link frame, concatenated, with the owning item of every row."""
        pts, fns, eds, rad, ps, fs, es = [], [], [], [], [0], [0], [0]
        oc, oh, og, oR, rstart, obb_item, v_item, f_item, e_item = [], [], [], [], [0], [], [], [], []
        for k, (_, _, shape_L, vol_L) in enumerate(self._items):
            p, f, e, r = shape_L._sat
            pts.append(p); fns.append(f.reshape(-1, 3)); eds.append(e.reshape(-1, 3)); rad.append(r)
            ps.append(ps[-1] + len(p)); fs.append(fs[-1] + len(fns[-1])); es.append(es[-1] + len(eds[-1]))
            v_item += [k] * len(p); f_item += [k] * len(fns[-1]); e_item += [k] * len(eds[-1])
            c, h, g, R = local_obbs(vol_L)
            oc.append(c); oh.append(h); og.append(g); oR.append(R)
            rstart.append(rstart[-1] + len(c))
            obb_item += [k] * len(c)
        cat = lambda a: np.ascontiguousarray(np.concatenate(a), dtype=np.float64)  # noqa: E731
        self._pts_L, self._fn_L, self._ed_L = cat(pts), cat(fns), cat(eds)
        self._ra = np.array(rad, dtype=np.float64)
        self._ps, self._fs, self._es = (np.array(x, dtype=np.int64) for x in (ps, fs, es))
        self._v_item, self._f_item, self._e_item = (np.array(x, dtype=np.int64) for x in (v_item, f_item, e_item))
        self._oc, self._oh, self._og, self._oR = cat(oc), cat(oh), cat(og), cat(oR)
        self._rstart = np.array(rstart, dtype=np.int64)
        self._obb_item = np.array(obb_item, dtype=np.int64)
        self._robot_of = [(rname, li) for rname, li, _, _ in self._items]

    def _poses(self, q) -> np.ndarray:
        """``(K, 4, 4)``: the pose in W of each moving shape's link at ``q``."""
        poses = self._kin.link_poses(self.flat_q(q))
        return np.stack([poses[rname][li] for rname, li in self._robot_of])

    def posed(self, q) -> tuple[list, list]:
        """``(volumes, shapes)`` in W at ``q``: each moving shape's low-resolution volume (Box / Prism)
        and its exact shape, in :attr:`owners` order (shape objects: for inspection and the reference
        path; the queries below pose arrays)."""
        X = self._poses(q)
        vols = [vol_L.transformed(X[k]) for k, (_, _, _, vol_L) in enumerate(self._items)]
        shapes = [shape_L.transformed(X[k]) for k, (_, _, shape_L, _) in enumerate(self._items)]
        return vols, shapes

    def _posed_arrays(self, X: np.ndarray, margin: float):
        """Kernel rows of the volumes grown by ``margin`` and the hulls in W, for poses ``X (K, 4, 4)``."""
        R, t = X[:, :3, :3], X[:, :3, 3]
        Ro = R[self._obb_item]
        c = np.einsum("nij,nj->ni", Ro, self._oc) + t[self._obb_item]
        rows = pack_obbs(c, self._oh + margin * self._og, np.matmul(Ro, self._oR), self.tol.parallel)
        pa = np.einsum("nij,nj->ni", R[self._v_item], self._pts_L) + t[self._v_item]
        fa = np.einsum("nij,nj->ni", R[self._f_item], self._fn_L)
        ea = np.einsum("nij,nj->ni", R[self._e_item], self._ed_L)
        return rows, pa, fa, ea

    # ------------------------------------------------------------------ queries
    def _range(self, threshold: float, stopping: float) -> float:
        return max(self.reach, max(threshold, stopping) + self.unknown_margin)

    def distances(self, q, *, reach: float | None = None):
        """Per moving shape, its least distance to a known column and to an unknown one (a filled
        cell or the off-map slabs), each ``(K,) float64, m``, ``inf`` beyond ``reach`` (default: the
        guard's).  Also returns the pyramid's descent (a :class:`TerrainResult`, candidates only)
        and, per shape, the nearest known and unknown ``(row, col)`` (``-1``: none or off the map)
        with the witness points ``(K, 2, 6)`` of both minima."""
        rng = self._range(self.threshold, self.stopping_distance) if reach is None else _length(reach, "reach")
        X = self._poses(q)
        rows, pa, fa, ea = self._posed_arrays(X, rng)
        res = self.pyramid.check_packed(rows, self._rstart)
        K = len(self._items)
        m = self.pyramid.map
        ci, link = np.nonzero(res.cell_links)
        rc = res.cells_hit[ci]
        lo = np.empty((len(ci), 3))
        lo[:, 0] = m.origin[0] + rc[:, 1] * m.cell
        lo[:, 1] = m.origin[1] + rc[:, 0] * m.cell
        lo[:, 2] = m.floor
        hi = lo + m.cell
        hi[:, 2] = m.heights[rc[:, 0], rc[:, 1]]
        d = np.empty(len(ci))
        w = np.empty((len(ci), 6))
        tl = self.tol
        bad = column_distances(pa, self._ps, fa, self._fs, ea, self._es, self._ra, link.astype(np.int64), lo, hi,
                               tl.length, d, w, tl.length, tl.parallel, tl.gjk_epsilon, tl.gjk_max_iterations,
                               tl.penetration_witness_offset)
        if bad >= 0:
            raise TerrainError("a convex distance kernel did not converge (GJK iteration limit); no verdict")
        out = np.full((2, K), np.inf)
        cell = np.full((2, K, 2), -1, np.int64)
        wit = np.zeros((2, K, 6))
        unk = ~m.known[rc[:, 0], rc[:, 1]]
        for u in (0, 1):
            sel = np.flatnonzero((unk == bool(u)) & (d <= rng))
            if len(sel):
                order = sel[np.lexsort((d[sel], link[sel]))]
                first = order[np.r_[True, link[order][1:] != link[order][:-1]]]
                out[u, link[first]] = d[first]
                cell[u, link[first]] = rc[first]
                wit[u, link[first]] = w[first]
        x0, y0, x1, y1 = self._map_xy
        lo_k = np.minimum.reduceat(pa[:, :2], self._ps[:-1], axis=0) - (self._ra + rng)[:, None]
        hi_k = np.maximum.reduceat(pa[:, :2], self._ps[:-1], axis=0) + (self._ra + rng)[:, None]
        edge = (lo_k[:, 0] < x0) | (lo_k[:, 1] < y0) | (hi_k[:, 0] > x1) | (hi_k[:, 1] > y1)
        for k in np.flatnonzero(edge):  # near the map's edge: the off-map slabs
            shape = self._items[k][2].transformed(X[k])
            for slab in self._slabs:
                ds = distance(shape, slab, tol=self.tol)
                if ds.distance <= rng and ds.distance < out[1, k]:
                    out[1, k] = ds.distance
                    cell[1, k] = -1
                    wit[1, k] = np.r_[ds.p_WA, ds.p_WB]
        return out[0], out[1], res, cell, wit

    def check(self, q, *, threshold: float | None = None, stopping_distance: float | None = None) -> TerrainReport:
        """The terrain category at ``q`` (see :class:`TerrainReport`)."""
        from ..detect import Status

        t0 = time.perf_counter()
        thr = self.threshold if threshold is None else _length(threshold, "threshold")
        sd = self.stopping_distance if stopping_distance is None else _length(stopping_distance, "stopping_distance")
        rng = self._range(thr, sd)
        known, unknown, res, cell_ku, wit = self.distances(q, reach=rng)
        dk, du = float(np.min(known)), float(np.min(unknown))
        level = max(self.tol.length, sd)
        if dk <= level:
            status = Status.COLLISION
        elif du <= thr + self.unknown_margin:
            status = Status.INCOMPLETE
        elif dk <= thr:
            status = Status.WARNING
        else:
            status = Status.CLEAR
        per = {}
        for o, a, b in zip(self.owners, known, unknown):
            per[o] = min(per.get(o, math.inf), float(a), float(b))
        link = cell = pA = pB = None
        unk = False
        # the pair named: for a COLLISION the known column that makes it (a deeper unknown column beside it was
        # named, as if the contact were with unseen ground), else the nearest of all
        side = known if status is Status.COLLISION else None
        d = min(dk, du) if side is None else float(np.min(side))
        if math.isfinite(d):
            both = np.minimum(known, unknown) if side is None else side
            k = int(np.argmin(both))
            u = int(unknown[k] < known[k]) if side is None else int(side is unknown)
            unk = bool(u)
            rc = cell_ku[u, k]
            cell = None if rc[0] < 0 else (int(rc[0]), int(rc[1]))
            link, pA, pB = self.owners[k], wit[u, k, :3].copy(), wit[u, k, 3:].copy()
            pA.flags.writeable = pB.flags.writeable = False
        return TerrainReport(status, d, dk, du, link, cell, unk, pA, pB, per, res.level, res.boxes_tested, res.tests,
                             thr, sd, rng, self.unknown_margin, (time.perf_counter() - t0) * 1e6,
                             self.pyramid.map.shape[1])

    def collides_many(self, Q, *, stopping_distance: float | None = None) -> np.ndarray:
        """``(M,) bool``: some moving shape within the collision level of a known or filled column, per
        row of ``Q`` ``(M, n_q)``: the pyramid's yes/no descent on the volumes (``first=True``), confirmed
        by the exact distances only where it hits.  ``stopping_distance``: the guard's own by default."""
        Q = np.asarray(Q, dtype=np.float64)
        if Q.ndim != 2 or Q.shape[1] != self.n_q:
            raise TerrainError(f"Q: expected shape (M, {self.n_q}), got {Q.shape}")
        sd = self.stopping_distance if stopping_distance is None else _length(stopping_distance, "stopping_distance")
        level = max(self.tol.length, sd)
        out = np.zeros(len(Q), bool)
        for i, q in enumerate(Q):
            rows = self._posed_arrays(self._poses(q), level)[0]
            if self.pyramid.check_packed(rows, self._rstart, first=True).cells_hit.size:
                known, unknown = self.distances(q, reach=level)[:2]
                out[i] = min(float(known.min()), float(unknown.min())) <= level
        return out
