"""Categories that a package above the detector composes onto it (today: the terrain).

``Detector(scene, terrain=T)`` hands ``T`` to the attach function that :mod:`armguard.terrain`
registered here (:func:`register_extra`) when it was imported, so the detector never imports
the package above it (the layers: ``docs/architecture.md``).  Whoever holds a terrain has
imported :mod:`armguard.terrain`, so its attach function is registered by then.
"""

from __future__ import annotations

from typing import Callable

from .._errors import DetectionError

__all__ = ["register_extra", "attach_extra"]

_ATTACH: dict[str, Callable] = {}


def register_extra(keyword: str, attach: Callable) -> None:
    """``Detector(..., keyword=value)`` will call ``attach(detector, value)``."""
    _ATTACH[keyword] = attach


def attach_extra(detector, keyword: str, value):
    """Attach ``value`` to ``detector`` through the function registered for ``keyword``."""
    attach = _ATTACH.get(keyword)
    if attach is None:
        raise DetectionError(f"{keyword}=: got a {type(value).__name__}, but no {keyword} category is registered "
                             f"(expected an object of armguard.{keyword})")
    return attach(detector, value)
