"""Keep the nearest line in sight: which shapes hide it from a camera.

viser draws line segments and meshes with the depth test on and offers no switch for it (only
labels and transform gizmos draw on top), so the view keeps the nearest line in sight by drawing
translucent what hides it:

* a shape the line runs through (:func:`~._view.see_through`: no camera sees past it);
* a shape standing between a browser tab's camera and the line (:func:`hidden_from`): the sight
  lines from the camera to :data:`SIGHT_FRACTIONS` of the line's length, each tested against the
  shapes whose bounding sphere comes near it, then exactly (a thin capsule's distance);
* the terrain, when the line runs under its surface or a sight line does
  (:func:`~._draw_overlays.line_buried` with samples at half a cell).

Every tab's camera counts (the scene is shared by the tabs): a shape hiding the line from any of
them is translucent.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["hidden_from", "sight_buried", "SIGHT_FRACTIONS", "SIGHT_PERIOD"]

SIGHT_FRACTIONS = (0.2, 0.5, 0.8)
"""Points of the nearest line (fractions of its length from the arm's end) the cameras must see."""
SIGHT_PERIOD = 0.15
"""s: after a camera moves, the view re-tests what hides the line at most this often."""
_SIGHT_RADIUS = 1e-4
"""m: radius of the sight capsules (a line, in effect)."""


def _targets(line) -> np.ndarray:
    L = np.asarray(line, dtype=np.float64).reshape(2, 3)
    return L[0] + np.asarray(SIGHT_FRACTIONS)[:, None] * (L[1] - L[0])


def hidden_from(eye, line, posed, *, skip=()) -> set[int]:
    """Indices of ``posed``'s shapes (a :class:`~._nodes.PosedItems`) that stand between the camera
    at ``eye`` (3,) m and the nearest ``line`` (2, 3) m: some sight line from ``eye`` to a point of
    :data:`SIGHT_FRACTIONS` passes inside them.  ``skip``: indices not tested (the pair's own
    shapes in a contact, where the line lies inside both)."""
    from ..geometry import Capsule, distance

    eye = np.asarray(eye, dtype=np.float64)
    if not np.all(np.isfinite(eye)) or not np.all(np.isfinite(np.asarray(line, dtype=np.float64))):
        return set()
    skip = set(skip)
    out: set[int] = set()
    for end, _ in _sight_ends(eye, line):
        sight = None
        for k in posed.near(eye, end, pad=_SIGHT_RADIUS):
            if k in skip or k in out:
                continue
            if sight is None:
                sight = Capsule(eye, end, _SIGHT_RADIUS)
            if distance(sight, posed.shape(k)).distance < 0.0:
                out.add(k)
    return out


def _sight_ends(eye, line):
    """``(end, length)`` of each sight line from ``eye`` towards a point of :data:`SIGHT_FRACTIONS`
    of ``line``, stopping just short of the point itself (points at the eye are skipped)."""
    for p in _targets(line):
        v = p - eye
        n = float(np.linalg.norm(v))
        if n >= 1e-9:
            yield p - min(1e-3, 0.01 * n) * v / n, n


def sight_buried(elevation, eye, line) -> bool:
    """Whether a sight line from ``eye`` to a point of :data:`SIGHT_FRACTIONS` of ``line`` runs
    under the surface of ``elevation`` (an ElevationMap): inside a cell's column at one of its
    samples, half a cell apart."""
    from ._draw_overlays import line_buried

    eye = np.asarray(eye, dtype=np.float64)
    if not np.all(np.isfinite(eye)):
        return False
    cell = max(float(elevation.cell), 1e-6)
    for end, n in _sight_ends(eye, line):
        samples = int(min(4000, max(33, math.ceil(2.0 * n / cell))))
        if line_buried(elevation, [eye, end], trim=0.0, samples=samples):
            return True
    return False
