"""What the 3-D view draws beyond the meshes: the obstacle's nearest feature, the camera framing.

Plain NumPy, no viser: :func:`feature_segments` gives the edges of a face / an edge of a shape to
highlight (a vertex or a curved surface gives none: the nearest-point marker shows it);
:func:`follow_view` the camera that frames the active arm and what it is nearest to, looking
from the arm's side of the scene -- or, when obstacles hide the arm from there, from the first
direction around it that sees the most of it; :func:`pair_view` the camera on the nearest line,
from a direction that sees the line past every shape; :func:`see_through` the shapes the line
runs through, which no camera can see past (the view draws them translucent).
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import Box, ConvexPolyhedron, FeatureKind, Polygon, Prism

__all__ = ["feature_segments", "follow_view", "pair_view", "see_through", "visible_count", "marker_radius", "PAIR_CONTEXT", "PAIR_SHIFT", "FOLLOW_ELEVATION_DEG", "FOLLOW_MARGIN",
           "PANEL_SHARE", "DEFAULT_ASPECT", "visible_offset", "MARKER_LINE_FRACTION", "MARKER_SCENE_RANGE"]

FOLLOW_ELEVATION_DEG = 30.0
"""Camera elevation above the horizontal of the follow view."""
FOLLOW_MARGIN = 2.0
"""The follow view's camera distance, in multiples of the distance that just fits the framed points."""
PANEL_SHARE = 0.25
"""Share of the view's width the control panel covers at the default layout (viser's "large"
panel, 24 em = 384 px and its margin, over a window 1600 px wide): the follow view frames its
points in the rest, left of the panel.  viser tells the server the canvas's aspect and field of
view, not where the panel is, so the share is fixed."""
DEFAULT_ASPECT = 1.6
"""Width / height of the view when the browser has not said (a 1600 x 1000 window)."""


def visible_offset(fov_rad: float, aspect: float, panel_share: float = PANEL_SHARE) -> tuple[float, float]:
    """``(shift, half)`` for a camera of vertical field of view ``fov_rad`` on a canvas ``aspect``
    wide per unit height whose right ``panel_share`` the control panel covers: a look-at point
    ``shift`` times the camera distance to the right of a point puts that point in the middle of
    the visible part (left of the panel), and ``half`` (rad) is the half-angle a framed sphere must
    fit in there, horizontally and vertically."""
    share = min(max(float(panel_share), 0.0), 0.9)
    t = float(aspect) * math.tan(0.5 * fov_rad)  # tan of the half horizontal field of view
    return share * t, min(0.5 * fov_rad, math.atan((1.0 - share) * t))


SEE_THROUGH_TRIM = 0.05
""":func:`see_through` ignores this fraction of the line at each end (where it meets its own pair)."""
_AZIMUTHS = (0.0, 180.0, 35.0, -35.0, 145.0, -145.0, 70.0, -70.0, 110.0, -110.0)
_ELEVATIONS = (30.0, 50.0, 15.0, 70.0)


def see_through(line, shapes) -> list[int]:
    """Indices of ``shapes`` that the nearest ``line`` (2, 3) m runs through (past its end trims).

    A shape the line passes inside hides it from every direction: no camera placement shows it,
    so the view draws such shapes translucent.
    """
    from ..geometry import Capsule, distance

    L = np.asarray(line, dtype=np.float64).reshape(2, 3)
    d = L[1] - L[0]
    if float(np.linalg.norm(d)) < 1e-9:
        return []
    seg = Capsule(L[0] + SEE_THROUGH_TRIM * d, L[1] - SEE_THROUGH_TRIM * d, 1e-9)
    return [k for k, sh in enumerate(shapes) if distance(seg, sh).distance < 0.0]


def visible_count(eye, targets, shapes, radius) -> int:
    """How many ``targets`` (n, 3) m the camera at ``eye`` sees past ``shapes``: the sight line to
    each (a capsule of ``radius`` m -- one for all, or (n,) -- ending ``2 radius`` short of it)
    clear of every shape."""
    from ..geometry import Capsule, distance

    eye = np.asarray(eye, dtype=np.float64)
    T = np.asarray(targets, dtype=np.float64).reshape(-1, 3)
    radii = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(T),))
    n = 0
    for p, radius in zip(T, radii):
        v = p - eye
        L = float(np.linalg.norm(v))
        if L <= 3.0 * radius:
            n += 1
            continue
        sight = Capsule(eye, p - 2.0 * radius * v / L, radius)
        if all(distance(sight, sh).distance > 0.0 for sh in shapes):
            n += 1
    return n


