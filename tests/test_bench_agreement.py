"""``bench agreement`` reads ``armguard compare``'s summary (``compare.json``'s fields): a renamed
field would stop the benchmark after every test had passed.  On a small run of a built-in model the
tables must carry every backend's timings and the analytic/coal agreement (no verdict disagreement)."""

from __future__ import annotations

import re

from bench.agreement import _judged, tables

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
    assert re.search(r"\| (— \(none beyond tolerance\)|[1-5]: analytic off ≤ [0-9.e+-]+, coal off ≤ [0-9.e+-]+) \|$", row), row


def test_the_reference_column_reads_the_judged_entries():
    """The last column: the worst entries that carry the reference's answer, each side's largest error."""
    p = {"a": "x", "b": "y", "worst": [
        {"why": "distance", "slow_reference": {"distance": -0.05, "error": {"x": 3e-13, "y": 0.033}}},
        {"why": "distance", "slow_reference": {"distance": 0.2, "error": {"x": 1e-12, "y": 0.001}}},
        {"why": "distance", "slow_reference": {"distance": None, "why": "SceneError: no shape"}},
        {"why": "distance"}]}
    assert _judged(p) == "2: x off ≤ 1.0e-12, y off ≤ 3.3e-02"
    assert _judged({"a": "x", "b": "y", "worst": [{"why": "verdict"}]}) == "— (none beyond tolerance)"

