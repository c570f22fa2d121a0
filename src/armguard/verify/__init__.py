"""Trajectory verification (Hermes made certain), the on-line guard, and batches on Dask.

* :func:`verify` — one trajectory: sampled (Hermes, ``Ed = v / f``) or certified
  (conservative advancement with lever-arm bounds: never misses a collision);
* :meth:`Verifier.check_edges` — a planner's straight edges, certified (``CLEAR`` / ``COLLISION``
  / ``INCOMPLETE`` per edge);
* :func:`verify_many` — many trajectories, serially or on a Dask cluster;
* :class:`Guard` — the on-line guard for a controller loop (SRI's collision prediction,
  Hermes's automatic / operator-jog / single-joint modes);
* :class:`StoppingDistance` — Hermes's stopping distance as a step function of speed and load.
"""

from ._edges import ALL_ROBOTS, EdgeResults, EdgeStatus
from ._guard import Guard, GuardDecision, GuardMode, GuardVerdict
from ._many import verify_many
from ._oracle import CATEGORIES, CHECKS, ClearanceModel
from ._report import (
    Clearance,
    ClearanceProfile,
    Collision,
    CollisionKind,
    MethodDetails,
    VerificationReport,
    VerificationStatus,
)
from ._stopping import StoppingDistance, discretisation_error
from ._subdivide import Subdivided
from ._trajectory_file import load_trajectory
from ._verify import DRAKE_JOINT_STEP, Verifier, verify

__all__ = [
    "verify",
    "load_trajectory",
    "verify_many",
    "Verifier",
    "EdgeResults",
    "ALL_ROBOTS",
    "EdgeStatus",
    "VerificationReport",
    "VerificationStatus",
    "Collision",
    "CollisionKind",
    "Clearance",
    "ClearanceProfile",
    "MethodDetails",
    "StoppingDistance",
    "Subdivided",
    "discretisation_error",
    "ClearanceModel",
    "CATEGORIES",
    "CHECKS",
    "DRAKE_JOINT_STEP",
    "Guard",
    "GuardDecision",
    "GuardMode",
    "GuardVerdict",
]


# ``armguard.verify`` is both this subpackage and the function: once the subpackage has been
# imported, Python binds the name ``armguard.verify`` to the module, so the module itself is made
# callable as :func:`verify` (the contract is ``armguard.verify(scene, trajectory, ...)``).
import sys as _sys  # noqa: E402
import types as _types  # noqa: E402


class _CallableModule(_types.ModuleType):
    def __call__(self, *args, **kwargs):
        return verify(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableModule
