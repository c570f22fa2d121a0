"""The clip backend: Smith's yes / no / maybe clipping checker over a Model's active pairs.

Every active pair of the Model (:attr:`armguard.model.Model.pairs`) is answered by
:mod:`armguard.clip`'s 8-step procedure (with the second-level shell cells SRI did not build):
one side is the guarded test object ``VOL`` (a :class:`armguard.clip.Guard`), the other the
obstacle ``OB`` clipped against the guard's planes.

**Which side is the guard.**  For each pair the guard is, in this order of preference:

1. a curved shape (Sphere, Capsule) — a guard holds it exactly (its inner and outer polytopes
   and the labelled shell between them), whereas a curved obstacle has to be bracketed (below);
2. the moving side (a link or a payload: the paper's ``VOL`` is the moving part of the arm)
   over a static body;
3. side A of the Model's pair (the link of an arm–arm or arm–payload pair).

A shape without volume (a Polygon) is never the guard, and a Cylinder only when the other side
cannot be one (a cylinder against a cylinder or a polygon): its guard's outer prism reaches
``Tolerances.clip_chord`` beyond it, so its shell has corners the second level leaves MAYBE,
where bracketing it as an obstacle settles more.  So a capsule link against a box table
guards the capsule; a box tool against a capsule link (moving–moving) guards the capsule; two
capsule links guard side A.  The obstacle is built once in its own frame (W for a static body,
its link frame for a link, the holding link's frame for a payload) and each configuration poses
the guard relative to it, ``X_OB_VOL = X_W_OB⁻¹ X_W_VOL`` (the procedure depends only on that
relation — Smith's step 1, ``REL``).  Guards are built once per link shape, in the link frame,
and re-posed per configuration.

**A curved obstacle** (both sides curved: capsule against capsule; or a cylinder) is bracketed by
polytopes ``PI ⊂ shape ⊂ PO``: a sphere's or capsule's own guard polytopes
(:data:`BRACKET_RINGS` surface sampling), a cylinder's inscribed and circumscribed ``n``-gon
prisms (Smith §IV's segments and ruled strips, ``n`` from ``Tolerances.clip_chord``:
:func:`armguard.clip.curved_polytopes`).  CLEAR against ``PO`` proves CLEAR, INTERSECTED against
``PI`` proves INTERSECTED, anything else is MAYBE — so the chord tolerance costs MAYBE answers
in a band about the shape, never a wrong one.

**The workspace box** (solid outside the box, as coal's six half-spaces) is a clipping volume of
six planes: a convex shape stays inside exactly when its support along each wall's outward
normal does (``max`` over the posed core points plus the core radius), so workspace pairs are
always definite; touching (within ``Tolerances.clip_plane``) counts as a collision.

**The MAYBE policy.**  :meth:`ClipChecker.verdicts` answers the three values per configuration
(INTERSECTED if any pair is, else MAYBE if any pair is, else CLEAR); :meth:`ClipChecker.collides`
answers True for INTERSECTED **and for MAYBE** — conservative: a MAYBE is never reported clear.
The backend answers verdicts only (``capabilities = {VERDICTS}``): asking it for distances
(``pair_distances``, ``nearest``, ``min_distance_many``) raises BackendError naming that.

Options: ``subdivide`` (true or false, default true: the second level), ``inner_scale`` (in (0, 1)),
``max_depth`` (an integer >= 0), ``rings`` (``[points per ring, rings per quarter meridian]``, or the
text ``"16,4"`` from ``--backend-option clip.rings=16,4``; passed to
:meth:`armguard.clip.Guard.from_shape`), ``bracket_rings`` (curved obstacles' surface sampling,
default :data:`BRACKET_RINGS`).  A value of another kind is refused naming the option.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from armguard._errors import BackendError, ClipError
from armguard._tolerance import DEFAULT_TOLERANCES
from armguard._values import number
from armguard.backends import Capability, CheckerBase, check_margin, check_Q
from armguard.clip import DEFAULT_INNER_SCALE, DEFAULT_MAX_DEPTH, DEFAULT_RINGS, ClipStatus, Guard, Obstacle, curved_polytopes
from armguard.clip._kernels import procedure_many
from armguard.geometry import Capsule, Cylinder, Polygon, Sphere
from armguard.kinematics import invert_pose
from armguard.model import WORKSPACE

__all__ = ["ClipBackend", "ClipChecker", "ClipBatch", "BRACKET_RINGS", "CODES", "STATUS"]

BRACKET_RINGS = (16, 4)
"""A curved obstacle's bracketing polytopes: ``(points per ring, rings per quarter meridian)``
of :meth:`Guard.from_shape`.  Finer than a guard's default (the bracket has no shell cells to
settle the band between ``PI`` and ``PO``): the band is about 2 % of the radius."""

CODES = {ClipStatus.CLEAR: 0, ClipStatus.INTERSECTED: 1, ClipStatus.MAYBE: 2}
"""``ClipStatus -> int8`` (the kernels' codes)."""

STATUS = np.array([ClipStatus.CLEAR, ClipStatus.INTERSECTED, ClipStatus.MAYBE], dtype=object)
"""``int8 code -> ClipStatus`` (index with a code array to get an enum array)."""

_CLEAR, _HIT, _MAYBE = 0, 1, 2
_OPTIONS = ("bracket_rings", "inner_scale", "max_depth", "rings", "subdivide")


def _flag(v, name: str) -> bool:
    """An option that is true or false (``"no"`` was read as True)."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    raise BackendError(f"clip: option {name}: expected true or false, got {v!r}")


def _fraction(v, name: str) -> float:
    """An option in (0, 1) (text too: ``--backend-option inner_scale=0.5``)."""
    return number(v, f"clip: option {name}", BackendError, low=0.0, high=1.0, low_open=True, high_open=True, text=True)


def _count(v, name: str) -> int:
    """An option that is an integer >= 0."""
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
        raise BackendError(f"clip: option {name}: expected an integer >= 0, got {v!r}")
    return int(v)


def _rings(v, name: str) -> tuple:
    """A curved shape's sampling: ``[points per ring (>= 3), rings per quarter meridian (>= 1)]``, or the text
    ``"16,4"`` (``--backend-option clip.rings=16,4``)."""
    try:
        n, m = (int(x) for x in v.strip("[]() ").split(",")) if isinstance(v, str) else v
    except (TypeError, ValueError):
        n = m = None
    if any(isinstance(x, bool) or not isinstance(x, (int, np.integer)) for x in (n, m)) or n < 3 or m < 1:
        raise BackendError(f"clip: option {name}: expected [points per ring >= 3, rings per quarter meridian >= 1] "
                           f"(or the text '16,4'), got {v!r}")
    return (int(n), int(m))


@dataclass(frozen=True)
class ClipBatch:
    """Verdicts for ``M`` configurations and the Model's ``P`` active pairs.

    ``pair_codes (M, P) int8``: each pair's code (0 CLEAR, 1 INTERSECTED, 2 MAYBE) with the second
    level when it was asked for; ``pair_codes_8 (M, P) int8``: the same after the 8 steps alone
    (as SRI ran it); ``pair_steps (M, P) int8``: the deciding step (3-9, ``armguard.clip.STEP_NAMES``;
    0 for the workspace walls and for bracketed pairs, decided outside the procedure);
    ``codes (M,) int8``: per configuration, INTERSECTED if any pair is, else MAYBE if any is,
    else CLEAR.
    """

    pair_codes: np.ndarray
    pair_codes_8: np.ndarray
    pair_steps: np.ndarray
    codes: np.ndarray

    @property
    def status(self) -> np.ndarray:
        """``(M,)`` object array of :class:`ClipStatus`."""
        return STATUS[self.codes]

    @property
    def codes_8(self) -> np.ndarray:
        """``(M,) int8``: the per-configuration verdict after the 8 steps alone."""
        return _combine(self.pair_codes_8)

    def maybe_share(self, *, second_level: bool = True, per: str = "configuration") -> float:
        """Share of MAYBE answers, per ``"configuration"`` or per ``"pair"`` check, with or
        without the second level."""
        if per == "configuration":
            c = self.codes if second_level else self.codes_8
        elif per == "pair":
            c = self.pair_codes if second_level else self.pair_codes_8
        else:
            raise BackendError(f"maybe_share: per must be 'configuration' or 'pair', got {per!r}")
        return float(np.mean(c == _MAYBE)) if c.size else 0.0


def _combine(pair_codes: np.ndarray) -> np.ndarray:
    hit = np.any(pair_codes == _HIT, axis=1)
    maybe = np.any(pair_codes == _MAYBE, axis=1)
    return np.where(hit, _HIT, np.where(maybe, _MAYBE, _CLEAR)).astype(np.int8)


def _curved(shape) -> bool:
    return isinstance(shape, (Sphere, Capsule, Cylinder))


@dataclass(frozen=True)
class _Geom:
    name: str
    frame: int  # index into the checker's moving frames, -1: W (static)
    shape: object  # in the frame
    side_a: bool


@dataclass(frozen=True)
class _Plan:
    kind: str  # "clip", "bracket", "workspace"
    guard: _Geom
    obstacle: _Geom | None


class ClipChecker(CheckerBase):
    """A verdicts-only Checker over :mod:`armguard.clip` (see the module docstring)."""

    name = "clip"
    capabilities = frozenset({Capability.VERDICTS})

    def __init__(self, model, options: Mapping | None = None) -> None:
        super().__init__(model)
        opts = dict(options or {})
        unknown = sorted(set(opts) - set(_OPTIONS))
        if unknown:
            raise BackendError(f"clip: unknown options {unknown}; options are {list(_OPTIONS)}")
        self.subdivide = _flag(opts.get("subdivide", True), "subdivide")
        self._guard_opts = {"inner_scale": _fraction(opts.get("inner_scale", DEFAULT_INNER_SCALE), "inner_scale"),
                            "max_depth": _count(opts.get("max_depth", DEFAULT_MAX_DEPTH), "max_depth"),
                            "rings": _rings(opts.get("rings", DEFAULT_RINGS), "rings")}
        self._bracket_rings = _rings(opts.get("bracket_rings", BRACKET_RINGS), "bracket_rings")
        self.tol = DEFAULT_TOLERANCES
        self.representation = dict(model.notes)
        self._build()

    # ---------------------------------------------------------------- building (once)
    def _build(self) -> None:
        scene = self.model.scene_for()  # the system the Model holds (model.scene may have been edited since)
        self._frames: list[tuple[str, int]] = []  # (robot, link index)
        frame_of: dict[tuple[str, int], int] = {}
        geoms: dict[str, tuple[int, object]] = {}

        def frame(robot: str, li: int) -> int:
            key = (robot, li)
            if key not in frame_of:
                frame_of[key] = len(self._frames)
                self._frames.append(key)
            return frame_of[key]

        for bn, body in scene.bodies.items():
            for i, sh in enumerate(body.shapes):
                geoms[self.model.geometry_name(bn, i)] = (-1, sh)
        for rn, robot in scene.robots.items():
            for li, ln in enumerate(robot.link_names):
                for i, sh in enumerate(robot.link_shapes.get(ln, ())):
                    geoms[self.model.geometry_name(f"{rn}/{ln}", i)] = (frame(rn, li), sh)
        for pn, p in scene.payloads.items():
            f = frame(p.robot, scene.robots[p.robot].link_index(p.link))
            for i, sh in enumerate(p.shapes):
                geoms[self.model.geometry_name(pn, i)] = (f, sh.transformed(p.X_LP))
        self._guards: dict[str, Guard] = {}
        self._guard_cache: dict = {}
        self._obstacles: dict[str, Obstacle] = {}
        self._brackets: dict[str, tuple[Obstacle, Obstacle]] = {}
        self._plans: list[_Plan] = []
        pairs = self.model.pairs
        for a, b in zip(pairs.a, pairs.b):
            ga = _Geom(a, *geoms[a], True)
            if b == WORKSPACE:
                self._plans.append(_Plan("workspace", ga, None))
                self._workspace_core(ga)
                continue
            plan = self._plan(ga, _Geom(b, *geoms[b], False))
            self._plans.append(plan)
            try:
                if plan.guard.name not in self._guards:
                    self._guards[plan.guard.name] = self._guard(plan.guard.shape, **self._guard_opts)
                ob = plan.obstacle
                if plan.kind == "bracket" and ob.name not in self._brackets:
                    if isinstance(ob.shape, Cylinder):
                        outer, inner, _ = curved_polytopes(ob.shape, self.tol.clip_chord, max_sides=self.tol.max_prism_sides)
                    else:
                        g = self._guard(ob.shape, rings=self._bracket_rings, max_depth=0)  # no cells: only PO and PI
                        outer, inner = g.outer, g.inner
                    self._brackets[ob.name] = (Obstacle.from_shape(outer, name=ob.name), Obstacle.from_shape(inner, name=ob.name))
                elif plan.kind == "clip" and ob.name not in self._obstacles:
                    self._obstacles[ob.name] = Obstacle.from_shape(ob.shape, name=ob.name)
            except ClipError as exc:
                raise BackendError(f"clip: pair ({a}, {b}): {exc}") from exc
        ws = scene.workspace
        self._ws = None if ws is None else (np.asarray(ws.lo, float), np.asarray(ws.hi, float))

    def _guard(self, shape, **options) -> Guard:
        """One Guard per distinct shape in its frame (the arms of a scene often share link shapes)."""
        key = (pickle.dumps(shape), tuple(sorted(options.items())))
        g = self._guard_cache.get(key)
        if g is None:
            g = self._guard_cache[key] = Guard.from_shape(shape, tol=self.tol, **options)
        return g

    @staticmethod
    def _plan(ga: _Geom, gb: _Geom) -> _Plan:
        def rank(g: _Geom):  # higher is the better guard (the module docstring's order)
            return (_curved(g.shape), g.frame >= 0, g.side_a)

        cands = [g for g in (ga, gb) if not isinstance(g.shape, (Polygon, Cylinder))]
        cands = cands or [g for g in (ga, gb) if not isinstance(g.shape, Polygon)]
        if not cands:
            raise BackendError(f"clip: pair ({ga.name}, {gb.name}): two shapes without volume (Polygons); no guard")
        guard = max(cands, key=rank)
        ob = gb if guard is ga else ga
        return _Plan("bracket" if _curved(ob.shape) else "clip", guard, ob)

    def _workspace_core(self, g: _Geom) -> None:
        """A link shape's core points and radius for :meth:`_workspace` (its extent along a wall's normal:
        exact for spheres, capsules, boxes and polytopes); a cylinder as ``(centre, axis)`` with its radius
        and half length, whose extent is exact in closed form (its core points are a circumscribed prism, 2 %
        of the radius wide of it: INTERSECTED 1 mm inside the wall)."""
        if not hasattr(self, "_ws_core"):
            self._ws_core: dict[str, tuple] = {}
        sh = g.shape
        if isinstance(sh, Cylinder):
            self._ws_core[g.name] = (np.stack([sh.center, sh.axis]), (float(sh.radius), float(sh.half_length)))
        else:
            self._ws_core[g.name] = (np.atleast_2d(np.asarray(sh.core_points, float)), float(sh.core_radius))

    # ---------------------------------------------------------------- checking
    def _frame_poses(self, Q: np.ndarray) -> np.ndarray:
        """``(n_frames, M, 4, 4)``: each moving frame's pose in W for the rows of ``Q``."""
        fk = self.model.link_poses(self.model.scene_q(Q))  # the Model's kinematics (pin_model)
        out = np.empty((len(self._frames), len(Q), 4, 4))
        for f, (rn, li) in enumerate(self._frames):
            out[f] = fk[rn][:, li]
        return out

    def _run(self, guard: Guard, X_rel: np.ndarray, ob: Obstacle, subdivide: bool) -> tuple[np.ndarray, np.ndarray]:
        M = len(X_rel)
        status = np.empty(M, dtype=np.int8)
        step = np.empty(M, dtype=np.int8)
        procedure_many(guard.pack(), X_rel, ob.pack(), np.eye(4), self.tol.clip_plane, subdivide, status, step)
        return status, step

    def check_pairs(self, Q, *, subdivide: bool | None = None) -> ClipBatch:
        """Every active pair at each row of ``Q (M, nq)`` (pin_model's order): a :class:`ClipBatch`.

        The 8 steps run on every check; the second level (``subdivide``, default the backend's
        option) reruns only the checks the 8 steps left MAYBE."""
        Q = check_Q(self.model, Q)
        sub = self.subdivide if subdivide is None else bool(subdivide)
        M, P = len(Q), len(self._plans)
        X = self._frame_poses(Q) if self._frames else np.empty((0, M, 4, 4))
        X_inv = invert_pose(X) if len(X) else X
        codes8 = np.empty((M, P), dtype=np.int8)
        steps = np.zeros((M, P), dtype=np.int8)
        eye = np.broadcast_to(np.eye(4), (M, 4, 4))

        def rel(plan: _Plan, rows) -> np.ndarray:  # the guard's pose in the obstacle's frame
            g, ob = plan.guard, plan.obstacle
            Xg = X[g.frame, rows] if g.frame >= 0 else eye[rows]
            return np.ascontiguousarray(Xg if ob.frame < 0 else X_inv[ob.frame, rows] @ Xg)

        every = slice(None)
        for k, plan in enumerate(self._plans):
            if plan.kind == "workspace":
                codes8[:, k] = self._workspace(plan.guard.name, X[plan.guard.frame])
            else:
                codes8[:, k], steps[:, k] = self._pair(plan, rel(plan, every), False)
        codes = codes8.copy()
        if sub:
            for k in np.flatnonzero(np.any(codes8 == _MAYBE, axis=0)):
                rows = np.flatnonzero(codes8[:, k] == _MAYBE)
                codes[rows, k], steps[rows, k] = self._pair(self._plans[k], rel(self._plans[k], rows), True)
        return ClipBatch(codes, codes8, steps, _combine(codes) if P else np.zeros(M, np.int8))

    def _pair(self, plan: _Plan, X_rel: np.ndarray, subdivide: bool) -> tuple[np.ndarray, np.ndarray]:
        """Codes and steps of one clip or bracketed pair for the guard poses ``X_rel (m, 4, 4)``
        in the obstacle's frame."""
        guard = self._guards[plan.guard.name]
        if plan.kind == "clip":
            return self._run(guard, X_rel, self._obstacles[plan.obstacle.name], subdivide)
        po, pi = self._brackets[plan.obstacle.name]
        s_out, _ = self._run(guard, X_rel, po, subdivide)
        s_in, _ = self._run(guard, X_rel, pi, subdivide)
        codes = np.where(s_out == _CLEAR, _CLEAR, np.where(s_in == _HIT, _HIT, _MAYBE)).astype(np.int8)
        return codes, np.zeros(len(X_rel), dtype=np.int8)

    def _workspace(self, name: str, Xg: np.ndarray) -> np.ndarray:
        """Codes for one link shape against the workspace walls: INTERSECTED where its support
        along a wall's outward normal reaches the wall (within ``clip_plane``), else CLEAR."""
        core, r = self._ws_core[name]
        lo, hi = self._ws
        if isinstance(r, tuple):  # a cylinder: centre and axis; along e_k it reaches h |a_k| + r sqrt(1 - a_k^2)
            (rad, h), R = r, Xg[:, :3, :3]
            c_W = R @ core[0] + Xg[:, :3, 3]
            a_W = R @ core[1]
            e = h * np.abs(a_W) + rad * np.sqrt(np.maximum(0.0, 1.0 - a_W * a_W))
            top, bottom = c_W + e, c_W - e
        else:
            P_W = np.einsum("mij,vj->mvi", Xg[:, :3, :3], core) + Xg[:, None, :3, 3]  # (M, V, 3)
            top, bottom = P_W.max(axis=1) + r, P_W.min(axis=1) - r
        excess = np.maximum(top - hi, lo - bottom).max(axis=1)
        return np.where(excess >= -self.tol.clip_plane, _HIT, _CLEAR).astype(np.int8)

    def verdicts(self, Q, *, subdivide: bool | None = None) -> np.ndarray:
        """``(M,)`` object array of :class:`ClipStatus` — INTERSECTED / CLEAR / MAYBE per row of ``Q``."""
        return self.check_pairs(Q, subdivide=subdivide).status

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        """``(M,) bool``: True where the verdict is INTERSECTED **or MAYBE** (conservative: a MAYBE
        is never answered clear).  Only ``margin = 0`` (contact): the guards are the shapes."""
        if check_margin(margin) != 0.0:
            raise BackendError(f"clip: answers contact only (margin 0), got margin={margin!r}; "
                               "use a distances backend for a margin")
        return self.check_pairs(Q).codes != _CLEAR

    def pair_distances(self, q):
        """Not answered: this backend answers verdicts only (BackendError)."""
        self._require(Capability.DISTANCES)

    @property
    def plans(self) -> tuple[tuple[str, str, str], ...]:
        """Per Model pair: ``(kind, guard name, obstacle name)`` — kind ``"clip"``, ``"bracket"``
        (curved obstacle) or ``"workspace"`` (obstacle ``"workspace"``)."""
        return tuple((p.kind, p.guard.name, p.obstacle.name if p.obstacle else WORKSPACE) for p in self._plans)


class ClipBackend:
    """Entry point ``clip`` of the group ``armguard.backends``."""

    name = "clip"

    def build(self, model, options: Mapping | None = None) -> ClipChecker:
        return ClipChecker(model, options)