def _turned(h, az_deg: float) -> np.ndarray:
    c, s_ = math.cos(math.radians(az_deg)), math.sin(math.radians(az_deg))
    return np.array([c * h[0] - s_ * h[1], s_ * h[0] + c * h[1], 0.0])


MARKER_LINE_FRACTION = 0.12
"""Nearest-point marker radius, in line lengths ..."""
MARKER_SCENE_RANGE = (0.003, 0.02)
"""... kept within these fractions of the scene radius (a contact still shows its markers)."""


def marker_radius(line_length: float, scene_radius: float) -> float:
    """Radius (m) of the nearest-point markers for a line of ``line_length`` m in a scene of ``scene_radius`` m."""
    lo, hi = MARKER_SCENE_RANGE
    return float(np.clip(MARKER_LINE_FRACTION * abs(line_length), lo * scene_radius, hi * scene_radius))


def _loop(ix) -> list[tuple[int, int]]:
    ix = [int(i) for i in ix]
    return [(ix[k], ix[(k + 1) % len(ix)]) for k in range(len(ix))]


def _box_face(box: Box, k: int) -> list[tuple[int, int]]:
    from ..geometry._feature import BOX_EDGES

    V = np.asarray(box.vertices)
    c, R = np.asarray(box.center), np.asarray(box.rotation)
    s = (V - c) @ R  # local coordinates: each vertex's sign on each axis
    axis, sign = k // 2, (1.0 if k % 2 else -1.0)
    on = {i for i in range(8) if s[i, axis] * sign > 0.0}
    return [(int(a), int(b)) for a, b in BOX_EDGES if a in on and b in on]


def feature_segments(shape, feature) -> np.ndarray:
    """``(k, 2, 3) float64`` m in W: the edges of ``feature`` of ``shape`` (a face's outline, an edge).

    Indices follow :mod:`armguard.geometry._feature`.  Vertices and curved surfaces give ``(0, 2, 3)``.
    """
    empty = np.zeros((0, 2, 3))
    if feature is None or feature.kind in (FeatureKind.VERTEX, FeatureKind.SURFACE):
        return empty
    k = int(feature.index)
    pairs: list[tuple[int, int]] = []
    if isinstance(shape, Box):
        from ..geometry._feature import BOX_EDGES

        V = np.asarray(shape.vertices)
        if feature.kind is FeatureKind.EDGE and 0 <= k < len(BOX_EDGES):
            pairs = [tuple(BOX_EDGES[k])]
        elif feature.kind is FeatureKind.FACE and 0 <= k < 6:
            pairs = _box_face(shape, k)
    elif isinstance(shape, Prism):
        V = np.asarray(shape.core_points)
        n = len(V) // 2
        if feature.kind is FeatureKind.FACE:
            if k < n:
                pairs = _loop([k, (k + 1) % n, n + (k + 1) % n, n + k])
            elif k == n:
                pairs = _loop(range(n))
            elif k == n + 1:
                pairs = _loop(range(n, 2 * n))
        elif feature.kind is FeatureKind.EDGE:
            if k < n:
                pairs = [(k, (k + 1) % n)]
            elif k < 2 * n:
                pairs = [(k, n + (k - n + 1) % n)]
            elif k < 3 * n:
                pairs = [(k - 2 * n, k - n)]
    elif isinstance(shape, ConvexPolyhedron):
        V = np.asarray(shape.vertices)
        if feature.kind is FeatureKind.FACE and 0 <= k < len(shape.faces):
            pairs = _loop(shape.faces[k])
        elif feature.kind is FeatureKind.EDGE and 0 <= k < len(shape.edges):
            pairs = [tuple(shape.edges[k])]
    elif isinstance(shape, Polygon):
        V = np.asarray(shape.vertices)
        n = len(V)
        if feature.kind is FeatureKind.FACE:
            pairs = _loop(range(n))
        elif feature.kind is FeatureKind.EDGE and 0 <= k < n:
            pairs = [(k, (k + 1) % n)]
    else:
        return empty
    if not pairs:
        return empty
    return np.array([[V[a], V[b]] for a, b in pairs], dtype=np.float64)


