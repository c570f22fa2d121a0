"""The one test every entry point makes of joint values before numpy reads them as float64.

``np.asarray(x, dtype=float64)`` takes a complex array's real part (a ``ComplexWarning`` only) and
reads ``True`` as 1 (rad or m): a verdict from values no caller meant.  :func:`refuse_complex_or_bool`
is called by the Checkers (``backends.check_q`` / ``check_Q``), the Detectors, ``Trajectory`` and
``verify``'s ``q_others``, each with its own error class.
"""

from __future__ import annotations

import numpy as np

__all__ = ["refuse_complex_or_bool"]


def refuse_complex_or_bool(x, what: str, error: type) -> None:
    """Raise ``error`` naming ``what`` when ``x`` is (or, as a list, becomes) a complex or boolean array."""
    kind = getattr(x, "dtype", None)
    if kind is None and isinstance(x, (list, tuple)):
        try:
            kind = np.asarray(x).dtype
        except (TypeError, ValueError):
            return  # ragged or not numbers: the caller's own conversion says so
    if kind is not None and getattr(kind, "kind", "") in ("c", "b"):
        raise error(f"{what}: expected real joint values, got dtype {kind}")
