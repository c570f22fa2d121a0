"""The Detector: Ranger's real-time virtual sensor (seed ``000``) for any scene.

``Detector(scene, threshold=...)`` compiles the scene once (one kinematic tree, element
arrays, conservative per-link obstacle lists, a BVH over static obstacles); ``check(q)`` is
one numba call (FK, transforms, broad and narrow phase) and returns a
:class:`DetectionReport` with the nearest pair per category, the pairs within the threshold
and the status; ``check(q, budget_us=...)`` is the anytime mode; ``check_many`` /
``collides_many`` run over many configurations in parallel.  :func:`check_reference` is the
brute-force path the tests compare against.  With a backend other than the analytic one,
``Detector(scene, backend=...)`` is a :class:`RangerDetector`: the same algorithm (obstacle lists,
priorities, the anytime budget) over that backend's Checker (:mod:`._ranger`).  A configuration with a joint outside its limits
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