def follow_view(points, scene_center, *, line=None, fov_rad: float = math.radians(75.0),
                aspect: float = DEFAULT_ASPECT, panel_share: float = PANEL_SHARE, min_radius: float = 0.25,
                targets=None, obstacles=(), weights=None, target_radii=None, axis=None) -> tuple[np.ndarray, np.ndarray]:
    """Camera ``(position, look_at)`` (3,) m framing ``points`` (n, 3) m.

    Looks at the centre ``c`` of their bounding box horizontally from the arm's side of the scene
    (the direction from ``scene_center`` to ``c``; -y when they coincide) -- turned, when
    ``line`` (2, 3) (the nearest-obstacle line) is given, to the horizontal direction
    perpendicular to it on that side, so the line is seen across, not end-on -- raised by
    :data:`FOLLOW_ELEVATION_DEG`, far enough that a sphere around the box fits the part of the
    view left of the control panel (``panel_share`` of a canvas ``aspect`` wide per unit height,
    vertical field of view ``fov_rad``), times :data:`FOLLOW_MARGIN`.  The look-at point is moved
    to the camera's right so that ``c`` sits in the middle of that part (:func:`visible_offset`),
    not under the panel.  The framed sphere's radius is at least ``min_radius`` m.

    With ``targets`` (n, 3) m (points of the arm) and ``obstacles`` (shapes that may hide them),
    the direction is the first, turning about the vertical from that one (then ±35°, ±70°,
    ±110°, ±145°, 180°, at elevations 30°, 50°, 15°, 70°), that sees the largest weighted number
    of targets past the obstacles (:func:`visible_count` with sight lines as wide as
    ``target_radii`` (n,) m, default 1 % of the framed sphere, so a link's whole cross-section is
    seen, not only its axis; ``weights`` (n,), default 1 each), times the sine of the angle
    between the view and ``axis`` (3,) (the nearest link's axis, seen across rather than end-on):
    the first direction that sees them all at least 45° off the axis.
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    P = P[np.all(np.isfinite(P), axis=1)]
    if len(P) == 0:
        P = np.asarray(scene_center, dtype=np.float64).reshape(1, 3)
    lo, hi = P.min(axis=0), P.max(axis=0)
    c = 0.5 * (lo + hi)
    r = max(min_radius, 0.5 * float(np.linalg.norm(hi - lo)), 1e-3)
    h = c - np.asarray(scene_center, dtype=np.float64)
    h[2] = 0.0
    n = float(np.linalg.norm(h))
    h = h / n if n > 1e-6 else np.array([0.0, -1.0, 0.0])
    if line is not None:
        d = np.asarray(line, dtype=np.float64).reshape(2, 3)
        d = d[1] - d[0]
        perp = np.array([-d[1], d[0], 0.0])
        m = float(np.linalg.norm(perp))
        if m > 0.2 * float(np.linalg.norm(d)) and m > 1e-9:
            perp /= m
            h = perp if float(perp @ h) >= 0.0 else -perp
    shift, half = visible_offset(fov_rad, aspect, panel_share)
    dist = FOLLOW_MARGIN * r / math.sin(half)

    def pose(hh, el_deg):
        el = math.radians(el_deg)
        direction = np.array([math.cos(el) * hh[0], math.cos(el) * hh[1], math.sin(el)])
        right = np.cross(-direction, [0.0, 0.0, 1.0])
        right /= max(float(np.linalg.norm(right)), 1e-12)
        look = c + shift * dist * right
        return look + dist * direction, look

    first = pose(h, FOLLOW_ELEVATION_DEG)
    T = None if targets is None else np.asarray(targets, dtype=np.float64).reshape(-1, 3)
    if T is None or len(T) == 0 or not obstacles:
        return first
    w = np.ones(len(T)) if weights is None else np.asarray(weights, dtype=np.float64)
    full = float(w.sum())
    best, best_score = first, -1.0
    sight_r = np.full(len(T), 0.01 * r) if target_radii is None else np.maximum(
        np.asarray(target_radii, dtype=np.float64), 0.01 * r)
    a_hat = None
    if axis is not None and float(np.linalg.norm(axis)) > 1e-9:
        a_hat = np.asarray(axis, dtype=np.float64) / float(np.linalg.norm(axis))
    for el in (FOLLOW_ELEVATION_DEG,) + tuple(e for e in _ELEVATIONS if e != FOLLOW_ELEVATION_DEG):
        for az in _AZIMUTHS:
            eye, look = pose(_turned(h, az), el)
            across = 1.0
            if a_hat is not None:
                view = (c - eye) / max(float(np.linalg.norm(c - eye)), 1e-12)
                across = math.sqrt(max(0.0, 1.0 - float(view @ a_hat) ** 2))
            seen = float(sum(wk for p, wk, rk in zip(T, w, sight_r) if visible_count(eye, p, obstacles, rk)))
            if seen * across > best_score:
                best, best_score = (eye, look), seen * across
            if seen >= full and across >= math.sqrt(0.5):
                return eye, look
    return best


PAIR_CONTEXT = 3.5
"""The pair view frames a sphere of this many half line lengths about the nearest line's middle ..."""
PAIR_SHIFT = 1.4
"""... its look-at point moved this many sphere radii to the camera's right (the line sits in the
middle of the canvas left of the control panel) ..."""
PAIR_MARGIN = 1.6
"""... from this many times the distance that just fits the sphere."""
_PAIR_ELEVATIONS = (30.0, 50.0, 15.0, 70.0)
_PAIR_AZIMUTHS = (0.0, 180.0, 35.0, -35.0, 145.0, -145.0, 70.0, -70.0)


