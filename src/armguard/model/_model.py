"""The Model: Pinocchio's model and GeometryModel, the active pairs, and the scene extras."""

from __future__ import annotations

import contextlib
import hashlib
import os
import threading
import types
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import DetectionError
from .._values import refuse_complex_or_bool
from .._tolerance import DEFAULT_TOLERANCES
from . import _joint_limits
from ._entry import scene_of  # re-exported: it was defined here

__all__ = ["Model", "GeometryPairs", "WORKSPACE", "file_sha256", "scene_of"]

WORKSPACE = "workspace"
"""The name of side B of a pair measured against the workspace box's walls (no GeometryObject)."""


_BOUND_LOCK = threading.Lock()  # Model.scene_for: one copy per Model, whichever thread asks first
_TREE_LOCK = threading.Lock()  # Model.kinematic_tree: compiled once per Model and robot set


def file_sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@dataclass(frozen=True)
class GeometryPairs:
    """The active pairs of a Model, in one fixed order every backend answers in.

    ``a``, ``b`` ``(n,)`` GeometryObject names (``b`` is :data:`WORKSPACE` for the workspace box);
    ``owner_a``, ``owner_b`` ``(n,)`` the scene owners (``"robot/link"``, body or payload names);
    ``category`` ``(n,)`` category names (``arm-arm``, ``arm-vehicle``, ``arm-environment``,
    ``arm-payload``, ``payload-*``, ``workspace``): ``collides``' margins may be given by these.
    """

    a: tuple
    b: tuple
    owner_a: tuple
    owner_b: tuple
    category: tuple

    def __len__(self) -> int:
        return len(self.a)

    @property
    def names(self) -> np.ndarray:
        """``(n, 2)`` object array of GeometryObject names, read-only: the checkers hand this array to
        every result they return (``PairDistances.pairs``), so a write into one result's names would
        rename the pair in every later result."""
        out = np.empty((len(self.a), 2), dtype=object)
        out[:, 0], out[:, 1] = self.a, self.b
        out.flags.writeable = False
        return out


def _frozen_spec(scene):
    """A private shallow copy of ``scene`` (its parts are immutable, its containers new): what a
    Model lists its pairs from and its edits start from, whatever the scene does later."""
    spec = scene.copy()
    spec._model_of_record = None
    return spec


def _with_meshes(files, collision_model) -> tuple:
    """``files`` (resolved) then the mesh files the GeometryModel's objects were read from, each once,
    each followed by the files it reads its geometry from (a glTF's buffers)."""
    from ._hull_cache import mesh_dependencies

    out = [Path(p).resolve() for p in files]
    meshes = sorted({Path(go.meshPath).resolve() for go in collision_model.geometryObjects
                     if go.meshPath and os.path.isabs(go.meshPath) and Path(go.meshPath).is_file()})
    return tuple(dict.fromkeys([*out, *(f for m in meshes for f in (m, *(d.resolve() for d in mesh_dependencies(m))))]))


