"""Flat float64 views of a shape for the kernels, built once when the shape is constructed.

Every shape carries (as private attributes set by its constructor):

* ``_pk``: the closed-form kernels' parameter buffer -- Sphere ``[c, c, r]`` (a zero-length
  capsule, 7 floats), Capsule ``[p0, p1, r]`` (7), Box ``[c, h, R_WB row-major]`` (15), Cylinder
  ``[c, r, r, h, R_WC row-major]`` (15: the box layout, the axis is ``R_WC[:, 2]``); empty for the
  polytopes;
* ``_sat``: ``(core_points (n, 3), face_normals (F, 3), edge_directions (E, 3), radius)`` for
  GJK + SAT, with face normals and edge directions reduced to one per parallel class;
* ``_poly`` (polytopes only): faces with offsets and edges with their two faces, for the
  segment-polytope kernel (see :func:`polytope_data`);
* ``_adj`` (polytopes only): the vertex graph for hill-climbing support queries (see
  :func:`polytope_adjacency`);
* ``_pbuf`` (polytopes only): all of the above in one float and one int buffer, for the
  single-call entry point (see :func:`polytope_buffers`).

Shapes are immutable, so this is computed once, explicitly, at construction.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES
from ._pair_support_table import TABLE_N

__all__ = ["attach_packed", "unique_directions", "face_edges", "unique_pairs", "polytope_data", "polytope_adjacency", "hull_graph", "polytope_buffers"]

_EMPTY = np.zeros((0, 3), dtype=np.float64)


def unique_directions(d: np.ndarray, parallel: float) -> np.ndarray:
    """Unit directions of the non-zero rows of ``d (n, 3)``, one per parallel class (sign ignored).

    Each direction is signed so that its largest component is positive and rounded to a grid of
    ``parallel / 2`` per component; directions in one grid cell (``|sin| < parallel``) are one
    class, kept as the first of them (its own sign), in input order.  O(n log n): a hull of
    thousands of edges takes milliseconds.  Two directions closer than ``parallel`` that straddle
    a cell boundary both stay (a duplicate axis, harmless to SAT); no two directions farther
    apart than ``parallel`` are ever merged."""
    rows = np.asarray(d, dtype=np.float64).reshape(-1, 3)
    n = np.linalg.norm(rows, axis=1)
    nz = n > 0.0
    if not nz.any():
        return _EMPTY
    u = rows[nz] / n[nz, None]
    sign = np.where(u[np.arange(len(u)), np.argmax(np.abs(u), axis=1)] < 0.0, -1.0, 1.0)
    key = np.round(u * sign[:, None] / (0.5 * parallel)).astype(np.int64)
    # the first row of each distinct key (np.unique(key, axis=0, return_index=True), by a stable
    # lexsort of the three columns instead of a sort of structured rows)
    o = np.lexsort((key[:, 2], key[:, 1], key[:, 0]))
    ks = key[o]
    first = o[np.r_[True, np.any(ks[1:] != ks[:-1], axis=1)]]
    return np.ascontiguousarray(u[np.sort(first)])


def face_edges(faces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(a, b, face)``: every boundary edge ``a -> b`` of every face (vertex index loops), with
    the index of its face; one concatenation, no per-face work in Python beyond the lengths."""
    if not len(faces):
        z = np.zeros(0, dtype=np.int64)
        return z, z, z
    lens = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    a = np.concatenate(faces, dtype=np.int64, casting="unsafe")  # as np.asarray(f, dtype=np.int64) of each
    first = np.cumsum(lens) - lens
    nxt = np.arange(1, len(a) + 1, dtype=np.int64)
    nxt[first + lens - 1] = first  # each face's last vertex closes the loop to its first
    return a, a[nxt], np.repeat(np.arange(len(faces), dtype=np.int64), lens)


