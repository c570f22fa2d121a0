"""Running code on several threads so that shared state shows: the conformance suite's thread check and
the thread tests use it."""

from __future__ import annotations

import sys
import threading

__all__ = ["run_in_threads"]


def run_in_threads(targets, switch_interval: float = 1e-5) -> None:
    """Call each of ``targets`` (functions of no argument) on a thread of its own and return when all
    have returned, the interpreter switching threads every ``switch_interval`` seconds meanwhile (as
    often as it will at the default 10 µs, so that a call is interrupted inside its work, where
    shared scratch or a half-made update shows).  Exceptions are the targets' to catch and record."""
    old = sys.getswitchinterval()
    sys.setswitchinterval(switch_interval)
    try:
        threads = [threading.Thread(target=t) for t in targets]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
    finally:
        sys.setswitchinterval(old)
