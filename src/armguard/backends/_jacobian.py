"""Jacobians of signed distance: ``d(distance)/dq`` for every pair, from the witness points.

For a pair (A, B) with witness points ``p_WA``, ``p_WB`` and the unit normal
``nhat_AB_W = (p_WB - p_WA) / distance`` (from A towards B when apart; in penetration it points
from B's deepest point to A's, ``docs/notation.md``), the derivative of the signed distance
with respect to the joint velocities ``v`` (``pin_model.nv``) is

    d(distance)/dq = nhat_AB_W^T (J_WB(p_WB) - J_WA(p_WA))                       (1)

where ``J_WA(p)`` ``(3, nv)`` is the translational Jacobian of the point ``p`` rigidly attached
to A's link (zero for world-fixed shapes and the workspace walls).  Equation (1) is the
envelope theorem applied to the closest-point problem (Faverjon & Tournassoud, ICRA 1987; Drake's
``CalcDistanceDerivatives``): it is the derivative wherever the witness points are unique and
the distance is not zero; elsewhere it is one of the one-sided derivatives, and ``smooth`` is
False.

With Pinocchio's world-frame Jacobian ``J_j`` ``(6, nv)`` of the link's joint ``j``
(``computeJointJacobians`` then ``getJointJacobian(..., WORLD)``: linear velocity of the point at
W's origin, then angular velocity; zero outside the joint's ancestors; mimic joints folded onto
their leaders), the row of one side is the wrench ``w = [nhat, p x nhat]`` applied to it:
``nhat^T J_W(p) = w^T J_j``.  One Pinocchio call per joint, then one ``einsum`` over all pairs:
no per-pair Python.  This is the framework's witness-point path (coal) and the slow
reference of the analytic backend, which computes the same rows inside its kernel from its own
forward kinematics (:mod:`armguard_analytic._engine._pair_jacobian`).

**Smoothness.**  ``smooth`` is False where

* ``|distance| <= Tolerances.length`` (touching: ``nhat`` is not defined by the witnesses; the
  row is then the forward difference of that pair, a one-sided derivative), or
* the witness points are not unique: A's support face in the direction ``nhat_AB_W`` and B's in
  ``-nhat_AB_W`` (the vertices within ``Tolerances.jacobian_face`` of the support plane; a
  cylinder's disk when ``nhat`` is within ``Tolerances.jacobian_parallel`` of its axis; a
  workspace wall is a plane) span a common direction: a face against a face or an edge, or two
  parallel edges (``|sin| <= Tolerances.jacobian_parallel``).  A capsule is its segment, swept.

The faces are taken from the Model's ``collision_model`` (coal shapes): for the analytic
backend, whose cylinders are circumscribed prisms, a prism's side face counts as the
cylinder's side line (a face against a prism side may then be called smooth).
"""

from __future__ import annotations

import threading
import weakref

import numpy as np
from numba import njit

from .._errors import BackendError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._face_graph import face_scratch, face_span, face_span_graph, vertex_graph  # noqa: F401  (face_span: the reference scan)

__all__ = ["WitnessJacobian", "cores_meet", "finite_difference_rows"]



def _shape_vertices(geom) -> tuple:
    """``(vertices (k, 3) in the shape's frame, disk axis (3,), disk radius)`` of a coal shape:
    the polytope whose (swept) support faces are the shape's (a cylinder: its axis segment plus a
    disk); ``None`` for a shape armguard cannot describe (its pairs get ``smooth = False``)."""
    import coal

    z = np.zeros(3)
    if isinstance(geom, coal.Capsule):
        h = float(geom.halfLength)
        return np.array([[0.0, 0.0, -h], [0.0, 0.0, h]]), z, 0.0
    if isinstance(geom, coal.Sphere):
        return np.zeros((1, 3)), z, 0.0
    if isinstance(geom, coal.Box):
        hx, hy, hz = (float(x) for x in geom.halfSide)
        return np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]), z, 0.0
    if isinstance(geom, coal.Cylinder):
        h = float(geom.halfLength)
        return np.array([[0.0, 0.0, -h], [0.0, 0.0, h]]), np.array([0.0, 0.0, 1.0]), float(geom.radius)
    if isinstance(geom, coal.ConvexBase):
        pts = np.array(geom.points(), dtype=np.float64)
        return pts.reshape(-1, 3), z, 0.0
    return None


