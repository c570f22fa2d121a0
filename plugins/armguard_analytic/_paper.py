"""``fidelity = "paper"``: the seeds' minimalist checkers, as the Ranger (1997) and Hermes (undated) papers state them.

Ranger (Bon & Seraji, seed ``000``) answers distances:

* **link–link** (§2, §3): the distance between the two link axes minus both radii.  The axes'
  closest points are Ranger's §3: infinite lines with unit directions ``A_1``, ``A_2``
  (eq. 1), ``a = D_12 . A_1``, ``b = A_1 . A_2``, ``c = D_12 . A_2`` with ``D_12 = P_2 - P_1``,
  ``t_1 = a + t_2 b`` (eq. 5), ``t_2 = (a b - c) / (1 - b^2)`` (eq. 6; the OCR text's equations
  were checked by substituting eq. 4 into eqs. 2-3), then §3.2's correction: both in their
  segments, keep them; one in, move the other to its end-point nearest the infinite-line point
  and re-project onto the first segment; both out, the two-stage correction (each clamped to
  its end-point, each end-point projected onto the opposing segment, the pair with the smaller
  distance kept).  Parallel lines (``1 - b^2 <= Tolerances.parallel^2``) are "handled ... with
  straightforward geometric computations [15]" (an internal report we do not have): we take the
  least of the four end-point-to-segment distances, which is exact for parallel segments and
  is Hermes's parallel branch (seed ``001``, link–link module).  A segment shorter than
  ``Tolerances.length`` is its first end-point.  This is exact for segment pairs.
* **link–face** (§2, §4): only the link's *distal* end-point ``P`` is tested against a face:
  face normal ``n`` the normalised average of ``A_i x A_(i+1)`` over the counter-clockwise
  vertices, position ``p_f`` their average, ``d_of = n . p_f`` (eq. 7), ``d_f = n . P - d_of``
  (eq. 8), projection ``Q = P - d_f n`` (eq. 9), and ``Q`` is in the face iff
  ``n . (A_i x B_i) > 0`` for every edge, ``B_i = Q - v_i`` (eq. 10).  If it is not, the face
  contributes nothing; if it is, the distance is "the distance between the nearest points less
  the radius", ``|d_f| - r`` (the text's §4 says the normal comes from edges "directed clockwise"
  yet the vertices are counter-clockwise from outside; with counter-clockwise vertices ``n`` is
  outward, the sign eq. 8 needs).  Plus **link–edge** (§2): every edge of the obstacle against
  the link axis (the §3 kernel) minus the link radius.  A pair's distance is the least of its
  face and edge terms.  Each term is the distance from a point of the link axis to a point of
  the obstacle less ``r``, so it is never below the exact signed distance (which is at most
  ``-r`` once the axis meets the obstacle): the paper can only miss closer points.  The distal
  end-point is the capsule end-point farther from the origin of the parent link's frame at the
  scene's default configuration.
* **link–bounding box** (§2): for both end-points of each link, the six subtractions against
  the box limits; the least is the distance (``> 0`` inside).  The paper subtracts the link
  radius for faces, edges and links but not here, and neither do we: this distance is the
  link *axis*'s, larger than the exact one by the radius, and its link witness point is the
  end-point itself.

Hermes (Sciomachen & Magnani, seed ``001``) answers yes/no; with ``verdicts = "hermes"``,
``collides`` runs its four modules (:mod:`._paper_hermes`, §3, Figs. 5-11) on the pairs they
cover, and :attr:`PaperChecker.hermes_modules` names each pair's: the **link–obstacle module**
for a link against a closed convex polyhedron: the obstacle is grown by the link radius plus the
margin (the stopping distance) by moving its face planes out (the text's "obstacle growing",
325 FLOP for 54 faces: plane offsets, no new vertices); a pre-test intersects the link segment
with the obstacle's circumscribing sphere (centre the vertex barycentre, radius to the farthest
vertex) grown the same way; then, face by face, the link's line meets the grown face plane at
``t`` in [0, 1] and the point is tested against the other grown planes ("on the face").  A
segment parallel to a face plane is not considered, so a link wholly inside the grown obstacle is
not a collision; plane growing covers more than the capsule's true reach near edges and vertices
(false alarms).  The **link–link module** (the determinant, its eight cases, the parallel and
coincident branches), the **payload–link module** (the line–sphere discriminant, then the axes'
distance) and the **payload–obstacle module** (the spheres, ``D1``/``D2`` against ``R``, the
projections, the edges) are stated in :mod:`._paper_hermes`.  Distances (``pair_distances``)
stay Ranger's §3 for link–link and payload–link pairs in both papers (the Hermes link–link module
computes the same distance except for parallel axes).

**Fallback to exact**: a pair the papers have no distance method for (a payload against an obstacle, a
non-capsule link such as Ranger's camera box, spheres, moving polytopes) is answered by the
exact kernels (``convex_convex``, GJK + SAT); :attr:`PaperChecker.methods` names each pair's
method and :attr:`PaperChecker.representation` the geometries answered exactly.

``verdicts``: ``"ranger"`` (``collides`` is paper distance ``<= margin``), ``"hermes"`` (as above),
``"auto"`` (default: ``"hermes"`` when the scene has no workspace box and every body shape is a
closed polytope (Box, ConvexPolyhedron, Prism), as Hermes's world model; else ``"ranger"``).
Every pair is evaluated on every call (the papers' static obstacle lists; no pruning).
"""