class Model:
    """A robot system as Pinocchio sees it, with what armguard adds.

    Attributes
    ----------
    name : str
    pin_model : pinocchio.Model        kinematics, joint limits, frames (the model of record)
    collision_model : pinocchio.GeometryModel   every shape, as coal geometry (capsules, convex hulls)
    scene : armguard.Scene             the same system as armguard's Scene (robots, bodies, payloads), with
                                       the sidecar's workspace, trajectories and canned tests; its
                                       edits of bodies and payloads make a derived Model
                                       (``model_of``, :mod:`armguard.model._derive`)
    robots, bodies, payloads           what ``pin_model`` moves and the GeometryModel holds (read-only)
    workspace, trajectories, canned_tests   the scene's extras
    pairs : GeometryPairs              the active pairs (SRDF and the papers' rules applied)
    notes : Mapping[str, str]          GeometryObject name -> representation note (where a backend
                                       cannot hold the exact shape)
    files : tuple[Path, ...]           the files it was loaded from (sidecar, URDF, SRDF, then every
                                       mesh file its geometry was read from); ``sha256`` their hashes
    srdf : Srdf or None                the SRDF it was loaded with: ``srdf.file``, ``srdf.found`` (how it
                                       was found, ``docs/models.md``) and ``srdf.warnings``
    hull_cache : Mapping or None       where the mesh hulls came from: ``folder`` (the hull cache,
                                       None when off), ``hits`` (read from it), ``computed``; None
                                       when the model has no mesh
    link_frames : Mapping[str, int]    scene link ``"robot/link"`` -> the ``pin_model`` BODY frame F it is
                                       fixed to: its pose ``X_WL = oMf[F] @ link_placement(link)``
    hulls : Mapping[str, MeshPolytope] GeometryObject name -> the mesh hull its ``coal.Convex`` was built
                                       from (vertices, triangles and merged faces, in the object's
                                       frame; :func:`armguard.model._hull.mesh_polytope`), for meshes
    """

    def __init__(self, name, pin_model, collision_model, scene, *, q_index, geometry_names, notes, files,
                 circular=(), srdf=None, hull_cache=None, link_frames=None, link_placements=None, hulls=None) -> None:
        self.name = str(name)
        self.pin_model = pin_model
        self.collision_model = collision_model
        self.scene = scene
        q_index = np.asarray(q_index, dtype=np.int64)
        q_index.flags.writeable = False
        self._q_index = q_index
        self._circular = np.asarray(circular, dtype=np.int64)  # scene positions of continuous joints
        self._geom = dict(geometry_names)
        self.notes = types.MappingProxyType(dict(notes))
        self.files = _with_meshes(files, collision_model)
        self.srdf = srdf
        self.hull_cache = (types.MappingProxyType({k: v for k, v in hull_cache.items() if k != "sha256"})
                           if hull_cache else None)
        known = dict(hull_cache.get("sha256", {})) if hull_cache else {}  # mesh files the hull cache hashed
        self.sha256 = types.MappingProxyType({str(p): known.get(str(p)) or file_sha256(p) for p in self.files})
        self._pairs = None
        self._spec, self._spec_revision = _frozen_spec(scene), scene.revision  # the system as made: pairs and edits start from it
        self._geom_index = {go.name: i for i, go in enumerate(collision_model.geometryObjects)}
        self.link_frames = types.MappingProxyType(dict(link_frames or {}))
        self._link_placements = {k: np.array(v, dtype=np.float64) for k, v in (link_placements or {}).items()}
        self._robots = tuple(scene.robots.items())  # the Robots pin_model moves (immutable objects)
        self.hulls = types.MappingProxyType(dict(hulls or {}))
        # the bodies and payloads the GeometryModel holds (immutable objects): geometry_is_of(scene)
        self._parts = (tuple(scene.bodies.items()), tuple(scene.payloads.items()))
        scene._model_of_record = self  # model_of(scene) finds it (the scene it built is this model's)

    tol = DEFAULT_TOLERANCES

    # ---------------------------------------------------------------- what it is made of
    @property
    def robots(self) -> types.MappingProxyType:
        """Robot name -> the Robot (kinematic chain, link shapes) ``pin_model`` moves, in q order."""
        return types.MappingProxyType(dict(self._robots))

    @property
    def bodies(self) -> types.MappingProxyType:
        """Body name -> the Body (shapes in W, category) whose objects the GeometryModel holds."""
        return types.MappingProxyType(dict(self._parts[0]))

    @property
    def payloads(self) -> types.MappingProxyType:
        """Payload name -> the Payload (holding link, ``X_LP``, shapes) whose objects it holds."""
        return types.MappingProxyType(dict(self._parts[1]))

    @property
    def workspace(self):
        """The workspace box (``WorkspaceBox``: ``lo``, ``hi`` in W) the pairs are measured against, or
        None: the scene's when this Model was made (see :attr:`pairs`)."""
        return self._spec.workspace

    def is_model_of(self, scene) -> bool:
        """Whether this Model is ``scene`` as it is now: made from it (or handed out for it by
        :meth:`scene_for`) and nothing changed since that :attr:`pairs` or the shapes depend on
        (the scene's ``revision``: robots, bodies, payloads, pair filters, the workspace box)."""
        made = self._spec_revision if scene is self.scene else self.__dict__.get("_bound", (None, None))[1]
        lock = getattr(scene, "lock", None)
        with lock if lock is not None else contextlib.nullcontext():  # no edit while it is compared
            return (scene.revision == made and self.moves_robots_of(scene) and self.geometry_is_of(scene)
                    and self._same_filters(scene))

    def scene_for(self):
        """A copy of the system this Model holds, whose Model is this one (made again once edited): what is
        built on a Model (``scene_of``) answers for it, as its Checkers do, whatever :attr:`scene` does later
        (it was :attr:`scene` while unedited: a Verifier then followed a later edit its Checker missed)."""
        with _BOUND_LOCK:
            bound = self.__dict__.get("_bound")
            if bound is None or getattr(bound[0], "revision", None) != bound[1]:  # none yet, or edited since
                s = self._spec.copy()
                s._model_of_record = self
                bound = self._bound = (s, s.revision)
            return bound[0]

    def _same_filters(self, scene) -> bool:
        s = self._spec
        return (scene._disabled == s._disabled and scene._self_pairs == s._self_pairs
                and scene._exclude_adjacent == s._exclude_adjacent and scene.workspace is s.workspace)

    @property
    def trajectories(self):
        """Name -> the trajectories the model's sidecar or scene file names."""
        return self._spec.trajectories

    @property
    def canned_tests(self):
        """Name -> the canned tests (Ranger's operator checks) of the sidecar or scene file."""
        return self._spec.canned_tests

    def link_placement(self, link: str) -> np.ndarray:
        """``X_FL`` (4, 4): scene link ``link``'s frame in its BODY frame ``link_frames[link]``: the
        identity for a URDF's link; a DH link's ``X_post`` where the scene was written as URDF (the URDF
        link is the joint frame there, :mod:`armguard.model.export`).  A fresh copy."""
        X = self._link_placements.get(link)
        return np.eye(4) if X is None else X.copy()

    def moves_robots_of(self, scene) -> bool:
        """Whether ``pin_model`` is the kinematics of ``scene``'s robots: the scene holds the very
        Robot objects (same names, same order) this Model was built with.  ``set_robot_base``,
        ``add_robot`` (or a copy's own robots) make it False; bodies, payloads and pairs do not."""
        robots = scene.robots
        return len(robots) == len(self._robots) and all(
            a == n and r is self_r for (a, r), (n, self_r) in zip(robots.items(), self._robots))

    def geometry_is_of(self, scene) -> bool:
        """Whether ``collision_model`` holds exactly the shapes of ``scene``: it is this Model's scene,
        with the robots it was built with (:meth:`moves_robots_of`) and the very Body and Payload
        objects (same names, same order).  ``add_body``, ``remove_body``, ``attach_payload``,
        ``grasp``... make it False; pair filters and the workspace box do not."""
        if (scene is not self.scene and scene is not self.__dict__.get("_bound", (None,))[0]) or not self.moves_robots_of(scene):
            return False
        bodies, payloads = self._parts
        return (len(bodies) == len(scene.bodies) and len(payloads) == len(scene.payloads)
                and all(a == n and b is o for (a, b), (n, o) in zip(scene.bodies.items(), bodies))
                and all(a == n and b is o for (a, b), (n, o) in zip(scene.payloads.items(), payloads)))

    # joint limits (armguard.model._joint_limits): Pinocchio's order, and the scene's
    check_pin_limits = _joint_limits.check_pin_limits
    within_pin_limits = _joint_limits.within_pin_limits
    _pin_limit_table = _joint_limits.pin_limit_table
    check_limits = _joint_limits.check_limits

    def __repr__(self) -> str:
        return (f"Model({self.name!r}, nq={self.pin_model.nq}, {self.collision_model.ngeoms} geometries, "
                f"{len(self.pairs)} pairs)")

    # ---------------------------------------------------------------- edits: a new Model each
    def edited(self, edit) -> "Model":
        """A new Model: ``edit(scene)`` applied to a private copy of the system this Model holds (its
        scene as it was when this Model was made: robots, bodies, payloads, pair filters, workspace,
        trajectories, canned tests).  This Model, its scene and the Checkers built on it are left as
        they were; the new one is derived from this one (:mod:`armguard.model._derive`: no URDF
        round trip unless a robot changed other than by ``set_robot_base`` or ``add_robot``).
        The ``with_*`` methods are the common edits."""
        from ._load import model_of

        scene = self._spec.copy()  # what this Model holds, whatever its scene did since
        scene._model_of_record = self
        edit(scene)
        return model_of(scene)

    def with_body(self, name: str, shapes, *, category: str = "environment") -> "Model":
        """This Model with a static body of ``shapes`` (given in W) added (:meth:`Scene.add_body`)."""
        return self.edited(lambda s: s.add_body(name, shapes, category=category))

    def without_body(self, name: str) -> "Model":
        """This Model without body ``name`` (:meth:`Scene.remove_body`)."""
        return self.edited(lambda s: s.remove_body(name))

    def with_payload(self, name: str, robot: str, link: str, shapes, X_LP=None) -> "Model":
        """This Model with ``shapes`` (in frame P) held at ``X_LP`` by ``robot``'s ``link``
        (:meth:`Scene.attach_payload`)."""
        return self.edited(lambda s: s.attach_payload(name, robot, link, shapes, X_LP))

    def with_payload_released(self, name: str, q) -> "Model":
        """WORKMATE's release: payload ``name`` left as a static body where it is at ``q``
        (``(nq,)``, Pinocchio's order; :meth:`Scene.release_payload`)."""
        q_scene = self.scene_q(q)
        return self.edited(lambda s: s.release_payload(name, q_scene))

    def with_grasp(self, body: str, robot: str, link: str, q) -> "Model":
        """WORKMATE's grasp: static ``body`` held by ``robot``'s ``link`` where it is at ``q``
        (``(nq,)``, Pinocchio's order; :meth:`Scene.grasp`)."""
        q_scene = self.scene_q(q)
        return self.edited(lambda s: s.grasp(body, robot, link, q_scene))

    def with_robot_base(self, robot: str, X_WB) -> "Model":
        """This Model with ``robot`` mounted at ``X_WB`` (4, 4) (:meth:`Scene.set_robot_base`)."""
        return self.edited(lambda s: s.set_robot_base(robot, X_WB))

    def with_robot(self, robot, *, home=None) -> "Model":
        """This Model with ``robot`` (a ``Robot``, e.g. ``load_model(...).robots[...]`` or a DH
        table's) added after its own (:meth:`Scene.add_robot`); its joints come after this Model's
        in ``q``."""
        return self.edited(lambda s: s.add_robot(robot, home=home))

    def with_workspace(self, lo, hi) -> "Model":
        """This Model with the workspace box ``lo``, ``hi`` ((3,) m in W; :meth:`Scene.set_workspace`)."""
        return self.edited(lambda s: s.set_workspace(lo, hi))

    def with_pair_disabled(self, a: str, b: str) -> "Model":
        """This Model with owners ``a`` and ``b`` never checked against each other (a robot's name
        stands for all its links; :meth:`Scene.disable_pair`)."""
        return self.edited(lambda s: s.disable_pair(a, b))

    # ---------------------------------------------------------------- configurations
    @property
    def nq(self) -> int:
        return int(self.pin_model.nq)

    @property
    def q_index(self) -> np.ndarray:
        """``(n,) int64``: flat scene q[k] = pinocchio q[q_index[k]] (``scene.joint_names`` order)."""
        return self._q_index

    @property
    def has_continuous_joints(self) -> bool:
        """Whether a joint is continuous (Pinocchio's ``q`` holds its ``(cos, sin)``, the scene's ``q`` its angle)."""
        return len(self._circular) > 0

    @property
    def q_joint_names(self) -> tuple:
        """The name of the joint each position of Pinocchio's ``q`` belongs to, ``(nq,)``."""
        m = self.pin_model
        return tuple(m.names[j] for j in range(1, m.njoints) for _ in range(m.joints[j].nq))

    def q_layout(self, n_got: int | None = None) -> str:
        """Pinocchio's ``q`` in words for an error about a ``q`` of ``n_got`` values: a continuous joint's two
        positions as ``name (cos, sin)``; ``n_got`` joint angles (not ``nq``): ``Model.pin_q`` makes it."""
        circ = {self.pin_model.names[j] for j in range(1, self.pin_model.njoints) if self.pin_model.joints[j].nq == 2}
        names = [f"{n} (cos, sin)" if n in circ else n for n in self.joint_names]
        text = f"{self.nq} values in pin_model's order {names}"
        n_scene = len(self._q_index)
        if circ and n_got == n_scene != self.nq:
            text += (f"; {n_got} values are one angle a joint: Model.pin_q(angles) gives Pinocchio's q "
                     f"(the scene's order {list(self._spec.joint_names)})")
        return text

    @property
    def continuous_q(self) -> np.ndarray:
        """Positions in Pinocchio's ``q`` of each continuous joint's ``cos`` (its ``sin`` follows), ``(k,)`` int64."""
        return self._q_index[self._circular]

    @property
    def q_in_scene_order(self) -> bool:
        """Whether Pinocchio's ``q`` already is the scene's flat ``q``: the same joints in the same
        order, none continuous (then :meth:`scene_q` only copies)."""
        qi = self._q_index
        return not self.has_continuous_joints and len(qi) == self.nq and bool(np.array_equal(qi, np.arange(len(qi))))

    def scene_q(self, q) -> np.ndarray:
        """Pinocchio-ordered ``q`` ``(..., nq)`` -> the scene's flat order ``(..., n)``."""
        refuse_complex_or_bool(q, "q", DetectionError)
        q = np.asarray(q, dtype=np.float64)
        if q.shape[-1:] != (self.nq,):
            raise DetectionError(f"q: expected {self.q_layout(q.shape[-1] if q.ndim else None)}, got shape {q.shape}")
        out = q.take(self._q_index, axis=-1)
        circ = self._circular
        if len(circ):  # continuous joints: pinocchio's (cos, sin) -> the angle
            i = self._q_index[circ]
            c, s = q[..., i], q[..., i + 1]
            with np.errstate(invalid="ignore"):
                off = ~(np.abs(c * c + s * s - 1.0) <= _joint_limits.UNIT_CIRCLE)  # (0, 0) was angle 0, (-0, -0) -pi, NaN passed
            if off.any():
                where = np.argwhere(off)[0]
                k = int(circ[where[-1]])
                row = f" (row {int(where[0])})" if q.ndim > 1 else ""
                raise DetectionError(f"q{row}: continuous joint {self._spec.joint_names[k]!r}: (cos, sin) = "
                                     f"({float(c[tuple(where)]):.6g}, {float(s[tuple(where)]):.6g}) is not on the unit "
                                     f"circle (|cos² + sin² - 1| <= {_joint_limits.UNIT_CIRCLE:g})")
            out[..., circ] = np.arctan2(s, c)
        return out

    def pin_q(self, q_scene) -> np.ndarray:
        """The scene's flat ``q`` ``(..., n)`` -> Pinocchio's order ``(..., nq)``."""
        refuse_complex_or_bool(q_scene, "q_scene", DetectionError)
        q_scene = np.asarray(q_scene, dtype=np.float64)
        n = len(self._q_index)
        if q_scene.shape[-1:] != (n,):  # a raw numpy broadcast error
            raise DetectionError(f"q_scene: expected {n} values in the scene's order {list(self._spec.joint_names)}, "
                                 f"got shape {q_scene.shape}")
        out = np.zeros(q_scene.shape[:-1] + (self.nq,))
        out[..., self._q_index] = q_scene
        for k in self._circular:
            i = self._q_index[k]
            out[..., i], out[..., i + 1] = np.cos(q_scene[..., k]), np.sin(q_scene[..., k])
        return out

    @property
    def joint_names(self) -> tuple:
        """Pinocchio's independent joint names, in q order."""
        m = self.pin_model
        return tuple(m.names[j] for j in range(1, m.njoints) if m.joints[j].nq > 0)

    def neutral(self) -> np.ndarray:
        """The scene's default configuration in Pinocchio's order (each arm's home)."""
        return self.pin_q(self._spec.flat_q(self._spec.default_q()))

    def random_q(self, n: int, rng=None) -> np.ndarray:
        """``(n, nq)`` uniform in-limit configurations (Pinocchio's order); ``rng`` a seed or a numpy Generator."""
        from .._values import whole_number

        n = whole_number(n, "random_q: n", DetectionError)  # 2.7 gave 2 rows, True 1
        try:
            rng = np.random.default_rng(rng)
        except (TypeError, ValueError):
            raise DetectionError(f"random_q: rng: expected a seed (an integer >= 0) or a numpy Generator, got {rng!r}") from None
        robots = [r for _, r in self._robots]
        lo = np.concatenate([r.lower for r in robots]) if robots else np.zeros(0)
        hi = np.concatenate([r.upper for r in robots]) if robots else np.zeros(0)
        lo, hi = np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)
        return self.pin_q(lo + (hi - lo) * rng.random((n, len(lo))))

    def group_joints(self, group: str) -> tuple[str, ...]:
        """The movable joints of SRDF group ``group`` (its ``<joint>`` members, the joints of its
        ``<chain>`` and of the groups it names), as its robot calls them, in the robot's order; a
        :class:`~armguard.SceneError` for an unknown group or one spanning several robots."""
        return self.group_robot_joints(group)[1]

    def group_robot_joints(self, group: str) -> tuple[str, tuple[str, ...]]:
        """``(robot, joints)``: the robot SRDF group ``group`` moves and :meth:`group_joints`."""
        from .._errors import SceneError

        groups = self.srdf.groups if self.srdf is not None else {}
        if group not in groups:
            raise SceneError(f"unknown SRDF group {group!r}; the model's groups are {sorted(groups)}")
        m = self.pin_model
        by_iq = {m.joints[j].idx_q: m.names[j] for j in range(1, m.njoints) if m.joints[j].nq > 0}
        scene_of = {by_iq.get(int(iq)): sn for iq, sn in zip(self._q_index, self._spec.joint_names)}
        urdf: set = set()
        todo, seen = [group], set()
        while todo:
            g = groups.get(todo.pop())
            if g is None or g.name in seen:
                continue
            seen.add(g.name)
            urdf.update(g.joints)
            todo.extend(g.subgroups)
            for base, tip in g.chains:  # the joints on the path from tip up to base
                fid = m.getFrameId(tip) if m.existFrame(tip) else None
                while fid is not None and m.frames[fid].name != base and fid != 0:
                    fr = m.frames[fid]
                    if fr.type.name == "JOINT":
                        urdf.add(fr.name)
                    fid = fr.parentFrame if fr.parentFrame != fid else None
        flat = [scene_of[j] for j in urdf if j in scene_of]
        robots = {sn.split("/", 1)[0] for sn in flat}
        if len(robots) != 1:
            raise SceneError(f"SRDF group {group!r} moves {'no joint' if not robots else f'joints of robots {sorted(robots)}'}: "
                             "a trajectory moves the joints of one robot")
        (r,) = robots
        mine = {sn.split("/", 1)[1] for sn in flat}
        return r, tuple(j for j in self.robots[r].joint_names if j in mine)

    # ---------------------------------------------------------------- kinematics
    def kinematic_tree(self, robots=None) -> tuple:
        """``(tree, link_off, joint_off)``: the forward kinematics of ``robots`` (names, in q order;
        default every robot) compiled from ``pin_model`` (:func:`armguard.model._tree.pin_tree`:
        joint tree, placements, mimic couplings; equal to Pinocchio's ``forwardKinematics`` to
        1e-12), once per robot set.  Rows are the robots' links in order (``link_off[r]`` + link
        index); joint terms index the scene's flat q.  The analytic engine, the verifier's lever
        arms, the terrain guard and the console all move links with it."""
        from ._tree import pin_tree

        key = tuple(r for r, _ in self._robots) if robots is None else tuple(robots)
        cache = self.__dict__.get("_kinematic_trees")
        if cache is None or key not in cache:
            with _TREE_LOCK:
                cache = self.__dict__.setdefault("_kinematic_trees", {})
                if key not in cache:
                    cache[key] = pin_tree(self, key)
        return cache[key]

    def link_poses(self, q) -> dict:
        """Robot name -> ``(..., n_links, 4, 4)`` world poses X_WL in its ``link_names`` order, at
        ``q``: the scene's flat ``(..., n)`` array or a mapping robot -> its joints (as
        :meth:`Scene.link_poses`, which moves the Robots' own chains: the reference this is held to)."""
        from ..kinematics._fk import fk_kernel

        q = self._spec.flat_q(q)  # validated: a NaN or a wrong length raises
        tree, link_off, _ = self.kinematic_tree()
        X = fk_kernel(tree, q)
        return {name: X[..., int(link_off[i]):int(link_off[i]) + len(robot.link_names), :, :]
                for i, (name, robot) in enumerate(self._robots)}

    def robot_link_poses(self, robot: str, q_robot) -> np.ndarray:
        """``(..., n_links, 4, 4)``: robot ``robot``'s links at its own joints ``q_robot`` ``(..., n_joints)``
        (the other robots at home: no link of one robot moves with another's joints)."""
        from ..kinematics._fk import fk_kernel

        names = [r for r, _ in self._robots]
        if robot not in names:
            from .._errors import SceneError

            raise SceneError(f"unknown robot {robot!r}; robots are {names}")
        rob = dict(self._robots)[robot]
        q_robot = rob.check_q(q_robot)
        k0 = sum(len(r.joint_names) for n, r in self._robots[:names.index(robot)])
        base = self._spec.flat_q(self._spec.default_q())
        q = np.broadcast_to(base, q_robot.shape[:-1] + base.shape).copy()
        q[..., k0:k0 + len(rob.joint_names)] = q_robot
        tree, link_off, _ = self.kinematic_tree((robot,))
        return fk_kernel(tree, q)

    def shapes_at(self, q=None) -> list:
        """The world-frame geometry of the system this Model holds at ``q`` (default: every robot
        at home), as :meth:`Scene.shapes_at` lists it, the links moved by :meth:`link_poses`."""
        q = self._spec.default_q() if q is None else q
        return self._spec.shapes_at(q, poses=self.link_poses(q))

    # ---------------------------------------------------------------- pairs
    def geometry_name(self, owner: str, i: int) -> str:
        """The GeometryObject name of shape ``i`` of scene owner ``owner``."""
        return self._geom[(owner, i)]

    def geometry_index(self, name: str) -> int:
        return self._geom_index[name]

    @property
    def pairs(self) -> GeometryPairs:
        """The active pairs of the system as this Model was made (listed on first use, then fixed):
        a later edit of the scene (a body, a pair filter, the workspace box) makes another Model
        (``model_of``), so every Checker built on this one answers for the same pairs."""
        if self._pairs is None:
            self._pairs = self._compute_pairs()
        return self._pairs

    def _compute_pairs(self) -> GeometryPairs:
        """Every shape pair of :meth:`Scene.allowed_pairs` (owner pairs in its order, shapes of A
        outer, of B inner), then one workspace row per robot shape (links, then payloads, owner
        order) when the scene has a workspace box: :func:`~armguard.model.compile_scene`'s element
        pairs, without compiling the geometry (tests/test_engine_from_model.py holds it to that)."""
        scene = self._spec
        n_shapes = {}  # the owners whose objects this Model holds
        for name, body in self._parts[0]:
            n_shapes[name] = len(body.shapes)
        for r, robot in self._robots:
            for ln in robot.link_names:
                if robot.link_shapes.get(ln):
                    n_shapes[f"{r}/{ln}"] = len(robot.link_shapes[ln])
        for name, p in self._parts[1]:
            n_shapes[name] = len(p.shapes)
        geom = self._geom
        a, b, oa, ob, cat = [], [], [], [], []
        for p in scene.allowed_pairs():
            if p.a not in n_shapes or p.b not in n_shapes:
                continue
            c = p.category.value
            for i in range(n_shapes[p.a]):
                na = geom[(p.a, i)]
                for j in range(n_shapes[p.b]):
                    a.append(na), b.append(geom[(p.b, j)]), oa.append(p.a), ob.append(p.b), cat.append(c)
        if scene.workspace is not None:
            bodies = dict(self._parts[0])
            moving = [o for o in n_shapes if o not in bodies]  # dict order: bodies, links, payloads
            for o in moving:
                for i in range(n_shapes[o]):
                    a.append(geom[(o, i)]), b.append(WORKSPACE), oa.append(o), ob.append(WORKSPACE), cat.append("workspace")
        return GeometryPairs(tuple(a), tuple(b), tuple(oa), tuple(ob), tuple(cat))
