"""Seed tables: where GJK starts on a link-frame pair whose relative pose depends on one to three joints.

GJK on two hulls of links a few joints apart takes many iterations from a cold start on the public
robots' hulls, even along a good first direction: their nearest features are faces and edges nearly
parallel, and GJK builds its simplex one support at a time.  The pose of link B in link A's frame,
though, depends only on the joints between them (the links on one chain from the root and not on the other: their joint values,
mimic terms included).  For a pair whose pose depends on one, two or three joint values, this module
runs the narrow phase at the nodes of a grid over them (64 nodes for one joint, 32 x 32 for two,
16 x 16 x 16 for three; a revolute joint that turns a whole turn or more, or without limits, over
one turn with its values wrapped onto the grid; any other over its limits, at most 4 pi wide:
:func:`_axis`) and keeps, per node, the
simplex GJK ended with when the hulls are apart (the support index pairs of up to three vertices)
or the facet EPA ended on when they overlap (three vertices).  At a check,
:func:`._narrow.narrow_rel` starts GJK from the seed of the node nearest the check's joint values
(``_pair_gjk._gjk_body``'s ``seed``); where the hulls overlap, GJK reaches its tetrahedron from the
facet's vertices.  EPA itself still starts from GJK's tetrahedron: inserting the seed facet into its
polytope as well saved ur3's overlapping pairs few EPA iterations, too few for the code (on hulls
of 400-650 vertices the nearest facet changes between grid nodes).  A vertex of a seed is a point of the Minkowski difference at every pose, and GJK
and EPA stop only on their usual tests after true supports, so a seed changes the number of
iterations, never the answer.  ``python -m bench pair_profile`` counts them: on kuka_iiwa's separated
pairs two joints apart 2.5 seeded against 9.7 from a cold start, three joints apart 3.0 against 5.4.
A pair whose pose depends on four joints or more (links far apart, about 4 iterations cold) has no
table: a grid over four joints fine enough to help would take megabytes a pair, and a 16^3 table over
three of them (the others at their middle) was tried on ur3 (9 of its 21 pairs are such): with the
best of four choices of the three, the mean GJK iterations of ``bench pair_profile`` fell by less
than a twentieth, too little for 229 kB a pair.  Nor did a start from a face of one hull turned
towards the other and the other's vertex facing back (a face table of 384 cells a hull, the face
nearest each cell's direction, with the side better turned chosen at the check): it cut those
pairs' GJK support evaluations (ur3 5.8 -> 4.3, panda 4.0 -> 2.6, kinova 4.9 -> 3.8, 10 random
configurations) but not the time, each seed vertex entering the simplex at the cost of an
iteration's sub-algorithm (the kernel over 200 configurations: ur3 and panda within 2 %, kinova 4-6 %
slower; measured 2026-12-05, not kept).

Made at each build, in Python over the compiled ``gjk_dir_rel`` and ``epa_depth`` (the signatures
the kernels call); kept per process (:data:`CACHE_BYTES`, keyed by the hulls, the
links' chains and the grid), so a rebuild after a scene edit makes none again.

Layout (``._layout``): ``spair`` ``(n_pairs, 6)`` int64 ``[first row of the pair's table in sdt (-1:
none), nodes per joint, joints (1-3) + 4 << m for each periodic joint m, joint i, j, k]``; ``sgrid`` ``(n_pairs, 6)`` float64 ``[lower,
1 / step]`` per joint; ``sdt`` ``(rows, 7)`` int64, a row per node, row-major over the joints:
``[n, ia_0, ib_0, ia_1, ib_1, ia_2, ib_2]`` (``n = 0``: no seed, GJK starts cold).
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict

import numpy as np

from armguard.geometry._pair_epa import EPA_WORK_SIZE, epa_depth
from armguard.geometry._pair_gjk import GJK_SEPARATED, _inner_point, gjk_dir_rel
from armguard.kinematics._fk import fk_kernel

__all__ = ["CACHE_BYTES", "NODES", "pair_joints", "seed_row", "seed_tables"]

NODES = {1: 64, 2: 32, 3: 16}
"""Grid nodes per joint of a pair whose pose depends on one, two or three joint values (64, 32 x 32
and 16 x 16 x 16 nodes).  Powers of two: a periodic grid wraps a node index with a mask
(``._narrow._seed``), not an integer division."""
assert all(n & (n - 1) == 0 for n in NODES.values())
_SPAN_MAX = 4.0 * math.pi
"""A joint's grid covers its limits, at most this wide around their middle (rad or m); a value
outside the grid takes the nearest edge node's seed (a poorer start, the same answer)."""


def _chain(parent: np.ndarray, link: int) -> set:
    """``link`` and its ancestors in the engine tree (empty for -1, W)."""
    out = set()
    while link >= 0:
        out.add(int(link))
        link = int(parent[link])
    return out