@njit(cache=True, nogil=True)
def unique_witness(dims, dirs, tol_par):  # pragma: no cover - numba
    """Whether two support faces of dimensions ``dims`` ``(2,)`` (1-D faces along ``dirs[side]``)
    touch at one point only: not a face against a face or an edge, nor two parallel edges."""
    if dims[0] >= 1 and dims[1] >= 1:
        if dims[0] + dims[1] >= 3:
            return False
        x0 = dirs[0, 1] * dirs[1, 2] - dirs[0, 2] * dirs[1, 1]
        x1 = dirs[0, 2] * dirs[1, 0] - dirs[0, 0] * dirs[1, 2]
        x2 = dirs[0, 0] * dirs[1, 1] - dirs[0, 1] * dirs[1, 0]
        if np.sqrt(x0 * x0 + x1 * x1 + x2 * x2) <= tol_par:
            return False
    return True


@njit(cache=True)
def _face_spans(R, u, g, vstart, V, adj, adj_start, disk_axis, disk_r, tol_face, tol_par, dims, dirs, hbuf, fbuf,
                mark, qbuf):  # pragma: no cover - numba
    """For each query ``i``: the dimension (0, 1, 2) of shape ``g[i]``'s support face in the
    world direction ``u[i]`` (the shape's rotation in W is ``R[i]``), and for a 1-D face its
    direction in W (``dirs[i]``).  ``g[i] == -1``: a plane (dimension 2).  Over the hulls' vertex
    graphs ``adj``, ``adj_start`` (:func:`armguard.backends._face_graph.vertex_graph`); ``hbuf``,
    ``fbuf``, ``mark`` (all False), ``qbuf``: scratch of ``len(V)`` (:func:`face_scratch`)."""
    for i in range(len(g)):
        gi = g[i]
        if gi < 0:
            dims[i] = 2
            continue
        dims[i] = face_span_graph(R[i], u[i], vstart[gi], vstart[gi + 1], V, disk_axis[gi], disk_r[gi], tol_face, tol_par,
                                  dirs[i], hbuf, fbuf, adj[adj_start[gi]:adj_start[gi + 1]], mark, qbuf)


@njit(cache=True)
def _witness_rows(p_WA, p_WB, d, ja, jb, ga, gb, Jj, R_WJ, R_JG, vstart, V, adj, adj_start, disk_axis, disk_r, described,
                  cstart, cols, eps_len, tol_face, tol_par, jac, smooth):  # pragma: no cover - numba
    """Equation (1) and the uniqueness test for every pair: ``jac`` ``(n, nv)``, ``smooth`` ``(n,)``
    (False also where touching); ``Jj`` ``(njoints, 6, nv)`` per joint, ``R_WJ`` ``(njoints, 3, 3)``;
    joint ``j``'s Jacobian is zero outside its columns ``cols[cstart[j]:cstart[j + 1]]``."""
    n, nv = jac.shape
    R = np.zeros((2, 3, 3))
    u = np.empty((2, 3))
    nh = np.empty(3)
    cA = np.empty(3)
    cB = np.empty(3)
    g = np.empty(2, np.int64)
    dims = np.zeros(2, np.int64)
    dirs = np.zeros((2, 3))
    hbuf, fbuf, mark, qbuf = face_scratch(V.shape[0])
    for i in range(n):
        di = d[i]
        if abs(di) <= eps_len:
            for k in range(nv):
                jac[i, k] = 0.0
            smooth[i] = False
            continue
        for r in range(3):
            nh[r] = (p_WB[i, r] - p_WA[i, r]) / di
        for r in range(3):  # p x nhat
            r1, r2 = (r + 1) % 3, (r + 2) % 3
            cA[r] = p_WA[i, r1] * nh[r2] - p_WA[i, r2] * nh[r1]
            cB[r] = p_WB[i, r1] * nh[r2] - p_WB[i, r2] * nh[r1]
        a, b = ja[i], jb[i]
        for k in range(nv):
            jac[i, k] = 0.0
        if b > 0:
            for c in range(cstart[b], cstart[b + 1]):
                k = cols[c]
                jac[i, k] += nh[0] * Jj[b, 0, k] + nh[1] * Jj[b, 1, k] + nh[2] * Jj[b, 2, k] \
                    + cB[0] * Jj[b, 3, k] + cB[1] * Jj[b, 4, k] + cB[2] * Jj[b, 5, k]
        if a > 0:
            for c in range(cstart[a], cstart[a + 1]):
                k = cols[c]
                jac[i, k] -= nh[0] * Jj[a, 0, k] + nh[1] * Jj[a, 1, k] + nh[2] * Jj[a, 2, k] \
                    + cA[0] * Jj[a, 3, k] + cA[1] * Jj[a, 4, k] + cA[2] * Jj[a, 5, k]
        ok = True
        g[0], g[1] = ga[i], gb[i]
        for side in range(2):
            if g[side] >= 0:
                ok = ok and described[g[side]]
                jo = a if side == 0 else b
                for r in range(3):
                    for c in range(3):
                        R[side, r, c] = R_WJ[jo, r, 0] * R_JG[g[side], 0, c] + R_WJ[jo, r, 1] * R_JG[g[side], 1, c] \
                            + R_WJ[jo, r, 2] * R_JG[g[side], 2, c]
        for r in range(3):
            u[0, r] = nh[r]
            u[1, r] = -nh[r]
        dirs[:] = 0.0
        _face_spans(R, u, g, vstart, V, adj, adj_start, disk_axis, disk_r, tol_face, tol_par, dims, dirs, hbuf, fbuf,
                    mark, qbuf)
        ok = ok and unique_witness(dims, dirs, tol_par)
        smooth[i] = ok


