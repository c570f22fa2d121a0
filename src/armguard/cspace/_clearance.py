"""What a forbidden-values map is built from: the mapped links, their lever arms, and a clearance hook.

* :func:`map_links` picks the links the map covers (default: every link with geometry that
  joints 1–3 move and no other joint does — HERA's links 1–3) and proves that the other joints
  are irrelevant for them: their lever-arm rows (the verifier's
  :class:`armguard.verify._oracle.ClearanceModel`, built from :func:`armguard.verify._motion.chain_bounds`)
  are exactly zero for every joint but the three, i.e. the links' geometry does not depend on
  them.  A link that another joint moves is refused.
* :func:`box_lever` is the per-joint bound ``(3,) m/rad``: any point of any mapped link moves at
  most ``sum_j |dq_j| lever_j`` for a joint-space step ``dq`` (the bound certified trajectory
  verification steps with), so on a box of half-widths ``h`` about ``c`` every clearance is at
  least ``d(c) - h . lever``.
* :class:`CheckerClearance` is the default clearance hook: ``(Q (M, 3) rad) -> (M,) m``, the
  smallest signed distance between the mapped links and the static obstacles (the scene's
  bodies), from any backend's Checker (``armguard.checker``; the analytic one by default) over
  a Model whose only active pairs are those (:func:`sub_model` of :func:`link_obstacle_scene`).
  :class:`DetectorClearance` is the same from the analytic :class:`armguard.Detector` on a Scene
  alone.  Any callable with that signature can replace them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import scene_of
from .._errors import ForbiddenMapError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["MapLinks", "map_links", "pick_robot", "link_obstacle_scene", "rest_scene", "DetectorClearance", "CheckerClearance",
           "resolve_scene", "sub_model", "checker_over"]


def resolve_scene(model):
    """``(scene, spec)``: ``model`` as a Scene (a built-in name, a ``.yaml`` / ``.urdf`` path, or a Scene) and the
    string it was loaded from (None for a Scene object)."""
    from ..scene import Scene, load_scene

    if isinstance(model, Scene):
        return model, None
    return load_scene(model), str(model)


@dataclass(frozen=True)
class MapLinks:
    """The robot, joints and links a map covers.

    Attributes
    ----------
    robot : str
    joints : (3,) tuple of str
        Joint names of joints 1, 2, 3 (robot joint names).
    joint_index : (3,) tuple of int
        Their positions in the robot's joint vector.
    flat_index : (3,) tuple of int
        Their positions in the scene's flat joint vector.
    links : tuple of str
        Mapped link names (robot link names).
    lever : (3,) float64, m/rad
        Elementwise maximum over the mapped links of their lever-arm rows on joints 1–3.
    """

    robot: str
    joints: tuple
    joint_index: tuple
    flat_index: tuple
    links: tuple
    lever: np.ndarray


def pick_robot(scene, robot: str | None) -> str:
    """``robot``, checked to be in ``scene``; None names the scene's only robot."""
    if robot is None:
        if len(scene.robots) != 1:
            raise ForbiddenMapError(f"robot: the scene has robots {list(scene.robots)}; name one")
        robot = next(iter(scene.robots))
    if robot not in scene.robots:
        raise ForbiddenMapError(f"robot {robot!r} is not in the scene; robots are {list(scene.robots)}")
    return robot


