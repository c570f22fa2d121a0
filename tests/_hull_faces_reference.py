"""The plain-Python reference of ``armguard.geometry._hull_faces``: the seeded planar-face merge
as it was first written (a scalar flood over Python lists), kept to test the fast version against.
"""

from __future__ import annotations

import numpy as np

from armguard._errors import GeometryError
from armguard._tolerance import DEFAULT_TOLERANCES


def merge_hull_faces_reference(points: np.ndarray, tol: float):
    """Merge a scipy hull's triangles into planar polygon faces, CCW seen from outside.

    A face is a connected set of *adjacent* hull triangles lying in one plane (normals within
    ``1e-9`` and every vertex within ``tol`` (scaled) of the first triangle's plane); its vertex
    loop is walked along the boundary edges of its outward-oriented triangles, so every edge of
    the hull's triangulation on a face boundary is shared by exactly two faces (a closed,
    consistently oriented polyhedron even for nearly coplanar mesh hulls).

    Returns ``(vertex_index_map, faces, planes, triangles)``: faces and the hull's (oriented)
    triangles index into the returned vertex set.
    """
    from scipy.spatial import ConvexHull, QhullError

    # the hull is built about the points' own centre (a local frame): far from the origin the
    # coordinates' round-off would otherwise swamp a small solid, and flatness is judged against
    # the shape's own extent, not its distance from the origin
    o_W = 0.5 * (points.min(axis=0) + points.max(axis=0))
    points = points - o_W
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError) as exc:
        raise GeometryError(
            "ConvexPolyhedron.vertices: need at least four non-coplanar points "
            f"(the hull has no volume): {exc.__class__.__name__}"
        ) from exc
    scale = max(1.0, float(np.max(np.abs(points))))
    if hull.volume <= DEFAULT_TOLERANCES.coplanar_volume * scale**3:
        raise GeometryError("ConvexPolyhedron.vertices: the points are coplanar (hull volume 0)")
    eq = hull.equations  # n . x + c <= 0 inside; n unit outward
    tri = np.array(hull.simplices, dtype=np.int64)
    p0 = points[tri[:, 0]]
    flip = np.einsum("ij,ij->i", np.cross(points[tri[:, 1]] - p0, points[tri[:, 2]] - p0), eq[:, :3]) < 0.0
    tri[flip, 1], tri[flip, 2] = tri[flip, 2], tri[flip, 1].copy()  # counter-clockwise about the outward normal
    tris = [tuple(t) for t in tri.tolist()]
    n_tri = len(tris)
    nbrs = hull.neighbors.tolist()
    # a seed none of whose neighbours has its normal within 1e-9 is a face of its own (the first
    # test of the search below, done for every triangle at once)
    alone = np.all(np.einsum("ij,ikj->ik", eq[:, :3], eq[hull.neighbors, :3]) <= 1.0 - 1e-9, axis=1).tolist()
    group = [-1] * n_tri
    groups: list[list[int]] = []
    normals, offsets = eq[:, :3].tolist(), eq[:, 3].tolist()
    corners = points[tri].tolist()  # (T, 3, 3): plain floats, the search below is scalar Python
    lim, cos_min = tol * scale, 1.0 - 1e-9
    for seed in range(n_tri):
        if group[seed] >= 0:
            continue
        g = len(groups)
        group[seed] = g
        if alone[seed]:
            groups.append([seed])
            continue
        x0, y0, z0 = normals[seed]
        c0 = offsets[seed]
        members, stack = [seed], [seed]
        while stack:
            t = stack.pop()
            for nb in nbrs[t]:
                if nb < 0 or group[nb] >= 0:
                    continue
                # the same face: the normal within 1e-9 of the seed's and every vertex on its plane
                a, b, c = normals[nb]
                if a * x0 + b * y0 + c * z0 > cos_min and all(
                        abs(px * x0 + py * y0 + pz * z0 + c0) <= lim for px, py, pz in corners[nb]):
                    group[nb] = g
                    members.append(nb)
                    stack.append(nb)
        groups.append(members)
    used = np.unique(np.asarray(hull.vertices, dtype=np.int64))
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    first = np.array([members[0] for members in groups], dtype=np.int64)
    planes = np.empty((len(groups), 4))
    planes[:, :3] = eq[first, :3]
    planes[:, 3] = -eq[first, 3] + eq[first, :3] @ o_W  # the local plane offsets, back in W
    # a face of one triangle: its loop from its smallest vertex (all at once)
    single = remap[tri[first]]
    single = np.take_along_axis(single, (np.argmin(single, axis=1)[:, None] + np.arange(3)) % 3, axis=1)
    faces: list[np.ndarray] = []
    for g, members in enumerate(groups):
        if len(members) == 1:
            faces.append(single[g])
            continue
        directed = {(a, b) for t in members for a, b in ((tris[t][0], tris[t][1]), (tris[t][1], tris[t][2]), (tris[t][2], tris[t][0]))}
        nxt = {a: b for a, b in directed if (b, a) not in directed}  # boundary edges, CCW
        start = min(nxt)
        loop, v = [start], nxt[start]
        while v != start and len(loop) <= len(nxt):
            loop.append(v)
            v = nxt[v]
        if v != start or len(loop) != len(nxt):  # pragma: no cover - a planar convex face has one boundary loop
            raise GeometryError("ConvexPolyhedron: could not build a face boundary from the hull (degenerate hull)")
        faces.append(remap[loop])
    return used, faces, planes, remap[tri]
