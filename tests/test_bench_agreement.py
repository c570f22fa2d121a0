"""``bench agreement`` reads ``armguard compare``'s summary (``compare.json``'s fields): a renamed
field would stop the benchmark after every test had passed.  On a small run of a built-in model the
tables must carry every backend's timings and the analytic/coal agreement (no verdict disagreement)."""

from __future__ import annotations

import re

from bench.agreement import tables

from armguard.backends import available


def test_the_agreement_tables_come_out_of_a_small_run():
    text = tables(("gmf_s480", "no_such_robot"), 20)
    times = next(ln for ln in text.splitlines() if ln.startswith("| gmf_s480 | 2"))  # 20 + trajectory samples
    cells = [c.strip() for c in times.strip("|").split("|")]
    n_b = 3 if "fcl" in available() else 2
    assert len(cells) == 3 + 2 * n_b + 1
    assert all(float(c) > 0 for c in cells[3:3 + n_b])  # µs per configuration
    assert all(c.endswith(" k") and float(c[:-2]) > 0 for c in cells[3 + n_b:3 + 2 * n_b])  # yes/no per s
    row = next(ln for ln in text.splitlines() if ln.startswith("| gmf_s480 | analytic/coal |"))
    assert re.search(r"\| 0 / 0 \| 0 \| [0-9.e+-]+ / [0-9.e+-]+ \|", row), row
    assert "| no_such_robot | not installed |" in text