def map_links(scene, robot: str | None, joints=None, links=None, tol: Tolerances = DEFAULT_TOLERANCES) -> MapLinks:
    """Pick and check the mapped links of ``robot`` (see the module docstring)."""
    scene = scene_of(scene, "map")  # a Model: its scene
    from ..verify._oracle import ClearanceModel

    robot = pick_robot(scene, robot)
    rob = scene.robots[robot]
    names = tuple(rob.joint_names)
    joints = tuple(names[:3]) if joints is None else tuple(joints)
    if len(joints) != 3 or len(set(joints)) != 3:
        raise ForbiddenMapError(f"joints: expected three different joints of {robot!r}, got {joints}")
    for j in joints:
        if j not in names:
            raise ForbiddenMapError(f"joint {j!r} is not a joint of {robot!r}; joints are {list(names)}")
    jidx = tuple(names.index(j) for j in joints)
    k0 = 0
    for name, r in scene.robots.items():
        if name == robot:
            break
        k0 += len(r.joint_names)
    fidx = tuple(k0 + j for j in jidx)
    model = ClearanceModel(scene, source="reference", tol=tol)
    parts = {o: model.lever[i] for i, o in enumerate(model.parts) if model._part_kind[o] == "link"}
    own = {o.split("/", 1)[1]: row for o, row in parts.items() if o.split("/", 1)[0] == robot}
    others = np.ones(model.n_q, dtype=bool)
    others[list(fidx)] = False
    if links is None:
        links = tuple(ln for ln in rob.link_names if ln in own and own[ln][list(fidx)].sum() > 0.0
                      and not np.any(own[ln][others] > 0.0))
        if not links:
            raise ForbiddenMapError(f"no link of {robot!r} with geometry is moved by {joints} alone")
    links = tuple(links)
    for ln in links:
        if ln not in rob.link_names:
            raise ForbiddenMapError(f"link {ln!r} is not a link of {robot!r}; links are {list(rob.link_names)}")
        if ln not in own:
            raise ForbiddenMapError(f"link {ln!r} has no geometry: nothing to map")
        moved_by = [scene.joint_names[k] for k in np.flatnonzero(others & (own[ln] > 0.0))]
        if moved_by:
            raise ForbiddenMapError(f"link {ln!r} is also moved by {moved_by}: a map over {joints} cannot cover it")
    lever = np.max(np.stack([own[ln][list(fidx)] for ln in links]), axis=0)
    return MapLinks(robot, joints, jidx, fidx, links, np.ascontiguousarray(lever))


def _owners(robot: str, links) -> set:
    return {f"{robot}/{ln}" for ln in links}


def link_obstacle_scene(scene, robot: str, links):
    """A copy of ``scene`` in which only the pairs (mapped link, static body) are checked (no workspace walls)."""
    sub = scene.copy()
    own = _owners(robot, links)
    for cp in scene.allowed_pairs():
        if not ((cp.a in own and cp.b in scene.bodies) or (cp.b in own and cp.a in scene.bodies)):
            sub.disable_pair(cp.a, cp.b)
    if sub.workspace is not None:
        sub.clear_workspace()
    return sub


def rest_scene(scene, robot: str, links):
    """A copy of ``scene`` in which every pair but (mapped link, static body) is checked (Fig. 14's geometric part)."""
    sub = scene.copy()
    own = _owners(robot, links)
    for cp in scene.allowed_pairs():
        if (cp.a in own and cp.b in scene.bodies) or (cp.b in own and cp.a in scene.bodies):
            sub.disable_pair(cp.a, cp.b)
    return sub


