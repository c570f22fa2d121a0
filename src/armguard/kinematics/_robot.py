"""The Robot: an immutable kinematic tree with limits, collision shapes and batched FK."""

from __future__ import annotations

import enum
import math
import types
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from .._errors import KinematicsError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import refuse_complex_or_bool
from ..geometry import Shape
from ._fk import JT_FIXED, JT_PRISMATIC, JT_REVOLUTE, FlatTree, fk_kernel, fk_reference

__all__ = ["JointType", "DHRow", "Coupling", "JointSpec", "Robot"]


class JointType(str, enum.Enum):
    """Kind of a joint.  A URDF ``continuous`` joint is REVOLUTE with infinite limits."""

    FIXED = "fixed"
    REVOLUTE = "revolute"
    PRISMATIC = "prismatic"


_JT_CODE = {JointType.FIXED: JT_FIXED, JointType.REVOLUTE: JT_REVOLUTE, JointType.PRISMATIC: JT_PRISMATIC}



def _finite(value, name: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError) as exc:
        raise KinematicsError(f"{name}: expected a number, got {value!r}") from exc
    if not math.isfinite(x):
        raise KinematicsError(f"{name}: must be finite, got {x}")
    return x


def joint_type_from(value, name: str) -> JointType:
    """Coerce ``value`` (a JointType or its string) to JointType, listing the valid ones otherwise."""
    try:
        return JointType(value)
    except ValueError:
        valid = ", ".join(repr(j.value) for j in JointType)
        raise KinematicsError(f"{name}: unknown joint type {value!r}; expected one of {valid}") from None


@dataclass(frozen=True)
class DHRow:
    """One row of a Denavit-Hartenberg table (m, rad).

    For a revolute joint ``theta`` is the joint's offset (joint angle = theta + q); for a
    prismatic joint ``d`` is the offset (joint length = d + q).
    """

    a: float
    alpha: float
    d: float
    theta: float = 0.0
    joint_type: str = "revolute"

    def __post_init__(self) -> None:
        for key in ("a", "alpha", "d", "theta"):
            object.__setattr__(self, key, _finite(getattr(self, key), f"DHRow.{key}"))
        jt = joint_type_from(self.joint_type, "DHRow.joint_type")
        if jt is JointType.FIXED:
            raise KinematicsError("DHRow.joint_type: a DH row is a 'revolute' or 'prismatic' joint, got 'fixed'")
        object.__setattr__(self, "joint_type", jt.value)


@dataclass(frozen=True)
class Coupling:
    """A dependent joint: value = ``offset + sum(coeff * q[independent])`` (rad or m).

    A dependent joint is not commanded and is not in ``Robot.joint_names`` (URDF mimic joints:
    ``Coupling("finger2", {"finger1": 1.0})``).  A *drive* coupling, whose terms name its own
    joint, keeps the joint commanded but maps its command to the DH joint angle: the GMF S-480
    parallelogram linkage (WORKMATE, seed ``004``), whose commanded forearm angle ``j3`` is
    measured from the horizontal, so the DH elbow angle is ``j3 - j2``:
    ``Coupling("j3", {"j3": 1.0, "j2": -1.0})``.
    """

    joint: str
    terms: Mapping[str, float]
    offset: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.joint, str) or not self.joint:
            raise KinematicsError(f"Coupling.joint: expected a joint name, got {self.joint!r}")
        if not isinstance(self.terms, Mapping):
            raise KinematicsError(f"Coupling({self.joint}).terms: expected a mapping joint -> factor, got {self.terms!r}")
        terms = {str(k): _finite(v, f"Coupling({self.joint}).terms[{k!r}]") for k, v in dict(self.terms).items()}
        object.__setattr__(self, "terms", types.MappingProxyType(terms))
        object.__setattr__(self, "offset", _finite(self.offset, f"Coupling({self.joint}).offset"))

    def __reduce__(self):  # mappingproxy does not pickle; rebuild from plain values (Dask workers)
        return (Coupling, (self.joint, dict(self.terms), self.offset))


