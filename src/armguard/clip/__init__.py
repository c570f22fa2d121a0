"""Smith's clipping collision checker: yes / no / maybe by clipping obstacles to guard volumes.

R. C. Smith, *Fast Robot Collision Detection Using Graphics Hardware* (SRI, 1985), as WORKMATE
ran it on the IRIS's clipping pipeline — here as numba kernels over flat arrays:

* :class:`Guard` — a guarded test object ``VOL``: outer and inner convex polyhedra ``PO`` / ``PI``,
  outer and inner spheres ``RO`` / ``RI`` about ``CS``, and the labelled convex cells of the shell
  between ``PO`` and ``PI`` for the second-level tests SRI did not build;
* :class:`Obstacle` — an obstacle ``OB`` as segments and convex polygons (a solid as its faces;
  a curved solid — Cylinder, Sphere, Capsule — as its circumscribed polytope of short segments
  and ruled strips within the chord tolerance, §IV: :func:`curved_polytopes`);
* :func:`check` / :func:`check_list` / :func:`check_many` — Appendix A's 8 steps, answering
  :class:`ClipStatus` INTERSECTED / CLEAR / MAYBE and the step that decided;
* :class:`Predictor` — WORKMATE's collision prediction: the guard swept over the next control
  interval, checked before the arm gets there;
* :class:`ClipModel` — guards from a list of link shapes, obstacles from static shapes, one
  verdict per pair (what a backend wrapper builds on);
* :func:`cyrus_beck`, :func:`sutherland_hodgman` — the clipping kernels.

``ANSWERS = "verdicts"``: this checker answers yes / no / maybe, never distances.
"""

from ._cells import CellKind, CellTree
from ._curved import chord_sides, circumscribed_band, curved_polytopes
from ._guard import DEFAULT_INNER_SCALE, DEFAULT_MAX_DEPTH, DEFAULT_RINGS, Guard
from ._kernels import cyrus_beck, sutherland_hodgman
from ._model import ClipModel, ModelVerdict, PairVerdict
from ._obstacle import DEFAULT_BOUNDS_MIN_VERTICES, Obstacle
from ._predict import DEFAULT_MAX_HALVINGS, Prediction, Predictor, interpolate_pose, rotation_growth, swept_guard
from ._procedure import STATUS_CODES, STEP_NAMES, ClipResult, ClipStatus, ListResult, check, check_list, check_many

ANSWERS = "verdicts"
"""The capability a backend wrapper declares: verdicts (yes / no / maybe), not distances."""

__all__ = [
    "ANSWERS",
    "Guard",
    "ClipModel",
    "ModelVerdict",
    "PairVerdict",
    "Obstacle",
    "CellKind",
    "CellTree",
    "ClipStatus",
    "ClipResult",
    "ListResult",
    "check",
    "check_list",
    "check_many",
    "Predictor",
    "Prediction",
    "swept_guard",
    "rotation_growth",
    "interpolate_pose",
    "DEFAULT_MAX_HALVINGS",
    "cyrus_beck",
    "chord_sides",
    "circumscribed_band",
    "curved_polytopes",
    "sutherland_hodgman",
    "STEP_NAMES",
    "STATUS_CODES",
    "DEFAULT_INNER_SCALE",
    "DEFAULT_MAX_DEPTH",
    "DEFAULT_RINGS",
    "DEFAULT_BOUNDS_MIN_VERTICES",
]
