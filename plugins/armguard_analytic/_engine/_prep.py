"""Detector set-up helpers: the static polytopes' H/V descriptions and the kinematic blocks."""

from __future__ import annotations

import numpy as np


def _static_polytopes(cs, static_shapes) -> dict:
    """H/V descriptions (W) of the static polytope elements, concatenated for the kernel.

    For each static element with a polytope core, :func:`armguard.geometry._pack.polytope_data`
    of its shape (vertices, face planes, edges with their faces, edge bisectors, centroid);
    ``poly_of (G,)`` maps an element to its polytope number (-1: none), ``pvs``, ``pps``, ``pes``
    are CSR offsets into the vertex, plane and edge rows.  Built once per ``prepare``."""
    from armguard.geometry._pack import polytope_data

    G = cs.n_elements
    poly_of = np.full(G, -1, np.int64)
    pv, ppl, ped, pbis, pcen = [], [], [], [], []
    pvs, pps, pes = [0], [0], [0]
    for g, shape in static_shapes.items():
        if g >= G or int(cs.elem_core[g]) != 3:
            continue
        try:
            v, pl, ed, bi, cen = polytope_data(shape)
        except Exception:  # noqa: BLE001 - no H/V description: the generic convex kernel serves it
            continue
        poly_of[g] = len(pcen)
        pv.append(v); ppl.append(pl); ped.append(ed); pbis.append(bi); pcen.append(cen)
        pvs.append(pvs[-1] + len(v)); pps.append(pps[-1] + len(pl)); pes.append(pes[-1] + len(ed))
    cat = lambda parts, w, dt: np.concatenate(parts).astype(dt) if parts else np.zeros((0, w), dt)  # noqa: E731
    return {"poly_of": poly_of, "pv": cat(pv, 3, np.float64), "ppl": cat(ppl, 4, np.float64),
            "ped": cat(ped, 4, np.int64), "pbis": cat(pbis, 3, np.float64),
            "pcen": np.array(pcen, dtype=np.float64).reshape(-1, 3), "pvs": np.array(pvs, np.int64),
            "pps": np.array(pps, np.int64), "pes": np.array(pes, np.int64)}


def _fk_blocks(parent: np.ndarray, link_robot: np.ndarray, n_joints: list[int]):
    """FK blocks: ``rob_l (R + 1,)`` link offsets and ``rob_j (R + 1,)`` joint offsets of each robot,
    and ``parent_loc (n_links,)`` each link's parent numbered within its block (-1: a root).

    The kernel recomputes a block's link poses only when that robot's joint values changed since
    the last check (an idle arm's links keep their poses).  When the robots' links are not
    contiguous blocks with parents inside them, one block holds every link and joint."""
    n = len(parent)
    R = len(n_joints)
    rob_l = np.searchsorted(link_robot, np.arange(R + 1)).astype(np.int64) if n else np.zeros(R + 1, np.int64)
    rob_j = np.concatenate([[0], np.cumsum(n_joints)]).astype(np.int64)
    ok = n == len(link_robot) and bool(np.all(np.diff(link_robot) >= 0)) and rob_l[-1] == n
    parent_loc = np.array(parent, dtype=np.int64)
    if ok:
        for r in range(R):
            for i in range(rob_l[r], rob_l[r + 1]):
                p = parent[i]
                if p >= 0:
                    if not rob_l[r] <= p < i:
                        ok = False
                    parent_loc[i] = p - rob_l[r]
    if not ok:
        return (np.array([0, n], np.int64), np.array([0, int(sum(n_joints))], np.int64),
                np.array(parent, dtype=np.int64))
    return rob_l, rob_j, parent_loc


def warm_start_option(value) -> bool:
    """The analytic backend's option ``warm_start`` (:mod:`armguard_analytic`), checked: True or False."""
    from armguard._errors import BackendError

    if value not in (True, False):
        raise BackendError(f"analytic: warm_start {value!r} is not one of [True, False]")
    return bool(value)


def _warm_option(backend, backend_options) -> bool:
    """:func:`warm_start_option` of the Detector's backend options, as resolved (argument > environment >
    ``armguard.toml``)."""
    from armguard.backends import resolve

    return warm_start_option(resolve(backend, backend_options)[1].get("warm_start", False))
