"""The Detector over any backend, under its earlier names.

:class:`CheckerDetector` is :class:`armguard.detect._ranger.RangerDetector` (Ranger's algorithm
over a backend's Checker); :func:`other_backend` says whether the precedence picks a backend
without a Ranger cycle of its own.
"""

from __future__ import annotations

from ._ranger import RangerDetector, fast_path

__all__ = ["CheckerDetector", "other_backend"]

CheckerDetector = RangerDetector


def other_backend(backend, backend_options) -> bool:
    """Whether ``Detector(..., backend=backend, backend_options=backend_options)`` is a
    :class:`RangerDetector` (the chosen backend declares no ``ranger_detector`` for these options)."""
    return fast_path(backend, backend_options) is None
