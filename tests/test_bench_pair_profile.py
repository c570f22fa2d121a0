"""``bench pair_profile`` replays GJK in Python to count its work: the replay must run the compiled
kernel's own helpers (a helper renamed or removed in ``armguard.geometry._pair_gjk`` once broke it
silently, the benchmark writing an error row), and count the path the kernel takes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _row(name: str) -> dict:
    """``python -m bench.pair_profile NAME 10``'s JSON row, in a fresh process: the replay swaps the GJK
    module's compiled helpers for their Python bodies."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    proc = subprocess.run([sys.executable, "-m", "bench.pair_profile", name, "10"], capture_output=True,
                          text=True, cwd=ROOT, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads([ln for ln in proc.stdout.splitlines() if ln.startswith("{")][-1])


def test_pair_profile_counts_gjk_work():
    row = _row("kuka_iiwa")
    assert row["pairs"] == row["poly_pairs"] == 21
    assert row["gjk_pairs"] > 100  # separated hull pairs of 20 configurations
    # from a cold start GJK evaluates the first support and one per iteration, the last one
    # verifying: at least two; from a seed (the pairs' tables) at least the verifying one, and fewer
    # than cold on kuka_iiwa's hulls (its pairs two joints apart: 9.7 cold, 2.5 seeded)
    assert 1.0 <= row["it"] <= row["it_p90"] <= 64
    assert 2.0 <= row["it_cold"] and row["it"] < 0.8 * row["it_cold"]
    seeded, cold, along = row["by_joints"]["2"]  # the six pairs two joints apart, 32 x 32 tables
    assert 1.0 <= seeded < 0.5 * cold
    # along the answer's own direction a cold start still builds its simplex one support at a time
    # (at least the first and the verifying one) and never takes more than 64 iterations
    far = row["by_joints"]["0"]  # the pairs with no table
    assert 2.0 <= along <= 64 and 2.0 <= far[2] <= far[1]
    # every hull of kuka_iiwa has a vertex graph: each support climbs both hulls, once each
    assert row["climb"] == 2 * row["it"]
    assert row["dot"] >= row["climb"]


def test_pair_profile_times_each_kind_of_pair():
    """The by-kind table: every pair counted once per configuration, in one of the three kinds, each
    kind's hot time positive and an overlapping pair (EPA after GJK) dearer than an apart one."""
    row = _row("ur3")
    kinds = row["by_kind"]
    assert set(kinds) == {"apart, seed table", "apart, no table", "overlapping"}
    assert abs(sum(c for c, _ in kinds.values()) - row["pairs"]) < 1e-9
    for c, t in kinds.values():
        assert c > 0.0 and 0.0 < t < 1e6  # ur3 has pairs of every kind at random configurations (ns each)
    assert kinds["overlapping"][1] > kinds["apart, seed table"][1]
    assert 0.0 < row["us_again"] and 0.0 < row["us_alone_cycling"]
