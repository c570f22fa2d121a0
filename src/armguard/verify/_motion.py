"""Configuration-independent bounds on how far any point of a link can move (conservative advancement).

For a joint-space straight line ``q(s) = q0 + s (q1 - q0)`` (every Trajectory segment), the
velocity of a point ``p`` of link ``L`` is

    dp/ds = sum_E  c_Ej dq_j ( w_E x (p - a_E) )   (revolute joint E, axis w_E through a_E)
          + sum_E  c_Ej dq_j   u_E                  (prismatic joint E, direction u_E)

over the physical joints ``E`` between the root and ``L`` and the independent joints ``j``
driving them with coefficient ``c_Ej`` (1 for an ordinary joint; a coupling's coefficient
for a dependent joint such as the GMF S-480 parallelogram).  Hence, for every configuration,

    |dp/ds| <= sum_j |dq_j| * lever[j, L],
    lever[j, L] = sum_{E driven by j} |c_Ej| * rho_E(L)      (revolute)   or  |c_Ej|  (prismatic)

with ``rho_E(L)`` an upper bound, over *all* configurations, of the distance from the axis of
``E`` to any point of ``L``.  We take (triangle inequality along the chain)

    rho_E(L) <= dist(axis_E, o_child(E)) + sum_{edges K->M from child(E) to L} maxlen(K->M) + R_L

where ``o_X`` is the origin of link frame X, ``R_L`` the radius of L's geometry about ``o_L``,
and ``maxlen(K->M)`` bounds ``|o_M - o_K|`` over all configurations: ``|f - o_K| + rho_M`` for a
revolute joint (``f`` the foot of ``o_M`` on the axis, fixed in K; ``rho_M`` the radius of the
circle ``o_M`` runs on), ``|o_M - o_K|`` for a fixed joint, and ``|o_M - o_K|`` plus the joint's
travel for a prismatic one.  These are the chain's *configuration-independent lever-arm bounds*
(the bound Schwarzer, Saha & Latombe use for exact edge checking); they hold at every
configuration, so the clearance of a pair can drop by at most ``rate * (s1 - s0)`` on
``[s0, s1]``.

The chain geometry (axes, circle radii, coupling coefficients) is measured from forward
kinematics (the Model's, compiled from ``pin_model``; or the Robot's own chain): ``X_PL(q)``
for every link and its parent at a reference configuration and with each joint moved by
``_PROBE`` — a rigid motion is identified exactly from two poses, so no assumption is made
about DH versus URDF conventions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import VerificationError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["ChainBounds", "chain_bounds", "relative_joints", "shape_radius_about"]

_PROBE = 0.25  # rad (or m) a joint is moved by to identify the motion it drives; any value in (0, pi / max|c|) works:
_FIRST = 1e-3  # it is cut to a 1 rad turn of the fastest link a joint drives, read from a first move of _FIRST


def _inv(X: np.ndarray) -> np.ndarray:
    R = X[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ X[:3, 3]
    return out


def _probes(robot, fk, q_ref, n_q: int) -> np.ndarray:
    """``(n_q,)`` how far each joint is moved to identify the motions it drives: ``_PROBE``, less where that would
    turn a link more than 1 rad (a mimic follower at 8 pi rad/m: a 0.25 probe turned it 2 pi, read as no turn
    at all, and a pair it moves was proved apart).  The rate is read from a first probe of ``_FIRST``,
    which no rate below pi / _FIRST (3,141 rad per unit) wraps."""
    Q = np.repeat(q_ref[None, :], n_q + 1, axis=0)
    for j in range(n_q):
        Q[j + 1, j] += _FIRST
    X = np.asarray(fk(Q), dtype=np.float64)
    if not np.all(np.isfinite(X)):
        raise VerificationError(f"robot {robot.name!r}: forward kinematics is not finite at the reference configuration")
    rate = np.ones(n_q)
    for j in range(n_q):
        for k in range(X.shape[1]):  # each link's own turn (in W: the sum of the joints above it, a bound on each)
            ang, _ = _rotation_angle_axis(X[j + 1, k, :3, :3] @ X[0, k, :3, :3].T)
            rate[j] = max(rate[j], ang / _FIRST)
    if np.any(rate * _FIRST > 1.0):
        raise VerificationError(f"robot {robot.name!r}: a joint turns a link faster than {1.0 / _FIRST:g} rad per unit "
                                "(a mimic multiplier that large): its lever arms cannot be measured")
    return np.where(rate * _PROBE <= 1.0, _PROBE, 1.0 / rate)  # at most a 1 rad turn, far from pi (and every
    # chain turning its links at most 4 rad per unit, as every URDF joint without a fast mimic, keeps _PROBE)


def _rotation_angle_axis(R: np.ndarray) -> tuple[float, np.ndarray]:
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = 0.5 * float(np.linalg.norm(w))
    c = 0.5 * (float(np.trace(R)) - 1.0)
    ang = math.atan2(s, c)
    if s > 0.0:
        return ang, w / (2.0 * s)
    return ang, np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class ChainBounds:
    """Per-robot lever-arm bounds.

    Attributes
    ----------
    robot_name : str
    link_names : tuple[str, ...]
    A : (n_joints, n_links) float64, m/rad
        ``sum_E |c_Ej| rho_E(o_L)`` over revolute joints E driven by j: the bound for the link origin's
        lever (``rho`` without the geometry radius).
    W : (n_joints, n_links) float64, 1
        ``sum_E |c_Ej|`` over revolute joints E driven by j: the bound on the link's angular rate per unit dq_j.
    P : (n_joints, n_links) float64, 1
        ``sum_E |c_Ej|`` over prismatic joints driven by j.
    """

    robot_name: str
    link_names: tuple[str, ...]
    A: np.ndarray
    W: np.ndarray
    P: np.ndarray

    def lever(self, link: str, radius: float) -> np.ndarray:
        """``(n_joints,) float64``: bound on ``|dp/dq_j|`` for every point within ``radius`` (m) of the link origin."""
        k = self.link_names.index(link)
        return self.A[:, k] + self.W[:, k] * radius + self.P[:, k]


def chain_bounds(robot, tol: Tolerances = DEFAULT_TOLERANCES, *, fk=None) -> ChainBounds:
    """Measure the chain of ``robot`` (a :class:`armguard.kinematics.Robot`) and return its lever-arm bounds.

    ``fk``: ``Q (m, n_joints) -> (m, n_links, 4, 4)``, the forward kinematics measured (the
    Model's, :meth:`armguard.model.Model.robot_link_poses`, moving links with ``pin_model``);
    by default the Robot's own chain."""
    names = tuple(robot.link_names)
    n_links = len(names)
    n_q = len(robot.joint_names)
    lo = np.asarray(robot.lower, dtype=np.float64)
    hi = np.asarray(robot.upper, dtype=np.float64)
    both = np.isfinite(lo) & np.isfinite(hi)  # unlimited (continuous) joints: no midpoint, no inf - inf
    mid = 0.5 * (np.where(both, lo, 0.0) + np.where(both, hi, 0.0))
    q_ref = np.where(both, mid, np.where(np.isfinite(lo), lo, np.where(np.isfinite(hi), hi, 0.0)))
    fk = robot.forward_kinematics if fk is None else fk
    probe = _probes(robot, fk, q_ref, n_q)
    Q = np.repeat(q_ref[None, :], n_q + 1, axis=0)
    for j in range(n_q):
        Q[j + 1, j] += probe[j]
    X = np.asarray(fk(Q), dtype=np.float64)  # (n_q + 1, n_links, 4, 4)
    if not np.all(np.isfinite(X)):
        raise VerificationError(f"robot {robot.name!r}: forward kinematics is not finite at the reference configuration")
    scale = max(1.0, float(np.max(np.abs(X[0, :, :3, 3]))))
    eps_len = tol.kinematic_probe * scale
    eps_ang = tol.kinematic_probe

    parent = [None] * n_links
    for k, nm in enumerate(names):
        p = robot.parent_link(nm)
        parent[k] = None if p is None else names.index(p)

    # per edge (link k with its parent): drivers and geometry
    rev_c = np.zeros((n_q, n_links))  # |c| of revolute drivers
    pri_c = np.zeros((n_q, n_links))  # |c| of prismatic drivers
    rho = np.zeros(n_links)  # distance of o_k from the (revolute) axis of its own joint
    maxlen = np.zeros(n_links)  # bound on |o_k - o_parent| over all configurations
    for k in range(n_links):
        pk = parent[k]
        if pk is None:
            continue
        X0 = _inv(X[0, pk]) @ X[0, k]  # X_PL at q_ref
        t0 = X0[:3, 3]
        axis_foot = None
        travel = 0.0
        for j in range(n_q):
            X1 = _inv(X[j + 1, pk]) @ X[j + 1, k]
            M = X1 @ _inv(X0)  # the rigid motion (in P) taking L's points at q_ref to q_ref + probe e_j
            ang, u = _rotation_angle_axis(M[:3, :3])
            t = M[:3, 3]
            if ang > eps_ang:
                rev_c[j, k] = ang / probe[j]
                # fixed points of x -> R x + t: (I - R) a = t, a least-squares point on the axis
                a = np.linalg.lstsq(np.eye(3) - M[:3, :3], t, rcond=None)[0]
                f = a + u * float(np.dot(t0 - a, u))
                rho[k] = max(rho[k], float(np.linalg.norm(t0 - f)))
                axis_foot = f if axis_foot is None else axis_foot
                if abs(float(np.dot(t, u))) > eps_len:
                    raise VerificationError(f"robot {robot.name!r}: link {names[k]!r} moves on a screw, not a revolute or prismatic joint")
            elif float(np.linalg.norm(t)) > eps_len:
                c = float(np.linalg.norm(t)) / probe[j]
                pri_c[j, k] = c
                span = max(hi[j] - q_ref[j], q_ref[j] - lo[j])
                travel += c * span
        if axis_foot is not None:
            maxlen[k] = float(np.linalg.norm(axis_foot)) + rho[k]
        else:
            maxlen[k] = float(np.linalg.norm(t0)) + travel  # inf for an unbounded prismatic joint

    # accumulate along the chain (links are in topological order: parents first)
    A = np.zeros((n_q, n_links))
    Wm = np.zeros((n_q, n_links))
    P = np.zeros((n_q, n_links))
    for k in range(n_links):
        pk = parent[k]
        if pk is None:
            continue
        # every joint above the parent now acts on o_k through one more edge of length <= maxlen[k]
        through = np.where(Wm[:, pk] > 0.0, Wm[:, pk] * maxlen[k] if math.isfinite(maxlen[k]) else math.inf, 0.0)
        A[:, k] = A[:, pk] + through + rev_c[:, k] * rho[k]
        Wm[:, k] = Wm[:, pk] + rev_c[:, k]
        P[:, k] = P[:, pk] + pri_c[:, k]
    # a relative safety margin for the round-off of the measurement
    A = A * (1.0 + tol.kinematic_probe) + np.where(Wm > 0, eps_len, 0.0)
    return ChainBounds(str(robot.name), names, A, Wm * (1.0 + tol.kinematic_probe), P * (1.0 + tol.kinematic_probe))


def _ancestors(robot, link: str) -> list:
    out = [link]
    p = robot.parent_link(link)
    while p is not None:
        out.append(p)
        p = robot.parent_link(p)
    return out


def relative_joints(robot, bounds: ChainBounds, link_a: str, link_b: str) -> list[int]:
    """The joints of ``robot`` (indices into its ``joint_names``) that can change the relative pose
    of its links ``link_a`` and ``link_b``: every joint but those that move only the links' common
    ancestor, and with it both links by one rigid motion (their distance cannot change).

    A joint that moves the common ancestor and also drives an edge between the ancestor and either
    link (a coupled joint) is kept: its angular-rate or prismatic row differs between the link and
    the ancestor.  Without a common ancestor every joint is kept.  On such a pair the clearance's
    rate is bounded by ``sum over these joints of |dq_j| (lever_a[j] + lever_b[j])``: in the
    ancestor's frame the other joints move nothing, and ``lever[j]`` bounds the speed of the link's
    points under joint ``j`` in any frame (a distance to ``j``'s axes)."""
    anc_a, anc_b = _ancestors(robot, link_a), _ancestors(robot, link_b)
    common = next((x for x in anc_a if x in anc_b), None)
    nj = len(robot.joint_names)
    if common is None:
        return list(range(nj))
    ic, ia, ib = (bounds.link_names.index(x) for x in (common, link_a, link_b))
    W, P = bounds.W, bounds.P
    return [j for j in range(nj)
            if W[j, ia] != W[j, ic] or P[j, ia] != P[j, ic] or W[j, ib] != W[j, ic] or P[j, ib] != P[j, ic]]


def shape_radius_about(shapes, p_W: np.ndarray) -> float:
    """Radius (m) of a ball about ``p_W`` ``(3,)`` containing every shape of ``shapes`` (world frame)."""
    r = 0.0
    for s in shapes:
        pts = np.asarray(s.core_points)
        r = max(r, float(np.max(np.linalg.norm(pts - p_W, axis=1))) + float(s.core_radius))
    return r