class WitnessJacobian:
    """Equation (1) for the pairs of a Model, prepared once (joint of each side, support masks,
    the shapes' vertices); :meth:`rows` answers one configuration.  Thread-safe (per-thread
    ``pinocchio.Data``)."""

    def __init__(self, model, tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        import pinocchio as pin

        self.model = model
        self.tol = tol
        pm = model.pin_model
        self.nv = int(pm.nv)
        geoms = model.collision_model.geometryObjects
        verts, axes, radii, starts = [], [], [], [0]
        self._joint = np.empty(len(geoms), np.int64)
        self._R_JG = np.empty((len(geoms), 3, 3))  # geometry in its joint's frame
        self._described = np.ones(len(geoms), bool)
        for i, go in enumerate(geoms):
            self._joint[i] = go.parentJoint
            self._R_JG[i] = go.placement.rotation
            sv = _shape_vertices(go.geometry)
            if sv is None:
                self._described[i] = False
                sv = (np.zeros((1, 3)), np.zeros(3), 0.0)
            verts.append(sv[0])
            axes.append(sv[1])
            radii.append(sv[2])
            starts.append(starts[-1] + len(sv[0]))
        self._V = np.ascontiguousarray(np.concatenate(verts))
        self._vstart = np.asarray(starts, np.int64)
        self._disk_axis = np.ascontiguousarray(np.array(axes).reshape(-1, 3))
        self._disk_r = np.asarray(radii, np.float64)
        self._graph = vertex_graph(self._V, self._vstart, self._disk_r)  # support faces by a climb, not a scan
        self._pin = pin
        self._tls = threading.local()
        self._pairs_key = None
        # Without mimic joints, joint j's world Jacobian is data.J's columns of the joints that
        # support j (pin_model.supports), the rest zero: one masked copy of data.J replaces a
        # getJointJacobian call per joint.  Mimic joints fold a follower onto its leader's column,
        # which data.J alone does not tell apart: those models keep getJointJacobian.
        self._mimic = any("Mimic" in j.shortname() for j in pm.joints)
        mask = np.zeros((pm.njoints, 1, self.nv))
        for j in range(1, pm.njoints):
            for s in pm.supports[j]:
                js = pm.joints[s]
                if s > 0 and js.nv > 0:
                    mask[j, 0, js.idx_v:js.idx_v + js.nv] = 1.0
        self._support_mask = mask
        # each joint's nonzero columns (with mimic joints: every column, as a follower's motion lands
        # in its leader's column, which need not support it)
        cols = [np.arange(self.nv) if self._mimic else np.flatnonzero(mask[j, 0]) for j in range(pm.njoints)]
        self._cstart = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int64)
        self._cols = np.concatenate(cols).astype(np.int64)

    def _sides(self) -> tuple:
        """Per Model pair row: geometry index and joint of A and of B (-1 / 0 for the workspace)."""
        pairs = self.model.pairs
        key = (self.model.scene.revision, len(pairs))
        if self._pairs_key == key:
            return self._side_arrays
        ga, gb = [], []
        for a, b in zip(pairs.a, pairs.b):
            for name, out in ((a, ga), (b, gb)):
                if name == "workspace":
                    out.append(-1)
                else:
                    try:
                        out.append(self.model.geometry_index(name))
                    except KeyError:
                        raise BackendError(f"distance Jacobian: geometry {name!r} is not in the Model's collision_model "
                                           "(a shape added to the scene after loading)") from None
        ga, gb = np.asarray(ga, np.int64), np.asarray(gb, np.int64)
        ja = np.where(ga >= 0, self._joint[np.maximum(ga, 0)], 0)
        jb = np.where(gb >= 0, self._joint[np.maximum(gb, 0)], 0)
        self._side_arrays = (ga, gb, ja, jb)
        self._pairs_key = key
        return self._side_arrays

    def _joints_used(self, ja, jb) -> list:
        key = (ja.tobytes(), jb.tobytes())
        hit = self.__dict__.get("_used")
        if hit is None or hit[0] != key:
            hit = self._used = (key, sorted(j for j in set(ja.tolist()) | set(jb.tolist()) if j > 0))
        return hit[1]

    def _data(self):
        """This thread's ``(pinocchio.Data, Jj (njoints, 6, nv) buffer)``."""
        try:
            return self._tls.data
        except AttributeError:
            pm = self.model.pin_model
            d = self._tls.data = (pm.createData(), np.zeros((pm.njoints, 6, self.nv)))
            return d

    def joint_jacobians(self, q, joints) -> tuple:
        """``(Jj (njoints, 6, nv), R_WJ (njoints, 3, 3))`` at ``q``: the world-frame Jacobian of each
        joint in ``joints`` (linear velocity of the point at W's origin, then angular velocity;
        zero outside the joint's supports, mimic joints folded onto their leaders) and its rotation;
        joint 0 (the world) has a zero Jacobian and the identity.  Rows of other joints are
        unspecified.  The arrays are this thread's buffers, valid until its next call."""
        pin = self._pin
        pm = self.model.pin_model
        data, Jj = self._data()
        pin.computeJointJacobians(pm, data, q)
        R_WJ = np.empty((pm.njoints, 3, 3))
        R_WJ[0] = np.eye(3)
        oMi = data.oMi
        if self._mimic:
            for j in joints:
                Jj[j] = pin.getJointJacobian(pm, data, j, pin.ReferenceFrame.WORLD)
                R_WJ[j] = oMi[j].rotation
        else:
            np.multiply(data.J[None], self._support_mask, out=Jj)
            for j in joints:
                R_WJ[j] = oMi[j].rotation
        Jj[0] = 0.0
        return Jj, R_WJ

    def rows(self, q, result, idx=None, *, refine=None) -> tuple:
        """``(jacobian (n, nv) float64, smooth (n,) bool)`` for ``result`` (a PairDistances at
        ``q``, checked, of the Model rows ``idx``; None: every row).  ``refine(k_rows)`` gives
        the one-sided rows of the touching pairs (the checker's forward differences)."""
        ga, gb, ja, jb = self._sides()
        if idx is not None:
            ga, gb, ja, jb = ga[idx], gb[idx], ja[idx], jb[idx]
        Jj, R_WJ = self.joint_jacobians(q, self._joints_used(ja, jb))
        n = len(result.distance)
        jac = np.empty((n, self.nv))
        smooth = np.empty(n, bool)
        tol = self.tol
        d = np.ascontiguousarray(result.distance, dtype=np.float64)
        _witness_rows(np.ascontiguousarray(result.p_WA), np.ascontiguousarray(result.p_WB), d, ja, jb, ga, gb, Jj,
                      R_WJ, self._R_JG, self._vstart, self._V, *self._graph, self._disk_axis, self._disk_r, self._described,
                      self._cstart, self._cols, tol.length, tol.jacobian_face, tol.jacobian_parallel, jac, smooth)
        meet = cores_meet(self.model, d, idx, tol.length)
        smooth[meet] = False
        touching = np.flatnonzero((np.abs(d) <= tol.length) | meet)
        if len(touching) and refine is not None:
            jac[touching] = refine(touching)
        return jac, smooth


