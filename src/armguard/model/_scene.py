"""The scene model: robots, static bodies, payloads, workspace box, pair filters, canned tests.

A :class:`Scene` is a mutable container of immutable parts.  Every mutating method checks
all of its inputs before it changes anything, so a failed call leaves the scene as it was.

Owners (the things a distance is measured between) are named:

* a static body by its name (``"tail"``), kind ``"body"``, shapes in the world frame W;
* a robot link by ``"robot/link"`` (``"hera/link3"``), kind ``"link"``, shapes in the link frame L;
* a payload by its name, kind ``"payload"``, shapes in the payload frame P held at ``X_LP`` by a link.
"""

from __future__ import annotations

import functools
import threading
import types
from typing import Mapping, Sequence

import numpy as np

from .._errors import KinematicsError, SceneError
from .._values import refuse_complex_or_bool
from ..geometry import Shape
from ._allowed import adjacent, allowed_pairs
from ._entry import unknown_robots_text
from ._items import (  # noqa: F401  (re-exported: the scene's parts live in _items.py)
    BODY_CATEGORIES,
    Body,
    CannedTest,
    CheckPair,
    PairCategory,
    Payload,
    SceneItem,
    WorkspaceBox,
    _canned_motion,
    _check_name,
    _check_pose,
    _check_shapes,
)

__all__ = ["Scene", "Body", "Payload", "SceneItem", "WorkspaceBox", "CheckPair", "PairCategory", "CannedTest",
           "BODY_CATEGORIES"]


def _locked(method):
    """``method`` run holding the scene's :attr:`Scene.lock`: an edit is never seen half made, and a
    read that walks the containers never sees one change under it."""

    @functools.wraps(method)
    def run(self, *args, **kwargs):
        with self._lock:
            return method(self, *args, **kwargs)

    return run


