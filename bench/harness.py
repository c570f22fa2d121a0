"""The backend harness itself: what ``armguard compare`` costs beside the backends it runs.

10⁴ seeded random configurations of Hermes plus its trajectories' samples, analytic vs coal,
serially in one process: the wall time of each stage (answering, comparing, writing
``compare.json`` and the PNGs) and the backends' own µs per configuration from the same run.
"""

from __future__ import annotations

import tempfile
import time

TITLE = "Harness: armguard compare on Hermes, analytic vs coal"


def run(quick: bool) -> str:
    from armguard.harness import resolve_model, run_compare

    n = 2000 if quick else 10_000
    model = resolve_model("hermes")
    rows = ["| configurations | answers | comparison | compare.json + PNGs | total wall | analytic µs/config | coal µs/config "
            "| coal / analytic (distances, yes/no) | verdict disagreements | max abs Δd |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        comp = run_compare("hermes", ("analytic", "coal"), n_configs=n, seed=0, trajectories="all", out_dir=out, model=model)
        wall = time.perf_counter() - t0
    s = comp.summary
    tm, p, b = s["timing"], s["pairs"]["analytic/coal"], s["backends"]
    rows.append(f"| {s['configs']['total']} | {tm['answers_s']:.1f} s | {tm['compare_s']:.1f} s | {tm['outputs_s']:.1f} s "
                f"| {wall:.1f} s | {b['analytic']['us_per_config']:.1f} | {b['coal']['us_per_config']:.1f} "
                f"| {p['speed_ratio']['distances']:.1f}×, {p['speed_ratio']['yes_no']:.1f}× | {p['verdict_disagreements']} "
                f"| {p['max_abs_distance_error']:.1e} m |")
    note = (f"\n\nReproduce the run itself: `armguard compare hermes --backends analytic,coal --configs {n} --out DIR`. "
            "The answers stage is the backends' own time (each `pair_distances(q)` from Python, then `collides(Q)`); "
            "the harness's share is the comparison and the outputs. Per-model comparisons: "
            "[backends.md](backends.md).")
    return "\n".join(rows) + note