@dataclass(frozen=True, eq=False)
class JointSpec:
    """One joint of the tree, connecting ``parent`` link to ``child`` link (the builders' input).

    ``X_pre`` (4, 4): parent frame -> joint frame; ``axis`` (3,) unit, in the joint frame;
    ``X_post`` (4, 4): after the motion -> child link frame.  ``lower``/``upper`` rad or m
    (+-inf when unbounded), ``max_velocity`` rad/s or m/s, ``max_acceleration`` rad/s^2 or m/s^2
    (inf when unknown).  ``coupling`` makes the joint dependent (not commanded).
    """

    name: str
    joint_type: JointType
    parent: str
    child: str
    X_pre: np.ndarray
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    X_post: np.ndarray | None = None
    lower: float = -math.inf
    upper: float = math.inf
    max_velocity: float = math.inf
    max_acceleration: float = math.inf
    coupling: Coupling | None = None

    def __post_init__(self) -> None:
        # a type given as its string ("prismatic") failed every ``is JointType.X`` test: the joint was
        # exported and checked as revolute, and "fixed" became a commanded joint
        object.__setattr__(self, "joint_type", joint_type_from(self.joint_type, f"joint {self.name!r}"))
        for key in ("lower", "upper", "max_velocity", "max_acceleration"):
            v = getattr(self, key)
            try:
                x = math.nan if isinstance(v, (bool, np.bool_)) else float(v)
            except (TypeError, ValueError):
                x = math.nan
            if math.isnan(x):
                raise KinematicsError(f"joint {self.name!r}: {key}: expected a number (rad or m, +-inf when unbounded), "
                                      f"got {v!r}")
            object.__setattr__(self, key, x)


def _readonly(a) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


