"""The backend harness itself: what ``armguard compare`` costs beside the backends it runs.

10⁴ seeded random configurations of Hermes plus its trajectories' samples, analytic vs coal,
serially in one process: the wall time of each stage (answering, comparing, writing
``compare.json`` and the PNGs) and the backends' own µs per configuration from the same run.
Then the verdicts-only backends through the same harness: clip vs coal on puma560, forbidden
(a map built here: 1°, or 6° with ``quick``) vs analytic on Hermes — unsafe answers, the MAYBE
share, the false-forbidden rate and yes/no configurations/s.
"""

from __future__ import annotations

import tempfile
import time

TITLE = "Harness: armguard compare on Hermes, analytic vs coal; verdicts-only backends"


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
    return "\n".join(rows) + note + "\n\n" + verdict_rows(quick)


def verdict_rows(quick: bool) -> str:
    """The verdicts-only backends against a distance backend's truth, through ``run_compare``."""
    import math

    from armguard.cspace import ForbiddenMap
    from armguard.harness import run_compare

    n = 2000 if quick else 10_000
    rows = ["| run | configurations | unsafe (said clear, collides) | said collision, clear | MAYBE (8 steps -> second level) "
            "| false-forbidden (of all / of the clear) | yes/no configurations/s (verdict backend, reference) | wall |",
            "|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as out:
        deg = 6.0 if quick else 1.0
        t0 = time.perf_counter()
        fmap = ForbiddenMap.build("hermes", out=f"{out}/hermes.agmap", resolution=math.radians(deg),
                                  **({"max_depth": 3} if quick else {}))
        build_s = time.perf_counter() - t0
        runs = [("puma560: clip vs coal", "puma560", ("clip", "coal"), None),
                (f"hermes: forbidden ({deg:g}° map) vs analytic", "hermes", ("forbidden", "analytic"),
                 {"forbidden": {"map": str(fmap.path)}})]
        for label, spec, pair, options in runs:
            t0 = time.perf_counter()
            comp = run_compare(spec, pair, n_configs=n, seed=0, trajectories="all", options=options, plots=False)
            wall = time.perf_counter() - t0
            p, b = comp.summary["pairs"][f"{pair[0]}/{pair[1]}"], comp.summary["backends"]
            maybe = (f"{100 * p['maybe_share_first_level']:.2f} % -> {100 * p['maybe_share']:.2f} %"
                     if p["maybe_share"] is not None else "—")
            ff = p["false_forbidden"]
            ffs = f"{100 * ff['share']:.2f} % / {100 * ff['share_of_clear']:.2f} %" if ff else "—"
            rows.append(f"| {label} | {p['configurations']} | {p['unsafe_disagreements']} | "
                        f"{100 * p['conservative_share']:.2f} % | {maybe} | {ffs} | "
                        f"{b[pair[0]]['yes_no_configs_per_s'] / 1e3:.1f} k, {b[pair[1]]['yes_no_configs_per_s'] / 1e3:.1f} k "
                        f"| {wall:.1f} s |")
    note = (f"\n\nThe map was built in {build_s:.1f} s (`armguard cspace build hermes --resolution {deg:g}deg`). Reproduce: "
            f"`armguard compare puma560 --backends clip,coal --configs {n}` and `armguard compare hermes --backends "
            f"forbidden,analytic --backend-option forbidden.map=MAP --configs {n}`; what the columns mean: "
            "[backends.md](backends.md#verdict-backends-clip-and-forbidden).")
    return "\n".join(rows) + note