_ROUND: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()  # Model -> (key, r_a (P,), r_b (P,))


def cores_meet(model, d, idx=None, length: float = DEFAULT_TOLERANCES.length) -> np.ndarray:
    """``(n,) bool``: the rows ``idx`` (None: every Model pair row) with distances ``d`` whose two
    shapes are spheres or capsules with their cores (centres, axis segments) meeting, ``|d + r_a +
    r_b| <= length``.  There the distance is the cores' (a kink at 0: it grows whichever way they
    part) less the radii: no one normal, no derivative; ranger's crossing capsules had witness rows of
    -0.51 m/rad in directions where the distance does not move.  Such rows are not smooth and are
    taken one-sided (forward differences), by the framework's witness Jacobian and the analytic
    backend's kernel alike."""
    pairs = model.pairs
    key = (getattr(model.scene, "revision", None), len(pairs))
    hit = _ROUND.get(model)
    if hit is None or hit[0] != key:
        radius = {}
        for go in model.collision_model.geometryObjects:
            if type(go.geometry).__name__ in ("Sphere", "Capsule"):
                radius[go.name] = float(go.geometry.radius)
        r_a = np.array([radius.get(a, np.nan) for a in pairs.a], dtype=np.float64)
        r_b = np.array([radius.get(b, np.nan) for b in pairs.b], dtype=np.float64)
        hit = _ROUND[model] = (key, r_a, r_b)
    r_a, r_b = (hit[1], hit[2]) if idx is None else (hit[1][idx], hit[2][idx])
    with np.errstate(invalid="ignore"):
        return np.abs(np.asarray(d, dtype=np.float64) + r_a + r_b) <= length


