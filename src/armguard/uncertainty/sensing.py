"""The sensing procedure's glitch test (Smith & Cheeseman, Section 5.2 step 2 and Section 6).

Section 5.2, step 2: "Given the uncertain prior location of the object to be sensed ... and the
error associated with the sensor, decide whether the probability of the actual observation is
below a predetermined threshold.  Such errors would occur, for example, if the camera locked onto
the wrong object."  Section 6: the procedure "supplies a quantitative method for judging when a
sensor has 'glitched' — i.e. its measured value is too unlikely, given the prior expectations."

The rule, with the paper's Gaussian assumption (Section 5.3, Appendix A): the innovation
``ν = z − x̂`` (observation minus expectation; planar angle wrapped into (−π, π], on SE(3) the
left perturbation ``log(T_z T̂⁻¹)``) has covariance ``S = C_x̂ + C_z`` (the sensor's error
independent of the prior's, Section 5.2's first assumption).  Its squared Mahalanobis length
``m² = νᵀ S⁻¹ ν`` is χ²-distributed with ``dof`` = 3 (plane) or 6 (space) degrees of freedom
when the sensor is right, so the observation is a glitch when ``m² > k²`` with
``k² = χ²_dof.ppf(confidence)``: a sound observation is rejected with probability
``1 − confidence``.  Step 3 then merges an accepted observation (Eqns. 5–7); a glitch leaves the
expectation unchanged.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import Union

import numpy as np
from scipy import stats

from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number
from . import se2 as _se2
from . import se3 as _se3
from .confidence import k2_for_confidence
from .pose2 import UncertainPose2
from .pose3 import UncertainPose3

__all__ = ["GlitchStatus", "GlitchTest", "Sensing", "glitch_test", "sense"]

Relation = Union[UncertainPose2, UncertainPose3]


class GlitchStatus(enum.Enum):
    """Verdict of :func:`glitch_test`."""

    CONSISTENT = "consistent"  # m² <= k²: the observation is plausible given the expectation
    GLITCH = "glitch"  # m² > k²: too unlikely; rejected


@dataclass(frozen=True)
class GlitchTest:
    """One observation tested against its expectation.

    Attributes
    ----------
    status : GlitchStatus
    mahalanobis2 : float, dimensionless — ``m² = νᵀ S⁻¹ ν``.
    k2 : float, dimensionless — the gate, ``χ²_dof.ppf(confidence)``.
    confidence : float — probability that a sound observation passes.
    dof : int — 3 (x, y, θ) or 6 (ρ, φ).
    p_value : float — probability of an innovation at least this unlikely from a sound
        sensor, ``χ²_dof.sf(m²)``; a glitch exactly when ``p_value < 1 − confidence``.
    innovation : (dof,) float64 — ``ν`` (m, m, rad or m×3, rad×3).
    """

    status: GlitchStatus
    mahalanobis2: float
    k2: float
    confidence: float
    dof: int
    p_value: float
    innovation: np.ndarray


@dataclass(frozen=True)
class Sensing:
    """Section 5.2 steps 2–3: the test and the relation after it.

    Attributes
    ----------
    status : GlitchStatus
    test : GlitchTest
    pose : UncertainPose2 or UncertainPose3 — the expectation merged with the observation
        (Eqns. 5–7) when CONSISTENT, the expectation unchanged when GLITCH.
    """

    status: GlitchStatus
    test: GlitchTest
    pose: Relation


def _innovation(expected: Relation, observed: Relation) -> np.ndarray:
    if isinstance(expected, UncertainPose2) and isinstance(observed, UncertainPose2):
        nu = np.array(observed.mean - expected.mean)
        nu[2] = _se2.wrap_angle(nu[2])
        return nu
    if isinstance(expected, UncertainPose3) and isinstance(observed, UncertainPose3):
        return _se3._log(observed.mean @ _se3._invert(expected.mean))
    raise UncertaintyError(
        "glitch_test: expected and observed must both be UncertainPose2 or both UncertainPose3, got "
        f"{type(expected).__name__} and {type(observed).__name__}"
    )


def glitch_test(expected: Relation, observed: Relation, confidence: float = 0.99, *,
                tol: Tolerances = DEFAULT_TOLERANCES) -> GlitchTest:
    """Is ``observed`` too unlikely given ``expected``?  (Section 5.2 step 2; see the module.)

    Parameters
    ----------
    expected : UncertainPose2 or UncertainPose3 — the relation predicted from the network.
    observed : the same kind — the sensor's measurement of it, with the sensor's covariance.
    confidence : float in (0, 1) — probability that a sound observation is accepted.

    Raises :class:`~armguard.UncertaintyError` when ``S = C_x̂ + C_z`` is singular (condition
    below :attr:`Tolerances.merge_conditioning`: both claim exact knowledge along a common
    direction, so no probability can be given).
    """
    confidence = number(confidence, "glitch_test: confidence", UncertaintyError, low=0.0, high=1.0, low_open=True,
                        high_open=True)
    nu = _innovation(expected, observed)
    dof = nu.size
    s = expected.cov + observed.cov
    ev = np.linalg.eigvalsh(s)
    if ev[-1] <= 0.0 or ev[0] < tol.merge_conditioning * ev[-1]:
        raise UncertaintyError(
            f"glitch_test: the innovation covariance C_expected + C_observed is singular (eigenvalues {ev})"
        )
    m2 = float(nu @ np.linalg.solve(s, nu))
    if not math.isfinite(m2):  # unreachable from validated relations; never a verdict from NaN
        raise UncertaintyError(f"glitch_test: Mahalanobis distance is not finite ({m2})")
    k2 = k2_for_confidence(float(confidence), dim=dof)
    status = GlitchStatus.GLITCH if m2 > k2 else GlitchStatus.CONSISTENT
    nu.flags.writeable = False
    return GlitchTest(status, m2, k2, float(confidence), dof, float(stats.chi2.sf(m2, dof)), nu)


def sense(expected: Relation, observed: Relation, confidence: float = 0.99, *,
          tol: Tolerances = DEFAULT_TOLERANCES) -> Sensing:
    """Section 5.2 steps 2–3: test ``observed`` (:func:`glitch_test`), merge it if consistent."""
    test = glitch_test(expected, observed, confidence, tol=tol)
    if test.status is GlitchStatus.GLITCH:
        return Sensing(test.status, test, expected)
    return Sensing(test.status, test, expected.merge(observed, tol=tol))
