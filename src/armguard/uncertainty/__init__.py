"""Uncertain spatial relations after Smith & Cheeseman, *On the Representation and Estimation
of Spatial Uncertainty* (SRI 1985; IJRR 5(4), 1986): compounding ⊕, reversal ⊖, merging,
network reduction (a Wheatstone bridge by the paper's link deletion, or the joint
least-squares estimate), the sensing procedure's glitch test, confidence ellipses, polar
sensors, Monte Carlo validation — in the plane
(:class:`UncertainPose2`, (x, y, θ)) and on SE(3) (:class:`UncertainPose3`, exponential
coordinates, no Euler-angle poles) — and uncertain placements of obstacles and robot bases in
the checks (:func:`clearance_sigmas`, :func:`verify_with_confidence`).  Guide: ``docs/uncertainty.md``.
"""

from __future__ import annotations

from . import se2, se3
from ._checks import ClearanceStatus, GroupSigma, PairSigma, SigmaReport, UncertainPlacement, clearance_sigmas
from ._confident import ConfidentVerification, verify_with_confidence
from ._grow import grow_shape
from .confidence import Box2, Ellipse, Polygon2, confidence_for_k2, ellipse, k2_for_confidence, probability_inside
from .montecarlo import (
    Agreement,
    MonteCarloResult,
    agreement,
    monte_carlo,
    monte_carlo_chain,
    monte_carlo_chain3,
    path_length,
)
from .plot import plot_monte_carlo
from .network import NetworkReduction, ReductionStatus, joint_estimate, reduce_network, reduce_network_report
from .pose2 import UncertainPose2
from .pose3 import UncertainPose3
from .se2 import polar_to_cartesian
from .sensing import GlitchStatus, GlitchTest, Sensing, glitch_test, sense

__all__ = [
    "UncertainPose2",
    "UncertainPose3",
    "reduce_network",
    "reduce_network_report",
    "joint_estimate",
    "NetworkReduction",
    "ReductionStatus",
    "glitch_test",
    "sense",
    "GlitchStatus",
    "GlitchTest",
    "Sensing",
    "polar_to_cartesian",
    "k2_for_confidence",
    "confidence_for_k2",
    "Ellipse",
    "ellipse",
    "Box2",
    "Polygon2",
    "probability_inside",
    "MonteCarloResult",
    "Agreement",
    "monte_carlo",
    "monte_carlo_chain",
    "monte_carlo_chain3",
    "agreement",
    "path_length",
    "plot_monte_carlo",
    "se2",
    "se3",
    "UncertainPlacement",
    "clearance_sigmas",
    "verify_with_confidence",
    "grow_shape",
    "ClearanceStatus",
    "PairSigma",
    "GroupSigma",
    "SigmaReport",
    "ConfidentVerification",
]
