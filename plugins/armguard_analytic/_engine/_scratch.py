"""One thread's scratch of the fused Detector, and the compiled entry point it calls."""

from __future__ import annotations

import os
import time
from typing import TYPE_CHECKING

import numpy as np

from . import _entry, _kernel as kn

if TYPE_CHECKING:
    from ._built import Built

__all__ = ["CPUS", "GIL_RELEASE_US", "MIN_ROWS_PER_THREAD", "_Scratch", "_entry_point", "compiled", "median_call_us",
           "row_threads"]

CPUS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
"""The processors this process may run on (its CPU affinity: a control process pinned to some cores,
a container's share), read once: asking the system takes longer than a one-row ``collides``
needs for all its work.  A batch spreads over at most these."""
MIN_ROWS_PER_THREAD = 256
"""Below this many configurations per thread, a thread of a batch costs more than it saves."""


def row_threads(M: int) -> int:
    """How many threads a batch of ``M`` configurations is split over (one for small batches)."""
    return max(1, min(M, CPUS, -(-M // MIN_ROWS_PER_THREAD)))

GIL_RELEASE_US = 12.0
"""A compiled call releases the GIL when one call takes at least this long (µs, measured when the
Detector or the Checker's call plan is made: :func:`median_call_us`).  Below it, handing the GIL to
another thread and taking it back costs more than the call: two threads sharing a gmf_s480 or hermes
checker made fewer calls than one thread, holding the GIL about as many; above it the threads run
in parallel (ranger, z1; ``python -m bench backends``, the two "2 threads" columns)."""


def compiled(dispatcher, call: tuple):
    """The compiled overload of ``dispatcher`` for exactly the types of ``call`` (compiled, or loaded
    from numba's cache, by calling it once), called without numba's dispatcher.

    The dispatcher types every argument on every call (~40 ns an array); the callers always pass the
    same buffers (float64 / int64, C-contiguous, writeable), so after one typed call the overload
    for that signature is the one that would be picked every time.  Falls back to the dispatcher
    when numba does not expose the overload."""
    dispatcher(*call)
    try:
        from numba import typeof

        return dispatcher.overloads[tuple(typeof(a) for a in call)].entry_point
    except (KeyError, AttributeError):  # pragma: no cover - numba internals changed
        return dispatcher


def median_call_us(run, Q: np.ndarray) -> float:
    """Median wall time (µs) of ``run(q)`` over the rows of ``Q`` (each a different configuration:
    one repeated would train the branch predictor and time half the real cost)."""
    ts = []
    for q in Q:
        t = time.perf_counter()
        run(q)
        ts.append(time.perf_counter() - t)
    return float(np.median(ts)) * 1e6 if ts else 0.0


def _entry_point(*args, release_gil: bool = True):
    """The compiled ``detect_entry`` (or, holding the GIL, ``detect_entry_held``) for these
    argument types (:func:`compiled`)."""
    return compiled(_entry.detect_entry if release_gil else _entry.detect_entry_held, args)


class _Scratch:
    """One thread's scratch and outputs of one revision ``b`` of a fused Detector (:mod:`._built`).

    Every thread calling a Detector gets its own (``b.tls``), copied from the pristine buffers of
    :meth:`FusedDetector.prepare`, so threads never share a buffer the kernel writes; the model
    buffers (``H``, ``MF``, ``MI``) are read-only in the kernel and shared.  The state the anytime
    mode keeps between checks (last distances, time since checked) is per thread too."""

    __slots__ = ("b", "SF", "SI", "q1", "ev", "pflag", "plb", "iprm_by_mode", "entry_args", "last_raw", "batch")

    def __init__(self, b: "Built") -> None:
        L = b.layout
        self.b = b
        self.SF = b.SF0.copy()
        self.SI = b.SI0.copy()
        self.q1 = np.zeros((1, b.model.n_q))
        self.ev = L.view(self.SF, "ev")
        self.pflag = L.view(self.SI, "pflag")
        self.plb = L.view(self.SF, "plb")
        self.iprm_by_mode = {mode: ip.copy() for mode, ip in b.iprm_by_mode.items()}
        self.entry_args = (b.fn, self.q1, b.H, b.MF, b.MI, self.SF, self.SI, b.prm,
                           self.iprm_by_mode[kn.MODE_EXACT], b.all_p)
        self.last_raw = None  # this thread's last report, still reading SF / SI
        self.batch = None  # the buffers of this thread's one-thread batches (:meth:`batch_buffers`)

    def bind_prm(self, prm: np.ndarray) -> tuple:
        """``entry_args`` with the threshold array ``prm`` (``FusedDetector._set_limits`` publishes a
        new one instead of writing the old)."""
        a = self.entry_args
        self.entry_args = a = (*a[:7], prm, *a[8:])
        return a

    def batch_buffers(self, mode: int) -> tuple:
        """``(SF, SI, iprm)`` for a batch run on this thread alone, in ``mode``: scratch of its own (a
        batch never moves the state ``check`` keeps between calls, nor a report still reading
        ``SF``), made on the thread's first batch and reused by the next ones, as one batch reuses it
        from row to row."""
        bb = self.batch
        if bb is None:
            bb = self.batch = (self.b.SF0.copy(), self.b.SI0.copy(), {}, np.empty((1, 4)), np.empty(1, np.int64))
        ip = bb[2].get(mode)
        if ip is None:  # the kernel only reads it
            ip = bb[2][mode] = self.b.iprm.copy()
            ip[kn.I_MODE], ip[kn.I_STATE] = mode, 0
        return bb[0], bb[1], ip

    def one_row_outputs(self) -> tuple:
        """``(min_d (1, 4), status (1,))``: this thread's outputs for a one-row batch whose caller
        returns neither array (``_batch.yesno_rows``: a new verdict array), made with its batch
        scratch."""
        bb = self.batch
        return bb[3], bb[4]