def pair_joints(tree, la: int, lb: int) -> tuple:
    """The joint values (indices into ``q``) that ``X_AB`` of links ``la``, ``lb`` (-1: W) depends on:
    those of the links on one chain from the root and not on the other (mimic terms included)."""
    out = set()
    for i in _chain(tree.parent, la) ^ _chain(tree.parent, lb):
        if tree.jtype[i] != 0:
            out.update(int(j) for j in tree.term_joint[tree.term_start[i]:tree.term_start[i + 1]])
    return tuple(sorted(out))


def _seeded(core_a: int, core_b: int, b_moving: bool) -> bool:
    """Whether ``._step.evaluate_pair`` sends the pair to ``narrow_rel``'s GJK (no cylinder)."""
    return ((core_a in (2, 3) and core_b in (2, 3)) or (core_a == 3 and core_b <= 1)
            or (core_a <= 1 and core_b == 3 and b_moving))


def seed_tables(tree, qlim, glink, core, vstart, verts, gadj, gadjs, gdir, gdirs, pair_a, pair_b, mov_idx,
                eps_len: float, gjk_eps: float, max_iter: int) -> dict:
    """``spair``, ``sgrid`` and ``sdt`` (the module docstring) for the pairs ``pair_a``, ``pair_b``."""
    P = len(pair_a)
    spair = np.full((P, 6), -1, dtype=np.int64)
    sgrid = np.zeros((P, 6))
    rows: list = []
    n_rows = 0
    for p in range(P):
        a, b = int(pair_a[p]), int(pair_b[p])
        if b < 0 or not _seeded(int(core[a]), int(core[b]), mov_idx[b] >= 0):
            continue
        la, lb = int(glink[a]), int(glink[b])
        js = pair_joints(tree, la, lb)
        if not 1 <= len(js) <= 3:
            continue
        n = NODES[len(js)]
        grid = [_axis(tree, qlim, j, n) for j in js]
        if any(g is None for g in grid):
            continue
        lo, inv, wrap = (np.array([g[k] for g in grid]) for k in range(3))
        axes = [lo[k] + np.arange(n) / inv[k] for k in range(len(js))]
        part = (verts[vstart[a]:vstart[a + 1]], gadj[gadjs[a]:gadjs[a + 1]], gdir[gdirs[a]:gdirs[a + 1]],
                verts[vstart[b]:vstart[b + 1]], gadj[gadjs[b]:gadjs[b + 1]], gdir[gdirs[b]:gdirs[b + 1]])
        table = _table(tree, qlim, la, lb, js, axes, part, (eps_len, gjk_eps, max_iter))
        mask = sum(4 << k for k in range(len(js)) if wrap[k])
        spair[p, :3 + len(js)] = (n_rows, n, len(js) + mask) + js
        sgrid[p, :2 * len(js)] = np.ravel(np.column_stack([lo, inv]))
        rows.append(table)
        n_rows += len(table)
    sdt = np.concatenate(rows) if rows else np.zeros((1, 7), dtype=np.int64)
    return {"spair": spair, "sgrid": sgrid, "sdt": sdt}


def _axis(tree, qlim, j: int, n: int):
    """``(lower, 1 / step, periodic)`` of joint value ``j``'s grid of ``n`` nodes, or None (no grid).

    A revolute joint whose value enters every link with coefficient +-1 and whose limits span a
    whole turn or more (or none: a continuous joint) is periodic: nodes ``-pi + 2 pi k / n``, values
    wrapped onto them.  Else the grid spans the limits (at most :data:`_SPAN_MAX` around their
    middle; a value beyond takes the edge node)."""
    terms = np.nonzero(tree.term_joint == j)[0]
    links = np.searchsorted(tree.term_start, terms, side="right") - 1
    turn = len(terms) > 0 and bool(np.all(tree.jtype[links] == 1)) and bool(np.all(np.abs(tree.term_coeff[terms]) == 1.0))
    q0, q1 = float(qlim[j, 0]), float(qlim[j, 1])
    if turn and not (q1 - q0 < 2.0 * math.pi):  # infinite limits included
        return -math.pi, n / (2.0 * math.pi), True
    if not (math.isfinite(q0) and math.isfinite(q1)) or q1 <= q0:
        return None
    mid, half = 0.5 * (q0 + q1), 0.5 * min(q1 - q0, _SPAN_MAX)
    return mid - half, (n - 1) / (2.0 * half), False


_cache: OrderedDict = OrderedDict()
_cache_lock = threading.Lock()
CACHE_BYTES = 64 << 20
"""Bytes of seed tables kept in this process (least recently used dropped first; a 16^3 table is
229 kB): a Detector rebuilt after a scene edit, or a second checker on the same model, finds its
tables here instead of making them again (``tests/test_engine_seeds.py``)."""


