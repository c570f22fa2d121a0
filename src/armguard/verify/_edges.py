"""Certified edges for motion planners: is the straight joint-space motion ``q0 -> q1`` free?

A sampling planner asks this of thousands of short edges (OMPL's ``MotionValidator``, MoveIt's and
Drake's edge checks).  Those peers sample the edge every 0.01-0.05 rad and can step over a thin
obstacle between two samples; :meth:`Verifier.check_edges` answers for every configuration of the
edge, with the lever-arm bounds of the certified verifier (:mod:`._motion`, per pair over the joints
between its two links' common ancestor and either link: :func:`._motion.relative_joints`).

**The covering** (Schwarzer, Saha & Latombe, *Adaptive dynamic collision checking for single and
multiple articulated robots in complex environments*, IEEE T-RO 21(3), 2005, §III: an evaluated
configuration with clearances ``d_p`` is the centre of a free interval).  Along
``q(s) = q0 + s (q1 - q0)`` pair ``p``'s clearance shrinks by at most ``rate_p |s' - s|``, so an
evaluation at ``s`` proves every ``s'`` with ``|s' - s| < rho = min_p (d_p - m) / rate_p`` at least
``m`` (the margin) from every obstacle.  Both ends are evaluated first; then, widest first, each
interval not yet covered by two neighbouring evaluations' radii is evaluated at its middle and split
in two.  The edge is

* ``CLEAR`` when the radii cover ``[0, 1]``: certified, not sampled;
* ``COLLISION`` at the first evaluation whose smallest gap ``min_p d_p - m`` is at most
  ``Tolerances.verify_contact``: a configuration of the edge in contact (or within the margin),
  found widest gap first, so in the middle of a long collision rather than at its start; with
  ``first_contact=True`` conservative advancement then goes from the end of the prefix proven free
  to the first contact (as :meth:`Verifier.verify` of the two-knot trajectory does);
* ``INCOMPLETE`` when ``max_evaluations`` are spent (``Tolerances.edge_max_evaluations``, 1000, by
  default: a grazing edge), never ``CLEAR``.

Every evaluation is one ``pair_distances`` of the moving robot's pairs (an edge end met before in the
same call, a roadmap's node or a common start, takes the clearances found then: the same configuration,
the same bits); the per-pair arithmetic is the certified verifier's :func:`._advance.advance_step` (its
``step`` is ``rho``).  A NaN clearance
is an error, never a verdict.
"""

from __future__ import annotations

import enum
import heapq
import math
import time as _time
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from .._errors import ArmguardError, KinematicsError, VerificationError
from .._values import has_bool, refuse_complex_or_bool
from ._advance import advance_step
from ._record import _Run

__all__ = ["EdgeStatus", "EdgeResults", "check_edges_on"]


class EdgeStatus(enum.IntEnum):
    """The verdict on one edge (``EdgeResults.code`` holds these values)."""

    CLEAR = 0  #: every configuration of the edge at least the margin from every obstacle (certified)
    COLLISION = 1  #: a configuration of the edge found in contact (within the margin)
    INCOMPLETE = 2  #: the evaluation budget was spent before either was proven: no verdict


