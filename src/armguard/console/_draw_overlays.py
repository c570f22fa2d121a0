"""The 3-D view's overlays: the terrain, the pyramid boxes a check tested, the confidence ellipsoids.

Plain NumPy mesh builders (:func:`terrain_meshes`, :func:`box_edges`, :func:`ellipsoid_mesh`,
testable without a browser) and :class:`OverlayDrawer`, which puts them on a viser scene.

* **Terrain**: the map as the checker sees it — each cell a column from the floor to its height
  (top faces, and the walls between neighbouring cells of different heights); seen cells in
  :data:`TERRAIN_COLOR`, unseen (filled) cells in :data:`UNKNOWN_COLOR`.
  While the nearest line runs under the terrain's surface (:func:`line_buried`: inside a column,
  as in a link's contact with the ground, or through a rock between its ends), the terrain is
  drawn translucent (:data:`TERRAIN_SEE_THROUGH_OPACITY`) so the line and its markers stay in
  sight; viser draws line segments with the depth test on.
  The same when a browser tab's camera sees the line through the terrain
  (:func:`~._sight.sight_buried`).
* **Tested boxes** (only on request: :meth:`OverlayDrawer.set_boxes_visible`, the Views tab's
  checkbox; up to :data:`~._overlays.MAX_TERRAIN_BOXES` edge sets cost a software-WebGL frame
  seconds): the pyramid boxes the last check visited, as edges, one colour per level
  (:data:`LEVEL_COLORS`, coarse to fine); boxes a link volume hit are drawn thicker.
* **Ellipsoids**: each uncertain placement's origin position ellipsoid at 90 % and 99.9 %,
  translucent (:data:`ELLIPSOID_COLORS`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["OverlayDrawer", "terrain_meshes", "box_edges", "ellipsoid_mesh", "TERRAIN_COLOR", "UNKNOWN_COLOR",
           "LEVEL_COLORS", "ELLIPSOID_COLORS", "TERRAIN_SEE_THROUGH_OPACITY", "line_buried"]

TERRAIN_COLOR = (150, 120, 80)
UNKNOWN_COLOR = (55, 70, 105)
"""Unseen (filled) cells: a dark slate, far (CIELAB ΔE > 90) from the magenta feature outline and
darker than the grey vehicle body."""
TERRAIN_SEE_THROUGH_OPACITY = 0.3
"""Opacity of the terrain while the nearest line runs under its surface (opaque otherwise)."""
LINE_SAMPLES = 33
""":func:`line_buried` tests the line at this many evenly spaced points (ends trimmed)."""
LEVEL_COLORS = ((40, 40, 40), (0, 90, 200), (0, 160, 160), (0, 170, 60), (150, 170, 0), (230, 150, 0),
                (230, 70, 0), (200, 0, 90), (120, 0, 160), (90, 90, 90), (255, 255, 255))
"""Edge colour of the tested boxes per pyramid level (0: the top box); deeper levels reuse the last."""
ELLIPSOID_COLORS = {0.9: ((60, 200, 60), 0.45), 0.999: ((60, 140, 230), 0.2)}
"""(colour, opacity) per confidence; other confidences use the last."""
_BOX_EDGES = ((0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7))


def line_buried(elevation, line, *, trim: float = 0.05, samples: int = LINE_SAMPLES) -> bool:
    """Whether the segment ``line (2, 3)`` m runs under the surface of ``elevation`` (an
    :class:`armguard.terrain.ElevationMap`): some of ``samples`` points along it, past
    ``trim`` of its length at each end (where it meets its own pair), lies inside a cell's column
    (above the floor, below the cell's height).  Off the map: not buried."""
    L = np.asarray(line, dtype=np.float64).reshape(2, 3)
    if not np.all(np.isfinite(L)):
        return False
    t = np.linspace(trim, 1.0 - trim, int(samples))[:, None]
    P = L[0] + t * (L[1] - L[0])
    c = float(elevation.cell)
    col = np.floor((P[:, 0] - float(elevation.origin[0])) / c).astype(np.int64)
    row = np.floor((P[:, 1] - float(elevation.origin[1])) / c).astype(np.int64)
    ny, nx = np.asarray(elevation.heights).shape
    on = (row >= 0) & (row < ny) & (col >= 0) & (col < nx)
    if not np.any(on):
        return False
    h = np.asarray(elevation.heights, dtype=np.float64)[row[on], col[on]]
    z = P[on, 2]
    return bool(np.any((z < h) & (z > float(elevation.floor))))


def terrain_meshes(elevation) -> dict[bool, tuple[np.ndarray, np.ndarray]]:
    """``{True: (V, F) of the seen cells, False: (V, F) of the unseen ones}`` (m in W; F int32).

    Each cell's top quad at its height, and between two neighbouring cells the wall from the
    lower top to the higher one, owned by the higher cell (so an unseen rock stands out whole).
    """
    h = np.asarray(elevation.heights, dtype=np.float64)
    known = np.asarray(elevation.known, dtype=bool)
    ny, nx = h.shape
    c = float(elevation.cell)
    x0, y0 = (float(v) for v in elevation.origin)
    quads: dict[bool, list] = {True: [], False: []}
    iy, ix = np.mgrid[0:ny, 0:nx]
    xa, xb = x0 + ix * c, x0 + (ix + 1) * c
    ya, yb = y0 + iy * c, y0 + (iy + 1) * c
    top = np.stack([np.stack([xa, ya, h], -1), np.stack([xb, ya, h], -1),
                    np.stack([xb, yb, h], -1), np.stack([xa, yb, h], -1)], axis=-2)  # (ny, nx, 4, 3)
    for k in (True, False):
        quads[k].append(top[known == k])
    # walls along x (between columns ix and ix + 1) and along y (rows iy and iy + 1)
    for axis in (1, 0):
        a = h[:, :-1] if axis == 1 else h[:-1, :]
        b = h[:, 1:] if axis == 1 else h[1:, :]
        ka = known[:, :-1] if axis == 1 else known[:-1, :]
        kb = known[:, 1:] if axis == 1 else known[1:, :]
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        owner_known = np.where(a >= b, ka, kb)
        if axis == 1:
            jy, jx = np.mgrid[0:ny, 0:nx - 1]
            x = x0 + (jx + 1) * c
            p0, p1 = np.stack([x, y0 + jy * c], -1), np.stack([x, y0 + (jy + 1) * c], -1)
        else:
            jy, jx = np.mgrid[0:ny - 1, 0:nx]
            y = y0 + (jy + 1) * c
            p0, p1 = np.stack([x0 + jx * c, y], -1), np.stack([x0 + (jx + 1) * c, y], -1)
        wall = np.stack([np.concatenate([p0, lo[..., None]], -1), np.concatenate([p1, lo[..., None]], -1),
                         np.concatenate([p1, hi[..., None]], -1), np.concatenate([p0, hi[..., None]], -1)], axis=-2)
        tall = hi - lo > 1e-9
        for k in (True, False):
            quads[k].append(wall[tall & (owner_known == k)])
    out = {}
    for k in (True, False):
        q = np.concatenate(quads[k]).reshape(-1, 4, 3) if quads[k] else np.zeros((0, 4, 3))
        n = len(q)
        base = 4 * np.arange(n, dtype=np.int32)[:, None]
        faces = np.concatenate([base + np.array([0, 1, 2], np.int32), base + np.array([0, 2, 3], np.int32)])
        out[k] = (q.reshape(-1, 3), faces.reshape(-1, 3))
    return out


def box_edges(boxes) -> np.ndarray:
    """``(12 n, 2, 3)`` edges of axis-aligned boxes given as rows ``[c (3), h (3)]`` (m)."""
    B = np.asarray(boxes, dtype=np.float64).reshape(-1, 6)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
    corners = B[:, None, :3] + signs[None] * B[:, None, 3:]  # (n, 8, 3)
    e = np.array(_BOX_EDGES)
    return np.stack([corners[:, e[:, 0]], corners[:, e[:, 1]]], axis=2).reshape(-1, 2, 3)


def ellipsoid_mesh(center, axes, subdivisions: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """``(V, F)``: the unit icosphere mapped by ``x -> center + axes @ x`` (axes columns: semi-axes, m)."""
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    A = np.asarray(axes, dtype=np.float64)
    A = A + np.eye(3) * 1e-6 * max(1e-3, float(np.abs(A).max()))  # a flat ellipsoid stays drawable
    return np.asarray(m.vertices) @ A.T + np.asarray(center, dtype=np.float64), np.asarray(m.faces)


class OverlayDrawer:
    """Draw the terrain, the tested boxes and the ellipsoids of a console state on a viser scene."""

    def __init__(self, server) -> None:
        self.server = server
        self._handles: list = []
        self._levels: dict = {}
        self._boxes_key = None
        self._ellipsoid_key = None
        self._ellipsoids: list = []
        self.terrain_handles: dict = {}
        self.show_boxes = False
        self._last_tv = None

    def clear(self) -> None:
        for h in self._handles + self._ellipsoids + [h for pair in self._levels.values() for h in pair]:
            try:
                h.remove()
            except Exception:
                pass
        self._handles, self._ellipsoids, self._levels = [], [], {}
        self._boxes_key = self._ellipsoid_key = None
        self.terrain_handles = {}

    def build(self, state) -> None:
        self.clear()
        m = getattr(state, "terrain", None)
        if m is None:
            return
        sc = self.server.scene
        for k, (V, F) in terrain_meshes(m).items():
            if len(F):
                h = sc.add_mesh_simple(f"/terrain/{'seen' if k else 'unseen'}", V.astype(np.float32), F,
                                       color=TERRAIN_COLOR if k else UNKNOWN_COLOR, flat_shading=True,
                                       side="double", cast_shadow=False, receive_shadow=False)
                self._handles.append(h)
                self.terrain_handles[k] = h

    def draw(self, snap, state, eyes=()) -> None:
        self._see_through_terrain(snap, state, eyes)
        self._last_tv = snap.terrain
        self._draw_boxes(snap.terrain if self.show_boxes else None)
        self._draw_ellipsoids(state)

    def set_boxes_visible(self, on: bool) -> None:
        """Show (or hide) the pyramid boxes the last check tested."""
        self.show_boxes = bool(on)
        self._draw_boxes(self._last_tv if self.show_boxes else None)

    def _see_through_terrain(self, snap, state, eyes=()) -> None:
        """The terrain translucent while the nearest line runs under its surface, or a tab's
        camera at one of ``eyes`` sees it through the terrain; opaque otherwise."""
        from ._sight import sight_buried

        m = getattr(state, "terrain", None)
        r = snap.readout
        line = None if m is None or r.p_WA is None or r.p_WB is None else [r.p_WA, r.p_WB]
        buried = line is not None and (line_buried(m, line) or any(sight_buried(m, e, line) for e in eyes))
        want = TERRAIN_SEE_THROUGH_OPACITY if buried else None
        for h in self.terrain_handles.values():
            if h.opacity != want:
                h.opacity = want

    def _draw_boxes(self, tv) -> None:
        sc = self.server.scene
        key = None if tv is None else (tv.boxes.tobytes(), tv.hit.tobytes())
        if key == self._boxes_key:
            return
        self._boxes_key = key
        empty = np.zeros((1, 2, 3), np.float32)
        n_levels = 0 if tv is None else int(tv.n_levels)
        for lvl in range(max(n_levels, len(self._levels))):
            if lvl not in self._levels:
                col = LEVEL_COLORS[min(lvl, len(LEVEL_COLORS) - 1)]
                self._levels[lvl] = tuple(
                    sc.add_line_segments(f"/terrain/tested/level{lvl:02d}/{kind}", empty, col,
                                         thickness=w, thickness_units="screen", visible=False)
                    for kind, w in (("missed", 1.5), ("hit", 3.0)))
            for h, want_hit in zip(self._levels[lvl], (False, True)):
                sel = np.zeros(0, bool) if tv is None else (tv.levels == lvl) & (tv.hit == want_hit)
                if not np.any(sel):
                    if h.visible:
                        h.visible = False
                    continue
                h.points = box_edges(tv.boxes[sel]).astype(np.float32)
                h.visible = True

    def _draw_ellipsoids(self, state) -> None:
        if not getattr(state, "placements", ()):
            ells = ()
        else:
            ells = state.ellipsoids()
        key = tuple((e.name, e.confidence, e.center.round(6).tobytes(), e.axes.round(6).tobytes()) for e in ells)
        if key == self._ellipsoid_key:
            return
        self._ellipsoid_key = key
        for h in self._ellipsoids:
            h.remove()
        self._ellipsoids = []
        sc = self.server.scene
        for i, e in enumerate(ells):
            col, alpha = ELLIPSOID_COLORS.get(e.confidence, list(ELLIPSOID_COLORS.values())[-1])
            V, F = ellipsoid_mesh(e.center, e.axes)
            self._ellipsoids.append(sc.add_mesh_simple(
                f"/uncertain/{i:02d}_{e.name.replace(' @ ', '_at_')}_{e.confidence:g}", V.astype(np.float32), F, color=col, opacity=alpha,
                cast_shadow=False, receive_shadow=False))
