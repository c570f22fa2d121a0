"""What the console adds to a scene's own checks: a sensed terrain and uncertain placements.

Mixed into :class:`~._state.ConsoleState` (its lock, scene, detector and ``_changed``).

**Terrain** (:meth:`OverlayMixin.set_terrain`): an :class:`armguard.terrain.ElevationMap` is
attached to the console's detector (:func:`armguard.terrain.attach_terrain`, every robot's
moving links), so the panel gets the ``terrain`` category; after each check
:func:`tested_boxes` replays the pyramid's coarse-to-fine descent on the same link volumes and
lists the boxes it visited (by level), which the view draws.

**Uncertain placements** (:meth:`OverlayMixin.set_placements`): bodies or robot bases placed by
an uncertain relation (:class:`armguard.uncertainty.UncertainPlacement`); each update runs
:func:`armguard.uncertainty.clearance_sigmas` on the detector (linearised sigmas and the χ²
bound, no Monte Carlo) and :func:`confidence_ellipsoids` gives each placed origin's position
ellipsoid at :data:`ELLIPSOID_CONFIDENCES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._meshes import link_poses
from ._parse import ConsoleInputError

__all__ = ["OverlayMixin", "TerrainView", "Ellipsoid", "tested_boxes", "confidence_ellipsoids",
           "isotropic_placement", "parse_uncertain", "least_terrain_distance", "depth_is_resolved", "FAR_REACH",
           "MAX_TERRAIN_BOXES", "ELLIPSOID_CONFIDENCES"]

FAR_REACH = 3.0
"""m: how far :func:`least_terrain_distance` looks for the terrain when the check is clear beyond its reach."""
MAX_TERRAIN_BOXES = 400
"""At most this many tested pyramid boxes are drawn (the coarsest first, as the descent visits them)."""
ELLIPSOID_CONFIDENCES = (0.9, 0.999)
"""Confidence levels of the drawn position ellipsoids (3-D: ``k² = χ²₃.ppf(c)``)."""


@dataclass(frozen=True)
class TerrainView:
    """The terrain as the last check saw it.

    ``boxes (n, 6)`` m, rows ``[c_W, h]`` of the pyramid boxes the descent visited (at most
    :data:`MAX_TERRAIN_BOXES`), ``levels (n,)`` their pyramid level (0 the coarsest), ``hit (n,)``
    whether a link volume overlapped the box; ``visited`` every box the descent visited (the
    pyramid's own ``boxes_tested``), ``report`` the :class:`armguard.terrain.TerrainReport`.

    ``far`` ``(distance m, link, limit m)``: when the report is clear beyond its reach (distance ``inf``),
    the least distance of any moving link to the terrain found by :func:`least_terrain_distance`
    (``(inf, None, limit)``: farther than ``limit``, :data:`FAR_REACH`); None otherwise.  ``depth_resolved``: in
    contact, whether the report's depth is the link's true depth into the terrain (the union of
    columns; :func:`depth_is_resolved`) -- False: only a lower bound on it.
    """

    boxes: np.ndarray = field(repr=False)
    levels: np.ndarray = field(repr=False)
    hit: np.ndarray = field(repr=False)
    visited: int
    n_levels: int
    report: object = None
    far: tuple | None = None
    depth_resolved: bool = True


@dataclass(frozen=True)
class Ellipsoid:
    """A placed origin's position ellipsoid: ``center (3,)`` m, ``axes (3, 3)`` (columns: the
    semi-axes, m), at ``confidence``."""

    name: str
    center: np.ndarray
    axes: np.ndarray
    confidence: float


def least_terrain_distance(guard, q, rep, *, limit: float = FAR_REACH) -> tuple[float, str | None]:
    """``(distance m, owner)``: the least exact distance of a moving link to a terrain column (seen,
    unseen or off the map) at ``q``, for a report ``rep`` that is clear beyond its ``reach``: the
    guard's own :meth:`~armguard.terrain.TerrainGuard.distances` with the reach doubled until some
    column is within it, up to ``limit`` (then ``(inf, None)``: farther than ``limit``)."""
    r = max(float(rep.reach), 1e-3)
    while r < limit:
        r = min(2.0 * r, limit)
        known, unknown = guard.distances(q, reach=r)[:2]
        both = np.minimum(known, unknown)
        k = int(np.argmin(both))
        if math.isfinite(both[k]):
            return float(both[k]), guard.owners[k]
    return math.inf, None


def depth_is_resolved(guard, q, rep, *, slack: float = 2e-3) -> bool:
    """Whether a penetrating report's depth ``-rep.distance`` is the nearest link's true depth into
    the terrain (the least translation that frees it from every column), to within ``slack`` m.

    The report's distance is the deepest single column's signed distance (the separating-axis
    depth, :mod:`armguard.terrain._exact`); freeing the link from the union of columns takes at
    least that much, and it is exactly that when moving the link by it (plus ``slack``) along the
    witness direction clears every column -- checked here with the pyramid's exact mode.  A link
    driven deeper into the ground escapes one column sideways but not the terrain, so the depth
    is then only a lower bound (False).  Not in contact: True.  Off the map: False (the slabs
    around the map are not in the pyramid)."""
    if not (rep.distance < 0.0 and rep.p_WA is not None and rep.link is not None):
        return True
    if rep.cell is None:
        return False
    n = np.asarray(rep.p_WB, dtype=np.float64) - np.asarray(rep.p_WA, dtype=np.float64)
    norm = float(np.linalg.norm(n))
    if norm == 0.0:
        return False
    X = np.eye(4)
    X[:3, 3] = n / norm * (-float(rep.distance) + slack)
    vols, shapes = guard.posed(q)
    sel = [k for k, o in enumerate(guard.owners) if o == rep.link]
    res = guard.pyramid.check([vols[k].transformed(X) for k in sel], shapes=[shapes[k].transformed(X) for k in sel],
                              exact=True)
    return res.status.value == "clear"


def tested_boxes(guard, q, threshold: float, stopping_distance: float, *, cap: int = MAX_TERRAIN_BOXES):
    """Replay :meth:`TerrainGuard.check`'s descent at ``q`` and list the boxes it visits.

    The same link rows (the guard's volumes grown by its reach) and the same box test
    (:func:`armguard.terrain._kernels.aabb_obp_overlap`), visited in the kernel's depth-first
    order.  Returns ``(boxes (n, 6), levels (n,), hit (n,), visited)``, the first ``cap`` boxes.
    """
    from ..terrain._kernels import aabb_obp_overlap

    pyr = guard.pyramid
    rng = guard._range(threshold, stopping_distance)
    rows, _, _, _ = guard._posed_arrays(guard._poses(q), rng)
    rstart = guard._rstart
    K = len(rstart) - 1
    L = pyr.n_levels
    out_i, out_l, out_h = [], [], []
    visited = 0
    stack = [(0, 0, 0, (1 << K) - 1)]
    while stack:
        lvl, iy, ix, mask = stack.pop()
        gi = int(pyr.offsets[lvl]) + iy * int(pyr.level_nx[lvl]) + ix
        visited += 1
        hit = 0
        for k in range(K):
            if mask >> k & 1 and aabb_obp_overlap(pyr.boxes, gi, rows, int(rstart[k]), int(rstart[k + 1])):
                hit |= 1 << k
        if len(out_i) < cap:
            out_i.append(gi)
            out_l.append(lvl)
            out_h.append(bool(hit))
        if hit == 0 or lvl == L - 1:
            continue
        ch, cw = int(pyr.level_ny[lvl + 1]), int(pyr.level_nx[lvl + 1])
        for dy in (1, 0):
            for dx in (1, 0):
                cy, cx = 2 * iy + dy, 2 * ix + dx
                if cy < ch and cx < cw:
                    stack.append((lvl + 1, cy, cx, hit))
    idx = np.array(out_i, dtype=np.int64)
    return pyr.boxes[idx].copy(), np.array(out_l, dtype=np.int64), np.array(out_h, dtype=bool), visited


def confidence_ellipsoids(placements, confidences=ELLIPSOID_CONFIDENCES) -> tuple[Ellipsoid, ...]:
    """Each placement's origin position ellipsoid (``Σ_δo``, the translation block of its
    ``cov_origin``) at each confidence: semi-axes ``sqrt(k² λ_i) v_i``, ``k² = χ²₃.ppf(c)``."""
    from scipy import stats

    out = []
    for p in placements:
        w, V = np.linalg.eigh(np.asarray(p.cov_origin)[:3, :3])
        for c in confidences:
            k2 = float(stats.chi2.ppf(float(c), 3))
            out.append(Ellipsoid(p.name, np.array(p.origin, dtype=np.float64),
                                 V * np.sqrt(np.clip(w, 0.0, None) * k2), float(c)))
    return tuple(out)


def _frame_of(scene, name: str) -> np.ndarray:
    """``X_W`` (4, 4) of a placed thing: a robot's base link at home, a body's centroid (axes of W)."""
    X = np.eye(4)
    if name in scene.robots:
        return np.array(link_poses(scene, scene.default_q())[name][0], dtype=np.float64)
    if name in scene.bodies:
        pts = np.concatenate([np.atleast_2d(np.asarray(s.core_points)) for s in scene.bodies[name].shapes])
        X[:3, 3] = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        return X
    raise ConsoleInputError(f"uncertain placement {name!r}: not a body or robot of scene {scene.name!r}; "
                            f"bodies are {list(scene.bodies)}, robots {list(scene.robots)}")


def isotropic_placement(scene, name: str, sigma_m: float, sigma_deg: float = 0.0):
    """An :class:`UncertainPlacement` of body or robot ``name`` with an isotropic spread about its
    own frame (:func:`_frame_of`): ``sigma_m`` m along every axis, ``sigma_deg`` deg about every
    axis (mapped to W's axes by the adjoint, as ``docs/uncertainty.md``'s ``surveyed``)."""
    from ..uncertainty import UncertainPlacement, UncertainPose3, se3

    for v, what in ((sigma_m, "SIGMA_M"), (sigma_deg, "SIGMA_DEG")):
        if not (math.isfinite(v) and v >= 0.0):
            raise ConsoleInputError(f"uncertain placement {name!r}: {what} must be finite and >= 0, got {v}")
    if sigma_m == 0.0 and sigma_deg == 0.0:
        raise ConsoleInputError(f"uncertain placement {name!r}: SIGMA_M and SIGMA_DEG are both 0 (nothing uncertain)")
    T = _frame_of(scene, name)
    Ad = se3.adjoint(T)
    C = np.diag([sigma_m**2] * 3 + [math.radians(sigma_deg) ** 2] * 3)
    return UncertainPlacement(name, UncertainPose3(T, Ad @ C @ Ad.T))


def reanchored(placements, old_scene, new_scene) -> tuple[tuple, list]:
    """``placements`` after a reload from ``old_scene`` to ``new_scene``: each moved with its body or robot base
    (``D = X_new X_old^-1`` applied on the left, the covariance by ``Ad(D)``: the same spread about the moved
    frame; they kept the old pose, so the ellipsoids and sigmas measured from where the body was); a placement
    whose body or robot is gone is dropped.  Returns ``(placements, names dropped)``."""
    from ..uncertainty import UncertainPlacement, UncertainPose3, se3

    kept, dropped = [], []
    for p in placements:
        try:
            D = _frame_of(new_scene, p.name) @ np.linalg.inv(_frame_of(old_scene, p.name))
        except ConsoleInputError:
            dropped.append(p.name)
            continue
        if np.allclose(D, np.eye(4), rtol=0.0, atol=1e-12):
            kept.append(p)
        elif isinstance(p.pose, UncertainPose3):
            Ad = se3.adjoint(D)
            kept.append(UncertainPlacement(p.name, UncertainPose3(D @ p.pose.mean, Ad @ p.pose.cov @ Ad.T)))
        else:  # a planar placement of a body that moved: no planar relation to carry it by
            dropped.append(p.name)
    return tuple(kept), dropped


def split_uncertain(text: str) -> tuple[str, float, float]:
    """``BODY=SIGMA_M[,SIGMA_DEG]`` (the CLI's ``--uncertain``) as ``(BODY, SIGMA_M, SIGMA_DEG)``, the
    sigmas finite, >= 0 and not both 0; the body's name is checked against a scene by :func:`parse_uncertain`."""
    name, eq, spec = str(text).partition("=")
    if not eq or not name.strip():
        raise ConsoleInputError(f"--uncertain: expected BODY=SIGMA_M[,SIGMA_DEG], got {text!r}")
    parts = [x.strip() for x in spec.split(",")]
    if not 1 <= len(parts) <= 2:
        raise ConsoleInputError(f"--uncertain {text!r}: expected SIGMA_M or SIGMA_M,SIGMA_DEG after '='")
    try:
        vals = [float(x) for x in parts]
    except ValueError:
        raise ConsoleInputError(f"--uncertain {text!r}: SIGMA_M and SIGMA_DEG must be numbers (m, deg)") from None
    sigma_m, sigma_deg = vals[0], vals[1] if len(vals) > 1 else 0.0
    for v, what in ((sigma_m, "SIGMA_M"), (sigma_deg, "SIGMA_DEG")):
        if not (math.isfinite(v) and v >= 0.0):
            raise ConsoleInputError(f"--uncertain {text!r}: {what} must be finite and >= 0, got {v}")
    if sigma_m == 0.0 and sigma_deg == 0.0:
        raise ConsoleInputError(f"--uncertain {text!r}: SIGMA_M and SIGMA_DEG are both 0 (nothing uncertain)")
    return name.strip(), sigma_m, sigma_deg


def parse_uncertain(scene, text: str):
    """``BODY=SIGMA_M[,SIGMA_DEG]`` (the CLI's ``--uncertain``, :func:`split_uncertain`) as :func:`isotropic_placement`."""
    return isotropic_placement(scene, *split_uncertain(text))


class OverlayMixin:
    """Terrain and uncertain placements of the console state."""

    _terrain_map = None
    _terrain_view: TerrainView | None = None
    _placements: tuple = ()
    _sigmas = None

    # ------------------------------------------------------------------ terrain
    @property
    def terrain(self):
        """The attached :class:`armguard.terrain.ElevationMap` (None: no terrain)."""
        return self._terrain_map

    def set_terrain(self, elevation) -> None:
        """Check every arm against ``elevation`` (an ElevationMap in W; None detaches)."""
        from ..terrain import ElevationMap

        if elevation is not None and not isinstance(elevation, ElevationMap):
            raise ConsoleInputError(f"terrain: expected an ElevationMap, got {type(elevation).__name__}")
        with self._lock:
            old = self._terrain_map
            self._terrain_map = elevation
            try:
                self._rebuild_detector()
                self._changed("" if elevation is None else f"terrain: {elevation.shape[0]} x {elevation.shape[1]} "
                              f"cells of {elevation.cell:g} m")
            except Exception:
                self._terrain_map = old
                self._rebuild_detector()
                self._evaluate()
                raise

    def _attach_overlays(self) -> None:
        """Called after the detector is (re)built: attach the terrain to it."""
        guard = self._terrain_guard()
        if guard is None:
            return
        from ..terrain import attach_terrain

        attach_terrain(self._detector, guard)

    def _terrain_guard(self):
        """A TerrainGuard of the scene against the loaded terrain (its pyramid built once), or None."""
        if self._terrain_map is None:
            return None
        from ..terrain import TerrainGuard

        pyr = getattr(self, "_pyramid", None)
        if pyr is None or pyr.map is not self._terrain_map:
            from ..terrain import TerrainPyramid

            pyr = self._pyramid = TerrainPyramid(self._terrain_map, tol=self._tol)
        return TerrainGuard(self._scene, pyr, tol=self._tol)

    # ------------------------------------------------------------------ uncertain placements
    @property
    def placements(self) -> tuple:
        return self._placements

    def set_placements(self, placements) -> None:
        """Uncertain placements of bodies or robot bases (UncertainPlacement objects; () clears)."""
        from ..uncertainty import UncertainPlacement

        ps = (placements,) if isinstance(placements, UncertainPlacement) else tuple(placements or ())
        with self._lock:
            old = self._placements
            self._placements = ps
            try:
                self._changed("" if not ps else "uncertain: " + ", ".join(p.name for p in ps))
            except Exception:
                self._placements = old
                self._evaluate()
                raise

    def add_uncertain(self, name: str, sigma_m: float, sigma_deg: float = 0.0) -> None:
        """Add an isotropic placement of ``name`` (:func:`isotropic_placement`), replacing one of that name."""
        from .._values import number

        sigma_m = number(sigma_m, "uncertain placement: sigma", ConsoleInputError, low=0.0, unit=" (m)", text=True)
        sigma_deg = number(sigma_deg, "uncertain placement: sigma_deg", ConsoleInputError, low=0.0, unit=" (deg)", text=True)
        p = isotropic_placement(self._scene, name, sigma_m, sigma_deg)
        self.set_placements(tuple(x for x in self._placements if x.name != name) + (p,))

    def ellipsoids(self) -> tuple[Ellipsoid, ...]:
        """The placed origins' ellipsoids and, for the least-sigmas pair, those of its witness
        point on each placed side (``point_cov``: the rotation's lever arm included), named
        ``"NAME @ nearest"``."""
        from ..uncertainty._checks import _moved_by

        out = list(confidence_ellipsoids(self._placements))
        rep = self._sigmas
        if rep is not None and rep.overall is not None:
            pair = rep.overall.nearest
            for p in self._placements:
                moved = _moved_by(self._scene, p)
                for owner, x in ((pair.a, pair.p_WA), (pair.b, pair.p_WB)):
                    if owner in moved and not ({pair.a, pair.b} <= moved):
                        w, V = np.linalg.eigh(p.point_cov(np.asarray(x, dtype=np.float64)))
                        for c in ELLIPSOID_CONFIDENCES:
                            from scipy import stats

                            k2 = float(stats.chi2.ppf(c, 3))
                            out.append(Ellipsoid(f"{p.name} @ nearest", np.array(x, dtype=np.float64),
                                                 V * np.sqrt(np.clip(w, 0.0, None) * k2), c))
        return tuple(out)

    # ------------------------------------------------------------------ per update
    def _evaluate_overlays(self) -> None:
        """After the panel's check (lock held): the terrain boxes and the sigmas, or None."""
        self._terrain_view = None
        self._sigmas = None
        last, self._last_report = getattr(self, "_last_report", None), None
        backend_terrain, self._backend_terrain = getattr(self, "_backend_terrain", None), None
        if not self._detection:
            return
        guard = getattr(self._detector, "terrain", None)
        if guard is not None:
            q = self._scene.flat_q(self._q)
            boxes, levels, hit, visited = tested_boxes(guard, q, self._threshold, self._stopping)
            rep = getattr(last, "terrain", None) if self._backend == "analytic" else backend_terrain
            if rep is None:
                rep = guard.check(q, threshold=self._threshold, stopping_distance=self._stopping)
            far = None
            if rep is not None and math.isinf(rep.distance):
                far = (*least_terrain_distance(guard, q, rep), FAR_REACH)
            resolved = depth_is_resolved(guard, q, rep) if rep is not None else True
            self._terrain_view = TerrainView(boxes, levels, hit, visited, guard.pyramid.n_levels, rep, far, resolved)
        if self._placements:
            from ..uncertainty import clearance_sigmas

            self._sigmas = clearance_sigmas(self._detector, self._scene.flat_q(self._q), self._placements, samples=0)