@dataclass(frozen=True)
class EdgeResults:
    """The verdicts on ``M`` edges ``Q0[i] -> Q1[i]`` (:meth:`Verifier.check_edges`); arrays read only.

    Attributes
    ----------
    code : (M,) int8
        :class:`EdgeStatus` values.
    s_free : (M,) float64, 1
        The edge's prefix proven clear: every configuration with ``s <= s_free`` (0 at ``Q0[i]``,
        1 at ``Q1[i]``) is at least ``margin`` from every obstacle; 1 for CLEAR, the last valid
        fraction of OMPL's ``checkMotion`` for COLLISION (at most ``s``: a clearance within
        ``verify_contact`` of the margin is a COLLISION, and may lie in a proven interval; ``-inf`` when
        ``Q0[i]`` itself is in contact), what the budget covered for INCOMPLETE.
    s : (M,) float64, 1
        COLLISION: where along the edge the configuration in contact was found (the first contact with
        ``first_contact=True``, within the contact tolerance).  INCOMPLETE: the evaluated
        configuration of smallest clearance.  NaN for CLEAR.
    q : (M, n) float64
        That configuration, all of the robot's joints in its order; NaN rows for CLEAR.
    distance : (M,) float64, m
        Its smallest clearance (COLLISION: at most ``margin + Tolerances.verify_contact``); NaN for CLEAR.
    pair : (M,) object
        Its closest pair ``(a, b)`` (scene owners, as :class:`armguard.verify.Collision` names them);
        None for CLEAR.
    evaluations : (M,) int64
        Clearance evaluations spent on each edge.
    robot : str
    joint_names : tuple of str
        The columns of ``Q0`` and ``Q1`` (the robot's joints, or the subset ``joints=`` named).
    held : dict
        The robot's joints not in ``joint_names`` and the value each was held at.
    margin : float or dict, m
        The margin every configuration keeps: one for every pair, or by pair category
        (``{"arm-arm": 0.0, "arm-vehicle": 0.02, ...}``, every checked category named; a mapping given), or
        by pair of parts (``{("ur5/ee_link", "ur5/forearm_link"): 0.01, ...}``; an array given).
    elapsed_s : float
        Wall time of the whole call.
    """

    code: np.ndarray
    s_free: np.ndarray
    s: np.ndarray
    q: np.ndarray
    distance: np.ndarray
    pair: np.ndarray
    evaluations: np.ndarray
    robot: str
    joint_names: tuple
    held: dict
    margin: float | dict
    elapsed_s: float

    def __post_init__(self) -> None:
        for name in ("code", "s_free", "s", "q", "distance", "pair", "evaluations"):
            getattr(self, name).flags.writeable = False

    def __len__(self) -> int:
        return len(self.code)

    @property
    def status(self) -> list:
        """``[EdgeStatus]`` per edge."""
        return [EdgeStatus(int(c)) for c in self.code]

    @property
    def clear(self) -> np.ndarray:
        """``(M,) bool``: the edges certified free (an INCOMPLETE edge is not)."""
        return self.code == EdgeStatus.CLEAR

    def counts(self) -> dict:
        """``{status name: number of edges}``."""
        return {st.name.lower(): int(np.sum(self.code == st)) for st in EdgeStatus}

    def summary(self) -> str:
        c = self.counts()
        ev = self.evaluations
        med = float(np.median(ev)) if len(ev) else 0.0
        if isinstance(self.margin, dict) and all(isinstance(k, str) for k in self.margin):
            hit = ("in collision or within their category's margin ("
                   + ", ".join(f"{c} {m * 1e3:g} mm" for c, m in sorted(self.margin.items())) + ")")
        elif isinstance(self.margin, dict):
            v = list(self.margin.values())
            hit = f"in collision or within their pair's margin ({min(v) * 1e3:g} to {max(v) * 1e3:g} mm)"
        else:
            hit = "in collision" if self.margin == 0.0 else f"in collision or within the margin ({self.margin * 1e3:g} mm)"
        who = "every robot (*)" if self.robot == ALL_ROBOTS else repr(self.robot)
        held = (f"; held still (the Verifier's home, or its q_others): {', '.join(f'{j} = {v:g}' for j, v in self.held.items())}" if self.held else "")
        return (f"{len(self)} edges of {who}: {c['clear']} clear, {c['collision']} {hit}, "
                f"{c['incomplete']} incomplete (evaluations per edge: median {med:g}, max "
                f"{int(ev.max()) if len(ev) else 0}; {self.elapsed_s * 1e3:.1f} ms){held}")


