"""Checking values an operator types: every failure is a :class:`ConsoleInputError` naming the field.

The console never applies a value it could not check, so a bad entry leaves the state as it was
(issue #5: "bad values typed into number fields: a clear message, no crash, no lost state").
"""

from __future__ import annotations

import math
import re

import numpy as np

from .._errors import ArmguardError

__all__ = ["ConsoleInputError", "parse_number", "parse_numbers", "wrap_continuous", "CONTINUOUS_SPAN_DEG"]

CONTINUOUS_SPAN_DEG = 360.0
"""A continuous joint (no limits) is shown within ±this many degrees (its slider's ends)."""


class ConsoleInputError(ArmguardError, ValueError):
    """An operator entered a value the console cannot use (not a number, not finite, out of range)."""


_SPLIT = re.compile(r"[,\s;]+")


def parse_number(
    value,
    field: str,
    *,
    lo: float = -math.inf,
    hi: float = math.inf,
    unit: str = "",
    scale: float = 1.0,
    open_lo: bool = False,
    slack: float = 0.0,
) -> float:
    """Return ``value`` (a number or its text) times ``scale`` as a finite float within ``[lo, hi]``
    (``(lo, hi]`` with ``open_lo``: ``lo`` itself refused, and the message writes the range so).
    ``slack`` widens the accepted range on both sides (a joint limit's tolerance, e.g. a value read
    back from a slider) but not the range a refusal names.

    ``lo`` / ``hi`` are in the typed unit (before ``scale``); ``unit`` only decorates messages.
    Raises ConsoleInputError with the field's name and the accepted range.
    """
    suffix = f" {unit}" if unit else ""
    what = f"a number ({unit})" if unit else "a number"
    if isinstance(value, bool):
        raise ConsoleInputError(f"{field}: expected {what}, got {value!r}")
    if isinstance(value, str):
        text = value.strip()
        if not text:
            raise ConsoleInputError(f"{field}: expected {what}, got an empty entry")
        try:  # as written in ASCII: Python's float() also takes "4_5" (45) and other scripts' digits ("９０")
            if not text.isascii() or "_" in text:
                raise ValueError(text)
            x = float(text)
        except ValueError:
            raise ConsoleInputError(f"{field}: expected {what}, got {text!r}") from None
        typed = repr(text)
    else:
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise ConsoleInputError(f"{field}: expected {what}, got {value!r}") from None
        typed = repr(x)
    if not math.isfinite(x):
        finite = f"a finite number ({unit})" if unit else "a finite number"
        raise ConsoleInputError(f"{field}: expected {finite}, got {typed}")
    if x < lo - slack or x > hi + slack or (open_lo and x == lo):
        raise ConsoleInputError(f"{field}: {x:g}{suffix} is outside {'(' if open_lo else '['}{lo:g}, {hi:g}]{suffix}; "
                                "value kept unchanged")
    return x * scale


def parse_numbers(value, field: str, count: int, *, unit: str = "", scale: float = 1.0, names=None) -> np.ndarray:
    """Return ``count`` finite numbers (text separated by commas/spaces, or a sequence) times ``scale``.

    Returns ``(count,) float64``.  Ranges are checked by the caller, which knows each entry's limits.
    ``names`` (``count`` strings, e.g. ``("x", "y", "z")``) name the entries in messages, else ``[i]``.
    """
    if isinstance(value, str):
        parts = [p for p in _SPLIT.split(value.strip()) if p]
    else:
        try:
            parts = list(value)
        except TypeError:
            raise ConsoleInputError(f"{field}: expected {count} numbers, got {value!r}") from None
    if len(parts) != count:
        what = f"{count} numbers ({unit})" if unit else f"{count} numbers"
        sep = f" ({', '.join(names)})" if names else ""
        got = "an empty entry" if not parts else f"{len(parts)}"
        raise ConsoleInputError(f"{field}: expected {what}{sep}, got {got}; value kept unchanged")
    label = (lambda i: f"{field} {names[i]}") if names else (lambda i: f"{field}[{i}]")
    return np.array(
        [parse_number(p, label(i), unit=unit, scale=scale) for i, p in enumerate(parts)], dtype=np.float64
    )


def wrap_continuous(x: float, field: str, k: float = 1.0, unit: str = "rad") -> tuple[float, str]:
    """``(x, note)``: an angle ``x`` of a continuous joint (in the unit ``k`` per rad: ``180/pi`` for
    deg) beyond ±:data:`CONTINUOUS_SPAN_DEG` (its slider's ends) wrapped into -180..180 deg, the same
    angle (``450`` deg -> ``90``), with a note saying so; within the span, unchanged and no note."""
    span = math.radians(CONTINUOUS_SPAN_DEG) * k
    if -span <= x <= span:
        return x, ""
    w = math.remainder(x / k, 2.0 * math.pi) * k
    w = 0.0 if w == 0.0 else w
    return w, (f"{field}: {x:g} {unit} wrapped to {w:.6g} {unit}, the same angle of this continuous joint "
               f"(shown within ±{span:g} {unit})")
