"""Per-element data for mesh hulls in the detector: vertex graphs and surface triangles.

The convex kernel (:func:`armguard.geometry._pair_epa.convex_convex_fast`) climbs a hull's
vertex graph for GJK's and EPA's support points and, in its rare exhaustive-SAT fallback, takes
the hull's axes from its triangles and graph instead of stored face normals and edge directions.
"""

from __future__ import annotations

import numpy as np

from ..geometry._pack import hull_graph
from ..geometry._pair_gjk import CLIMB_MIN_VERTICES

__all__ = ["vertex_graphs"]


def vertex_graphs(cs, fn_L: np.ndarray, ed_L: np.ndarray) -> dict:
    """Vertex graphs and surface triangles of the polytope elements with at least
    ``CLIMB_MIN_VERTICES`` core points (:func:`armguard.geometry._pack.hull_graph` of the element's
    points; indices local to the element, so they serve the moved points as well), each
    concatenated with CSR offsets ``(G + 1,)`` (an empty range: none, GJK and EPA scan the points).

    Those elements' face normals and edge directions are dropped from ``fn_L``, ``ed_L`` and their
    offsets (``pstart``, ``estart``): the convex kernel's SAT fallback takes their axes from the
    triangles and the graph, and the kernel then no longer moves thousands of normals per check."""
    adj, tri, adjs, tris, fkeep, ekeep = [], [], [0], [0], [], []
    pstart, estart = [0], [0]
    for g in range(cs.n_elements):
        vs, ve = int(cs.elem_vert_start[g]), int(cs.elem_vert_start[g + 1])
        a, t = np.zeros(0, np.int64), np.zeros((0, 3), np.int64)
        if int(cs.elem_core[g]) == 3 and ve - vs >= CLIMB_MIN_VERTICES:
            try:
                a, t = hull_graph(cs.verts[vs:ve])
            except Exception:  # noqa: BLE001 - a flat point set has no hull graph: scan it
                a, t = np.zeros(0, np.int64), np.zeros((0, 3), np.int64)
        adj.append(a); tri.append(t); adjs.append(adjs[-1] + len(a)); tris.append(tris[-1] + len(t))
        f = np.arange(cs.elem_plane_start[g], cs.elem_plane_start[g + 1])
        e = np.arange(cs.elem_edge_start[g], cs.elem_edge_start[g + 1])
        if len(a):
            f, e = f[:0], e[:0]
        fkeep.append(f); ekeep.append(e)
        pstart.append(pstart[-1] + len(f)); estart.append(estart[-1] + len(e))
    cat = lambda parts, dt: np.concatenate(parts).astype(dt) if parts else np.zeros(0, dt)  # noqa: E731
    fk, ek = cat(fkeep, np.int64), cat(ekeep, np.int64)
    return {"gadj": cat(adj, np.int64), "gadjs": np.array(adjs, np.int64),
            "gtri": cat(tri, np.int64).reshape(-1, 3), "gtris": np.array(tris, np.int64),
            "fn_L": np.ascontiguousarray(fn_L.reshape(-1, 3)[fk]), "ed_L": np.ascontiguousarray(ed_L.reshape(-1, 3)[ek]),
            "pstart": np.array(pstart, np.int64), "estart": np.array(estart, np.int64)}