def _key(tree, la: int, lb: int, js: tuple, axes: list, part: tuple, tol: tuple) -> bytes:
    """What a table depends on: both hulls (points, graphs, support tables), the rows of the engine
    tree on both links' chains, the joints and the grid, the tolerances."""
    h = hashlib.blake2b(digest_size=20)
    for arr in part:
        h.update(np.ascontiguousarray(arr).tobytes())
        h.update(b"|")
    for link in sorted(_chain(tree.parent, la) | _chain(tree.parent, lb)):
        for arr in (tree.X_pre[link], tree.axis[link], tree.X_post[link], tree.term_coeff[tree.term_start[link]:tree.term_start[link + 1]],
                    tree.term_joint[tree.term_start[link]:tree.term_start[link + 1]]):
            h.update(np.ascontiguousarray(arr).tobytes())
        h.update(np.array([link, tree.parent[link], tree.jtype[link], tree.has_post[link], tree.offset[link]]).tobytes())
    h.update(np.array([la, lb, *js, *tol], dtype=np.float64).tobytes())
    for ax in axes:
        h.update(np.ascontiguousarray(ax, dtype=np.float64).tobytes())
    return h.digest()


def _table(tree, qlim, la: int, lb: int, js: tuple, axes: list, part: tuple, tol: tuple) -> np.ndarray:
    """The seed rows of one pair, a row per node of the grid ``axes`` (one array of node values per
    joint of ``js``), row-major (cached, :data:`CACHE_BYTES`)."""
    key = _key(tree, la, lb, js, axes, part, tol)
    with _cache_lock:
        hit = _cache.get(key)
        if hit is not None:
            _cache.move_to_end(key)
            return hit
    # the kernels' argument types as the fused kernel's narrow phase passes them (._calls.NATIVE:
    # writeable arrays): a read-only hull would make numba compile a second gjk_dir_rel and epa_depth
    # for it, 11 s and 7 s of a cold first run (their warmed overloads are the writeable ones)
    pa, adja, taba, pb, adjb, tabb = (x if x.flags.writeable else x.copy() for x in part)
    eps_len, gjk_eps, max_iter = tol
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(js))
    Q = np.zeros((len(grid), qlim.shape[0]))
    Q[:] = np.clip(0.0, np.nan_to_num(qlim[:, 0]), np.nan_to_num(qlim[:, 1]))  # X_AB depends on none of them
    Q[:, list(js)] = grid
    Xs = fk_kernel(tree, Q)
    X_A = Xs[:, la] if la >= 0 else np.broadcast_to(np.eye(4), (len(Q), 4, 4))
    X_B = Xs[:, lb] if lb >= 0 else np.broadcast_to(np.eye(4), (len(Q), 4, 4))
    R_AB = np.einsum("nji,njk->nik", X_A[:, :3, :3], X_B[:, :3, :3])
    t_AB = np.einsum("nji,nj->ni", X_A[:, :3, :3], X_B[:, :3, 3] - X_A[:, :3, 3])
    d0 = np.array(_inner_point(pa, adja)) - (R_AB @ np.array(_inner_point(pb, adjb)) + t_AB)  # as narrow_rel's
    work = np.zeros(max(EPA_WORK_SIZE, 16))
    no_seed = np.zeros(0, dtype=np.int64)
    table = np.zeros((len(Q), 7), dtype=np.int64)
    for k in range(len(Q)):
        rot = np.ascontiguousarray(R_AB[k].ravel())
        tx, ty, tz = t_AB[k]
        st = gjk_dir_rel(pa, adja, taba, pb, adjb, tabb, rot, tx, ty, tz, d0[k, 0], d0[k, 1], d0[k, 2], eps_len,
                         gjk_eps, max_iter, work[0:16], math.inf, no_seed)[0]
        if st == GJK_SEPARATED and work[9] > 0:  # apart: GJK's final simplex
            table[k] = work[9:16]
        elif work[0] == 1.0:  # overlapping: the facet EPA ends on
            if epa_depth(pa, adja, pb, adjb, work, gjk_eps, rot, tx, ty, tz, taba, tabb, -math.inf)[0] \
                    and work[0] == 2.0:
                table[k] = (3, work[1], work[5], work[2], work[6], work[3], work[7])
    table.flags.writeable = False
    with _cache_lock:
        _cache[key] = table
        while sum(t.nbytes for t in _cache.values()) > CACHE_BYTES and len(_cache) > 1:
            _cache.popitem(last=False)
    return table


def seed_row(spair: np.ndarray, sgrid: np.ndarray, sdt: np.ndarray, p: int, q: np.ndarray) -> np.ndarray:
    """Pair ``p``'s seed at joint values ``q`` (engine order), as ``._narrow._seed`` picks it (the
    nearest node, each joint clamped to its grid): a row of ``sdt``, or an empty array (no table)."""
    if spair[p, 0] < 0:
        return np.zeros(0, dtype=np.int64)
    n, c, kk = int(spair[p, 1]), 0, int(spair[p, 2])
    for k in range(kk & 3):
        x = (q[spair[p, 3 + k]] - sgrid[p, 2 * k]) * sgrid[p, 2 * k + 1]
        if (kk >> (2 + k)) & 1:  # periodic: the nearest node, wrapped onto the grid (n a power of two)
            c = c * n + (int(math.floor(x + 0.5)) & (n - 1))
        else:
            c = c * n + int(min(max(x + 0.5, 0.0), n - 1.0))
    return np.ascontiguousarray(sdt[spair[p, 0] + c])
