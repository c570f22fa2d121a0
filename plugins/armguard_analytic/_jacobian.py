"""The analytic checker's distance Jacobians: the kernel's own, right after its distances.

:func:`armguard_analytic._engine._pair_jacobian.jacobian_rows` differentiates every checked pair from the
link poses the distance kernel has just computed (joint world axes and origins; revolute,
prismatic, continuous and coupled joints; Pinocchio's ``nv`` columns), with the reference's
smoothness test on the Model's ``collision_model`` shapes.  The reference is
:meth:`armguard.backends.CheckerBase.witness_jacobian` (Pinocchio's joint Jacobians at the same
witness points); ``tests/test_kernel_jacobian.py`` holds them equal.

What a call needs is prepared once per scene revision (:class:`JacobianPlan`): per Model pair row
the global link and the shape of each side, per scene joint its velocity column, per shape its
rotation in its link's frame (measured once at the neutral configuration from Pinocchio's
placement and the kernel's link pose: the two are rigidly attached) and its support vertices.
"""

from __future__ import annotations

import numpy as np

from armguard._errors import BackendError

__all__ = ["JacobianPlan"]


class JacobianPlan:
    """The per-revision arrays of :func:`~armguard_analytic._engine._pair_jacobian.jacobian_rows` for one
    analytic checker's call plan ``fast`` (see the module docstring)."""

    __slots__ = ("nv", "rows", "vcol", "gF", "gI", "V", "graph", "tol", "entry", "zero_gmap", "subsets", "tol_length")

    def __init__(self, checker, fast) -> None:
        import pinocchio as pin

        from armguard.backends._jacobian import WitnessJacobian

        from ._engine import _pair_jacobian as pj
        from ._engine._pair_rows import pair_rows

        model = checker.model
        pm = model.pin_model
        self.nv = int(pm.nv)
        dm = fast.b.model
        glink = np.asarray(dm.elem_glink, dtype=np.int64)
        parent = np.asarray(dm.tree.parent)
        if np.any(parent >= np.arange(len(parent))):  # the kernel's walk to a common ancestor needs it
            raise BackendError("analytic Jacobian: the scene's links are not numbered parents first")
        # the kernel's link poses at the neutral configuration (a scratch of its own)
        SF, SI, q1 = fast.new_scratch()
        q0 = np.ascontiguousarray(model.neutral(), dtype=np.float64)
        n = fast.n
        H, MF, MI, prm, iprm = fast.args
        err = pair_rows(fast.fn, q0, 0, 1, fast.gmap, H, MF, MI, SF, SI, prm, iprm, q1, np.empty(n), np.empty((n, 3)),
                        np.empty((n, 3)))
        if err:
            checker._kernel_error(fast, int(err), q0[None], False)
        X_WL = fast.b.layout.view(SF, "Xs")
        data = pm.createData()
        pin.forwardKinematics(pm, data, q0)
        geoms = model.collision_model.geometryObjects
        wj = WitnessJacobian(model, model.tol)  # the shapes' support vertices, as the reference reads them
        G = len(geoms)
        gF = np.zeros((G, pj.G_WIDTH))
        gI = np.zeros((G, 3), np.int64)
        gI[:, pj.G_VS] = wj._vstart[:-1]
        gI[:, pj.G_VE] = wj._vstart[1:]
        gI[:, pj.G_DESCRIBED] = wj._described
        gF[:, pj.G_AXIS:pj.G_AXIS + 3] = wj._disk_axis
        gF[:, pj.G_RADIUS] = wj._disk_r
        link_of = np.full(G, -2, np.int64)  # -2: not met
        pairs = model.pairs
        rows = np.empty((n, 4), np.int64)
        for k in range(n):
            p = int(fast.sel[k])
            ea, eb = int(dm.pair_a[p]), int(dm.pair_b[p])
            if fast.swap[k]:
                ea, eb = eb, ea
            for side, (name, e) in enumerate(((pairs.a[k], ea), (pairs.b[k], eb))):
                link = int(glink[e]) if e >= 0 else -1
                g = -1 if name == "workspace" else model.geometry_index(name)
                rows[k, pj.ROW_LINK_A + side] = link
                rows[k, pj.ROW_GEOM_A + side] = g
                if g < 0:
                    continue
                if link_of[g] == -2:
                    link_of[g] = link
                    go = geoms[g]
                    R_WG = data.oMi[go.parentJoint].rotation @ go.placement.rotation
                    if link < 0 and go.parentJoint != 0:
                        raise BackendError(f"analytic Jacobian: shape {name!r} is fixed in the scene but moves with "
                                           f"Pinocchio's joint {pm.names[go.parentJoint]!r}")
                    R = R_WG if link < 0 else X_WL[link, :3, :3].T @ R_WG
                    gF[g, :9] = R.reshape(9)
                elif link_of[g] != link:
                    raise BackendError(f"analytic Jacobian: shape {name!r} sits on two links ({link_of[g]}, {link})")
        self.rows = rows
        # Pinocchio's velocity column of each scene joint (a continuous joint's angle: its one column)
        col_of_q = {int(pm.joints[j].idx_q): int(pm.joints[j].idx_v) for j in range(1, pm.njoints) if pm.joints[j].nv > 0}
        self.vcol = np.array([col_of_q.get(int(i), -1) for i in model.q_index], dtype=np.int64)
        if np.any(self.vcol < 0):
            bad = [model.scene.joint_names[k] for k in np.flatnonzero(self.vcol < 0)]
            raise BackendError(f"analytic Jacobian: scene joints {bad} have no velocity column in pin_model")
        self.gF, self.gI, self.V = np.ascontiguousarray(gF), np.ascontiguousarray(gI), np.ascontiguousarray(wj._V)
        self.graph = wj._graph  # the hulls' vertex graphs: support faces by a climb, not a scan
        tol = model.tol
        self.tol_length = tol.length
        self.tol = np.array([tol.length, tol.jacobian_face, tol.jacobian_parallel])
        self.zero_gmap = fast.subset(np.zeros(0, np.int64))  # FK alone (distance_jacobian of a given result)
        self.subsets: dict = {}
        # the compiled overload for these argument types, called without the dispatcher
        call = (H, MF, MI, SF, rows, self.vcol, self.gF, self.gI, self.V, *self.graph, self.tol, np.ones(n), np.zeros((n, 3)),
                np.ones((n, 3)), np.empty((n, self.nv)), np.empty(n, np.bool_))
        pj.jacobian_rows(*call)
        try:
            from numba import typeof

            self.entry = pj.jacobian_rows.overloads[tuple(typeof(a) for a in call)].entry_point
        except (KeyError, AttributeError):  # pragma: no cover - numba internals changed
            self.entry = pj.jacobian_rows

    def rows_of(self, idx) -> np.ndarray:
        """The ``rows`` argument for the Model rows ``idx`` (None: all), kept per subset."""
        if idx is None:
            return self.rows
        key = idx.tobytes()
        r = self.subsets.get(key)
        if r is None:
            r = np.ascontiguousarray(self.rows[idx])
            if len(self.subsets) >= 256:
                self.subsets.clear()
            self.subsets[key] = r
        return r