class DetectorClearance:
    """The default clearance hook: ``(Q (M, 3) rad) -> (M,) float64 m``, mapped links vs static bodies.

    The other joints of the scene stay at ``scene.default_q()`` (they do not move the mapped
    links, :func:`map_links`).  A row whose links have no obstacle pair gets ``inf``.

    Parameters
    ----------
    scene : armguard.Scene
    links : MapLinks
    """

    def __init__(self, scene, links: MapLinks, tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        from ..detect import Detector

        self.links = links
        self._scene = link_obstacle_scene(scene, links.robot, links.links)
        self._detector = Detector(self._scene, threshold=0.0, tol=tol)
        self._base = np.asarray(scene.flat_q(scene.default_q()), dtype=np.float64)
        self._cols = np.array(links.flat_index, dtype=np.int64)

    def flat(self, Q3: np.ndarray) -> np.ndarray:
        """``(M, n_q)`` flat scene configurations for ``Q3`` ``(M, 3)`` rad."""
        Q = np.repeat(self._base[None, :], len(Q3), axis=0)
        Q[:, self._cols] = Q3
        return Q

    def __call__(self, Q3: np.ndarray) -> np.ndarray:
        Q3 = np.asarray(Q3, dtype=np.float64).reshape(-1, 3)
        if len(Q3) == 0:
            return np.zeros(0)
        rep = self._detector.check_many(self.flat(Q3))
        return rep.min_distance.min(axis=1)


def sub_model(model, scene):
    """A Model over ``scene`` (a copy of ``model.scene`` with pairs disabled or the workspace cleared) that
    shares ``model``'s Pinocchio model, GeometryModel, q order and files: its active pairs are ``scene``'s.

    Every backend builds its Checker from ``model.pairs``, so a Checker of the sub-Model checks exactly
    those pairs, on the very geometry of ``model`` (no re-export)."""
    from ..model import Model

    names = {}
    for owner in scene.owners():
        i = 0
        while True:
            try:
                names[(owner, i)] = model.geometry_name(owner, i)
            except KeyError:
                break
            i += 1
    return Model(model.name, model.pin_model, model.collision_model, scene, q_index=model.q_index,
                 circular=getattr(model, "_circular", ()), geometry_names=names, notes=model.notes, files=model.files,
                 link_frames=model.link_frames, link_placements={k: model.link_placement(k) for k in model.link_frames})


def checker_over(model, scene, backend, options=None, *, need_distances: bool = False,
                 needs: str = "a map's clearances need"):
    """``armguard.checker`` of ``backend`` over :func:`sub_model` ``(model, scene)``; with ``need_distances``,
    a backend that answers verdicts only is refused (:class:`ForbiddenMapError`; ``needs`` says who needs
    the distances)."""
    from .._errors import DetectionError
    from ..backends import Capability, checker

    sub = sub_model(model, scene)
    if len(sub.pairs) == 0:  # the map's own pairs (links 1-3 vs the static bodies), not the model's
        raise ForbiddenMapError(f"model {model.name!r} has no pair of a mapped link (links 1-3) against a static body: "
                                "a forbidden-values map has nothing to map (its pairs are links 1-3 vs the bodies; "
                                "add a body to the scene)")
    try:
        chk = checker(sub, backend, options)
    except DetectionError as exc:
        raise ForbiddenMapError(f"the map's pairs (links 1-3 vs the static bodies): {exc}") from None
    if need_distances and Capability.DISTANCES not in chk.capabilities:
        raise ForbiddenMapError(f"backend {chk.name!r} answers verdicts only; {needs} signed distances "
                                "(use analytic, coal or another backend that answers distances)")
    return chk


class CheckerClearance:
    """The clearance hook over a backend: ``(Q (M, 3) rad) -> (M,) float64 m``, mapped links vs static bodies.

    The other joints stay at ``model.neutral()`` (they do not move the mapped links, :func:`map_links`).
    The distances are the Checker's ``min_distance_many`` over a Model whose active pairs are (mapped
    link, static body) only; a model without such pairs gets ``inf``.

    Parameters
    ----------
    model : armguard.Model
    links : MapLinks
    backend : str | None
        Any installed backend that answers distances (None: ``armguard.checker``'s precedence).
    options : mapping | None
        The backend's options.
    """

    def __init__(self, model, links: MapLinks, backend: str | None = "analytic", options=None) -> None:
        self.links = links
        self.model = model
        scene = link_obstacle_scene(model.scene_for(), links.robot, links.links)  # the Model as made
        self.checker = checker_over(model, scene, backend, options, need_distances=True)
        self.backend = self.checker.name
        self._empty = len(self.checker.model.pairs) == 0
        self._base = np.asarray(model.neutral(), dtype=np.float64)
        self._cols = np.asarray(model.q_index, dtype=np.int64)[list(links.flat_index)]

    def pin(self, Q3: np.ndarray) -> np.ndarray:
        """``(M, nq)`` configurations in ``pin_model``'s order for ``Q3`` ``(M, 3)`` rad."""
        Q = np.repeat(self._base[None, :], len(Q3), axis=0)
        Q[:, self._cols] = Q3
        return Q

    def __call__(self, Q3: np.ndarray) -> np.ndarray:
        Q3 = np.asarray(Q3, dtype=np.float64).reshape(-1, 3)
        if len(Q3) == 0:
            return np.zeros(0)
        if self._empty:
            return np.full(len(Q3), np.inf)
        return np.asarray(self.checker.min_distance_many(self.pin(Q3)), dtype=np.float64)