from __future__ import annotations

import math
import threading
from typing import Mapping

import numpy as np

from armguard._errors import BackendError
from armguard._tolerance import DEFAULT_TOLERANCES
from armguard.backends import Capability, CheckerBase, check_q, check_Q
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Prism
from armguard.geometry.kernels import GJK_WORK_SIZE
from armguard.kinematics._fk import _fk_kernel

from ._engine._model import engine_tree
from ._paper_hermes import H_LINK_LINK, H_LINK_OBSTACLE, H_NONE, H_PAYLOAD_LINK, H_PAYLOAD_OBSTACLE, MODULES
from ._paper_kernels import (  # noqa: F401  (M_*, ranger_segment_segment and the pair kernels are read from here)
    M_BOX, M_EXACT, M_EXACT_BOX, M_FACE_EDGE, M_SEGSEG, _face_edge, _hermes_hit, _paper_rows, ranger_segment_segment,
)

__all__ = ["PaperChecker", "ranger_segment_segment", "paper_capsule_polytope", "hermes_link_obstacle",
           "hermes_link_link", "hermes_payload_link", "hermes_payload_obstacle", "METHODS", "VERDICTS"]

METHODS = ("ranger §3 segment-segment", "ranger §2/§4 distal end-point face + edges", "ranger §2 bounding box",
           "exact (no paper method)", "exact workspace (no paper method)")
VERDICTS = ("auto", "ranger", "hermes")


# ---------------------------------------------------------------- the Checker
def _unit_rows(v, eps):
    n = np.linalg.norm(v, axis=1)
    return np.where(n[:, None] > eps, v / np.where(n > eps, n, 1.0)[:, None], 0.0), n > eps


def _paper_face(V):
    """Ranger §4 for one face ``V`` (k, 3) counter-clockwise from outside: unit ``n``, ``d_of`` (eq. 7)."""
    A = np.roll(V, -1, axis=0) - V
    A = A / np.linalg.norm(A, axis=1)[:, None]
    n = np.cross(A, np.roll(A, -1, axis=0)).sum(axis=0)  # sum of the vertex normals A_i x A_(i+1)
    n = n / np.linalg.norm(n)
    return n, float(n @ V.mean(axis=0))


