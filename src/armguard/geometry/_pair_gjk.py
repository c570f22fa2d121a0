"""GJK distance between the convex hulls of two point sets (the cores), with witness points.

Gilbert, Johnson & Keerthi (1988).  The sub-algorithm that finds the point of the current
simplex closest to the origin is Johnson's distance sub-algorithm written as the Voronoi-region
tests of Ericson, *Real-Time Collision Detection* §5.1.2-5.1.6 (``ClosestPtPointTriangle``,
``ClosestPtPointTetrahedron`` with the query point at the origin; ``._pair_simplex``); the simplex keeps only the
vertices with non-zero barycentric weight.  Support points are the hull vertices maximising the
dot product, so on polytopes GJK terminates finitely; we stop when the duality gap
``(|v|^2 - v.w) / |v|`` is below ``gjk_epsilon``, when a support pair repeats, or when ``|v|``
stops decreasing.  Hitting ``max_iterations`` returns ``GJK_NOT_CONVERGED`` (callers raise).

The simplex lives in local scalars (vertex ``k``: ``w_k`` and the support indices; the witness
points are rebuilt from indices and weights only when GJK stops), so the kernel allocates
nothing and touches no memory but the two point sets; the ``work`` argument of the public
kernels is kept for their stable signatures (callers' scratch lives there).  Core B may be
translated by an offset ``o`` without copying its points.

Support points come from a scan of the points, or, for a polytope of at least
``CLIMB_MIN_VERTICES`` vertices whose vertex graph is given (B's: :func:`gjk_dir_adj`; A's and
B's: :func:`gjk_dir_adj2`), from hill climbing on that graph warm-started at the previous
support (Cameron, "Enhancing GJK", ICRA 1997).  The one body ``_gjk_body`` serves all: a graph
passed as ``None`` is a branch pruned at compile time, an empty one scans at run time.

``_gjk`` is that body as a compiled call of its own, compiled without numba's reference counting
(``_nrt=False``; it allocates nothing): with it, every call paid an atomic increment and decrement
per array argument, measured at about 30% of a batched capsule-hull query.  The analytic engine's
entry point :func:`gjk_dir_rel` (also ``_nrt=False``) inlines the body instead of calling ``_gjk``:
on the separated hull pairs of kinova and so101 that took 2-4 % less time per pair (``bench
pair_profile``; ur3 and kuka_iiwa unchanged within noise).  The other entry points call ``_gjk``:
inlining the body into each of them too doubled their cold compile time for no measured gain.
The simplex's compaction indexes tuples of its four vertices (``(x0, x1, x2, x3)[j]``) and the
triangle tests (``_closest_triangle``, ``_origin_outside``) are plain compiled calls: numba's IR
inlining of a selection helper at its 23 call sites, in every GJK copy, made ``gjk_dir``'s cold
compile 12.6 s, now 6.1 s.  Measured on the batched capsule-hull pairs (``bench pairwise``): the
same time per separated pair, 5 % more per penetrating one.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._pair_simplex import _closest_simplex, _closest_tetra, _closest_triangle, _origin_outside  # noqa: F401
from ._pair_support_table import table_cell, table_size, table_start, warm_start

__all__ = [
    "GJK_WORK_SIZE", "GJK_SEPARATED", "GJK_INTERSECTING", "GJK_NOT_CONVERGED", "ADJ_HEAD", "CLIMB_MIN_VERTICES",
    "gjk_core", "gjk_dir", "gjk_dir_adj", "gjk_dir_adj2", "gjk_dir_rel", "inner_difference",
    "table_cell", "table_size", "table_start", "warm_start",  # from ._pair_support_table
]

GJK_WORK_SIZE = 64
"""Length of the ``work`` array the GJK kernels need (float64)."""
GJK_SEPARATED = 0
"""Status: the cores are disjoint; the distance and witnesses are exact to ``gjk_epsilon``."""
GJK_INTERSECTING = 1
"""Status: the cores overlap or touch (core distance <= ``length``)."""
GJK_NOT_CONVERGED = 2
"""Status: ``max_iterations`` reached without meeting the stopping test."""
ADJ_HEAD = 6
"""Entries before the CSR offsets in a vertex-graph array (the extreme vertices along +-x, +-y, +-z)."""
CLIMB_MIN_VERTICES = 48
"""Callers climb B's vertex graph only from this many vertices on: below it a scan is faster
(a climb's unpredictable branches cost more than the dot products it saves; measured with
``bench/pairwise.py``-style capsule-hull batches: 20 vertices scan 101 ns vs climb 117 ns per
separated pair, 80 vertices 243 vs 145 ns, 160 vertices 459 vs 172 ns)."""


@njit(cache=True, inline="always")
def _climb(pb, adj, i, dx, dy, dz):  # pragma: no cover - compiled
    """Hill climbing of ``p . d`` over B's vertex graph from vertex ``i``: first improvement (it moves to
    the first strictly better neighbour it meets and scans that vertex's neighbours next).

    On the vertex graph of a convex polytope (or of any triangulation of its surface) a vertex
    with no strictly better neighbour maximises a linear function over the whole polytope (its
    edges span a cone containing the polytope), so the climb returns a true support vertex; the
    values strictly increase, so it terminates.  ``adj`` as :func:`armguard.geometry._pack.polytope_adjacency`.
    Steepest ascent (every neighbour scanned before a move) took 10-13 % longer per separated hull
    pair on ur3's, kuka_iiwa's and so101's hulls: warm-started climbs are one or two moves, and a
    move needs no full scan.  Steepest ascent again with branch-free selects (the neighbour loop
    without a data-dependent branch) took ur3's ``pair_distances`` kernel from 19.5 to 22.5 us.  Each
    neighbour's point stored beside its entry (three floats per entry, read in one stream instead of
    ``pb[adj[k]]`` after ``adj[k]``; the same supports, bit for bit) made the kernel slower where the
    hulls are large, the graph's bytes growing fourfold: so101 53 -> 64 us, kinova 21 -> 22.5 us,
    kuka_iiwa, ur3, panda and rover within 3 % (bare kernel, 3 alternating runs each; not kept).
    """
    # unsigned indices: numba indexes with a signed one only after a test for a negative index (the
    # wraparound), three instructions on each load of this loop's chain (the vertex graph's entries
    # are never negative)
    u = np.uint64(i)
    one = np.uint64(1)
    head = np.uint64(ADJ_HEAD)
    best = pb[u, 0] * dx + pb[u, 1] * dy + pb[u, 2] * dz
    k = np.uint64(adj[head + u])
    e = np.uint64(adj[head + u + one])
    while k < e:
        j = np.uint64(adj[k])
        s = pb[j, 0] * dx + pb[j, 1] * dy + pb[j, 2] * dz
        if s > best:
            best = s
            u = j
            k = np.uint64(adj[head + j])
            e = np.uint64(adj[head + j + one])
        else:
            k += one
    return np.int64(u)


@njit(cache=True, inline="always")
def _support(pb, adj, i, dx, dy, dz):  # pragma: no cover - compiled
    """Index of a vertex of ``pb`` maximising ``p . d``: a scan without ``adj`` (``None``, or an
    empty graph), else a climb from vertex ``i`` (``i < 0``: from the stored extreme vertex farthest
    along ``d``, :func:`_seed`)."""
    if adj is None:
        return _scan(pb, dx, dy, dz)
    if adj.shape[0] == 0:
        return _scan(pb, dx, dy, dz)
    if i < 0:
        i = _seed(pb, adj, dx, dy, dz)
    return _climb(pb, adj, i, dx, dy, dz)


@njit(cache=True, inline="always")
def _seed(pb, adj, dx, dy, dz):  # pragma: no cover - compiled
    """Where a cold climb starts: of the ``ADJ_HEAD`` stored extreme vertices, the one farthest
    along ``d`` (six dot products).  The graph of a detector element is built in its link frame,
    so its stored extremes are along the link's axes, not W's: picking by ``d``'s dominant W axis
    started climbs anywhere on the hull (~50 steps on a 6,877-vertex gripper hull)."""
    i = adj[0]
    best = pb[i, 0] * dx + pb[i, 1] * dy + pb[i, 2] * dz
    for k in range(1, ADJ_HEAD):
        j = adj[k]
        s = pb[j, 0] * dx + pb[j, 1] * dy + pb[j, 2] * dz
        if s > best:
            best = s
            i = j
    return i


@njit(cache=True, inline="always")
def _scan(pb, dx, dy, dz):  # pragma: no cover - compiled
    """Index of the first point of ``pb`` maximising ``p . d`` (a scan of every point)."""
    ib = 0
    best = -math.inf
    for k in range(pb.shape[0]):
        s = pb[k, 0] * dx + pb[k, 1] * dy + pb[k, 2] * dz
        if s > best:
            best = s
            ib = k
    return ib


@njit(cache=True, inline="always")
def _b_dir(rot, dx, dy, dz):  # pragma: no cover - compiled
    """``R_AB^T d``: a direction in A's frame as B's points see it (``rot`` ``None``: ``d``)."""
    if rot is None:
        return dx, dy, dz
    return (rot[0] * dx + rot[3] * dy + rot[6] * dz, rot[1] * dx + rot[4] * dy + rot[7] * dz,
            rot[2] * dx + rot[5] * dy + rot[8] * dz)


@njit(cache=True, inline="always")
def _b_point(pb, rot, i):  # pragma: no cover - compiled
    """``R_AB pb[i]``: B's point ``i`` in A's axes (``rot`` ``None``: as stored)."""
    x = pb[i, 0]
    y = pb[i, 1]
    z = pb[i, 2]
    if rot is None:
        return x, y, z
    return (rot[0] * x + rot[1] * y + rot[2] * z, rot[3] * x + rot[4] * y + rot[5] * z,
            rot[6] * x + rot[7] * y + rot[8] * z)


@njit(cache=True, inline="always")
def _m_support(pa, adja, ia, pb, adj, ib, rot, ox, oy, oz, dx, dy, dz):  # pragma: no cover - compiled
    """The support of ``M = A - (R_AB B + o)`` along ``-d``: A's along ``-d`` and B's along ``+d``,
    climbs from ``ia`` / ``ib``.  Returns ``(ia, ib, w)``."""
    ia = _support(pa, adja, ia, -dx, -dy, -dz)
    ex, ey, ez = _b_dir(rot, dx, dy, dz)
    ib = _support(pb, adj, ib, ex, ey, ez)
    qx, qy, qz = _b_point(pb, rot, ib)
    return ia, ib, pa[ia, 0] - qx - ox, pa[ia, 1] - qy - oy, pa[ia, 2] - qz - oz


@njit(cache=True, inline="always")
def _gjk_body(pa, adja, pb, adj, rot, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, simp, sep=math.inf, sa=-1,
              sb=-1, taba=None, tabb=None, seed=None):  # pragma: no cover
    """GJK from the initial direction ``d``; A's and B's supports by a scan (``adja`` / ``adj``
    ``None``, a branch numba prunes at compile time, or an empty graph) or by hill climbing on
    their vertex graphs.  ``rot`` (``None``: the identity, a branch pruned at compile time; else 9
    floats, ``R_AB`` row-major) rotates B: B's points are ``R_AB p + o``, so A's and B's points may
    stay in their own frames (A's frame is the one GJK works in; B's supports climb B's graph along
    ``R_AB^T d`` and only the support points are mapped).  ``simp`` (``None``, or a float64 array of >= 9 entries) receives the
    final simplex when the origin ends inside a tetrahedron: ``simp[0] = 1`` then, ``simp[1:5]``
    A's and ``simp[5:9]`` B's support indices of its four vertices (touching, the origin within
    ``eps_len`` of a smaller simplex: ``simp[0] = -n`` and its ``n`` vertices so; else ``simp[0] = 0``, as when
    GJK stalled with no support plane proving the cores apart, ``GJK_INTERSECTING`` then meaning "not settled":
    the caller's exact SAT decides); the
    penetration-depth kernel (``_pair_epa``) starts from it.

    ``sep`` (m; ``inf``: off): stop, ``GJK_SEPARATED``, as soon as a support plane proves the core
    distance above it (``v . w > sep |v|``: ``v . w / |v|`` is a lower bound on the distance); the
    distance returned is then ``|v|``, an upper bound, > ``sep``, not the distance (a yes/no caller
    needs only the side of ``sep``; van den Bergen §4.3.5's separating-axis early out).

    ``sa``, ``sb``: where A's and B's first climbs start (-1: the stored extreme vertex farthest along
    the direction, ``_seed``; a caller with a :func:`armguard.geometry._pack.support_table` passes its
    entry, :func:`table_start`).  ``taba``, ``tabb`` (``None``: none, a branch pruned at compile time;
    or the support tables, empty: none): every later climb starts from the better of the previous
    support and the table's entry for the new direction (:func:`warm_start`).

    ``seed`` (``None``, a branch pruned at compile time; or int64 ``[n, ia_0, ib_0, .., ia_2, ib_2]``,
    ``n`` 0 to 3; shorter than 7 entries or ``n = 0``: none): a starting simplex, the support index
    pairs of the simplex another configuration ended with (the analytic engine's seed tables,
    ``armguard_analytic._engine._seeds``).  Its vertices are points of ``A - (R_AB B + o)`` whatever
    the pose, so GJK may start from them: they enter the simplex one by one before the first support
    (the sub-algorithm drops a vertex that does not bring the simplex nearer the origin), and GJK
    stops only on the same tests after a true support, so a seed changes how many iterations GJK
    takes, never its answer beyond ``gjk_eps``.  (Entering a seed's last two vertices at once, one
    triangle test instead of a segment's and then a triangle's, changed ur3's, panda's, kinova's
    and kuka_iiwa's kernels by less than their noise, 3 %.)  On kuka_iiwa's hull pairs two joints apart: 9.7
    iterations from a cold start, 2.5 from the simplex of the nearest node of a 32 x 32 grid over
    their two joints (``python -m bench pair_profile``).  When ``simp`` has 16 entries or more, ``simp[9:16]`` receives the final
    simplex in ``seed``'s layout when GJK ends ``GJK_SEPARATED`` (else ``simp[9] = 0``): how a seed
    table is made."""
    ns = 0  # (each use of seed sits under "seed is not None", a branch numba prunes for None)
    ia = ib = 0
    x0 = y0 = z0 = 0.0
    if seed is not None:
        if seed.shape[0] >= 7 and seed[0] > 0:  # the first vertex: the seed's first
            ns = min(seed[0], 3)
            ia = seed[1]
            ib = seed[2]
            qx, qy, qz = _b_point(pb, rot, ib)
            x0, y0, z0 = pa[ia, 0] - qx - ox, pa[ia, 1] - qy - oy, pa[ia, 2] - qz - oz
    if ns == 0:  # the first vertex: supports along d
        ia, ib, x0, y0, z0 = _m_support(pa, adja, sa, pb, adj, sb, rot, ox, oy, oz, dx, dy, dz)
    ia0 = ia
    ib0 = ib
    na_t = table_size(taba)
    nb_t = table_size(tabb)
    x1 = y1 = z1 = x2 = y2 = z2 = x3 = y3 = z3 = 0.0
    ia1 = ib1 = ia2 = ib2 = ia3 = ib3 = 0
    l0 = 1.0
    l1 = l2 = l3 = 0.0
    n = 1
    vx = x0
    vy = y0
    vz = z0
    vv = vx * vx + vy * vy + vz * vz
    pvx, pvy, pvz = dx, dy, dz  # the direction of the last climbs
    pvv = dx * dx + dy * dy + dz * dz
    eps2 = eps_len * eps_len
    status = GJK_NOT_CONVERGED
    inside = False
    k_seed = 1
    wx = wy = wz = vw = 0.0
    stalled = False  # stopped without progress and without a proof of separation: no simplex to hand on (simp[0] = 0)
    for _it in range(max_iter + ns):
        if vv <= eps2:
            status = GJK_INTERSECTING
            break
        forced = False
        if seed is not None:
            if k_seed < ns:  # the seed's next vertex: no support, no stopping test
                forced = True
                ia = seed[1 + 2 * k_seed]
                ib = seed[2 + 2 * k_seed]
                k_seed += 1
                if (ia == ia0 and ib == ib0) or (n > 1 and ia == ia1 and ib == ib1):
                    continue  # already in the simplex
                qx, qy, qz = _b_point(pb, rot, ib)
                wx, wy, wz = pa[ia, 0] - qx - ox, pa[ia, 1] - qy - oy, pa[ia, 2] - qz - oz
        if not forced:
            # support of A along -v, of B along +v, climbs from the previous supports or, where v turned by
            # more than ~6 degrees since the last climbs (cos^2 < 0.99), the tables' entries if those are
            # farther along (past that turn the previous supports are as good and the look-ups cost more
            # than they save: -8-10 % per separated hull pair on ur3's, kuka_iiwa's and so101's hulls)
            turn = pvx * vx + pvy * vy + pvz * vz
            if turn < 0.0 or turn * turn < 0.99 * pvv * vv:
                ia = warm_start(pa, taba, na_t, ia, -vx, -vy, -vz)
                ex, ey, ez = _b_dir(rot, vx, vy, vz)
                ib = warm_start(pb, tabb, nb_t, ib, ex, ey, ez)
            pvx, pvy, pvz, pvv = vx, vy, vz, vv
            ia, ib, wx, wy, wz = _m_support(pa, adja, ia, pb, adj, ib, rot, ox, oy, oz, vx, vy, vz)
            vw = vx * wx + vy * wy + vz * wz
            if vv - vw <= gjk_eps * math.sqrt(vv):
                status = GJK_SEPARATED
                break
            if vw > 0.0 and vw * vw > sep * sep * vv and sep >= 0.0:
                status = GJK_SEPARATED  # proved apart by more than sep (the yes/no early out)
                break
            if (
                (ia == ia0 and ib == ib0)
                or (n > 1 and ia == ia1 and ib == ib1)
                or (n > 2 and ia == ia2 and ib == ib2)
            ):
                # a repeated support pair: no progress possible; apart only where w's plane proves it (below)
                status = GJK_SEPARATED if vw > 0.0 else GJK_INTERSECTING
                stalled = vw <= 0.0
                break
        if n == 1:
            x1, y1, z1, ia1, ib1 = wx, wy, wz, ia, ib
        elif n == 2:
            x2, y2, z2, ia2, ib2 = wx, wy, wz, ia, ib
        else:
            x3, y3, z3, ia3, ib3 = wx, wy, wz, ia, ib
        m, k0, k1, k2, k3 = _closest_simplex(n + 1, x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3)
        if m == 15:
            status = GJK_INTERSECTING  # the origin is inside the tetrahedron
            inside = True
            break
        nvx = k0 * x0 + k1 * x1 + k2 * x2 + k3 * x3
        nvy = k0 * y0 + k1 * y1 + k2 * y2 + k3 * y3
        nvz = k0 * z0 + k1 * z1 + k2 * z2 + k3 * z3
        nvv = nvx * nvx + nvy * nvy + nvz * nvz
        if nvv >= vv:
            if forced:
                continue  # a seed vertex that brings the simplex no nearer: dropped (slot n is free again)
            # no progress (rounding): the previous simplex is the answer -- apart only where the last support
            # plane proves the origin outside M (v . w > 0).  A simplex flattened by rounding on thin cores
            # (boxes 0.34 and 8 um thick, overlapping by 9 nm) stalled with |v| = 2.3e-7 m and v . w < 0: it was
            # reported apart by |v|; now "not separated", and the caller's exact SAT / EPA gives the depth
            status = GJK_SEPARATED if vw > 0.0 else GJK_INTERSECTING
            stalled = vw <= 0.0
            break
        # compact the kept vertices into slots 0 .. c-1, in order
        c = 0
        j0 = j1 = j2 = 0
        for j in range(4):
            if (m >> j) & 1:
                if c == 0:
                    j0 = j
                elif c == 1:
                    j1 = j
                else:
                    j2 = j
                c += 1
        nx0 = (x0, x1, x2, x3)[j0]
        ny0 = (y0, y1, y2, y3)[j0]
        nz0 = (z0, z1, z2, z3)[j0]
        na0 = (ia0, ia1, ia2, ia3)[j0]
        nb0 = (ib0, ib1, ib2, ib3)[j0]
        nl0 = (k0, k1, k2, k3)[j0]
        nx1 = (x0, x1, x2, x3)[j1]
        ny1 = (y0, y1, y2, y3)[j1]
        nz1 = (z0, z1, z2, z3)[j1]
        na1 = (ia0, ia1, ia2, ia3)[j1]
        nb1 = (ib0, ib1, ib2, ib3)[j1]
        nl1 = (k0, k1, k2, k3)[j1]
        nx2 = (x0, x1, x2, x3)[j2]
        ny2 = (y0, y1, y2, y3)[j2]
        nz2 = (z0, z1, z2, z3)[j2]
        na2 = (ia0, ia1, ia2, ia3)[j2]
        nb2 = (ib0, ib1, ib2, ib3)[j2]
        nl2 = (k0, k1, k2, k3)[j2]
        x0, y0, z0, ia0, ib0, l0 = nx0, ny0, nz0, na0, nb0, nl0
        x1, y1, z1, ia1, ib1, l1 = nx1, ny1, nz1, na1, nb1, nl1 if c > 1 else 0.0
        x2, y2, z2, ia2, ib2, l2 = nx2, ny2, nz2, na2, nb2, nl2 if c > 2 else 0.0
        l3 = 0.0
        n = c
        vx, vy, vz, vv = nvx, nvy, nvz, nvv
    # witnesses of the current simplex
    ax = ay = az = bx = by = bz = 0.0
    for k in range(n):
        lam = (l0, l1, l2, l3)[k]
        i = (ia0, ia1, ia2, ia3)[k]
        j = (ib0, ib1, ib2, ib3)[k]
        ax += lam * pa[i, 0]
        ay += lam * pa[i, 1]
        az += lam * pa[i, 2]
        qx, qy, qz = _b_point(pb, rot, j)
        bx += lam * qx
        by += lam * qy
        bz += lam * qz
    bx += ox
    by += oy
    bz += oz
    if simp is not None:
        simp[0] = 1.0 if inside else 0.0
        if inside:
            for k in range(4):
                simp[1 + k] = (ia0, ia1, ia2, ia3)[k]
                simp[5 + k] = (ib0, ib1, ib2, ib3)[k]
        elif status == GJK_INTERSECTING and not stalled:  # touching: the n vertices the origin is within eps_len of, -n
            simp[0] = -float(n)
            for k in range(4):
                simp[1 + k] = (ia0, ia1, ia2, ia3)[k] if k < n else 0
                simp[5 + k] = (ib0, ib1, ib2, ib3)[k] if k < n else 0
        if simp.shape[0] >= 16:  # the final simplex as a seed (see the docstring)
            simp[9] = n if status == GJK_SEPARATED else 0
            for k in range(3):
                simp[10 + 2 * k] = (ia0, ia1, ia2)[k] if k < n else 0
                simp[11 + 2 * k] = (ib0, ib1, ib2)[k] if k < n else 0
    if inside:
        return status, 0.0, ax, ay, az, bx, by, bz
    return status, math.sqrt(vv), ax, ay, az, bx, by, bz


_gjk = njit(cache=True, _nrt=False)(_gjk_body.py_func)
"""The body as a compiled call of its own (see the module docstring).  Built from the body's own
Python function, not a wrapper that inlines it: numba inlines by deep-copying the callee's IR
block by block, each copy taking the whole function's variable scope along (~2 s of a cold
compile for each wrapper's signature: ``python -m bench compile``).  Its numba cache files carry
the body's name; the inlined ``_gjk_body`` itself is never compiled on its own, so nothing else
writes them."""


@njit(cache=True)
def gjk_dir(pa, pb, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter):  # pragma: no cover - compiled
    """GJK from the initial direction ``d`` (m; pointing from B to A): see :func:`gjk_core`.

    The simplex lives in local scalars: vertex ``k`` is ``w_k = a_k - b_k`` (``x_k, y_k, z_k``)
    with the support indices ``ia_k, ib_k`` and its weight ``l_k``; the witnesses are rebuilt
    from the indices and weights only when GJK stops.  Allocation-free.  B's supports scan its
    points.
    """
    return _gjk(pa, None, pb, None, None, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, None)


@njit(cache=True)
def gjk_dir_adj(pa, pb, adj, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter):  # pragma: no cover - compiled
    """:func:`gjk_dir` for a polytope B with its vertex graph ``adj`` (int64, see
    :func:`armguard.geometry._pack.polytope_adjacency`): B's supports climb the graph from the
    previous support (a few neighbours instead of every vertex).  Same answer as :func:`gjk_dir`
    up to ties between equally extreme vertices."""
    return _gjk(pa, None, pb, adj, None, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, None)


@njit(cache=True)
def gjk_dir_adj2(pa, adja, pb, adjb, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, simp, sep):  # pragma: no cover
    """:func:`gjk_dir` climbing the vertex graphs of both A and B (either may be empty: a scan),
    writing the final simplex to ``simp``, stopping once the distance is proved above ``sep``
    (``inf``: never; see ``_gjk``)."""
    return _gjk(pa, adja, pb, adjb, None, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, simp, sep)


@njit(cache=True, _nrt=False)
def gjk_dir_rel(pa, adja, taba, pb, adjb, tabb, rot, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, simp,
                sep, seed):  # pragma: no cover
    """:func:`gjk_dir_adj2` with B's points in a frame of their own: hull(pa) against
    ``R_AB hull(pb) + o`` (``rot``: ``R_AB`` row-major, 9 floats), everything returned in A's frame.
    A caller holding both hulls in their link frames passes ``X_AB = X_WA^-1 X_WB`` and moves no
    vertex (only the support points GJK visits are rotated).  ``taba``, ``tabb``: each hull's
    :func:`armguard.geometry._pack.support_table` (empty: start from the stored extremes): the first
    climbs start from their entries, every later one from the better of its entry and the previous
    support (on ur3's and so101's hulls: 214 -> 131 dot products per separated pair).  ``seed``: a
    starting simplex (int64, empty: none; see ``_gjk_body``)."""
    sa = sb = -1
    if seed.shape[0] < 7 or seed[0] <= 0:  # a cold start: the tables' entries for d (a seed needs neither)
        ex, ey, ez = _b_dir(rot, dx, dy, dz)
        sa = table_start(taba, -dx, -dy, -dz)
        sb = table_start(tabb, ex, ey, ez)
    return _gjk_body(pa, adja, pb, adjb, rot, ox, oy, oz, dx, dy, dz, eps_len, gjk_eps, max_iter, simp, sep, sa, sb,
                     taba, tabb, seed)


@njit(cache=True, inline="always")
def centroid_difference(pa, pb):  # pragma: no cover - compiled
    """Centroid of the points ``pa (nA, 3)`` minus that of ``pb (nB, 3)``: GJK's first search
    direction (fewer iterations than an arbitrary vertex pair)."""
    na = pa.shape[0]
    nb = pb.shape[0]
    gx = gy = gz = 0.0
    for i in range(na):
        gx += pa[i, 0]
        gy += pa[i, 1]
        gz += pa[i, 2]
    hx = hy = hz = 0.0
    for i in range(nb):
        hx += pb[i, 0]
        hy += pb[i, 1]
        hz += pb[i, 2]
    return gx / na - hx / nb, gy / na - hy / nb, gz / na - hz / nb


@njit(cache=True, inline="always")
def _inner_point(p, adj):  # pragma: no cover - compiled
    """A point inside the hull of ``p``: the mean of the six extreme vertices a vertex graph stores
    (six reads), else the points' centroid (a scan)."""
    if adj.shape[0] == 0:
        gx = gy = gz = 0.0
        for i in range(p.shape[0]):
            gx += p[i, 0]
            gy += p[i, 1]
            gz += p[i, 2]
        n = p.shape[0]
        return gx / n, gy / n, gz / n
    gx = gy = gz = 0.0
    for k in range(6):
        gx += p[adj[k], 0]
        gy += p[adj[k], 1]
        gz += p[adj[k], 2]
    return gx / 6.0, gy / 6.0, gz / 6.0


@njit(cache=True, inline="always")
def inner_difference(pa, adja, pb, adjb):  # pragma: no cover - compiled
    """GJK's first search direction for two cores with vertex graphs (either may be empty): a point
    inside A's hull minus one inside B's (:func:`_inner_point`).  Any direction is correct; one
    between the hulls saves iterations, and where a graph is given this costs six reads, not the
    scan of thousands of vertices :func:`centroid_difference` makes (on so101's hulls of 2,100 to
    4,900 vertices, more than GJK itself)."""
    gx, gy, gz = _inner_point(pa, adja)
    hx, hy, hz = _inner_point(pb, adjb)
    return gx - hx, gy - hy, gz - hz


@njit(cache=True)
def gjk_core(pa, pb, ox, oy, oz, work, eps_len, gjk_eps, max_iter):  # pragma: no cover - compiled
    """Closest points of hull(pa) and hull(pb) + o.

    ``pa : (nA, 3)``, ``pb : (nB, 3) float64, m``; ``o`` (m) translates B; ``work`` is unused
    (kept for the stable signature: the simplex lives in registers, see :func:`gjk_dir`).
    Returns ``(status, dist, ax, ay, az, bx, by, bz)``: core distance and the witness points
    (B's includes the offset).  ``status`` is one of ``GJK_SEPARATED``, ``GJK_INTERSECTING``,
    ``GJK_NOT_CONVERGED``.  Starts from the supports along the centroid difference (fewer
    iterations than an arbitrary vertex pair).
    """
    dx, dy, dz = centroid_difference(pa, pb)
    return gjk_dir(
        pa, pb, ox, oy, oz, dx - ox, dy - oy, dz - oz,
        eps_len, gjk_eps, max_iter,
    )