def _rows(Q, name: str, joint_names, scene, robot: str, whole: bool = True) -> np.ndarray:
    n = len(joint_names)
    if Q is None or isinstance(Q, (str, bytes)):
        raise VerificationError(f"{name}: expected an array of joint values (M, {n}) or ({n},), got {Q!r}")
    refuse_complex_or_bool(Q, name, VerificationError)
    try:
        Q = np.asarray(Q, dtype=np.float64)
    except (TypeError, ValueError):
        dt = getattr(Q, "dtype", None)
        kind = {"U": "text", "S": "bytes", "O": "Python objects"}.get(getattr(dt, "kind", ""), str(dt))
        got = f"an array of {kind} (dtype {dt})" if dt is not None else type(Q).__name__
        raise VerificationError(f"{name}: expected numbers (M, {n}) or ({n},), got {got}") from None
    bad = np.argwhere(~np.isfinite(Q))
    if len(bad):
        raise VerificationError(f"{name}{[int(k) for k in bad[0]] if Q.ndim > 1 else [int(bad[0][0])]}: NaN or infinite "
                                f"({int(len(bad))} such values)")
    if Q.ndim == 1:
        Q = Q[None, :]
    if Q.ndim != 2 or Q.shape[1] != n:
        hint = []
        width = Q.shape[1] if Q.ndim == 2 else None
        if robot == ALL_ROBOTS:
            one = [rn for rn, r in scene.robots.items() if len(r.joint_names) == width]
            if one:
                hint.append(f"one robot's joints? pass robot={one[0]!r}")
        elif len(scene.robots) > 1 and width == len(scene.joint_names):
            hint.append(f"the scene's configuration of all robots: scene.split_q(Q)[{robot!r}] takes this robot's, "
                        f"robot={ALL_ROBOTS!r} moves them all")
        if width is not None and width < n and whole:
            hint.append("a subset of the joints? name its columns with joints= (a list, or an SRDF group's name)")
        elif width is not None and width != n:
            hint.append("a Pinocchio configuration converts with model.scene_q(Q)")
        raise VerificationError(f"{name}: expected shape (M, {n}) or ({n},), one value per joint {list(joint_names)}, "
                                f"got {np.shape(Q)}" + ("; " + "; ".join(hint) if hint else ""))
    return Q


def _within_limits(rob, Q0: np.ndarray, Q1: np.ndarray, tol) -> None:
    """The ends within the joint limits (then the whole straight edge is), else the culprit named."""
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    if bool(np.all((Q0 >= lo) & (Q0 <= hi) & (Q1 >= lo) & (Q1 <= hi))):
        return  # inside the limits themselves (the robot's own test allows their tolerance too)
    if bool(np.all(rob.within_limits(np.concatenate([Q0, Q1]), tol=tol))):
        return
    for name, Q in (("Q0", Q0), ("Q1", Q1)):
        for i, q in enumerate(Q):
            try:
                rob.check_limits(q, tol=tol)
            except KinematicsError as exc:
                raise VerificationError(f"{name}[{i}]: {exc}") from None


def _budget(max_evaluations, tol) -> int:
    if max_evaluations is None:
        return int(tol.edge_max_evaluations)
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, (int, np.integer)) or max_evaluations < 2:
        raise VerificationError(f"max_evaluations: expected an integer >= 2 (both ends), got {max_evaluations!r}")
    return int(max_evaluations)


def _margin(margin, model, scene):
    """A float (every pair), or a ``(P,)`` array over ``model``'s (the ClearanceModel's) pairs of parts: from a
    mapping by pair category (:func:`armguard.backends.by_category`), or from an array over the Model's
    pairs (:func:`armguard.backends.pair_margins`) with one margin for each pair of parts; else a
    VerificationError."""
    from ..backends import by_category

    if isinstance(margin, Mapping):
        out = by_category(model.pair_category, margin, VerificationError)
    elif np.ndim(margin) and not isinstance(margin, (str, bytes)):
        out = _per_part_pair(margin, model, scene)
    else:
        return _one_margin(margin, "margin")
    return float(out[0]) if np.all(out == out[0]) else out