def finite_difference_rows(checker, q, idx, *, step: float, one_sided: bool = False) -> tuple:
    """``(rows (n, nv), kink (n,) bool)``: central differences of ``checker``'s distances of the
    Model rows ``idx`` (None: every row) along each velocity direction (``pinocchio.integrate``,
    so continuous joints move on their circle); ``one_sided``: forward differences.  A step past a
joint limit is not taken: that column is the other side's one-sided difference.  ``kink``:
    the forward and backward differences differ by more than ``Tolerances.jacobian_kink``."""
    import pinocchio as pin

    from .._errors import JointLimitError

    pm = checker.model.pin_model
    tol = getattr(checker.model, "tol", DEFAULT_TOLERANCES)
    d0 = checker.pair_distances(q, pairs=idx).distance
    rows = np.empty((len(d0), pm.nv))
    kink = np.zeros(len(d0), bool)

    def at(dq):
        try:
            return checker.pair_distances(pin.integrate(pm, q, dq), pairs=idx).distance
        except JointLimitError:  # a step past a joint limit: the other side's difference only
            return None

    for k in range(pm.nv):
        e = np.zeros(pm.nv)
        e[k] = step
        dp = at(e)
        dm = None if one_sided and dp is not None else at(-e)
        if dp is None and dm is None:
            raise BackendError(f"finite differences: joint column {k} cannot move {step} either way within its limits (a range "
                               "narrower than the step: a smaller step)")
        if dp is None or dm is None:
            rows[:, k] = (dp - d0) / step if dm is None else (d0 - dm) / step
            continue
        if one_sided:
            rows[:, k] = (dp - d0) / step
            continue
        rows[:, k] = (dp - dm) / (2.0 * step)
        kink |= np.abs((dp - d0) - (d0 - dm)) / step > tol.jacobian_kink
    return rows, kink
