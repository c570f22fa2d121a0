"""Per-element data for mesh hulls in the detector: vertex graphs and surface triangles.

The convex kernel (:func:`armguard.geometry._pair_epa.convex_convex_fast`) climbs a hull's
vertex graph for GJK's and EPA's support points and, in its rare exhaustive-SAT fallback, takes
the hull's axes from its triangles and graph instead of stored face normals and edge directions.
"""

from __future__ import annotations

import numpy as np

from armguard.geometry._pack import hull_graph, support_table, unique_directions
from armguard.geometry._pair_gjk import CLIMB_MIN_VERTICES

__all__ = ["vertex_graphs", "link_obbs"]

_CYLINDER = 4  # armguard.geometry.CoreKind.CYLINDER


def vertex_graphs(cs, fn_L: np.ndarray, ed_L: np.ndarray, parallel: float) -> dict:
    """Vertex graphs, surface triangles and support tables (``gdir``, ``gdirs``:
    :func:`armguard.geometry._pack.support_table`) of the polytope elements with at least
    ``CLIMB_MIN_VERTICES`` core points (:func:`armguard.geometry._pack.hull_graph` of the element's
    points; indices local to the element, so they serve the moved points as well), each
    concatenated with CSR offsets ``(G + 1,)`` (an empty range: none, GJK and EPA scan the points).

    Those elements' face normals and edge directions are dropped from ``fn_L``, ``ed_L`` and their
    offsets (``pstart``, ``estart``): the convex kernel's SAT fallback takes their axes from the
    triangles and the graph, and the kernel then no longer moves thousands of normals per check.
    The other elements keep one face normal and one edge direction per parallel class
    (:func:`armguard.geometry._pack.unique_directions` with ``parallel``, as a shape's own SAT data):
    the SAT tests both signs of an axis, so a box's 6 normals and 12 edges are 3 axes and 3 edge
    classes, an octagonal prism's 10 and 24 are 5 and 5 (the SAT's edge-pair axes 288 -> 15)."""
    adj, tri, adjs, tris, fkeep, ekeep, tab, tabs = [], [], [0], [0], [], [], [], [0]
    fn = np.asarray(fn_L, dtype=np.float64).reshape(-1, 3)
    ed = np.asarray(ed_L, dtype=np.float64).reshape(-1, 3)
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
        tab.append(support_table(cs.verts[vs:ve]) if len(a) else np.zeros(0, np.int64)); tabs.append(tabs[-1] + len(tab[-1]))
        f = unique_directions(fn[cs.elem_plane_start[g]:cs.elem_plane_start[g + 1]], parallel)
        e = unique_directions(ed[cs.elem_edge_start[g]:cs.elem_edge_start[g + 1]], parallel)
        if len(a):
            f, e = f[:0], e[:0]
        fkeep.append(f); ekeep.append(e)
        pstart.append(pstart[-1] + len(f)); estart.append(estart[-1] + len(e))
    cat = lambda parts, dt: np.concatenate(parts).astype(dt) if parts else np.zeros(0, dt)  # noqa: E731
    return {"gadj": cat(adj, np.int64), "gadjs": np.array(adjs, np.int64),
            "gtri": cat(tri, np.int64).reshape(-1, 3), "gtris": np.array(tris, np.int64),
            "gdir": cat(tab, np.int64), "gdirs": np.array(tabs, np.int64),
            "fn_L": np.ascontiguousarray(cat(fkeep, np.float64).reshape(-1, 3)),
            "ed_L": np.ascontiguousarray(cat(ekeep, np.float64).reshape(-1, 3)),
            "pstart": np.array(pstart, np.int64), "estart": np.array(estart, np.int64)}


def link_obbs(cs, elem_glink: np.ndarray, tol_length: float) -> np.ndarray:
    """Oriented bounding boxes of the moving polytope elements in their link frames, for the yes/no
    cull: ``(G, 16)`` rows ``[c_L (3), h (3), R_LB (9, row-major, columns the box axes), ok]``,
    ``ok`` 1.0 where the row holds a box (a moving element with a polytope or cylinder core), else 0.
    A cylinder's box is its own (centre, axes, ``(r, r, h)``), grown as below.

    The axes are the principal axes of the element's core points (PCA, a fine fit for the long
    link hulls); the box spans the points' extent along them, grown by the core radius and by
    ``tol_length`` plus a rounding margin, so it contains the element.  In yes/no mode the kernel
    skips a pair whose boxes (grown by the collision level) do not overlap (JPL's division-free
    OBB test): cheaper than GJK on a few hundred vertices, and exact (the boxes contain the
    elements)."""
    G = cs.n_elements
    out = np.zeros((G, 16))
    for g in range(G):
        vs, ve = int(cs.elem_vert_start[g]), int(cs.elem_vert_start[g + 1])
        if int(cs.elem_core[g]) == _CYLINDER and elem_glink[g] >= 0:
            # a cylinder's own box: centre, axes R_LC, half extents (r, r, h), grown as below
            c, R, h = cs.elem_box_center[g], cs.elem_box_axes[g], cs.elem_box_half[g]
            size = float(np.max(np.abs(c))) + float(np.max(h)) + 1.0
            out[g, 0:3], out[g, 3:6] = c, h + tol_length + 1e-12 * size
            out[g, 6:15], out[g, 15] = np.asarray(R).reshape(-1), 1.0
            continue
        if int(cs.elem_core[g]) != 3 or elem_glink[g] < 0 or ve - vs < 4:
            continue
        p = np.asarray(cs.verts[vs:ve], dtype=np.float64)
        mean = p.mean(axis=0)
        _, R = np.linalg.eigh(np.cov((p - mean).T))
        if np.linalg.det(R) < 0.0:
            R[:, 0] = -R[:, 0]
        loc = (p - mean) @ R  # coordinates along the axes
        lo, hi = loc.min(axis=0), loc.max(axis=0)
        c = mean + R @ (0.5 * (lo + hi))
        size = float(np.max(np.abs(p))) + 1.0
        h = 0.5 * (hi - lo) + float(cs.elem_radius[g]) + tol_length + 1e-12 * size
        out[g, 0:3], out[g, 3:6], out[g, 6:15], out[g, 15] = c, h, R.reshape(-1), 1.0
    return out
