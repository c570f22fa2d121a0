"""Hermes's four paper-fidelity modules against coal, and their operation counts beside seed 001 §4
(1651 / 195 / 6064 multiplications per check, 11,000 FLOP, 18 kFLOPS -> 1.7 Hz).  The work is in
:mod:`bench.paper_fidelity` (``run_hermes``)."""

from __future__ import annotations

from .paper_fidelity import run_hermes

TITLE = "Hermes's modules (seed 001 §3) against coal, and their operation counts beside §4's"


def run(quick: bool) -> str:
    return run_hermes(quick)
