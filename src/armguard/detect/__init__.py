"""The Detector: Ranger's real-time virtual sensor (seed ``000``) for any scene.

``Detector(scene, threshold=...)`` is the public name (:mod:`._detector`): it builds the
Detector the chosen backend declares (``Backend.ranger_detector``), else a
:class:`RangerDetector`; both are subclasses.  The analytic backend's (the default) is its fused
engine in the plugin (``armguard_analytic._engine``): the scene compiled once (one kinematic
tree, element arrays, conservative per-link obstacle lists, a BVH over static obstacles) and
``check(q)`` as one numba call (FK, transforms, broad and narrow phase).  ``check`` returns a
:class:`DetectionReport` with the nearest pair per category, the pairs within the threshold and
the status; ``check(q, budget_us=...)`` is the anytime mode; ``check_many`` / ``collides_many``
run over many configurations in parallel.  :func:`check_reference` is the brute-force path the
tests compare against.  With any other backend, ``Detector(scene, backend=...)`` is a
:class:`RangerDetector`: the same algorithm (obstacle lists, priorities, the anytime budget) over
that backend's Checker (:mod:`._ranger`).  A configuration with a joint outside its limits
is refused by every entry point with :class:`JointLimitError` (see :mod:`armguard.kinematics._limits`).
"""

from .._errors import JointLimitError
from ._detector import Detector
from ._ranger import RangerDetector
from ._reference import check_reference
from ._report import (
    CATEGORIES,
    BatchReport,
    Category,
    DetectionReport,
    NotEvaluated,
    PairDistances,
    PairResult,
    Status,
)

__all__ = [
    "Detector",
    "RangerDetector",
    "JointLimitError",
    "DetectionReport",
    "Status",
    "Category",
    "CATEGORIES",
    "PairResult",
    "NotEvaluated",
    "BatchReport",
    "PairDistances",
    "check_reference",
]