def _per_part_pair(margin, model, scene) -> np.ndarray:
    """An ``(n,)`` margin per Model pair as one per pair of parts (the clearance of a pair of parts is the
    least over their shapes' pairs, so their margins must agree: by category and padding they do)."""
    from ..model import model_of

    pairs = model_of(scene).pairs
    try:
        arr = None if isinstance(margin, (list, tuple)) and has_bool(margin) else np.asarray(margin)
    except (TypeError, ValueError):
        arr = None
    if arr is not None and (arr.dtype == bool or arr.dtype.kind not in "fiu"):  # no text, no True read as 1 m
        arr = None
    if arr is None or arr.shape != (len(pairs),):
        raise VerificationError(f"margin: expected a number (m), a mapping by pair category or {len(pairs)} numbers (one "
                                f"per Model pair, Model.pairs order), got {np.shape(margin) if arr is not None else margin!r}")
    out = np.full(len(model.owner_a), np.nan)
    for k, (a, b) in enumerate(zip(pairs.owner_a, pairs.owner_b)):
        i = model._pair_key.get((a, b), model._pair_key.get((b, a)))
        x = float(arr[k])
        if not (math.isfinite(x) and x >= 0.0):
            raise VerificationError(f"margin[{k}] (parts {a!r} - {b!r}): expected a finite number >= 0 (m), got {x!r}")
        if i is None:
            continue
        if out[i] == out[i] and out[i] != x:
            raise VerificationError(f"margin: the pairs of parts {a!r} - {b!r} are given {out[i]:g} and {x:g} m: a pair of "
                                    "parts keeps one margin (pair_margins gives one, by category and padding)")
        out[i] = x
    if np.isnan(out).any():
        k = int(np.flatnonzero(np.isnan(out))[0])
        raise VerificationError(f"margin: no Model pair for the checked parts {model.owner_a[k]!r} - {model.owner_b[k]!r} "
                                "(the array is of another model?)")
    return out


def _one_margin(margin, what: str) -> float:
    m = math.nan
    if not isinstance(margin, (bool, np.bool_)) and np.ndim(margin) == 0 and np.asarray(margin).dtype.kind in "fiu":
        m = float(margin)
    if not (math.isfinite(m) and m >= 0.0):
        raise VerificationError(f"{what}: expected a finite number >= 0 (m), got {margin!r}")
    return m


#: ``robot=`` for edges of every robot at once (the scene's flat joint order, ``scene.joint_names``)
ALL_ROBOTS = "*"


class _AllRobots:
    """Every robot of a scene as one: the flat joint order, limits and messages of each robot's own."""

    def __init__(self, scene) -> None:
        self.name = ALL_ROBOTS
        self.joint_names = tuple(scene.joint_names)
        self._spans, k = [], 0
        for rob in scene.robots.values():
            self._spans.append((rob, k, k + len(rob.joint_names)))
            k += len(rob.joint_names)
        self.lower = np.concatenate([np.asarray(r.lower) for r, _, _ in self._spans])
        self.upper = np.concatenate([np.asarray(r.upper) for r, _, _ in self._spans])

    def within_limits(self, Q, *, tol) -> np.ndarray:
        return np.all([r.within_limits(Q[:, a:b], tol=tol) for r, a, b in self._spans], axis=0)

    def check_limits(self, q, *, tol) -> None:
        for r, a, b in self._spans:
            r.check_limits(q[a:b], tol=tol)


def _robot(verifier, robot):
    """``(name, robot)``: the robot whose edges these are, or every robot (``ALL_ROBOTS``: name None)."""
    names = list(verifier.scene.robots)
    if robot == ALL_ROBOTS:
        return None, _AllRobots(verifier.scene)
    if robot is None and verifier._robot is None and len(names) > 1:
        raise VerificationError(f"this scene has several robots {names}: pass robot= (the one whose edges these "
                                f"are, or {ALL_ROBOTS!r} for all of them at once)")
    rname = verifier._robot_of(None, robot)
    return rname, verifier.scene.robots[rname]


def _columns(rob, joints, scene) -> tuple:
    """``(names, index into the robot's joints)`` of the columns given (all the robot's joints by default)."""
    own = tuple(rob.joint_names)
    if joints is None:
        return own, np.arange(len(own))
    if isinstance(joints, str):  # an SRDF group's name, as an edges file's or a trajectory file's joint_names
        from ..model import model_of

        try:
            robot, group = model_of(scene).group_robot_joints(joints)
        except ArmguardError as exc:
            raise VerificationError(f"joints: expected a list of joint names or an SRDF group's name; {exc}") from None
        if robot != rob.name:  # arms may share joint names (ranger's j1 ...): never another arm's group
            raise VerificationError(f"joints: SRDF group {joints!r} moves robot {robot!r}, not {rob.name!r}")
        joints = group
    names = tuple(str(j) for j in joints)
    if not names:
        raise VerificationError(f"joints: an empty list (no joint to move); the robot's joints are {list(own)}")
    for j in names:
        if j not in own:
            raise VerificationError(f"joints: {j!r} is not a joint of robot {rob.name!r}; its joints are {list(own)}")
    if len(set(names)) != len(names):
        raise VerificationError(f"joints: a joint named twice in {list(names)}")
    return names, np.array([own.index(j) for j in names], dtype=np.int64)


