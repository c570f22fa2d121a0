"""``python -m bench srdf`` on a subset of robots (``ARMGUARD_BENCH_ROBOTS``) keeps the other robots' rows."""

from __future__ import annotations

import pytest

srdf_bench = pytest.importorskip("bench.srdf")


def _row(name, shipped="-", s10="2 (0)", s100="2 (0)", coal="1e+05: 0.0100"):
    return f"| {name} | 10 | 1.0 | 4 / 0 / 2 | 3 | 1 | {shipped} | {s10} | {s100} | {coal} |"


def test_a_subset_run_replaces_its_rows_and_keeps_the_others(monkeypatch):
    old = {"a": _row("a"), "b": _row("b", shipped="1 of 5"), "c": _row("c", s10="3 (1)")}
    monkeypatch.setattr(srdf_bench, "_previous", lambda: (old, {"b": ["b: the shipped SRDF disables x-y, which ..."]}))
    monkeypatch.setattr(srdf_bench, "_all_names", lambda: ["a", "b", "c", "d"])
    text = srdf_bench._section({"d": _row("d"), "b": _row("b", shipped="0 of 5")}, [], 100_000, subset=True)
    rows = [ln for ln in text.splitlines() if ln.startswith("| ") and not ln.startswith("| robot")]
    assert [r.split("|")[1].strip() for r in rows] == ["a", "b", "c", "d"]  # the full run's order
    assert rows[1] == _row("b", shipped="0 of 5")  # this run's row replaces the old one
    assert "x-y" not in text  # and the old note of a robot run again goes
    assert "Rows of a, c are kept" in text
    assert "c: 1 at 10^4 and 0 at 10^5" in text  # the summary is read from the merged table
    assert "(none does)" in text


def test_a_full_run_writes_its_rows_only(monkeypatch):
    monkeypatch.setattr(srdf_bench, "_previous", lambda: pytest.fail("a full run does not read the previous file"))
    text = srdf_bench._section({"a": _row("a", coal="1e+05: -0.0010")}, [], 100_000, subset=False)
    assert text.count("\n| a |") == 1 and "kept" not in text
    assert "(none does)" not in text  # a coal contact on a proven pair is not hidden