class PaperChecker(CheckerBase):
    """The analytic backend at ``fidelity = "paper"`` (see the module docstring).

    Attributes: ``methods`` ``(n,)`` the method answering each pair (Model pair order);
    ``verdicts`` ``"ranger"`` or ``"hermes"`` (resolved from the option); ``representation``
    GeometryObject name -> note for geometries answered by the exact kernels.  Not thread-safe
    (one scratch buffer per Checker).
    """

    name = "analytic"
    fidelity = "paper"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})

    def __init__(self, model, options: Mapping | None = None) -> None:
        super().__init__(model)
        opts = dict(options or {})
        fid = str(opts.pop("fidelity", "paper"))
        if fid != "paper":
            raise BackendError(f"analytic: PaperChecker is fidelity 'paper', got {fid!r}")
        verdicts = str(opts.pop("verdicts", "auto"))
        if verdicts not in VERDICTS:
            raise BackendError(f"analytic: verdicts {verdicts!r} is not one of {list(VERDICTS)}")
        if opts:
            raise BackendError(f"analytic: unknown options {sorted(opts)}; options are ['fidelity', 'verdicts']")
        self.tol = DEFAULT_TOLERANCES
        self._build(verdicts)

    # ---------------------------------------------------------------- compile
    def _build(self, verdicts: str) -> None:
        from armguard.model import WORKSPACE
        from armguard.scene import compile_scene

        model, scene, tol = self.model, self.model.scene, self.tol
        cs = compile_scene(scene)
        robots = tuple(cs.robot_names)
        tree, link_off, _ = engine_tree(scene, robots, model=model)  # from the Model's pin_model (Model.kinematic_tree)
        G = cs.n_elements
        moving = cs.elem_kind != 0
        glink = np.where(moving, link_off[np.maximum(cs.elem_robot, 0)] + cs.elem_link, -1) if len(link_off) else \
            np.full(G, -1, np.int64)
        shapes, names = [], []
        for e in range(G):
            o = int(cs.elem_owner[e])
            owner, i = cs.owner_names[o], e - int(cs.owner_elem_start[o])
            kind = int(cs.owner_kind[o])
            if kind == 0:
                shapes.append(scene.bodies[owner].shapes[i])
            elif kind == 1:
                r, ln = owner.split("/", 1)
                shapes.append(scene.robots[r].link_shapes[ln][i])
            else:
                shapes.append(scene.payloads[owner].shapes[i])
            names.append(model.geometry_name(owner, i))
        index = {n: e for e, n in enumerate(names)}
        if verdicts == "auto":
            closed = all(isinstance(s, (Box, ConvexPolyhedron, Prism)) for b in scene.bodies.values() for s in b.shapes)
            verdicts = "hermes" if closed and not cs.has_workspace else "ranger"
        self.verdicts = verdicts

        # FK at the default configuration: which capsule end-point is distal
        q0 = np.ascontiguousarray(scene.flat_q(scene.default_q())[None], dtype=np.float64)
        Xd = np.empty((1, tree.n_links, 4, 4))
        _fk_kernel(q0, tree.parent, tree.X_pre, tree.axis, tree.jtype, tree.X_post, tree.has_post, tree.offset,
                   tree.term_start, tree.term_joint, tree.term_coeff, Xd)

        def distal(e: int) -> int:
            lk = int(glink[e])
            par = int(tree.parent[lk])
            o = Xd[0, par, :3, 3] if par >= 0 else tree.X_pre[lk][:3, 3]
            v = cs.verts[cs.elem_vert_start[e]:cs.elem_vert_start[e] + 2] @ Xd[0, lk, :3, :3].T + Xd[0, lk, :3, 3]
            return 1 if np.linalg.norm(v[1] - o) >= np.linalg.norm(v[0] - o) else 0

        polytope = (Box, ConvexPolyhedron, Prism)
        from armguard.geometry import Polygon

        ra, rb, meth, dist, swap, herm, methods, rep = [], [], [], [], [], [], [], dict(model.notes)
        hcode, ha, hb = [], [], []
        kind = cs.elem_kind
        for na, nb in zip(model.pairs.a, model.pairs.b):
            a = index[na]
            sa = shapes[a]
            hc, hx, hy = H_NONE, 0, 0
            if verdicts == "hermes" and nb != WORKSPACE:  # Hermes's four modules (seed 001 §3)
                ib, sb_ = index[nb], shapes[index[nb]]
                cap = {e: isinstance(s_, Capsule) for e, s_ in ((a, sa), (ib, sb_))}
                closed = {e: isinstance(s_, polytope) and kind[e] == 0 and cs.elem_radius[e] == 0.0
                          for e, s_ in ((a, sa), (ib, sb_))}
                for x, y in ((a, ib), (ib, a)):
                    if cap[x] and kind[x] == 1 and closed[y]:
                        hc, hx, hy = H_LINK_OBSTACLE, x, y
                    elif cap[x] and cap[y] and kind[x] == 1 and kind[y] == 1:
                        hc, hx, hy = H_LINK_LINK, x, y
                    elif cap[x] and cap[y] and kind[x] == 1 and kind[y] == 2:
                        hc, hx, hy = H_PAYLOAD_LINK, x, y
                    elif cap[x] and kind[x] == 2 and closed[y]:
                        hc, hx, hy = H_PAYLOAD_OBSTACLE, x, y
                    if hc != H_NONE:
                        break
            hcode.append(hc), ha.append(hx), hb.append(hy)
            if nb == WORKSPACE:
                cap = isinstance(sa, Capsule) and cs.elem_kind[a] == 1
                b, mt, sw, h, d = a, (M_BOX if cap else M_EXACT_BOX), False, False, 0
                if not cap:
                    rep[na] = f"{type(sa).__name__} {'payload' if cs.elem_kind[a] == 2 else 'link'}: the papers' links " \
                              "are capsules; its pairs (bounding box included) are answered by the exact kernels"
            else:
                b = index[nb]
                sb = shapes[b]
                h, d, sw = False, 0, False
                if isinstance(sa, Capsule) and isinstance(sb, Capsule):
                    mt = M_SEGSEG
                else:
                    flip = not (isinstance(sa, Capsule) and cs.elem_kind[a] == 1)
                    ca, pb = (b, a) if flip else (a, b)
                    sc, sp = shapes[ca], shapes[pb]
                    if (isinstance(sc, Capsule) and cs.elem_kind[ca] == 1 and cs.elem_kind[pb] == 0
                            and isinstance(sp, polytope + (Polygon,)) and cs.elem_radius[pb] == 0.0):
                        a, b, sw, mt, d = ca, pb, flip, M_FACE_EDGE, distal(ca)
                        h = verdicts == "hermes" and isinstance(sp, polytope)
                    else:
                        mt = M_EXACT
                        noted = False
                        for e, s in ((a, sa), (b, sb)):
                            if cs.elem_kind[e] == 2:
                                rep[names[e]] = "payload: the papers give no payload-obstacle distance (Hermes's " \
                                                "payload-obstacle module is yes/no); its pairs with polytopes are exact"
                                noted = True
                            elif not isinstance(s, Capsule) and cs.elem_kind[e] == 1:
                                rep[names[e]] = f"{type(s).__name__} link: the papers' links are capsules; its pairs " \
                                                "(bounding box included) are answered by the exact kernels"
                                noted = True
                        if not noted:
                            rep.setdefault(nb, f"{type(sb).__name__}: no paper method against {type(sa).__name__}; "
                                               "exact kernels")
            ra.append(a), rb.append(b), meth.append(mt), dist.append(d), swap.append(sw), herm.append(h)
            methods.append(METHODS[mt] + (f" (verdict: hermes {MODULES[hc]} module)" if hc != H_NONE else ""))
        self.methods = tuple(methods)
        self.representation = rep
        self._n = len(ra)

        c = lambda x, dt=np.float64: np.ascontiguousarray(np.asarray(x, dtype=dt))  # noqa: E731
        i64 = np.int64
        ev = cs.verts[cs.edges[:, 1]] - cs.verts[cs.edges[:, 0]] if len(cs.edges) else np.zeros((0, 3))
        eL, eok = _unit_rows(ev, tol.length)
        elen = np.linalg.norm(ev, axis=1)
        e_ok = np.array([bool(np.all(eok[cs.elem_edge_start[e]:cs.elem_edge_start[e + 1]])) and
                         cs.elem_edge_start[e + 1] > cs.elem_edge_start[e] for e in range(G)], dtype=np.bool_)
        F = len(cs.face_vert_start) - 1
        fn, fd = np.zeros((F, 3)), np.zeros(F)
        for f in range(F):
            fn[f], fd[f] = _paper_face(cs.verts[cs.face_verts[cs.face_vert_start[f]:cs.face_vert_start[f + 1]]])
        sph = np.zeros((G, 4))
        for e in range(G):
            V = cs.verts[cs.elem_vert_start[e]:cs.elem_vert_start[e + 1]]
            sph[e, :3] = V.mean(axis=0)  # Hermes: the obstacle's barycentre and circumscribing radius
            sph[e, 3] = np.linalg.norm(V - sph[e, :3], axis=1).max()
        nL = c(cs.planes[:, :3]) if len(cs.planes) else np.zeros((0, 3))
        self._T = (c(tree.parent, i64), c(tree.X_pre), c(tree.axis), c(tree.jtype, i64), c(tree.X_post),
                   c(tree.has_post, np.bool_), c(tree.offset), c(tree.term_start, i64), c(tree.term_joint, i64),
                   c(tree.term_coeff))
        self._E = (c(glink, i64), c(cs.elem_vert_start, i64), c(cs.verts), c(cs.verts).copy(), c(cs.elem_plane_start, i64),
                   nL, nL.copy(), c(cs.elem_edge_start, i64), c(cs.edges.reshape(-1, 2), i64), c(eL), c(eL).copy(), c(elen), e_ok,
                   c(cs.elem_radius), c(cs.elem_face_start, i64), c(cs.face_vert_start, i64), c(cs.face_verts, i64),
                   c(fn), c(fd), c(cs.planes.reshape(-1, 4)), c(sph), c(cs.workspace_lo), c(cs.workspace_hi))
        self._R = (c(ra, i64), c(rb, i64), c(meth, i64), c(dist, i64), c(swap, np.bool_))
        prho = np.zeros(G)  # a capsule payload's cylinder: its circumscribing sphere's radius (Hermes)
        for e in range(G):
            if kind[e] == 2 and isinstance(shapes[e], Capsule):
                h = 0.5 * np.linalg.norm(cs.verts[cs.elem_vert_start[e] + 1] - cs.verts[cs.elem_vert_start[e]])
                prho[e] = math.sqrt(h * h + cs.elem_radius[e] ** 2)
        self.hermes_modules = tuple(MODULES[k] for k in hcode)
        self._H = (c(hcode, i64), c(ha, i64), c(hb, i64), c(prho))
        self._eps = (float(tol.length), float(tol.parallel), float(tol.gjk_epsilon), int(tol.gjk_max_iterations),
                     float(tol.penetration_witness_offset))
        self._work = np.zeros(GJK_WORK_SIZE)
        self._tls = threading.local()  # per thread: the W-frame copies in _E and the GJK work array

    def _scratch(self) -> tuple:
        """The calling thread's ``(E, work)``: ``_E`` with its own W-frame arrays (vW, nW, eW) and work."""
        try:
            return self._tls.s
        except AttributeError:
            E = list(self._E)
            for k in (3, 6, 10):  # vW, nW, eW: written per configuration
                E[k] = E[k].copy()
            s = self._tls.s = (tuple(E), np.zeros_like(self._work))
            return s

    # ---------------------------------------------------------------- kernels
    def _run(self, Qs, mode: int, margin: float, want: bool):
        M, P = Qs.shape[0], self._n
        out_d = np.empty((M if mode != 1 else 0, P))
        out_p = np.empty((M if want else 0, P, 6))
        out_hit = np.zeros(M if mode == 1 else 0, dtype=np.bool_)
        out_mod = np.zeros((M if mode == 2 else 0, P, 2), dtype=np.int64)
        E, work = self._scratch()
        bad = _paper_rows(np.ascontiguousarray(Qs, dtype=np.float64), self._T, E, self._R, mode, float(margin),
                          self._H, want, out_d, out_p, out_hit, out_mod, self._eps, work)
        if bad >= 0:
            m, p = divmod(int(bad), P)
            raise BackendError(f"analytic (paper): GJK did not converge on pair {tuple(self._pairs[p])} "
                               f"(configuration {m}); raise Tolerances.gjk_max_iterations")
        return out_d, out_p, out_hit, out_mod

    def paper_distances_many(self, Q, *, points: bool = False):
        """``(M, n)`` every pair's paper distance at each row of ``Q`` (M, nq); with ``points`` also
        ``(M, n, 6)`` ``[p_WA, p_WB]`` (plain arrays; :meth:`pair_distances_many` is the interface's)."""
        Q = check_Q(self.model, Q)
        d, p, _, _ = self._run(self.model.scene_q(Q), 0, 0.0, points)
        return (d, p) if points else d

    def pair_verdicts_many(self, Q, *, margin: float = 0.0):
        """Every pair's yes/no at each row of ``Q`` (M, nq), the rule :meth:`collides` uses (Hermes's
        module where :attr:`hermes_modules` names one, else paper distance ``<= margin``), without
        stopping at the first: ``(hit (M, n) bool, d (M, n) m, branch (M, n) int)``; ``d`` the module's
        distance (``inf`` where the module computes none), ``branch`` the module's exit
        (:data:`armguard_analytic._paper_hermes.BRANCHES`) or -1 for the distance rule."""
        Q = check_Q(self.model, Q)
        if not (margin >= 0.0 and math.isfinite(margin)):
            raise BackendError(f"margin: expected a finite length >= 0, got {margin!r}")
        d, _, _, mod = self._run(self.model.scene_q(Q), 2, margin, False)
        return mod[..., 0].astype(bool), d, mod[..., 1]

    # ---------------------------------------------------------------- the interface
    def pair_distances(self, q):
        q = check_q(self.model, q)
        d, p, _, _ = self._run(self.model.scene_q(q)[None], 0, 0.0, True)
        return self._result(d[0], p[0, :, :3].copy(), p[0, :, 3:].copy())

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        Q = check_Q(self.model, Q)
        if not (margin >= 0.0 and math.isfinite(margin)):
            raise BackendError(f"margin: expected a finite length >= 0, got {margin!r}")
        return self._run(self.model.scene_q(Q), 1, margin, False)[2]

    def min_distance_many(self, Q) -> np.ndarray:
        return self.paper_distances_many(Q).min(axis=1, initial=np.inf)


# one pair, from shapes in W (their own module; part of this one's interface)
from ._paper_pair import (  # noqa: E402
    hermes_link_link, hermes_link_obstacle, hermes_payload_link, hermes_payload_obstacle, paper_capsule_polytope,
)