def _flat(verifier, st, rname):
    """``(flat base configuration, k0, k1)`` of the state for robot ``rname`` (None: every robot), kept on it
    (read only)."""
    out = st.edge_bases.get(rname)
    if out is None:
        if rname is None:
            base = verifier.scene.flat_q(st.base)
            out = (base, 0, len(base))
        else:
            out = verifier._flat(rname, st.base)
        out[0].flags.writeable = False
        st.edge_bases[rname] = out
    return out


def _record_of(st, rname: str, base, k0: int, k1: int) -> _Run:
    """This thread's record for ``rname`` on state ``st`` (built once: its arrays are reused edge after edge;
    held by the thread, and freed with it)."""
    mine = st.edge_records.__dict__
    run = mine.get(rname)
    if run is None:
        run = _Run(st.model, base.copy(), k0, k1, rname)
        if not run.moving.any():
            raise VerificationError(f"robot {rname!r} has no pair to check (no shapes, or every pair with it disabled)")
        mine[rname] = run
    return run


_BIG_ANGLE = 1e6
"""rad: a continuous joint's start beyond it is taken at its angle in (-pi, pi] by :func:`_shortest` (at 1e17 a
short turn added to it rounds away)."""


def _shortest(rob, Q0: np.ndarray, Q1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Q0, Q1)`` with each continuous joint (no limits) of ``Q1`` moved by whole turns to within pi of ``Q0``'s:
    the edge turns it the short way, as ``pinocchio.interpolate`` and OMPL's SO(2) do.  The turn is found from
    both ends' angles (``atan2(sin, cos)``, as ``Model.pin_q`` reads Pinocchio's ``(cos, sin)``): at 1e17 rad the
    difference of the raw values rounded to whole turns, and an edge to a colliding angle came out still (CLEAR).
    ``Q0`` is kept as given (the results' ``q`` lie on the user's segment), but for a start beyond
    :data:`_BIG_ANGLE`, taken at its angle."""
    free = ~(np.isfinite(np.asarray(rob.lower)) | np.isfinite(np.asarray(rob.upper)))
    if not free.any():
        return Q0, Q1
    a0 = np.arctan2(np.sin(Q0[:, free]), np.cos(Q0[:, free]))
    a1 = np.arctan2(np.sin(Q1[:, free]), np.cos(Q1[:, free]))
    d = a1 - a0
    Q0, Q1 = Q0.copy(), Q1.copy()
    start = np.where(np.abs(Q0[:, free]) > _BIG_ANGLE, a0, Q0[:, free])
    Q0[:, free] = start
    Q1[:, free] = start + (d - 2.0 * np.pi * np.round(d / (2.0 * np.pi)))
    return Q0, Q1


def check_edges_on(verifier, st, Q0, Q1, robot, margin, max_evaluations, joints, first_contact=False,
                   continuous="line", progress=None) -> EdgeResults:
    """:meth:`Verifier.check_edges` on one state ``st`` of the scene (its clearance model and configurations)."""
    t_start = _time.perf_counter()
    model = st.model
    rname, rob = _robot(verifier, robot)
    names, cols = _columns(rob, joints, verifier.scene)
    Q0 = _rows(Q0, "Q0", names, verifier.scene, rob.name, joints is None)
    Q1 = _rows(Q1, "Q1", names, verifier.scene, rob.name, joints is None)
    if len(Q0) != len(Q1) and 1 not in (len(Q0), len(Q1)):
        raise VerificationError(f"Q0 and Q1: expected the same number of edges (or one of them a single "
                                f"configuration), got {len(Q0)} and {len(Q1)}")
    Q0, Q1 = np.broadcast_arrays(Q0, Q1)
    m = _margin(margin, model, verifier.scene)
    budget = _budget(max_evaluations, verifier.tol)
    base, k0, k1 = _flat(verifier, st, rname)
    held = {}
    if joints is not None:  # the columns in the robot's order; the joints not given stay where the verifier holds it
        home = base[k0:k1]
        full0, full1 = np.tile(home, (len(Q0), 1)), np.tile(home, (len(Q1), 1))
        full0[:, cols], full1[:, cols] = Q0, Q1
        Q0, Q1 = full0, full1
        held = {j: float(home[k]) for k, j in enumerate(rob.joint_names) if j not in names}
    if continuous == "shortest":
        Q0, Q1 = _shortest(rob, Q0, Q1)
    elif continuous != "line":
        raise VerificationError(f"continuous: expected 'line' (along the angle's line) or 'shortest', got {continuous!r}")
    _within_limits(rob, Q0, Q1, verifier.tol)
    run = _record_of(st, rname, base, k0, k1)
    contact = verifier.tol.verify_contact
    M = len(Q0)
    code = np.full(M, EdgeStatus.CLEAR, dtype=np.int8)
    s_free = np.ones(M)
    s_hit = np.full(M, math.nan)
    q_hit = np.full((M, k1 - k0), math.nan)
    d_hit = np.full(M, math.nan)
    pair = np.full(M, None, dtype=object)
    evals = np.zeros(M, dtype=np.int64)
    dQ = np.zeros(model.n_q)
    known_ends: dict = {}  # the clearances of the edge ends evaluated in this call, by configuration
    for i in range(M):
        q0, q1 = Q0[i], Q1[i]
        dq = q1 - q0
        dQ[k0:k1] = dq
        rates = model.pair_rates(dQ)
        if not np.all(np.isfinite(rates)):
            raise VerificationError("the motion bound is infinite (an unbounded prismatic joint): an edge cannot be certified")
        run.n = run.reused = 0  # one record per edge: its rows are not kept beyond it
        status, free, row, p = _cover(run, q0, q1, dq, rates, m, contact, budget, bool(first_contact), known_ends)
        evals[i] = run.n - run.reused
        if progress is not None and (i + 1) % 64 == 0:
            progress(i + 1, M)
        code[i] = status
        s_free[i] = free
        if status != EdgeStatus.CLEAR:
            s_hit[i] = run.s[row]
            q_hit[i] = run.Q[row]
            d_hit[i] = run.D[row, p]
            pair[i] = (model.owner_a[p], model.owner_b[p])
    if type(m) is float and (isinstance(margin, Mapping) or np.ndim(margin)):  # margins given per category or pair,
        m = np.full(len(model.pair_category), m)  # equal after all: still reported as given (each category's)
    given = m if type(m) is float else _margins_given(m, model, margin)
    return EdgeResults(code, s_free, s_hit, q_hit, d_hit, pair, evals, rob.name, names, held, given,
                       _time.perf_counter() - t_start)


def _margins_given(m, model, margin) -> dict:
    """``EdgeResults.margin`` of margins per pair: by category (a mapping given), else by pair of parts."""
    if isinstance(margin, Mapping):
        return {c: float(x) for c, x in zip(model.pair_category, m)}
    return {(a, b): float(x) for a, b, x in zip(model.owner_a, model.owner_b, m)}


_ENDS = 1024  # edge ends whose clearances one call keeps (a start shared by many goals, a roadmap's nodes)


def _evaluate(run, s, q0, q1, dq, rates, m, ends=None):
    """Evaluate at ``s``: ``(row, gap, closest pair, radius rho)``; a NaN clearance is an error.  ``ends``: the
    clearances of edge ends already evaluated in this call, by configuration (the ends' rows come from there,
    and go there)."""
    q = q0 if s == 0.0 else q1 if s == 1.0 else q0 + s * dq
    if ends is not None and (s == 0.0 or s == 1.0):
        key = q.tobytes()
        known = ends.get(key)
        if known is not None:
            row = run.put(0, s, q, known)
        else:
            row = run.eval(0, s, q)
            if len(ends) >= _ENDS:
                ends.clear()
            ends[key] = run.D[row].copy()
    else:
        row = run.eval(0, s, q)
    d = run.D[row]
    if type(m) is not float:  # a margin per pair: each pair's gap d - m against no margin
        d = d - m
        m = 0.0
    g, p, rho, _ = advance_step(d, d, rates, m, 0.0, False)
    if g != g:
        raise VerificationError(f"a clearance is NaN at s = {s!r} of the edge: no verdict")
    return row, g, int(p), rho


def _prefix(balls) -> float:
    """The end of the covered prefix ``[0, s_free]`` of the closed intervals ``[s - rho, s + rho]`` of
    ``balls`` (``-inf`` when none holds 0: the edge's start is in contact)."""
    end = -math.inf
    for s, rho in sorted(balls, key=lambda b: b[0] - b[1]):  # by left end
        left = s - rho
        if left > max(end, 0.0):
            break  # a gap: the prefix ends here (or 0 itself is not covered)
        end = max(end, s + rho)
    return min(end, 1.0)


def _first_contact(run, q0, q1, dq, rates, m, contact, budget, s_free, s_hit, row, p):
    """From the covering's COLLISION at ``s_hit``: conservative advancement from the proven prefix's end
    ``s_free`` towards it (as the certified verifier), so that ``s`` is the first contact and ``s_free``
    all before it.  With the budget spent first, the covering's answer stands."""
    s = max(s_free, 0.0)
    while run.n < budget:
        r, g, pp, rho = _evaluate(run, s, q0, q1, dq, rates, m)
        if g <= contact:
            return EdgeStatus.COLLISION, s, r, pp
        nxt = s + rho
        if not nxt > s or nxt >= s_hit:  # the contact found is the next one (or nothing is proven past s)
            return EdgeStatus.COLLISION, min(nxt, s_hit), row, p
        s = nxt
    return EdgeStatus.COLLISION, s_free, row, p


def _cover(run, q0, q1, dq, rates, m, contact, budget, first=False, ends=None):
    """The covering of one edge (see the module docstring): ``(status, s_free, row, pair)``; ``row``
    and ``pair`` are the configuration in contact (COLLISION) or of smallest gap (INCOMPLETE);
    ``first``: a COLLISION's configuration is the first contact along the edge (:func:`_first_contact`)."""
    hit = _covering(run, q0, q1, dq, rates, m, contact, budget, ends)
    if first and hit[0] == EdgeStatus.COLLISION and hit[1] >= 0.0:
        s_hit = run.s[hit[2]]
        if hit[1] < s_hit:
            return _first_contact(run, q0, q1, dq, rates, m, contact, budget, hit[1], s_hit, hit[2], hit[3])
    return hit


def _covering(run, q0, q1, dq, rates, m, contact, budget, known=None):
    balls = []
    best = (math.inf, -1, -1)  # gap, row, pair
    ends = (0.0,) if not np.any(dq) else (0.0, 1.0)  # a still edge is one configuration
    for s in ends:
        row, g, p, rho = _evaluate(run, s, q0, q1, dq, rates, m, known)
        if g <= contact:
            return EdgeStatus.COLLISION, min(_prefix(balls), s), row, p
        best = min(best, (g, row, p))
        balls.append((s, rho))
    if len(ends) == 1:
        return EdgeStatus.CLEAR, 1.0, -1, -1
    (a, ra), (b, rb) = balls
    heap = [(-((b - rb) - (a + ra)), a, ra, b, rb)]  # widest uncovered interval first
    while heap:
        _, a, ra, b, rb = heapq.heappop(heap)
        lo, hi = a + ra, b - rb
        if not lo < hi:
            continue  # covered by the two ends' radii
        if run.n >= budget:
            return EdgeStatus.INCOMPLETE, _prefix(balls), best[1], best[2]
        s = 0.5 * (lo + hi)
        row, g, p, rho = _evaluate(run, s, q0, q1, dq, rates, m)
        if g <= contact:  # (a gap within the contact tolerance may lie inside a proven interval: s_free <= s)
            return EdgeStatus.COLLISION, min(_prefix(balls), s), row, p
        best = min(best, (g, row, p))
        balls.append((s, rho))
        if s + rho < hi:
            heapq.heappush(heap, (-(hi - (s + rho)), s, rho, b, rb))
        if lo < s - rho:
            heapq.heappush(heap, (-((s - rho) - lo), a, ra, s, rho))
    return EdgeStatus.CLEAR, 1.0, -1, -1