class Scene:
    """Robots among static bodies, with payloads, a workspace box, pair filters and canned tests.

    Contract used by the detector, the verifier and external checks:

    * ``robots[name]`` -> ``Robot``; ``joint_names`` -> every movable joint as ``"robot/joint"``,
      in the order a flat ``q`` uses (robots in insertion order);
    * ``add_body(name, shapes)`` adds a static body of shapes given in W;
    * ``shapes_at(q)`` -> list of :class:`SceneItem` (bodies, then links, then payloads), in W;
    * ``q`` is a mapping robot name -> (n_joints,) array, or a flat (n,) array over ``joint_names``.
    """

    def __init__(self, name: str = "scene", *, description: str = "") -> None:
        self.name = str(name)
        self.description = str(description)
        self._robots: dict = {}
        self._homes: dict[str, np.ndarray] = {}
        self._self_pairs: dict[str, frozenset] = {}
        self._bodies: dict[str, Body] = {}
        self._payloads: dict[str, Payload] = {}
        self._workspace: WorkspaceBox | None = None
        self._exclude_adjacent = True
        self._disabled: set[frozenset] = set()
        self._trajectories: dict = {}
        self._canned: dict[str, CannedTest] = {}
        # How each robot was described (for save_scene): robot name -> dict in SI units.
        self._robot_sources: dict[str, dict] = {}
        # How each file trajectory was described (for save_scene): name -> dict in SI units.
        self._trajectory_specs: dict[str, dict] = {}
        # Bumped by every change to what is checked (robots, bodies, payloads, workspace, pair
        # filters), so that precomputed models (Verifier, Guard, Detector) can tell they are stale.
        self._revision = 0
        self._lock = threading.RLock()

    def __getstate__(self) -> dict:
        with self._lock:
            state = dict(self.__dict__)
        del state["_lock"]  # a lock does not travel (Dask ships scenes to its workers): each copy gets its own
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.RLock()

    # ---------------------------------------------------------------- read-only views
    @property
    def lock(self) -> threading.RLock:
        """Held by every edit and by the reads that walk several containers (and by
        :func:`armguard.model.model_of` while it builds the scene's Model): hold it to read the scene
        consistently while other threads may edit it (``with scene.lock: ...``)."""
        return self._lock

    @property
    def revision(self) -> int:
        """A counter bumped by every change to the checked geometry or pair filters.

        A model compiled from the scene (a Verifier's or Guard's clearance model, a Detector)
        records it and compares it before each query, so a body added after compiling is never
        silently left out.
        """
        return self._revision

    @property
    def robots(self) -> Mapping:
        """Robot name -> ``Robot`` (read-only view, insertion order)."""
        return types.MappingProxyType(self._robots)

    @property
    def bodies(self) -> Mapping[str, Body]:
        """Body name -> :class:`Body` (read-only view)."""
        return types.MappingProxyType(self._bodies)

    @property
    def payloads(self) -> Mapping[str, Payload]:
        """Payload name -> :class:`Payload` (read-only view)."""
        return types.MappingProxyType(self._payloads)

    @property
    def workspace(self) -> WorkspaceBox | None:
        """The workspace bounding box, or ``None``."""
        return self._workspace

    @property
    def trajectories(self) -> Mapping:
        """Name -> canned ``Trajectory`` for verification (read-only view)."""
        return types.MappingProxyType(self._trajectories)

    @property
    def canned_tests(self) -> Mapping[str, CannedTest]:
        """Name -> :class:`CannedTest` (Ranger's test setups; read-only view)."""
        return types.MappingProxyType(self._canned)

    @property
    def exclude_adjacent(self) -> bool:
        """Whether link pairs joined by one joint are left out of the checks (default True)."""
        return self._exclude_adjacent

    @exclude_adjacent.setter
    def exclude_adjacent(self, value: bool) -> None:
        with self._lock:
            self._exclude_adjacent = bool(value)
            self._revision += 1

    @property
    def disabled_pairs(self) -> frozenset:
        """The disabled owner pairs, each a ``frozenset`` of two owner names (or robot names)."""
        return frozenset(self._disabled)

    @property
    def self_pairs(self) -> Mapping[str, frozenset]:
        """Robot name -> its listed link pairs (Hermes-style: only these self pairs are checked)."""
        return types.MappingProxyType(self._self_pairs)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Every independent movable joint of every robot as ``"robot/joint"``: the order of a flat q."""
        with self._lock:
            return tuple(f"{r}/{j}" for r, robot in self._robots.items() for j in robot.joint_names)

    @_locked
    def owners(self) -> tuple[str, ...]:
        """Every owner with geometry: bodies, then ``robot/link`` owners, then payloads."""
        out = list(self._bodies)
        for r, robot in self._robots.items():
            out.extend(f"{r}/{ln}" for ln in robot.link_names if robot.link_shapes.get(ln))
        out.extend(self._payloads)
        return tuple(out)

    def moves(self, owner: str) -> bool:
        """Whether ``owner``'s pose depends on the configuration: a link (or a payload held by a
        link) with a revolute or prismatic joint between it and its robot's base.  A pair of two
        owners that do not move has the same distance at every configuration."""
        from ..kinematics import JointType

        if owner in self._payloads:
            r, link = self._payloads[owner].robot, self._payloads[owner].link
        elif "/" in owner and owner.split("/", 1)[0] in self._robots:
            r, link = owner.split("/", 1)
        else:
            return False  # a static body
        robot = self._robots[r]
        while link is not None:
            spec = robot.joint_of_link(link)
            if spec is not None and spec.joint_type is not JointType.FIXED:
                return True
            link = robot.parent_link(link)
        return False

    # ---------------------------------------------------------------- robots
    @_locked
    def add_robot(self, robot, *, home=None, self_pairs=None, _source: dict | None = None) -> None:
        """Add ``robot`` (a ``Robot``; its name must be new).

        home : (n_joints,) float, rad or m; default: zeros clipped into the joint limits.
        self_pairs : optional iterable of (link, link): only these own-link pairs are checked.
        """
        name = _check_name(getattr(robot, "name", None), "robot.name")
        if name in self._robots or name in self._bodies or name in self._payloads:
            raise SceneError(f"robot {name!r}: the name is already used in scene {self.name!r}")
        if home is None:
            q = np.clip(np.zeros(len(robot.joint_names)), robot.lower, robot.upper)
        else:
            q = robot.check_q(home)
            if q.shape != (len(robot.joint_names),):
                raise SceneError(f"robot {name!r}: home must be one configuration, got shape {q.shape}")
            bad = np.flatnonzero((q < robot.lower) | (q > robot.upper))
            if bad.size:
                j = int(bad[0])
                raise SceneError(f"robot {name!r}: home {robot.joint_names[j]!r} = {q[j]:.9g} is outside its limits "
                                 f"[{robot.lower[j]:.9g}, {robot.upper[j]:.9g}] (rad or m)")
        q = np.array(q, dtype=np.float64)
        q.flags.writeable = False
        pairs = None
        if self_pairs is not None:
            pairs = frozenset(self._check_link_pair(robot, p) for p in self_pairs)
        self._robots[name] = robot
        self._homes[name] = q
        if pairs is not None:
            self._self_pairs[name] = pairs
        if _source is not None:
            self._robot_sources[name] = _source
        self._revision += 1

    @staticmethod
    def _check_link_pair(robot, pair) -> tuple[str, str]:
        a, b = pair
        for ln in (a, b):
            if ln not in robot.link_names:
                raise SceneError(f"robot {robot.name!r}: unknown link {ln!r}; links are {list(robot.link_names)}")
        if a == b:
            raise SceneError(f"robot {robot.name!r}: a link pair needs two different links, got {a!r} twice")
        return (a, b) if a < b else (b, a)

    @_locked
    def set_robot_ik(self, robot: str, routine: str | None) -> None:
        """Robot ``robot``'s inverse kinematics: ``routine`` (see :meth:`armguard.kinematics.Robot.with_ik`;
        checked first, so an unknown routine leaves the scene as it was).  Changes no geometry."""
        if robot not in self._robots:
            raise SceneError(f"unknown robot {robot!r}; robots are {list(self._robots)}")
        self._robots[robot] = self._robots[robot].with_ik(routine)

    @_locked
    def set_robot_base(self, robot: str, X_WB) -> None:
        """Mount robot ``robot`` at ``X_WB`` (4, 4; its links and payloads move with it)."""
        self._robots[robot] = self._robot(robot).with_base(X_WB)
        self._revision += 1

    def home(self, robot: str) -> np.ndarray:
        """``(n_joints,) float64``: the home configuration of ``robot``."""
        self._robot(robot)
        return self._homes[robot]

    def _robot(self, name: str):
        try:
            return self._robots[name]
        except KeyError:
            raise SceneError(f"unknown robot {name!r}; robots are {list(self._robots)}") from None

    # ---------------------------------------------------------------- bodies
    @_locked
    def add_body(self, name: str, shapes: Sequence[Shape] | Shape, *, category: str = "environment") -> Body:
        """Add a static body made of ``shapes`` given in the world frame W; returns it."""
        _check_name(name, "body name")
        if name in self._bodies or name in self._robots or name in self._payloads:
            raise SceneError(f"body {name!r}: the name is already used in scene {self.name!r}")
        if category not in BODY_CATEGORIES:
            raise SceneError(f"body {name!r}: category must be one of {list(BODY_CATEGORIES)}, got {category!r}")
        body = Body(name, _check_shapes(shapes, f"body {name!r} shapes"), category)
        self._bodies[name] = body
        self._revision += 1
        return body

    @_locked
    def remove_body(self, name: str) -> Body:
        """Remove and return the body ``name``; disabled pairs naming it are dropped."""
        if name not in self._bodies:
            raise SceneError(f"unknown body {name!r}; bodies are {list(self._bodies)}")
        self._disabled = {p for p in self._disabled if name not in p}
        self._revision += 1
        return self._bodies.pop(name)

    # ---------------------------------------------------------------- payloads
    @_locked
    def attach_payload(self, name: str, robot: str, link: str, shapes, X_LP=None) -> Payload:
        """Attach a payload: ``shapes`` in its frame P, held at ``X_LP`` (4, 4; default identity) by ``robot``'s ``link``."""
        _check_name(name, "payload name")
        if name in self._bodies or name in self._robots or name in self._payloads:
            raise SceneError(f"payload {name!r}: the name is already used in scene {self.name!r}")
        r = self._robot(robot)
        if link not in r.link_names:
            raise SceneError(f"payload {name!r}: robot {robot!r} has no link {link!r}; links are {list(r.link_names)}")
        X = _check_pose(np.eye(4) if X_LP is None else X_LP, f"payload {name!r} X_LP")
        p = Payload(name, robot, link, _check_shapes(shapes, f"payload {name!r} shapes"), X)
        self._payloads[name] = p
        self._revision += 1
        return p

    @_locked
    def release_payload(self, name: str, q) -> Body:
        """WORKMATE release: payload ``name`` becomes a static body where it is at configuration ``q``."""
        if name not in self._payloads:
            raise SceneError(f"unknown payload {name!r}; payloads are {list(self._payloads)}")
        p = self._payloads[name]
        X_WL = self.link_pose(q, p.robot, p.link)
        X_WP = X_WL @ p.X_LP
        shapes = tuple(s.transformed(X_WP) for s in p.shapes)
        body = Body(name, shapes, "environment")
        del self._payloads[name]
        self._bodies[name] = body
        self._revision += 1
        return body

    @_locked
    def grasp(self, body: str, robot: str, link: str, q) -> Payload:
        """WORKMATE grasp: static ``body`` becomes a payload of ``robot``'s ``link``, held where it is at ``q``."""
        if body not in self._bodies:
            raise SceneError(f"unknown body {body!r}; bodies are {list(self._bodies)}")
        r = self._robot(robot)
        if link not in r.link_names:
            raise SceneError(f"grasp: robot {robot!r} has no link {link!r}")
        X_WL = self.link_pose(q, robot, link)
        X_LW = np.eye(4)
        X_LW[:3, :3] = X_WL[:3, :3].T
        X_LW[:3, 3] = -X_WL[:3, :3].T @ X_WL[:3, 3]
        shapes = tuple(s.transformed(X_LW) for s in self._bodies[body].shapes)
        p = Payload(body, robot, link, shapes, _check_pose(np.eye(4), "X_LP"))
        del self._bodies[body]
        self._payloads[body] = p
        self._revision += 1
        return p

    # ---------------------------------------------------------------- workspace, filters
    @_locked
    def set_workspace(self, lo, hi) -> WorkspaceBox:
        """Set the axis-aligned workspace box (``lo``, ``hi``: (3,) m in W)."""
        self._workspace = WorkspaceBox(lo, hi)
        self._revision += 1
        return self._workspace

    @_locked
    def clear_workspace(self) -> None:
        """Remove the workspace box."""
        self._workspace = None
        self._revision += 1

    @_locked
    def disable_pair(self, a: str, b: str) -> None:
        """Never check owners ``a`` and ``b`` against each other (a robot name stands for all its links)."""
        for n in (a, b):
            self._check_owner_or_robot(n)
        if a == b:
            raise SceneError(f"disable_pair: needs two different owners, got {a!r} twice")
        self._disabled.add(frozenset((a, b)))
        self._revision += 1

    @_locked
    def enable_pair(self, a: str, b: str) -> None:
        """Undo :meth:`disable_pair` (no effect when the pair was not disabled)."""
        self._disabled.discard(frozenset((a, b)))
        self._revision += 1

    @_locked
    def set_self_pairs(self, robot: str, pairs) -> None:
        """Hermes-style: check only these own-link pairs of ``robot`` (``None``: all non-adjacent pairs)."""
        r = self._robot(robot)
        if pairs is None:
            self._self_pairs.pop(robot, None)
            self._revision += 1
            return
        self._self_pairs[robot] = frozenset(self._check_link_pair(r, p) for p in pairs)
        self._revision += 1

    def _check_owner_or_robot(self, n: str) -> None:
        if n in self._robots or n in self._bodies or n in self._payloads:
            return
        if "/" in n:
            r, ln = n.split("/", 1)
            if r in self._robots and ln in self._robots[r].link_names:
                return
        links = [f"{r}/{n}" for r, rob in self._robots.items() if n in rob.link_names]  # a bare link name
        hint = f" (did you mean {' or '.join(map(repr, links))}?)" if links else ""
        raise SceneError(f"unknown owner {n!r}: expected a body, a payload, a robot or 'robot/link'{hint}")

    # ---------------------------------------------------------------- trajectories, tests
    @_locked
    def add_trajectory(self, name: str, trajectory) -> None:
        """Add a named canned ``Trajectory`` (its ``robot_name`` must be a robot of the scene)."""
        _check_name(name, "trajectory name")
        self._robot(trajectory.robot_name)
        if name in self._trajectories:
            raise SceneError(f"trajectory {name!r}: the name is already used")
        self._trajectories[name] = trajectory

    @_locked
    def add_canned_test(self, test: CannedTest) -> None:
        """Add a :class:`CannedTest`; its robots and configurations are checked."""
        _check_name(test.name, "canned test name")
        if test.name in self._canned:
            raise SceneError(f"canned test {test.name!r}: the name is already used")
        active = self._robot(test.robot)
        setup = {}
        for rname in self._robots:
            if rname not in test.setup:
                raise SceneError(f"canned test {test.name!r}: setup has no configuration for robot {rname!r}")
        for rname, q in test.setup.items():
            setup[rname] = self._check_in_limits(rname, q, f"canned test {test.name!r} setup.{rname}")
        goal, ee, psi = _canned_motion(test, active, self._check_in_limits)
        self._canned[test.name] = CannedTest(
            test.name, test.description, test.robot, float(test.threshold), types.MappingProxyType(setup), goal,
            ee, psi,
        )

    def _check_in_limits(self, rname: str, q, what: str) -> np.ndarray:
        r = self._robot(rname)
        q = r.check_q(q)
        if q.shape != (len(r.joint_names),):
            raise SceneError(f"{what}: expected {len(r.joint_names)} joint values, got shape {q.shape}")
        bad = np.flatnonzero((q < r.lower) | (q > r.upper))
        if bad.size:
            j = int(bad[0])
            raise SceneError(
                f"{what}: joint {r.joint_names[j]!r} = {q[j]:.10g} is outside [{r.lower[j]:.10g}, {r.upper[j]:.10g}]"
            )
        q = np.array(q)
        q.flags.writeable = False
        return q

    # ---------------------------------------------------------------- configurations
    @_locked
    def split_q(self, q) -> dict[str, np.ndarray]:
        """Robot name -> ``(..., n_joints)`` float64 from a mapping or a flat ``(..., n)`` array over ``joint_names``.

        A mapping must name every robot of the scene and no other; NaN/inf raise (KinematicsError).
        """
        if isinstance(q, Mapping):
            extra, missing = [k for k in q if k not in self._robots], [k for k in self._robots if k not in q]
            if extra:
                raise SceneError(unknown_robots_text(self._robots, extra))
            if missing:
                raise SceneError(f"q has no configuration for robots {missing}")
            return {name: self._robots[name].check_q(q[name]) for name in self._robots}
        refuse_complex_or_bool(q, "q", KinematicsError)  # True read as 1 rad, a complex value as its real part
        try:
            arr = np.asarray(q, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise SceneError(f"q: expected a mapping robot -> joints or a flat array, got {q!r}") from exc
        n = len(self.joint_names)
        if arr.ndim == 0 or arr.shape[-1] != n:
            raise SceneError(f"q: expected a flat array of {n} joint values (scene.joint_names), got shape {arr.shape}")
        out, k = {}, 0
        for name, robot in self._robots.items():
            m = len(robot.joint_names)
            out[name] = robot.check_q(arr[..., k : k + m])
            k += m
        return out

    @_locked
    def flat_q(self, q) -> np.ndarray:
        """``(..., n) float64``: ``q`` (mapping or flat) as one flat array over ``joint_names``."""
        parts = self.split_q(q)
        if not parts:
            return np.zeros(0)
        return np.concatenate([parts[n] for n in self._robots], axis=-1)

    @_locked
    def default_q(self) -> dict[str, np.ndarray]:
        """The home configuration of every robot: robot name -> (n_joints,) float64."""
        return {name: self._homes[name].copy() for name in self._robots}

    @_locked
    def link_poses(self, q) -> dict[str, np.ndarray]:
        """Robot name -> ``(..., n_links, 4, 4)`` world poses X_WL in ``link_names`` order."""
        parts = self.split_q(q)
        return {name: self._robots[name].forward_kinematics(parts[name]) for name in self._robots}

    def link_pose(self, q, robot: str, link: str) -> np.ndarray:
        """``(4, 4)``: pose X_WL of one link at configuration ``q`` (a mapping, a flat array, or that robot's joints)."""
        r = self._robot(robot)
        if link not in r.link_names:
            raise SceneError(f"robot {robot!r} has no link {link!r}")
        if isinstance(q, Mapping):
            qr = r.check_q(q[robot]) if robot in q else None
            if qr is None:
                raise SceneError(f"q has no configuration for robot {robot!r}")
        else:
            arr = np.asarray(q, dtype=np.float64)
            qr = r.check_q(arr) if arr.shape == (len(r.joint_names),) else self.split_q(arr)[robot]
        if qr.ndim != 1:
            raise SceneError(f"q: expected one configuration, got shape {qr.shape}")
        return r.forward_kinematics(qr)[r.link_index(link)]

    @_locked
    def shapes_at(self, q=None, *, poses=None) -> list[SceneItem]:
        """The world-frame geometry at configuration ``q`` (default: every robot at home).

        Returns a list of :class:`SceneItem`: bodies, then links (robots in order, links in
        ``link_names`` order), then payloads.  ``q`` is one configuration (no batch axes).
        ``poses``: the links' poses at ``q`` (robot name -> ``(n_links, 4, 4)``, as
        :meth:`armguard.model.Model.link_poses` computes them from ``pin_model``); by default
        the Robots' own chains move them (the reference the Model's kinematics is held to).
        """
        parts = self.split_q(self.default_q() if q is None else q)
        items: list[SceneItem] = []
        for b in self._bodies.values():
            items.extend(SceneItem(b.name, "body", s, category=b.category) for s in b.shapes)
        given, poses = poses, {}
        for name, robot in self._robots.items():
            if parts[name].ndim != 1:
                raise SceneError(f"shapes_at: expected one configuration, got shape {parts[name].shape} for {name!r}")
            X = robot.forward_kinematics(parts[name]) if given is None else np.asarray(given[name], dtype=np.float64)
            poses[name] = X
            for i, ln in enumerate(robot.link_names):
                for s in robot.link_shapes.get(ln, ()):
                    items.append(SceneItem(f"{name}/{ln}", "link", s.transformed(X[i]), robot=name, link=ln))
        for p in self._payloads.values():
            robot = self._robots[p.robot]
            X_WP = poses[p.robot][robot.link_index(p.link)] @ p.X_LP
            items.extend(
                SceneItem(p.name, "payload", s.transformed(X_WP), robot=p.robot, link=p.link) for s in p.shapes
            )
        return items

    # ---------------------------------------------------------------- pairs
    @_locked
    def allowed_pairs(self) -> tuple[CheckPair, ...]:
        """Every owner pair that must be checked, with its :class:`PairCategory`.

        * arm-arm: links of two different robots; own links of one robot that are not adjacent
          (joined by one joint or through links without geometry; kept when
          ``exclude_adjacent`` is False) or, where :meth:`set_self_pairs` listed pairs,
          exactly those pairs (Hermes checks only 1-3, 1-4, 1-6, 2-4, 2-6, 3-6);
        * arm-vehicle / arm-environment: a link and a body of that category;
        * arm-payload: a link and a payload, except the link that holds it;
        * payload-vehicle / payload-environment / payload-payload.

        Only owners with shapes take part; disabled pairs are left out (a robot name in a
        disabled pair stands for all its links).  Order: as listed above, then owner order.
        """
        return allowed_pairs(self)

    def _adjacent(self, robot: str, a: str, b: str) -> bool:
        """Whether links ``a`` and ``b`` of ``robot`` count as adjacent (:func:`._allowed.adjacent`)."""
        return adjacent(self, robot, a, b)

    def allowed_pairs_by_category(self) -> dict[PairCategory, tuple[tuple[str, str], ...]]:
        """:meth:`allowed_pairs` grouped: category -> tuple of (owner, owner)."""
        out: dict[PairCategory, list] = {c: [] for c in PairCategory}
        for p in self.allowed_pairs():
            out[p.category].append((p.a, p.b))
        return {c: tuple(v) for c, v in out.items()}

    # ---------------------------------------------------------------- other
    @_locked
    def compile(self):
        """The scene as flat arrays for kernels (see :func:`armguard.scene.compile_scene`)."""
        from ._compile import compile_scene

        return compile_scene(self)

    @_locked
    def copy(self) -> "Scene":
        """A shallow copy (the parts are immutable, the containers are new)."""
        s = Scene(self.name, description=self.description)
        s._robots = dict(self._robots)
        s._homes = dict(self._homes)
        s._self_pairs = dict(self._self_pairs)
        s._bodies = dict(self._bodies)
        s._payloads = dict(self._payloads)
        s._workspace = self._workspace
        s._exclude_adjacent = self._exclude_adjacent
        s._disabled = set(self._disabled)
        s._trajectories = dict(self._trajectories)
        s._canned = dict(self._canned)
        s._robot_sources = dict(self._robot_sources)
        s._trajectory_specs = dict(self._trajectory_specs)
        s._model_of_record = getattr(self, "_model_of_record", None)  # model_of(s, geometry=False) reuses its kinematics
        return s

    def __repr__(self) -> str:
        return (
            f"Scene({self.name!r}: {len(self._robots)} robots, {len(self._bodies)} bodies, "
            f"{len(self._payloads)} payloads, {len(self.joint_names)} joints)"
        )
