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
no per-pair Python.

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

import numpy as np
from numba import njit

from .._errors import BackendError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["WitnessJacobian", "finite_difference_rows"]

_PLANE = -1  # a workspace wall: the face is the whole plane


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


@njit(cache=True)
def _face_spans(R, u, g, vstart, V, disk_axis, disk_r, tol_face, tol_par, dims, dirs):  # pragma: no cover - numba
    """For each query ``i``: the dimension (0, 1, 2) of shape ``g[i]``'s support face in the
    world direction ``u[i]`` (the shape's rotation in W is ``R[i]``), and for a 1-D face its
    direction in W (``dirs[i]``).  ``g[i] == -1``: a plane (dimension 2)."""
    for i in range(len(g)):
        gi = g[i]
        if gi < 0:
            dims[i] = 2
            continue
        uL = R[i].T @ u[i]
        s, e = vstart[gi], vstart[gi + 1]
        if disk_r[gi] > 0.0:
            c = abs(uL[0] * disk_axis[gi, 0] + uL[1] * disk_axis[gi, 1] + uL[2] * disk_axis[gi, 2])
            if 1.0 - c <= tol_par:  # the disk faces u: a flat face
                dims[i] = 2
                continue
        hmax = -np.inf
        for k in range(s, e):
            h = uL[0] * V[k, 0] + uL[1] * V[k, 1] + uL[2] * V[k, 2]
            if h > hmax:
                hmax = h
        # the face: vertices within tol_face of the support plane; its extent from the first one
        k0 = -1
        for k in range(s, e):
            if uL[0] * V[k, 0] + uL[1] * V[k, 1] + uL[2] * V[k, 2] >= hmax - tol_face:
                k0 = k
                break
        far, k1 = 0.0, -1
        for k in range(s, e):
            if uL[0] * V[k, 0] + uL[1] * V[k, 1] + uL[2] * V[k, 2] >= hmax - tol_face:
                dd = (V[k, 0] - V[k0, 0]) ** 2 + (V[k, 1] - V[k0, 1]) ** 2 + (V[k, 2] - V[k0, 2]) ** 2
                if dd > far:
                    far, k1 = dd, k
        if far <= tol_face * tol_face:
            dims[i] = 0
            continue
        a = (V[k1] - V[k0]) / np.sqrt(far)
        dim = 1
        for k in range(s, e):
            if uL[0] * V[k, 0] + uL[1] * V[k, 1] + uL[2] * V[k, 2] >= hmax - tol_face:
                w = V[k] - V[k0]
                t = w[0] * a[0] + w[1] * a[1] + w[2] * a[2]
                off = w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - t * t
                if off > tol_face * tol_face:
                    dim = 2
                    break
        dims[i] = dim
        if dim == 1:
            dirs[i] = R[i] @ a


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
        self._R_JG = np.empty((len(geoms), 3, 3))
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
        self._pin = pin
        self._tls = threading.local()
        self._pairs_key = None

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

    def _data(self):
        try:
            return self._tls.data
        except AttributeError:
            d = self._tls.data = self.model.pin_model.createData()
            return d

    def rows(self, q, result, idx=None, *, refine=None) -> tuple:
        """``(jacobian (n, nv) float64, smooth (n,) bool)`` for ``result`` (a PairDistances at
        ``q``, checked, of the Model rows ``idx``; None: every row).  ``refine(k_rows)`` gives
        the one-sided rows of the touching pairs (the checker's forward differences)."""
        pin = self._pin
        ga, gb, ja, jb = self._sides()
        if idx is not None:
            ga, gb, ja, jb = ga[idx], gb[idx], ja[idx], jb[idx]
        data = self._data()
        pm = self.model.pin_model
        pin.computeJointJacobians(pm, data, q)
        # per joint of a pair side, (6, nv): world frame, linear velocity at W's origin then angular
        # velocity, zero outside the joint's ancestors (mimic joints folded onto their leaders)
        Jj = np.zeros((pm.njoints, 6, self.nv))
        for j in np.unique(np.concatenate([ja, jb])):
            if j > 0:
                Jj[j] = pin.getJointJacobian(pm, data, int(j), pin.ReferenceFrame.WORLD)
        p_WA, p_WB, d = result.p_WA, result.p_WB, result.distance
        n = len(d)
        tol = self.tol
        apart = np.abs(d) > tol.length
        nhat = np.zeros((n, 3))
        nhat[apart] = (p_WB[apart] - p_WA[apart]) / d[apart, None]
        wA = np.concatenate([nhat, np.cross(p_WA, nhat)], axis=1)
        wB = np.concatenate([nhat, np.cross(p_WB, nhat)], axis=1)
        jac = np.einsum("ni,nik->nk", wB, Jj[jb]) - np.einsum("ni,nik->nk", wA, Jj[ja])
        smooth = apart & self._unique(data, nhat, ga, gb, ja, jb)
        touching = np.flatnonzero(~apart)
        if len(touching) and refine is not None:
            jac[touching] = refine(touching)
        return jac, smooth

    def _unique(self, data, nhat, ga, gb, ja, jb) -> np.ndarray:
        """Whether the witness points are unique (see the module docstring), per pair."""
        n = len(ga)
        R_WJ = np.array([data.oMi[j].rotation for j in range(len(data.oMi))])
        g = np.concatenate([ga, gb])
        j = np.concatenate([ja, jb])
        R = np.ascontiguousarray(R_WJ[j] @ self._R_JG[np.maximum(g, 0)])
        u = np.ascontiguousarray(np.concatenate([nhat, -nhat]))  # A's face towards B, B's towards A
        dims = np.zeros(2 * n, np.int64)
        dirs = np.zeros((2 * n, 3))
        tol = self.tol
        _face_spans(R, u, g, self._vstart, self._V, self._disk_axis, self._disk_r, tol.jacobian_face,
                    tol.jacobian_parallel, dims, dirs)
        dA, dB = dims[:n], dims[n:]
        parallel = np.linalg.norm(np.cross(dirs[:n], dirs[n:]), axis=1) <= tol.jacobian_parallel
        shared = ((dA >= 1) & (dB >= 1) & ((dA + dB >= 3) | parallel))
        described = np.where(ga >= 0, self._described[np.maximum(ga, 0)], True) & \
            np.where(gb >= 0, self._described[np.maximum(gb, 0)], True)
        return ~shared & described


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
            raise JointLimitError(f"finite differences: joint column {k} cannot move {step} either way within its limits")
        if dp is None or dm is None:
            rows[:, k] = (dp - d0) / step if dm is None else (d0 - dm) / step
            continue
        if one_sided:
            rows[:, k] = (dp - d0) / step
            continue
        rows[:, k] = (dp - dm) / (2.0 * step)
        kink |= np.abs((dp - d0) - (d0 - dm)) / step > tol.jacobian_kink
    return rows, kink
