"""One thread's scratch of the fused Detector, and the compiled entry point it calls."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import _kernel as kn

if TYPE_CHECKING:
    from ._detector import FusedDetector

__all__ = ["_Scratch", "_entry_point"]


def _entry_point(*args):
    """The compiled ``detect_entry`` for these argument types, called without numba's dispatcher.

    The dispatcher types all nine arguments on every call (~0.3 µs of a ~4 µs check); ``check``
    always passes the same buffers (float64 / int64, C-contiguous, writeable), so after one
    typed call the overload for that signature is the one that would be picked every time.
    Falls back to the dispatcher when numba does not expose the overload."""
    kn.detect_entry(*args)  # compiles (or loads from the cache) for exactly these types
    try:
        from numba import typeof

        sig = tuple(typeof(a) for a in args)
        return kn.detect_entry.overloads[sig].entry_point
    except (KeyError, AttributeError):  # pragma: no cover - numba internals changed
        return kn.detect_entry


class _Scratch:
    """One thread's scratch and outputs of a :class:`FusedDetector`.

    Every thread calling a Detector gets its own (``threading.local``), copied from the pristine
    buffers of :meth:`FusedDetector.prepare`, so threads never share a buffer the kernel writes; the
    model buffers (``H``, ``MF``, ``MI``) are read-only in the kernel and shared.  The state the
    anytime mode keeps between checks (last distances, time since checked) is per thread too."""

    __slots__ = ("SF", "SI", "q1", "ev", "pflag", "plb", "iprm_by_mode", "entry_args", "last_raw")

    def __init__(self, det: "FusedDetector") -> None:
        L = det._layout
        self.SF = det._SF0.copy()
        self.SI = det._SI0.copy()
        self.q1 = np.zeros((1, det._model.n_q))
        self.ev = L.view(self.SF, "ev")
        self.pflag = L.view(self.SI, "pflag")
        self.plb = L.view(self.SF, "plb")
        self.iprm_by_mode = {mode: ip.copy() for mode, ip in det._iprm_by_mode.items()}
        self.entry_args = (self.q1, det._H, det._MF, det._MI, self.SF, self.SI, det._prm,
                           self.iprm_by_mode[kn.MODE_EXACT], det._all_p)
        self.last_raw = None  # this thread's last report, still reading SF / SI