def _pair_pose(mid, R, h, el_deg, fov_rad, shift):
    el = math.radians(el_deg)
    direction = np.array([math.cos(el) * h[0], math.cos(el) * h[1], math.sin(el)])
    right = np.cross(-direction, [0.0, 0.0, 1.0])
    right /= max(float(np.linalg.norm(right)), 1e-12)
    look = mid + shift * R * right
    dist = PAIR_MARGIN * R / math.sin(0.5 * fov_rad)
    return look + dist * direction, look


def pair_view(line, shapes=(), *, fov_rad: float = math.radians(75.0), min_radius: float = 0.02,
              shift: float = PAIR_SHIFT) -> tuple[np.ndarray, np.ndarray]:
    """Camera ``(position, look_at)`` (3,) m on the nearest-obstacle ``line`` (2, 3) m, seen across it.

    Frames a sphere of :data:`PAIR_CONTEXT` half line lengths (at least ``min_radius`` m) about
    the line's middle.  Candidate directions turn about the vertical from the horizontal
    perpendicular to the line (both sides, then ±35°, ±70°, ±145°) at elevations 30°, 50°, 15°,
    70°; those looking more along the line than across it (|cos| > 0.8) are skipped.  The first
    whose camera sees the line at 30 %, 50 % and 70 % of its length past every shape of
    ``shapes`` (:func:`visible_count`: each sight line, a thin capsule, clear of them all, up to
    the point itself) is taken; when none is, the first that sees the most of them.  Shapes the
    line runs through (:func:`see_through`; drawn translucent) do not count as hiding it.
    """
    L = np.asarray(line, dtype=np.float64).reshape(2, 3)
    mid = L.mean(axis=0)
    d = L[1] - L[0]
    n = float(np.linalg.norm(d))
    R = max(PAIR_CONTEXT * 0.5 * n, float(min_radius), 1e-3)
    d_hat = d / n if n > 1e-12 else np.array([0.0, 0.0, 1.0])
    h0 = np.array([-d_hat[1], d_hat[0], 0.0])
    h0 = h0 / np.linalg.norm(h0) if np.linalg.norm(h0) > 1e-6 else np.array([0.0, -1.0, 0.0])
    shapes = list(shapes)
    wrapped = set(see_through(L, shapes)) if n > 1e-9 else set()
    blockers = [sh for k, sh in enumerate(shapes) if k not in wrapped]
    targets = L[0] + np.array([0.3, 0.5, 0.7])[:, None] * d
    sight_r = min(0.02 * R, 0.1 * n) if n > 1e-9 else 0.02 * R
    best, best_seen = None, -1
    for el in _PAIR_ELEVATIONS:
        for az in _PAIR_AZIMUTHS:
            eye, look = _pair_pose(mid, R, _turned(h0, az), el, fov_rad, shift)
            view = (mid - eye) / np.linalg.norm(mid - eye)
            if abs(float(view @ d_hat)) > 0.8:
                continue
            seen = visible_count(eye, targets, blockers, sight_r) if blockers else len(targets)
            if seen > best_seen:
                best, best_seen = (eye, look), seen
            if seen == len(targets):
                return eye, look
    return best
