"""The verifier's view of a scene: every checked pair's clearance at a configuration, and how fast it can shrink.

A :class:`ClearanceModel` is built once per (scene, moving robot).  It lists the pairs to
check (Hermes's four checks: link-obstacle, link-link over the listed pairs, payload-obstacle,
payload-link; plus the workspace walls and payload-payload where the scene has them), each
with the moving parts on either side, and evaluates their signed distances at a
configuration through one of two sources:

* the Detector's ``pair_distances(q)`` (the fast path, when :mod:`armguard.detect` provides it);
* the reference: ``scene.shapes_at(q)`` and :func:`armguard.geometry.distance` over
  ``scene.allowed_pairs()`` (slow and obviously correct, the links moved by the Robots' own
  chains rather than by the Model's kinematics: the tests compare the two).

Each moving part (a link with shapes, or a payload carried by a link) gets a lever-arm row
``lever (n_q,)`` from :mod:`._motion`, measured on the Model's forward kinematics
(:meth:`armguard.model.Model.robot_link_poses`, compiled from ``pin_model``): any of its points
moves at most ``|dq| . lever``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..model import kinematics_of, scene_of
from .._errors import StaleModelError, VerificationError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._advance import owner_rows
from ._motion import chain_bounds, relative_joints, shape_radius_about

__all__ = ["ClearanceModel", "CATEGORIES", "CHECKS"]

#: Detector categories, in the order the clearance profile uses.
CATEGORIES = ("arm", "environment", "workspace", "payload")
#: Hermes's checks (plus the workspace walls and payload-payload).
CHECKS = ("link-obstacle", "link-link", "payload-obstacle", "payload-link", "link-workspace", "payload-workspace", "payload-payload")

_SCENE_CATEGORY = {  # scene PairCategory value -> (detector category, Hermes check)
    "arm-arm": ("arm", "link-link"),
    "arm-vehicle": ("environment", "link-obstacle"),
    "arm-environment": ("environment", "link-obstacle"),
    "arm-payload": ("payload", "payload-link"),
    "payload-vehicle": ("payload", "payload-obstacle"),
    "payload-environment": ("payload", "payload-obstacle"),
    "payload-payload": ("payload", "payload-payload"),
}
WORKSPACE = "workspace"


@dataclass(frozen=True)
class _Part:
    owner: str  # "robot/link" or payload name
    kind: str  # "link" or "payload"
    robot: str
    link: str  # the carrying link


class ClearanceModel:
    """Pairs, moving parts and lever arms of ``scene``; evaluates clearances at flat configurations.

    Parameters
    ----------
    scene : armguard.scene.Scene
    source : "auto" | "detector" | "reference"
        Where distances come from (see the module docstring); "auto" takes the detector when
        it offers ``pair_distances`` and the reference otherwise.
    backend, backend_options : str, mapping
        The detector's backend (``armguard.Detector(..., backend=)``): its distances, these bounds.
    """

    def __init__(self, scene, *, source: str = "auto", tol: Tolerances = DEFAULT_TOLERANCES, backend: str | None = None,
                 backend_options=None) -> None:
        kin = kinematics_of(scene)  # what moves the links: the Model's pin_model (None without robots)
        scene = scene_of(scene, "ClearanceModel")  # a Model: its scene
        if source not in ("auto", "detector", "reference"):
            raise VerificationError(f"source: expected one of 'auto', 'detector', 'reference', got {source!r}")
        self.scene = scene
        self.tol = tol
        #: the scene's revision this model was built from (see :meth:`is_stale`)
        self.scene_revision = getattr(scene, "revision", None)
        self.joint_names = tuple(scene.joint_names)
        self.n_q = len(self.joint_names)
        q_home = scene.flat_q(scene.default_q())
        poses = kin.link_poses(q_home) if kin is not None else {}
        items = scene.shapes_at(q_home, poses=poses)
        # moving parts and their lever arms
        parts: dict[str, _Part] = {}
        shapes: dict[str, list] = {}
        for it in items:
            if it.kind in ("link", "payload"):
                parts.setdefault(it.owner, _Part(it.owner, it.kind, it.robot, it.link))
                shapes.setdefault(it.owner, []).append(it.shape)
        self.parts = tuple(parts)
        self._part_index = {o: i for i, o in enumerate(self.parts)}
        offsets, k = {}, 0
        for name, robot in scene.robots.items():
            offsets[name] = k
            k += len(robot.joint_names)
        chains = {name: chain_bounds(robot, tol, fk=functools.partial(kin.robot_link_poses, name))
                  for name, robot in scene.robots.items()}
        lever = np.zeros((len(self.parts) + 1, self.n_q))  # last row: a static body (no motion)
        for i, o in enumerate(self.parts):
            p = parts[o]
            robot = scene.robots[p.robot]
            o_L = poses[p.robot][robot.link_index(p.link)][:3, 3]
            R = shape_radius_about(shapes[o], o_L)
            k0 = offsets[p.robot]
            lever[i, k0 : k0 + len(robot.joint_names)] = chains[p.robot].lever(p.link, R)
        self.lever = lever
        self._part_kind = {o: parts[o].kind for o in self.parts}
        self._part_robot = {o: parts[o].robot for o in self.parts}
        # the pair list
        pa, pb, cat, chk, pcat = [], [], [], [], []
        for cp in scene.allowed_pairs():
            pcat.append(getattr(cp.category, "value", cp.category))
            c, h = _SCENE_CATEGORY[pcat[-1]]
            pa.append(cp.a)
            pb.append(cp.b)
            cat.append(c)
            chk.append(h)
        if scene.workspace is not None:
            for o in self.parts:
                pa.append(o)
                pb.append(WORKSPACE)
                cat.append("workspace")
                pcat.append("workspace")
                chk.append("link-workspace" if parts[o].kind == "link" else "payload-workspace")
        if not pa:
            raise VerificationError("the scene has no pair to check (no moving part with shapes, or every pair disabled)")
        self.owner_a = tuple(pa)
        self.owner_b = tuple(pb)
        self.category = tuple(cat)
        self.check = tuple(chk)
        #: each pair's category as the Model names it (``Model.pairs.category``: "arm-arm", "arm-vehicle", ...)
        self.pair_category = tuple(pcat)
        n_parts = len(self.parts)
        self.index_a = np.array([self._part_index.get(a, n_parts) for a in pa], dtype=np.int64)
        self.index_b = np.array([self._part_index.get(b, n_parts) for b in pb], dtype=np.int64)
        self.category_code = np.array([CATEGORIES.index(c) for c in cat], dtype=np.int64)
        self._pair_key = {(a, b): i for i, (a, b) in enumerate(zip(pa, pb))}
        # each pair's lever row: the joints that can change its two sides' relative pose only
        pair_lever = lever[self.index_a] + lever[self.index_b]
        for i, (a, b) in enumerate(zip(pa, pb)):
            if a in parts and b in parts and parts[a].robot == parts[b].robot:
                r = parts[a].robot
                keep = np.zeros(self.n_q, dtype=bool)
                keep[[offsets[r] + j for j in relative_joints(scene.robots[r], chains[r], parts[a].link, parts[b].link)]] = True
                pair_lever[i, ~keep] = 0.0
        #: ``(P, n_q) m/rad``: a pair's clearance shrinks at most ``pair_lever @ |dq|`` over the joint step ``dq``
        self.pair_lever = pair_lever
        self._fixed: dict = {}  # robot -> (other robots' joints, full clearances there)
        self._backend = (backend, backend_options)
        self.source = self._pick_source(source)
        self.evaluations = 0

    def is_stale(self) -> bool:
        """True when the scene changed (a body added, a pair disabled, ...) after this model was built."""
        return getattr(self.scene, "revision", None) != self.scene_revision

    def _checked(self, fn, *args, **kwargs):
        """``fn(*args, **kwargs)`` if the scene is still the one this model was built from when it
        returns; else :class:`StaleModelError`, also in place of any error ``fn`` raised (rows of
        another scene do not fit this model's).  Checked after the answer: a source that follows scene
        edits (the Detector rebuilds on its next call) can only have answered for a newer scene if the
        revision had changed before it read the scene (edits hold the scene's lock while they change it
        and its revision), so an unchanged revision afterwards proves every row is of this model's pairs."""
        try:
            out = fn(*args, **kwargs)
        except Exception:
            self._refuse_if_stale()
            raise
        self._refuse_if_stale()
        return out

    def _refuse_if_stale(self) -> None:
        if getattr(self.scene, "revision", None) != self.scene_revision:
            raise StaleModelError(
                f"scene {getattr(self.scene, 'name', 'scene')!r} changed (revision {self.scene_revision} -> "
                f"{getattr(self.scene, 'revision', None)}) since this ClearanceModel was built: its pairs are no "
                "longer the scene's; build a new one (Verifier and Guard do so themselves)")

    # ----------------------------------------------------------------- sources
    def _pick_source(self, source: str) -> str:
        if source == "reference":
            return "reference"
        try:
            from ..detect import Detector  # noqa: F401
        except ImportError:
            if source == "detector":
                raise VerificationError("source='detector': armguard.detect is not available") from None
            return "reference"
        try:
            from ..detect import Detector

            det = Detector(self.scene, threshold=0.0, tol=self.tol, backend=self._backend[0],
                           backend_options=self._backend[1])
            long = getattr(getattr(det, "checker", None), "distances_may_run_long", False)
            if not hasattr(det, "pair_distances"):
                raise AttributeError("pair_distances")
            res = det.pair_distances(self.scene.flat_q(self.scene.default_q()))
            self._det = det
            self._det_map = self._map_detector_pairs(res)
        except (AttributeError, TypeError, VerificationError):
            if source == "detector":
                raise
            return "reference"
        if long:  # python-fcl's GJK stops early: a distance longer than the true one proves no clearance (a margin
            # 0.5 mm inside its error was verified SAFE, the "proven" bound above the true minimum)
            raise VerificationError(f"backend {det.backend!r}: its distances may run long (an early-stopping GJK), so "
                                    "they bound no clearance from below; certified verification, edges and guards need "
                                    "distances that do: use analytic or coal")
        return "detector"

    def _map_detector_pairs(self, res) -> np.ndarray:
        """Index of each detector pair in this model's pair list (verifies the detector checks the same pairs)."""
        idx = np.empty(len(res.distance), dtype=np.int64)
        for k, (a, b) in enumerate(zip(res.owner_a, res.owner_b)):
            a, b = str(a), str(b)
            i = self._pair_key.get((a, b), self._pair_key.get((b, a)))
            if i is None:
                raise VerificationError(f"detector pair ({a}, {b}) is not among the scene's allowed pairs")
            idx[k] = i
        if len(set(idx.tolist())) != len(self.owner_a):
            raise VerificationError("the detector does not check every pair the scene lists")
        self._det_perm = len(idx) == len(self.owner_a)
        return idx

    def distances(self, q: np.ndarray, robot: str | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Clearance of every pair at the flat configuration ``q`` ``(n_q,)``.

        Returns ``(distance (P,) m, p_WA (P, 3) m, p_WB (P, 3) m)`` in this model's pair order;
        ``distance`` is the minimum over the shapes of the two owners (signed).  ``robot``: the
        moving robot, when only its joints change between calls: the detector then evaluates only
        the pairs with a side on it, and the others are taken from the last full evaluation at the
        same joints of the other robots (they cannot have changed).  After a scene edit (on any thread,
        even during the call): :class:`armguard.StaleModelError`, never rows of another scene.

        ``evaluations`` counts the calls: a statistic of the model's life (under calls from several
        threads an increment may be lost); a verification counts its own.
        """
        self.evaluations += 1
        return self._checked(self._distances, q, robot)

    def _distances(self, q: np.ndarray, robot: str | None):
        if self.source == "detector" and robot is not None and self._det_perm:
            return self._moving_distances(q, robot)
        if self.source == "detector":
            res = self._det.pair_distances(q)
            dist = np.asarray(res.distance, dtype=np.float64)
            if self._det_perm:
                d = np.empty(len(self.owner_a))
                d[self._det_map] = dist
                pA = np.empty((len(d), 3))
                pB = np.empty((len(d), 3))
                pA[self._det_map] = res.p_WA
                pB[self._det_map] = res.p_WB
                return d, pA, pB
            # several shape pairs per owner pair: keep the nearest of each (NaN where one is NaN)
            if len(dist) != len(self._det_map):  # the detector follows an edited scene: not these pairs
                self._refuse_if_stale()
                raise VerificationError(f"the detector answered {len(dist)} pairs, not this model's {len(self._det_map)}")
            ev = np.empty((len(dist), 7))
            ev[:, 0], ev[:, 1:4], ev[:, 4:7] = dist, res.p_WA, res.p_WB
            P = len(self.owner_a)
            d, wit = np.full(P, np.inf), np.zeros((P, 6))
            owner_rows(ev, self._det_map, d, wit)
            return d, wit[:, :3].copy(), wit[:, 3:].copy()
        return self._reference(q)

    def _moving_distances(self, q: np.ndarray, robot: str):
        k0, k1 = self._joint_span(robot)
        key = np.concatenate([q[:k0], q[k1:]]).tobytes()
        fixed = self._fixed.get(robot)
        if fixed is None or fixed[0] != key:
            self.evaluations -= 1  # the full evaluation below counts once, as this call
            d, pA, pB = self.distances(q)
            fixed = (key, d, pA, pB)
            self._fixed[robot] = fixed
            return d.copy(), pA.copy(), pB.copy()
        res = self._det.pair_distances(q, robot=robot)
        idx = self._det_map[res.pair_index]
        d = fixed[1].copy()
        pA = fixed[2].copy()
        pB = fixed[3].copy()
        d[idx] = res.distance
        pA[idx] = res.p_WA
        pB[idx] = res.p_WB
        return d, pA, pB

    def moving_fast_path(self, robot: str | None) -> bool:
        """Whether :meth:`fixed_clearances` + the detector's ``pair_distances(q, robot=)`` serve ``robot``."""
        return self.source == "detector" and robot is not None and self._det_perm

    def fixed_clearances(self, q: np.ndarray, robot: str):
        """The full evaluation at the other robots' joints of ``q`` (cached; not counted as an evaluation).

        Returns ``(distance (P,) m, p_WA (P, 3) m, p_WB (P, 3) m)``, read only: the pairs without a side
        on ``robot`` keep these values while ``robot`` moves.  Only for :meth:`moving_fast_path`.
        """
        k0, k1 = self._joint_span(robot)
        key = np.concatenate([q[:k0], q[k1:]]).tobytes()
        fixed = self._fixed.get(robot)
        if fixed is None or fixed[0] != key:
            n = self.evaluations
            d, pA, pB = self.distances(q)
            self.evaluations = n
            fixed = (key, d, pA, pB)
            self._fixed[robot] = fixed
        return fixed[1], fixed[2], fixed[3]

    def _joint_span(self, robot: str) -> tuple[int, int]:
        k0 = 0
        for name, rob in self.scene.robots.items():
            if name == robot:
                return k0, k0 + len(rob.joint_names)
            k0 += len(rob.joint_names)
        raise VerificationError(f"unknown robot {robot!r}; robots are {list(self.scene.robots)}")

    def reference_distances(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The slow, obviously-correct path: ``shapes_at`` + ``geometry.distance`` over every shape pair
        (:class:`armguard.StaleModelError` after a scene edit, as :meth:`distances`)."""
        return self._checked(self._reference, q)

    def _reference(self, q: np.ndarray):
        from ..geometry import distance

        items = self.scene.shapes_at(q)
        by_owner: dict[str, list] = {}
        for it in items:
            by_owner.setdefault(it.owner, []).append(it.shape)
        ws = self.scene.workspace
        P = len(self.owner_a)
        d = np.full(P, np.inf)
        pA = np.zeros((P, 3))
        pB = np.zeros((P, 3))
        for i, (a, b) in enumerate(zip(self.owner_a, self.owner_b)):
            for sa in by_owner.get(a, ()):
                if b == WORKSPACE:
                    di, wa, wb = _workspace_distance(sa, ws.lo, ws.hi)
                    if di < d[i]:
                        d[i], pA[i], pB[i] = di, wa, wb
                    continue
                for sb in by_owner.get(b, ()):
                    r = distance(sa, sb, tol=self.tol)
                    if r.distance < d[i]:
                        d[i], pA[i], pB[i] = r.distance, r.p_WA, r.p_WB
        return d, pA, pB

    # ----------------------------------------------------------------- motion
    def pair_rates(self, dq: np.ndarray) -> np.ndarray:
        """``(P,) float64, m``: bound on how much each pair's clearance can shrink over the joint step ``dq`` ``(n_q,)``."""
        return self.pair_lever @ np.abs(dq)

    def max_point_speed(self, qdot: np.ndarray) -> float:
        """Bound (m/s) on the speed of the fastest point of any moving part at joint velocity ``qdot`` ``(n_q,)``."""
        return float(np.max(self.lever[:-1] @ np.abs(qdot))) if len(self.parts) else 0.0

    def moves(self, owner: str, k0: int, k1: int) -> bool:
        """Whether the joints ``k0:k1`` of the flat configuration move any point of ``owner`` (a part
        with a lever arm; a body, the workspace or a robot's base link: no)."""
        i = self._part_index.get(owner)
        return i is not None and bool(np.any(self.lever[i, k0:k1] > 0.0))

    def still(self, a: str, b: str) -> bool:
        """Whether no joint of any robot moves owner ``a`` or ``b`` (a base link and its table, the
        workspace walls): no path changes their clearance."""
        return not self.moves(a, 0, self.n_q) and not self.moves(b, 0, self.n_q)

    def moving_pairs(self, robot: str) -> np.ndarray:
        """``(P,) bool``: the pairs with a side on ``robot`` (a link of it, or a payload it carries):
        the only ones its motion can change, and the only ones a verification of it checks."""
        on = np.array([self._part_robot[o] == robot for o in self.parts] + [False], dtype=bool)
        return on[self.index_a] | on[self.index_b]

    def payload_parts(self) -> tuple[str, ...]:
        return tuple(o for o in self.parts if self._part_kind[o] == "payload")


def _workspace_distance(shape, lo: np.ndarray, hi: np.ndarray):
    """Signed distance (m) of a convex shape to the walls of the axis-aligned box [lo, hi]: > 0 inside,
    clear of every wall; < 0 when it sticks out.  Exact: for a wall x = lo_k the distance is
    ``min over the shape of x_k - lo_k``, the shape's support in -e_k."""
    best = np.inf
    pa = pb = None
    for k in range(3):
        for sign, wall in ((-1.0, lo[k]), (1.0, hi[k])):
            e = np.zeros(3)
            e[k] = sign
            s = shape.support(e)  # the point farthest towards this wall
            di = (wall - s[k]) * sign
            if di < best:
                best = di
                pa = s
                pb = s.copy()
                pb[k] = wall
    return best, pa, pb