def _check_X(value, name: str) -> np.ndarray:
    try:
        X = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise KinematicsError(f"{name}: expected a 4x4 pose, got {value!r}") from exc
    if X.shape != (4, 4):
        raise KinematicsError(f"{name}: expected a 4x4 pose, got shape {X.shape}")
    if not np.all(np.isfinite(X)):
        raise KinematicsError(f"{name}: contains NaN or infinite values")
    R = X[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0 or not np.allclose(X[3], [0, 0, 0, 1]):
        raise KinematicsError(f"{name}: not a rigid transform (rotation not orthonormal or last row not [0 0 0 1])")
    return X


class Robot:
    """An immutable kinematic tree (chain or tree) with joint limits and collision shapes.

    Build with :meth:`from_dh` or :meth:`from_urdf`; ``with_*`` methods return modified copies.

    Attributes
    ----------
    name : str
    joint_names : tuple[str, ...]      independent movable joints, the order of ``q``
    link_names : tuple[str, ...]       all links, root first (topological): the FK output order
    lower, upper : (n_joints,) float64  rad or m; -inf/+inf for continuous joints
    max_velocity, max_acceleration : (n_joints,) float64  rad/s (m/s), rad/s^2 (m/s^2); inf if unknown
    X_WB : (4, 4) float64              pose of the root link in the world W
    link_shapes : Mapping[str, tuple[Shape, ...]]   collision shapes in each link's own frame L
    adjacent_pairs : frozenset[tuple[str, str]]     link pairs joined by one joint (names sorted)
    tool_link : str                    end-effector link used by IK by default (the last link)
    ik : str or None                   the IK routine the model file names (``ik:``): a registered name
                                       (:func:`register_ik`), ``"module:function"`` or ``"numeric"``;
                                       None: the routine registered for ``name``, else numeric
    """

    def __init__(
        self,
        name: str,
        root_link: str,
        joints: Sequence[JointSpec],
        *,
        joint_names: Sequence[str] | None = None,
        link_shapes: Mapping[str, Sequence[Shape]] | None = None,
        X_WB=None,
        tool_link: str | None = None,
        dh: tuple | None = None,
        ik: str | None = None,
    ) -> None:
        if not isinstance(name, str) or not name:
            raise KinematicsError(f"Robot.name: expected a non-empty string, got {name!r}")
        self._name = name
        self._ik = None if ik is None else str(ik)
        self._root = str(root_link)
        self._specs = tuple(joints)
        for k, s in enumerate(self._specs):
            if not isinstance(s, JointSpec):
                raise KinematicsError(f"Robot {name!r}: joints[{k}]: expected a JointSpec, got {type(s).__name__}")
        self._dh = dh
        X_WB = np.eye(4) if X_WB is None else _check_X(X_WB, "X_WB")
        self._X_WB = _readonly(X_WB)
        self._order_links()
        self._resolve_joints(joint_names)
        self._tree = self._flatten()
        shapes = {ln: () for ln in self._link_names}
        self._link_shapes = types.MappingProxyType(shapes)
        if link_shapes:
            self._link_shapes = self._merged_shapes(link_shapes)
        self._tool_link = self._link_names[-1] if tool_link is None else tool_link
        if self._tool_link not in self._link_index:
            raise KinematicsError(f"tool_link: unknown link {self._tool_link!r}; links are {list(self._link_names)}")

    # ------------------------------------------------------------------ construction
    def _order_links(self) -> None:
        children: dict[str, list[JointSpec]] = {}
        seen_joint: set[str] = set()
        child_of: dict[str, str] = {}
        for j in self._specs:
            if j.name in seen_joint:
                raise KinematicsError(f"joint {j.name!r}: duplicate joint name")
            seen_joint.add(j.name)
            if j.child in child_of:
                raise KinematicsError(f"link {j.child!r} has two parent joints ({child_of[j.child]!r}, {j.name!r}); not a tree")
            if j.child == self._root:
                raise KinematicsError(f"joint {j.name!r}: the root link {self._root!r} cannot be a child")
            child_of[j.child] = j.name
            children.setdefault(j.parent, []).append(j)
        order = [self._root]
        spec_of_link: list[JointSpec | None] = [None]
        stack = list(reversed(children.get(self._root, [])))
        while stack:  # depth-first, siblings in declaration order
            j = stack.pop()
            order.append(j.child)
            spec_of_link.append(j)
            stack.extend(reversed(children.get(j.child, [])))
        if len(order) != len(self._specs) + 1:
            unreachable = sorted({j.child for j in self._specs} - set(order))
            raise KinematicsError(f"links {unreachable} are not connected to the root link {self._root!r}")
        self._link_names = tuple(order)
        self._link_index = {n: i for i, n in enumerate(order)}
        self._spec_of_link = tuple(spec_of_link)
        self._parent_index = np.array([-1] + [self._link_index[s.parent] for s in spec_of_link[1:]], dtype=np.int64)
        self._parent_index.flags.writeable = False

    def _resolve_joints(self, joint_names) -> None:
        movable = [s for s in self._spec_of_link[1:] if s.joint_type is not JointType.FIXED]
        # a coupling whose terms name its own joint keeps that joint commanded (a "drive" coupling:
        # GMF S-480, where the commanded forearm angle q3 gives the DH elbow angle q3 - q2)
        independent = [s for s in movable if s.coupling is None or s.name in s.coupling.terms]
        by_name = {s.name: s for s in movable}
        if joint_names is not None:
            names = tuple(str(n) for n in joint_names)
            if sorted(names) != sorted(s.name for s in independent):
                raise KinematicsError(
                    f"joint_names {list(names)} must list the independent movable joints "
                    f"{[s.name for s in independent]} (in any order)"
                )
        else:
            names = tuple(s.name for s in independent)
        self._joint_names = names
        jindex = {n: k for k, n in enumerate(names)}
        specs = [by_name[n] for n in names]
        self._joint_types = tuple(s.joint_type for s in specs)
        lower = np.array([s.lower for s in specs], dtype=np.float64)
        upper = np.array([s.upper for s in specs], dtype=np.float64)
        for s, lo, hi in zip(specs, lower, upper):
            if np.isnan(lo) or np.isnan(hi) or lo > hi:
                raise KinematicsError(f"joint {s.name!r}: limits must satisfy lower <= upper, got [{lo}, {hi}]")
        vmax = np.array([s.max_velocity for s in specs], dtype=np.float64)
        amax = np.array([s.max_acceleration for s in specs], dtype=np.float64)
        for s, v, a in zip(specs, vmax, amax):
            if not (v > 0.0) or not (a > 0.0):
                raise KinematicsError(f"joint {s.name!r}: max_velocity and max_acceleration must be > 0, got {v}, {a}")
        self._lower, self._upper = _readonly(lower), _readonly(upper)
        self._vmax, self._amax = _readonly(vmax), _readonly(amax)

        # resolve couplings (possibly chained) to terms over independent joints
        resolved: dict[str, tuple[dict[int, float], float]] = {
            n: ({k: 1.0}, 0.0) for n, k in jindex.items() if by_name[n].coupling is None
        }
        own = {n: ({k: 1.0}, 0.0) for n, k in jindex.items()}  # a drive coupling's own command

        def resolve(name: str, stack: tuple[str, ...]) -> tuple[dict[int, float], float]:
            if name in resolved:
                return resolved[name]
            if name in stack:
                raise KinematicsError(f"coupling cycle through joints {list(stack) + [name]}")
            s = by_name.get(name)
            if s is None or s.coupling is None:
                raise KinematicsError(f"coupling of joint {stack[-1]!r}: unknown joint {name!r}; movable joints are {sorted(by_name)}")
            terms: dict[int, float] = {}
            off = s.coupling.offset
            for src, coeff in s.coupling.terms.items():
                t, o = own[src] if src == name else resolve(src, stack + (name,))
                off += coeff * o
                for k, c in t.items():
                    terms[k] = terms.get(k, 0.0) + coeff * c
            resolved[name] = (terms, off)
            return resolved[name]

        self._couplings = tuple(s.coupling for s in movable if s.coupling is not None)
        for s in movable:
            resolve(s.name, ())
        self._resolved = resolved

    def _flatten(self) -> FlatTree:
        n = len(self._link_names)
        X_pre = np.tile(np.eye(4), (n, 1, 1))
        X_post = np.tile(np.eye(4), (n, 1, 1))
        has_post = np.zeros(n, dtype=np.bool_)
        axis = np.tile([0.0, 0.0, 1.0], (n, 1))
        jtype = np.zeros(n, dtype=np.int64)
        offset = np.zeros(n)
        term_start = [0, 0]  # the root (link 0) has no joint terms
        term_joint: list[int] = []
        term_coeff: list[float] = []
        X_pre[0] = self._X_WB
        for i in range(1, n):
            s = self._spec_of_link[i]
            X_pre[i] = _check_X(s.X_pre, f"joint {s.name!r}: origin")
            if s.X_post is not None:
                X_post[i] = _check_X(s.X_post, f"joint {s.name!r}: X_post")
                has_post[i] = not np.array_equal(X_post[i], np.eye(4))
            jtype[i] = _JT_CODE[s.joint_type]
            if s.joint_type is not JointType.FIXED:
                ax = np.asarray(s.axis, dtype=np.float64)
                nrm = float(np.linalg.norm(ax)) if ax.shape == (3,) and np.all(np.isfinite(ax)) else 0.0
                if nrm == 0.0:
                    raise KinematicsError(f"joint {s.name!r}: axis must be a finite non-zero 3-vector, got {s.axis!r}")
                axis[i] = ax / nrm
                terms, off = self._resolved[s.name]
                offset[i] = off
                for k, c in sorted(terms.items()):
                    term_joint.append(k)
                    term_coeff.append(c)
            term_start.append(len(term_joint))
        arrays = dict(
            parent=self._parent_index, X_pre=X_pre, axis=axis, jtype=jtype, X_post=X_post, has_post=has_post,
            offset=offset, term_start=np.array(term_start, dtype=np.int64),
            term_joint=np.array(term_joint, dtype=np.int64), term_coeff=np.array(term_coeff, dtype=np.float64),
        )
        for a in arrays.values():
            a.flags.writeable = False
        return FlatTree(**arrays)

    def _merged_shapes(self, link_shapes) -> Mapping[str, tuple[Shape, ...]]:
        merged = dict(self._link_shapes)
        if not isinstance(link_shapes, Mapping):
            raise KinematicsError(f"link_shapes: expected a mapping link -> shapes, got {type(link_shapes).__name__}")
        for link, shapes in dict(link_shapes).items():
            if link not in self._link_index:
                raise KinematicsError(f"link_shapes: unknown link {link!r}; links are {list(self._link_names)}")
            shapes = tuple(shapes)
            for k, sh in enumerate(shapes):
                if not isinstance(sh, Shape):
                    raise KinematicsError(f"link_shapes[{link!r}][{k}]: expected an armguard.geometry shape, got {type(sh).__name__}")
            merged[link] = shapes
        return types.MappingProxyType(merged)

    def __reduce__(self):  # rebuild from the constructor's inputs (mappingproxy does not pickle)
        return (_rebuild_robot, (self._name, self._root, self._specs, dict(
            joint_names=self._joint_names, link_shapes=dict(self._link_shapes), X_WB=self._X_WB,
            tool_link=self._tool_link, dh=self._dh, ik=self._ik)))

    def _copy(self, **changes) -> "Robot":
        kw = dict(
            joint_names=self._joint_names, link_shapes=dict(self._link_shapes), X_WB=self._X_WB,
            tool_link=self._tool_link, dh=self._dh, ik=self._ik,
        )
        kw.update(changes)
        name = kw.pop("name", self._name)
        return Robot(name, self._root, self._specs, **kw)

    # ------------------------------------------------------------------ public model
    name = property(lambda self: self._name)
    joint_names = property(lambda self: self._joint_names)
    link_names = property(lambda self: self._link_names)
    lower = property(lambda self: self._lower)
    upper = property(lambda self: self._upper)
    max_velocity = property(lambda self: self._vmax)
    max_acceleration = property(lambda self: self._amax)
    X_WB = property(lambda self: self._X_WB)
    link_shapes = property(lambda self: self._link_shapes)
    tool_link = property(lambda self: self._tool_link)
    ik = property(lambda self: self._ik)
    joint_types = property(lambda self: self._joint_types, doc="JointType of each joint in ``joint_names``.")
    couplings = property(lambda self: self._couplings, doc="The couplings (dependent joints) of the model.")
    dh = property(lambda self: self._dh, doc="``(convention, rows)`` when built from a DH table, else None.")
    root_link = property(lambda self: self._root)
    joints = property(lambda self: self._specs, doc="All joints (fixed and dependent included) as JointSpec.")
    flat_tree = property(lambda self: self._tree, doc="The flattened arrays the FK kernel reads (see ``_fk``).")

    @property
    def n_joints(self) -> int:
        """Number of independent movable joints (the length of ``q``)."""
        return len(self._joint_names)

    @property
    def adjacent_pairs(self) -> frozenset[tuple[str, str]]:
        return frozenset(tuple(sorted((s.parent, s.child))) for s in self._specs)

    def link_index(self, name: str) -> int:
        """Index of link ``name`` in ``link_names`` (the FK output order)."""
        try:
            return self._link_index[name]
        except KeyError:
            raise KinematicsError(f"robot {self._name!r}: unknown link {name!r}; links are {list(self._link_names)}") from None

    def parent_link(self, name: str) -> str | None:
        """Name of the parent link of ``name`` (None for the root)."""
        i = self.link_index(name)
        p = int(self._parent_index[i])
        return None if p < 0 else self._link_names[p]

    def joint_of_link(self, name: str) -> JointSpec | None:
        """The joint whose child is link ``name`` (None for the root)."""
        return self._spec_of_link[self.link_index(name)]

    def __repr__(self) -> str:
        return f"Robot({self._name!r}, {self.n_joints} joints, {len(self._link_names)} links)"

    # ------------------------------------------------------------------ validation
    def check_q(self, q) -> np.ndarray:
        """Coerce ``q`` to float64 ``(..., n_joints)`` (rad or m); KinematicsError on NaN/inf, wrong length,
        booleans or complex values (read as 1 rad, or their real part)."""
        refuse_complex_or_bool(q, f"robot {self._name!r}: q", KinematicsError)
        try:
            arr = np.asarray(q, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise KinematicsError(f"robot {self._name!r}: q must be numbers, got {q!r}") from exc
        if arr.ndim == 0 or arr.shape[-1] != self.n_joints:
            raise KinematicsError(
                f"robot {self._name!r}: q must have {self.n_joints} values in its last axis "
                f"({', '.join(self._joint_names)}), got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
            where = f"joint {self._joint_names[bad[-1]]!r}" + (f" of row {bad[:-1]}" if len(bad) > 1 else "")
            raise KinematicsError(f"robot {self._name!r}: q contains NaN or infinite values (first: {where}, "
                                  f"{float(arr[bad])})")
        return arr

    def within_limits(self, q, *, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
        """``(...)`` bool: whether every joint of ``q`` (..., n) is within [lower, upper] (+- ``tol.joint_limit``)."""
        q = self.check_q(q)
        return np.all((q >= self._lower - tol.joint_limit) & (q <= self._upper + tol.joint_limit), axis=-1)

    def check_limits(self, q, *, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
        """Like :meth:`check_q`, and raise KinematicsError naming the first joint outside its limits."""
        q = self.check_q(q)
        bad = (q < self._lower - tol.joint_limit) | (q > self._upper + tol.joint_limit)
        if np.any(bad):
            idx = tuple(int(i) for i in np.argwhere(bad)[0])
            k = idx[-1]
            at = "" if len(idx) == 1 else f" (row {idx[0]})" if len(idx) == 2 else f" (at index {idx[:-1]})"
            raise KinematicsError(
                f"robot {self._name!r}: joint {self._joint_names[k]!r} = {q[idx]:.10g} is outside its limits "
                f"[{self._lower[k]:.10g}, {self._upper[k]:.10g}]{at}"
            )
        return q

    # ------------------------------------------------------------------ kinematics
    def forward_kinematics(self, q) -> np.ndarray:
        """World poses of all links: ``q`` (..., n_joints) -> ``X_WL`` (..., n_links, 4, 4), in ``link_names`` order.

        Batched in a numba kernel (one compiled kernel for any tree).  Limits are not checked.
        """
        return fk_kernel(self._tree, self.check_q(q))

    def forward_kinematics_reference(self, q) -> np.ndarray:
        """Slow, obviously-correct FK (products of 4x4 joint transforms); same contract as :meth:`forward_kinematics`."""
        return fk_reference(self._tree, self.check_q(q))

    def link_pose(self, q, link: str | None = None) -> np.ndarray:
        """``X_WL`` (..., 4, 4) of one link (default: ``tool_link``)."""
        i = self.link_index(self._tool_link if link is None else link)
        return self.forward_kinematics(q)[..., i, :, :]

    def jacobian(self, q, link: str | None = None, p_L=None) -> np.ndarray:
        """Geometric Jacobian of point ``p_L`` (3,) m of ``link`` (default ``tool_link``, its origin).

        Returns ``(..., 6, n_joints)``: rows ``[v_WP; w_WL]`` (m/s, rad/s per unit joint speed) in W,
        so ``[v; w] = J @ qdot``.  Couplings and mimic joints contribute through their coefficients.
        """
        from ._jacobian import jacobian

        return jacobian(self, self.check_q(q), link, p_L)

    def jacobian_reference(self, q, link: str | None = None, p_L=None) -> np.ndarray:
        """Slow NumPy Jacobian (one joint column at a time); same contract as :meth:`jacobian`."""
        from ._jacobian import jacobian_reference

        return jacobian_reference(self, self.check_q(q), link, p_L)

    def inverse_kinematics(self, X_WE, *, q_seed=None, link: str | None = None, rng=None,
                           tol: Tolerances = DEFAULT_TOLERANCES, position_only: bool = False):
        """Joint values placing ``link`` (default ``tool_link``) at ``X_WE`` (4, 4); returns an IKResult.

        Uses the routine the model file names (``ik``, :meth:`with_ik`), else the plug-in registered
        for this robot's name (:func:`register_ik`), when ``link`` is the tool link; else damped least
        squares (with an ``ArmguardWarning``, once per robot, when the model names no routine) within limits, from ``q_seed`` (default zeros) and
        ``tol.ik_restarts`` random starts drawn from ``rng`` (default ``default_rng(0)``: repeatable).
        ``position_only`` reaches the position of ``X_WE`` with any orientation (arms with fewer
        than six joints; numerical solver).  ``q`` is None unless the status is SUCCESS; a success
        is verified by forward kinematics against ``tol.ik_position`` / ``tol.ik_orientation``.
        """
        from ._ik import solve_ik

        return solve_ik(self, X_WE, q_seed=q_seed, link=link, rng=rng, tol=tol, position_only=position_only)

    # ------------------------------------------------------------------ copies
    def with_base(self, X_WB) -> "Robot":
        """A copy mounted at ``X_WB`` (4, 4), the pose of the root link in W."""
        return self._copy(X_WB=_check_X(X_WB, "X_WB"))

    def with_link_shapes(self, link_shapes: Mapping[str, Sequence[Shape]]) -> "Robot":
        """A copy whose links listed in ``link_shapes`` get those shapes (in the link frame); others keep theirs."""
        return self._copy(link_shapes=dict(self._merged_shapes(link_shapes)))

    def with_name(self, name: str) -> "Robot":
        """A copy named ``name`` (the IK plug-in registry is keyed by name)."""
        return self._copy(name=name)

    def with_ik(self, routine: str | None) -> "Robot":
        """A copy whose inverse kinematics is ``routine`` (a registered name, ``"module:function"``, or
        ``"numeric"``; checked now: an unknown routine raises :class:`~armguard.KinematicsError`)."""
        if routine is not None:
            from ._ik import resolve_ik

            resolve_ik(routine)
        return self._copy(ik=routine)

    def with_tool_link(self, link: str) -> "Robot":
        """A copy whose IK end-effector is ``link``."""
        self.link_index(link)
        return self._copy(tool_link=link)

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_dh(cls, name, rows, *, convention="standard", joint_names=None, link_names=None, lower=None,
                upper=None, max_velocity=None, max_acceleration=None, couplings=(), link_shapes=None,
                X_WB=None, X_LT=None) -> "Robot":
        """A chain from a DH table; see :func:`armguard.kinematics._dh.robot_from_dh`."""
        from ._dh import robot_from_dh

        return robot_from_dh(
            cls, name, rows, convention=convention, joint_names=joint_names, link_names=link_names, lower=lower,
            upper=upper, max_velocity=max_velocity, max_acceleration=max_acceleration, couplings=couplings,
            link_shapes=link_shapes, X_WB=X_WB, X_LT=X_LT,
        )

    @classmethod
    def from_urdf(cls, path, *, name=None, X_WB=None, load_collision=True, mesh_dir=None) -> "Robot":
        """A tree from a URDF file, through Pinocchio: :func:`armguard.model._robot_urdf.robot_from_urdf`
        (one layer up: reached through :mod:`armguard._hooks`, which the package root fills)."""
        from .. import _hooks

        return _hooks.read_robot_urdf(path, name=name, X_WB=X_WB, load_collision=load_collision, mesh_dir=mesh_dir)


def _rebuild_robot(name, root, specs, kwargs) -> Robot:
    return Robot(name, root, specs, **kwargs)
