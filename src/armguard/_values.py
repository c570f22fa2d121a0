"""The tests every entry point makes of the values it is given, before it computes with them.

``np.asarray(x, dtype=float64)`` takes a complex array's real part (a ``ComplexWarning`` only) and
reads ``True`` as 1 (rad or m): a verdict from values no caller meant.  :func:`refuse_complex_or_bool`
is called by the Checkers (``backends.check_q`` / ``check_Q``), the Detectors, ``Trajectory`` and
``verify``'s ``q_others``, each with its own error class.

:func:`number` and :func:`whole_number` read one option (a margin, a confidence, a count): text,
``None``, ``True``, NaN or a value out of its range is the caller's error class naming the option,
never a ``TypeError`` / ``ValueError`` from deep inside, and never a NaN that compares false
everywhere (a NaN margin would make every pair "beyond" it).
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["refuse_complex_or_bool", "number", "whole_number"]


def number(value, what: str, error: type, *, low: float | None = None, high: float | None = None,
           low_open: bool = False, high_open: bool = False, unit: str = "", text: bool = False) -> float:
    """``value`` as a finite float within ``[low, high]`` (an end ``None``: unbounded; ``*_open``: the end
    excluded); else ``error("<what>: expected a finite number <range><unit>, got <value!r>")``.
    ``text``: a string that reads as such a number is taken too (an option given on a command line)."""
    x = math.nan
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "fiu":
        x = float(value)  # a 0-d array of a real kind: the number it holds
    elif not isinstance(value, (bool, np.bool_)) and isinstance(value, (numbers.Real, np.floating, np.integer)):
        try:
            x = float(value)
        except OverflowError:  # an int beyond any float (10**400): no finite number
            x = math.nan
    elif text and isinstance(value, str):
        try:
            x = float(value)
        except ValueError:
            x = math.nan
    ok = math.isfinite(x)
    if ok and low is not None:
        ok = x > low if low_open else x >= low
    if ok and high is not None:
        ok = x < high if high_open else x <= high
    if not ok:
        raise error(f"{what}: expected a finite number{_range(low, high, low_open, high_open)}{unit}, got {value!r}")
    return x


def whole_number(value, what: str, error: type, *, low: int | None = 0) -> int:
    """``value`` as an int ``>= low`` (an integral float such as ``2.0`` too; not ``True``, ``2.5`` or text);
    else ``error("<what>: expected an integer >= <low>, got <value!r>")``."""
    ok = not isinstance(value, (bool, np.bool_)) and isinstance(value, (numbers.Real, np.floating, np.integer))
    if ok:
        x = float(value)
        ok = math.isfinite(x) and x == int(x) and (low is None or x >= low)
    if not ok:
        bound = "" if low is None else f" >= {low}"
        raise error(f"{what}: expected an integer{bound}, got {value!r}")
    return int(value)


def _range(low, high, low_open: bool, high_open: bool) -> str:
    if low is not None and high is not None:
        return f" in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    if low is not None:
        return f" {'>' if low_open else '>='} {low:g}"
    if high is not None:
        return f" {'<' if high_open else '<='} {high:g}"
    return ""


def refuse_complex_or_bool(x, what: str, error: type) -> None:
    """Raise ``error`` naming ``what`` when ``x`` is (or, as a list, becomes) a complex or boolean array, or is
    a list holding a boolean among numbers (numpy reads ``[True, -1.5]`` as ``[1.0, -1.5]``: 1 rad)."""
    kind = getattr(x, "dtype", None)
    if kind is None and isinstance(x, (list, tuple)):
        if has_bool(x):
            raise error(f"{what}: expected real joint values, got a boolean in {_short(x)}")
        try:
            kind = np.asarray(x).dtype
        except (TypeError, ValueError):
            return  # ragged or not numbers: the caller's own conversion says so
    if kind is not None and getattr(kind, "kind", "") in ("c", "b"):
        raise error(f"{what}: expected real joint values, got dtype {kind}")


def has_bool(x) -> bool:
    """Whether the (nested) list or tuple ``x`` holds a ``bool`` or ``numpy.bool_`` anywhere."""
    for v in x:
        if isinstance(v, (bool, np.bool_)) or (isinstance(v, (list, tuple)) and has_bool(v)):
            return True
    return False


def _short(x) -> str:
    text = repr(x)
    return text if len(text) <= 80 else text[:77] + "..."