def unique_pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The distinct rows of ``[a, b]`` (non-negative int64 columns), sorted by ``a`` then ``b``:
    ``np.unique(..., axis=0)`` through one int64 key (a 1-D sort, not a row-wise one)."""
    if not len(a):
        return np.zeros((0, 2), dtype=np.int64)
    n = int(b.max()) + 1
    key = np.unique(a.astype(np.int64) * n + b)
    return np.stack([key // n, key % n], axis=1)


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.flags.writeable = False
    return a


def attach_packed(shape) -> None:
    """Set ``shape._pk`` and ``shape._sat`` (see the module docstring)."""
    from ._cylinder import Cylinder
    from ._shapes import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere

    par = 1e-9  # one class for directions closer than this sine: only affects duplicate axes
    pts = _ro(shape.core_points)
    if isinstance(shape, Sphere):
        pk = np.concatenate([shape.center, shape.center, [shape.radius]])
        faces, edges = _EMPTY, _EMPTY
    elif isinstance(shape, Capsule):
        pk = np.concatenate([shape.p0, shape.p1, [shape.radius]])
        faces = _EMPTY
        d = shape.p1 - shape.p0
        edges = unique_directions(d, par) if np.linalg.norm(d) > DEFAULT_TOLERANCES.length else _EMPTY
        if not len(edges):
            pts = _ro(shape.p0.reshape(1, 3))
    elif isinstance(shape, Box):
        pk = np.concatenate([shape.center, shape.half_extents, shape.rotation.reshape(-1)])
        faces = edges = _ro(shape.rotation.T)  # rows = box axes
    elif isinstance(shape, Cylinder):
        r, h = shape.radius, shape.half_length
        pk = np.concatenate([shape.center, [r, r, h], shape.rotation.reshape(-1)])
        faces = edges = _ro(shape.rotation[:, 2].reshape(1, 3))  # the caps' normal, the side's direction
    elif isinstance(shape, (ConvexPolyhedron, Prism)):
        pk = np.zeros(0)
        poly = shape if isinstance(shape, ConvexPolyhedron) else None
        if poly is None:
            R = shape.rotation
            n = shape.n_sides
            ang = np.arange(n) * (2.0 * np.pi / n)
            side = np.stack([np.cos(ang), np.sin(ang), np.zeros(n)], axis=1) @ R.T
            faces = unique_directions(np.vstack([side, R[:, 2]]), par)
            tang = np.stack([-np.sin(ang), np.cos(ang), np.zeros(n)], axis=1) @ R.T
            edges = unique_directions(np.vstack([tang, R[:, 2]]), par)
        else:
            faces = unique_directions(poly.planes[:, :3], par)
            v = poly.vertices
            edges = unique_directions(v[poly.edges[:, 1]] - v[poly.edges[:, 0]], par)
    elif isinstance(shape, Polygon):
        pk = np.zeros(0)
        faces = _ro(shape.normal.reshape(1, 3))
        v = shape.vertices
        edges = unique_directions(np.roll(v, -1, axis=0) - v, par)
    else:  # pragma: no cover - every shape class is listed above
        raise TypeError(f"unknown shape {type(shape).__name__}")
    # writable on purpose: numba's dispatcher types read-only arrays on a slow path (~5 µs a
    # call); the buffer is private and never written after construction
    object.__setattr__(shape, "_pk", np.ascontiguousarray(pk, dtype=np.float64))
    object.__setattr__(
        shape, "_sat", (np.array(pts), np.array(faces), np.array(edges), float(shape.core_radius))
    )
    if isinstance(shape, (ConvexPolyhedron, Polygon)):
        polytope_buffers(shape)


def _build_polytope_data(shape):
    """``(verts, planes, edges, bisectors, centroid)`` of a polytopal core (see polytope_data)."""
    from ._shapes import Box, Polygon, Prism

    if isinstance(shape, (Box, Prism)):
        shape = shape.as_polyhedron()
    if isinstance(shape, Polygon):
        v = np.asarray(shape.vertices, dtype=np.float64)
        n = np.asarray(shape.normal, dtype=np.float64)
        planes = np.array([[*n, shape.offset], [*(-n), -shape.offset]], dtype=np.float64)
        k = len(v)
        idx = np.arange(k)
        edges = np.stack([idx, (idx + 1) % k, np.zeros(k, np.int64), np.ones(k, np.int64)], axis=1)
        t = v[(idx + 1) % k] - v
        bis = np.cross(t, n)  # outward in-plane normal of a counter-clockwise polygon
        bis /= np.linalg.norm(bis, axis=1)[:, None]
    else:
        v = np.asarray(shape.vertices, dtype=np.float64)
        planes = np.asarray(shape.planes, dtype=np.float64)
        # every face's boundary edges (lo, hi, face), sorted by edge then face: an edge's first two
        # rows are the two faces meeting there
        a, b, fid = face_edges(shape.faces)
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        o = np.lexsort((fid, hi, lo))
        lo, hi, fid = lo[o], hi[o], fid[o]
        start = np.flatnonzero(np.r_[True, (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])])
        edges = np.stack([lo[start], hi[start], fid[start], fid[start + 1]], axis=1).astype(np.int64)
        bis = planes[edges[:, 2], :3] + planes[edges[:, 3], :3]
    # private writable copies: numba types read-only arrays on a slow path (see attach_packed)
    return (
        np.array(v, dtype=np.float64, order="C"),
        np.array(planes, dtype=np.float64, order="C"),
        np.array(edges, dtype=np.int64, order="C"),
        np.array(bis, dtype=np.float64, order="C"),
        np.array(v.mean(axis=0), dtype=np.float64, order="C"),
    )


def polytope_data(shape):
    """The H- and V-description of a polytopal core for the segment-polytope kernel.

    Returns ``(verts (V, 3), planes (F, 4), edges (E, 4) int64, bisectors (E, 3), centroid (3,))``:
    vertices (m); every face as ``[n, o]`` with unit outward ``n`` and ``n . x <= o`` inside (a
    Polygon has two faces, ``+normal`` and ``-normal``); every edge as ``[v0, v1, f1, f2]``
    (its vertices and the two faces meeting there) with a vector ``bisectors[e]`` inside the
    arc of outward normals at the edge (``n_f1 + n_f2``, or a Polygon edge's outward in-plane
    normal); the vertex centroid (m).  Built once per shape (at construction for
    ConvexPolyhedron and Polygon, at first use for Box and Prism) and stored as ``_poly``.
    """
    try:
        return shape._poly
    except AttributeError:
        data = _build_polytope_data(shape)
        object.__setattr__(shape, "_poly", data)
        return data


def _build_adjacency(shape) -> np.ndarray:
    from ._shapes import Polygon

    v, _planes, edges, _bis, _cen = polytope_data(shape)
    pairs = [edges[:, :2]]
    if not isinstance(shape, Polygon):
        # a triangulation of the surface as well: its graph alone already makes every local
        # maximum of a linear function global, whatever the merged faces look like
        tri = getattr(shape, "_hull_tri", None)  # Qhull's, kept by the constructor
        if tri is None:
            from scipy.spatial import ConvexHull

            tri = ConvexHull(v).simplices
        pairs += [tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]
    return _graph(v, pairs)


def hull_graph(points) -> tuple[np.ndarray, np.ndarray]:
    """The vertex graph of the convex hull of ``points (n, 3)`` (m) and its triangles.

    Returns ``(adj, tri)``: ``adj`` in the format of :func:`polytope_adjacency` (indices into
    ``points``), the edges of a triangulation of the hull's surface, so a climb over it finds a
    point maximising any linear function (points inside the hull, or inside a face, are left
    without neighbours and are never visited); ``tri (T, 3) int64`` that triangulation (Qhull's),
    whose normals are the hull's face normals and whose edges include the hull's edges (the SAT
    fallback of ``_pair_epa`` takes its axes from them).  Raises on a flat point set."""
    from scipy.spatial import ConvexHull

    v = np.asarray(points, dtype=np.float64).reshape(-1, 3)

    def make():
        tri = np.ascontiguousarray(ConvexHull(v).simplices, dtype=np.int64)
        return _graph(v, [tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), tri

    return _memo("hull_graph", v, make)


_MEMO: OrderedDict = OrderedDict()  # (kind, shape, digest of the points) -> arrays (read only), least recent first
_MEMO_LOCK = threading.Lock()
_MEMO_BYTES = 32 << 20  # kept at most: an edited Model (a body added) rebuilds its checkers' hulls' graphs and tables


def _memo(kind, v: np.ndarray, make):
    """``make()`` for the points ``v``, remembered by their bytes (the same points, the same answer): a Model
    edit rebuilds the analytic engine of the links it did not touch (so101: 17 hulls of up to 4,900
    vertices, 0.48 of the 0.78 s an edit took were these graphs and tables).  Returns fresh copies."""
    key = (kind, v.shape, hashlib.blake2b(np.ascontiguousarray(v).tobytes(), digest_size=16).digest())
    with _MEMO_LOCK:
        hit = _MEMO.get(key)
        if hit is not None:
            _MEMO.move_to_end(key)
    if hit is None:
        hit = make()
        hit = tuple(hit) if isinstance(hit, tuple) else (hit,)
        for a in hit:
            a.flags.writeable = False
        with _MEMO_LOCK:
            _MEMO[key] = hit
            total = sum(a.nbytes for h in _MEMO.values() for a in h)
            while total > _MEMO_BYTES and len(_MEMO) > 1:
                total -= sum(a.nbytes for a in _MEMO.popitem(last=False)[1])
    out = tuple(a.copy() for a in hit)
    return out if len(out) > 1 else out[0]


def support_table(points, n: int = TABLE_N) -> np.ndarray:
    """Where a cold support climb on ``points (V, 3)`` starts, by direction: ``(6 n n,) int64``, entry
    :func:`armguard.geometry._pair_support_table.table_cell` of a direction holds the point maximising ``p . u``
    for ``u`` the centre of that cell of the cube map (6 faces of ``n x n`` cells; the cube's face
    ``+x`` holds directions with ``x`` their largest component, and so on).

    A climb from there to the true support along ``d`` is a few steps (on so101's hulls of 770 to
    4,900 vertices: about 15 dot products instead of 60 to 100 from the best of the six extreme
    vertices); any start is correct (a climb over the hull's graph ends at a true support vertex),
    the table only shortens the walk.  GJK and EPA start every climb from the better of the table's
    entry and the previous support (``_pair_support_table.warm_start``); ``n = 16`` (1,536 entries, 12 kB a
    hull) took 4-8 % less time per separated hull pair than ``n = 8`` on ur3's and so101's hulls.

    Measured and not kept: flagging the entries whose whole cell lies in their vertex's normal cone
    (the cone over a cell is spanned by its four corner rays, so the test is the climb's stopping
    test at the corners; the flagged entry is the support itself, with no climb).  On ur3's hulls
    (75-650 vertices) about half the cells are such at ``n = 64``, yet the kernel's time at random
    configurations stayed within its noise, the tables consulted at every climb or only after a
    turn: a climb from a table's entry is already one scan of a vertex's neighbours.  Nor did ``n = 32``
    (6,144 entries): ur3's kernel 20.6 against 20.5 us, kinova's 29.1 against 30.1 us, within noise."""
    v = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return _memo(("support_table", int(n)), v, lambda: _support_table(v, n))


def _support_table(v: np.ndarray, n: int) -> np.ndarray:
    c = -1.0 + (np.arange(n) + 0.5) * (2.0 / n)
    uu, vv = np.meshgrid(c, c, indexing="ij")
    dirs = []
    for axis, (ku, kv) in enumerate(((1, 2), (0, 2), (0, 1))):
        for sign in (1.0, -1.0):
            d = np.zeros((n * n, 3))
            d[:, axis] = sign
            d[:, ku], d[:, kv] = uu.ravel(), vv.ravel()
            dirs.append(d)
    return np.ascontiguousarray(np.argmax(v @ np.concatenate(dirs).T, axis=0), dtype=np.int64)


def _graph(v: np.ndarray, pairs: list) -> np.ndarray:
    """CSR vertex graph (see :func:`polytope_adjacency`) of the undirected edges in ``pairs``."""
    e = np.concatenate(pairs).astype(np.int64)
    e = unique_pairs(np.minimum(e[:, 0], e[:, 1]), np.maximum(e[:, 0], e[:, 1]))
    e = e[e[:, 0] != e[:, 1]]
    both = np.concatenate([e, e[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    n = len(v)
    deg = np.bincount(both[:, 0], minlength=n)
    head = 6
    start = head + n + 1 + np.concatenate([[0], np.cumsum(deg)])
    ext = [int(np.argmax(s * v[:, k])) for k in range(3) for s in (1.0, -1.0)]
    return np.ascontiguousarray(np.concatenate([ext, start, both[:, 1]]), dtype=np.int64)


def polytope_adjacency(shape) -> np.ndarray:
    """The vertex graph of a polytopal core, for hill-climbing support queries (``_pair_gjk``).

    Returns ``adj (6 + V + 1 + 2 E') int64``: ``adj[0:6]`` the vertices extreme along ``+x, -x,
    +y, -y, +z, -z`` (where a climb starts); ``adj[6 + i] : adj[7 + i]`` the positions in ``adj``
    of vertex ``i``'s neighbours (indices into ``polytope_data(shape)[0]``).  The edges are the
    polytope's edges plus those of a triangulation of its surface (a Polygon: its cycle), so a
    vertex with no strictly better neighbour maximises any linear function.  Built once per
    shape (at construction for ConvexPolyhedron and Polygon, at first use for Box and Prism)
    and stored as ``_adj``.
    """
    try:
        return shape._adj
    except AttributeError:
        adj = _build_adjacency(shape)
        object.__setattr__(shape, "_adj", adj)
        return adj


def polytope_buffers(shape):
    """:func:`polytope_data`, :func:`polytope_adjacency` and the core radius in two flat buffers.

    Returns ``(fbuf, ibuf)``: ``fbuf`` float64 = ``[verts (3 V), planes (4 F), bisectors (3 E),
    centroid (3), core radius]``, ``ibuf`` int64 = ``[V, F, E, edges (4 E), adj]``; the kernel
    ``_pair_segment_polytope.capsule_polytope_packed`` takes views of them.  Built once per
    shape and stored as ``_pbuf``.
    """
    try:
        return shape._pbuf
    except AttributeError:
        v, planes, edges, bis, cen = polytope_data(shape)
        adj = polytope_adjacency(shape)
        fbuf = np.concatenate([v.ravel(), planes.ravel(), bis.ravel(), cen, [float(shape.core_radius)]])
        ibuf = np.concatenate([[len(v), len(planes), len(edges)], edges.ravel(), adj]).astype(np.int64)
        bufs = (np.ascontiguousarray(fbuf, dtype=np.float64), np.ascontiguousarray(ibuf, dtype=np.int64))
        object.__setattr__(shape, "_pbuf", bufs)
        return bufs
