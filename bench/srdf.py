"""Certified collision matrices (``armguard srdf``) against the shipped SRDF and MoveIt's sampling.

For each robot: the certified matrix's time (2 threads) and its pairs proven Never / witnessed /
undecided; the pairs the shipped SRDF disables that the search witnesses colliding; the pairs
MoveIt's rule (Never when not seen in N random configurations) would disable that can collide;
and a check of every proven-Never pair on random configurations with coal (the reference) --
any contact found there would be a bug.
"""

from __future__ import annotations

import sys
import time

import numpy as np

TITLE = "Certified collision matrices (armguard srdf)"
QUICK_ROBOTS = ["panda"]
# robots whose certified search takes its distances from coal (the reference backend) instead of the
# analytic kernel (none: so101 was one until its EPA stopped falling back to the exhaustive SAT)
CERTIFIED_BACKEND: dict[str, str] = {}


def _only() -> list[str]:
    import os

    return [n for n in os.environ.get("ARMGUARD_BENCH_ROBOTS", "").split(",") if n]


def _all_names() -> list[str]:
    """Every built-in model, then every public robot found installed (the public-robot table's set)."""
    from armguard.model import known_models

    ms = [m for m in known_models() if m.available]
    return [m.name for m in ms if m.source == "built-in"] + [m.name for m in ms if m.source != "built-in"]


def _names() -> list[str]:
    """:func:`_all_names`; ``ARMGUARD_BENCH_ROBOTS=a,b`` (environment) for a subset, in the same order
    (the rows of the others are kept from the previous file: :func:`_section`)."""
    only = _only()
    return [n for n in _all_names() if not only or n in only]


def _coal_check(model, setup, pairs, n: int, seed: int = 7) -> float:
    """Least coal distance over ``pairs`` (LinkPairs) at ``n`` random in-limit configurations (m)."""
    from armguard.cspace._clearance import checker_over
    from armguard.srdfgen import matrix_scene

    scene = matrix_scene(model.scene)
    keep = {frozenset((p.owner1, p.owner2)) for p in pairs}
    for cp in scene.allowed_pairs():
        if frozenset((cp.a, cp.b)) not in keep:
            scene.disable_pair(cp.a, cp.b)
    chk = checker_over(model, scene, "coal", need_distances=True)
    rng = np.random.default_rng(seed)
    best = np.inf
    for s in range(0, n, 5000):
        m = min(5000, n - s)
        Q = setup.lower + (setup.upper - setup.lower) * rng.random((m, len(setup.home)))
        best = min(best, float(np.min(chk.min_distance_many(model.pin_q(Q)))))
    return best


def run(quick: bool = False) -> str:
    import armguard
    from armguard.model._public import public_robot, public_robot_srdf
    from armguard.model._srdf import read_srdf
    from armguard.srdfgen import collision_matrix, pair_setup

    n_check = 10_000 if quick else 100_000
    rows = {}
    notes = []
    for name in (QUICK_ROBOTS if quick else _names()):
        print(f"bench srdf: {name} ...", file=sys.stderr, flush=True)
        model = armguard.load_model(name, srdf=False)
        t = time.perf_counter()
        backend = CERTIFIED_BACKEND.get(name, "analytic")
        cm = collision_matrix(model, workers=2, backend=backend)
        t_cert = time.perf_counter() - t
        print(f"bench srdf: {name} certified: {t_cert:.1f} s", file=sys.stderr, flush=True)
        c = cm.counts()
        witnessed = {frozenset((e.link1, e.link2)) for e in cm.entries if e.status == "witnessed"}
        sampled = {}
        for n in ((10_000,) if quick else (10_000, 100_000)):
            t = time.perf_counter()
            sm = collision_matrix(model, method="sampled", samples=n)
            print(f"bench srdf: {name} sampled {n}: {time.perf_counter() - t:.1f} s", file=sys.stderr, flush=True)
            never = {frozenset((e.link1, e.link2)) for e in sm.entries if e.reason == "Never"}
            sampled[n] = (len(never), len(never & witnessed))
        shipped = "-"
        found = public_robot_srdf(name) if public_robot(name) is not None else None
        if found is not None:  # the SRDF load_model reads: the table's, else the one its search finds
            srdf, partial = found
            dis = {frozenset((a, b)) for a, b, _ in read_srdf(srdf, partial=partial).disabled}
            if partial:  # a larger robot's SRDF (talos.srdf for one arm): its pairs of this URDF's links
                links = {f.name for f in model.pin_model.frames}
                dis = {p for p in dis if p <= links}
            bad = sorted(tuple(sorted(p)) for p in dis & witnessed)
            shipped = f"{len(bad)} of {len(dis)}"
            if bad:
                notes.append(f"{name}: the shipped SRDF disables {', '.join(f'{a}-{b}' for a, b in bad)}, "
                             "which the search witnesses colliding")
            at_home = sorted(tuple(sorted((e.link1, e.link2))) for e in cm.entries
                             if e.reason == "Default" and frozenset((e.link1, e.link2)) in dis)
            if at_home:
                notes.append(f"{name}: the shipped SRDF also disables {len(at_home)} pairs in contact at this table's home "
                             f"(the zero configuration clipped into the limits; not counted above): "
                             f"{', '.join(f'{a}-{b}' for a, b in at_home)}")
        setup = pair_setup(model)
        never_pairs = [p for p, e in zip(setup.pairs, cm.entries) if e.reason == "Never"]
        dmin = _coal_check(model, setup, never_pairs, n_check) if never_pairs else float("nan")
        s10 = sampled[10_000]
        s100 = sampled.get(100_000)
        rows[name] = (f"| {name} | {c['pairs']} | {t_cert:.1f}{'' if backend == 'analytic' else f' ({backend})'} | {c['Adjacent']} / {c['Default']} / {c['Never']} | "
                    f"{c['witnessed']} | {c['undecided']} | {shipped} | {s10[0]} ({s10[1]}) | "
                    + (f"{s100[0]} ({s100[1]})" if s100 else "-") + f" | {n_check:.0e}: {dmin:.4f} |")
    return _section(rows, notes, n_check, subset=not quick and bool(_only()))


HEAD = ("| robot | link pairs | certified (s, 2 threads) | Adjacent / Default / Never (proven) | witnessed | undecided | "
        "shipped SRDF disables, witnessed colliding | sampled Never at 10^4 (of them witnessed) | at 10^5 | "
        "coal on proven-Never pairs: samples, least distance (m) |\n|---|---|---|---|---|---|---|---|---|---|")


def _previous() -> tuple[dict, dict]:
    """``(rows, notes)`` of the section in docs/performance.md, by robot: a subset run keeps the others'."""
    from bench.__main__ import DOC, _SECTION

    text = DOC.read_text(encoding="utf-8") if DOC.exists() else ""
    sec = next((m.group(0) for m in _SECTION.finditer(text) if m.group(1) == "srdf"), "")
    rows, notes = {}, {}
    for line in sec.splitlines():
        if line.startswith("| ") and not line.startswith("| robot |"):
            rows[line.split("|")[1].strip()] = line
        elif line.startswith("- ") and ": the shipped SRDF" in line:
            notes.setdefault(line[2:].split(":", 1)[0], []).append(line[2:])
    return rows, notes


def _summary(rows: list[str]) -> str:
    """The wrong verdicts the table shows, in words (from its columns)."""
    wrong, bad = [], []
    for line in rows:
        c = [x.strip() for x in line.split("|")[1:-1]]
        w10 = int(c[7].split("(")[1].rstrip(")"))
        w100 = int(c[8].split("(")[1].rstrip(")")) if "(" in c[8] else 0
        if w10 or w100:
            wrong.append(f"{c[0]}: {w10} at 10^4 and {w100} at 10^5")
        if c[6] != "-" and not c[6].startswith("0 of"):
            bad.append(f"{c[0]}: {c[6].split(' of ')[0]}")
    out = []
    if wrong:
        out.append("Sampling would wrongly disable pairs that can collide -- " + "; ".join(wrong) + ".")
    if bad:
        out.append("Shipped SRDFs disable pairs the search witnesses colliding -- " + "; ".join(bad)
                   + " (the lint in [srdf.md](srdf.md) gives each with its witness).")
    return " ".join(out)


def _section(rows: dict, notes: list, n_check: int, subset: bool) -> str:
    """The section's Markdown: ``rows`` (robot -> table row) of this run, merged into the previous
    file's rows and notes when this run covers a subset (``ARMGUARD_BENCH_ROBOTS``)."""
    kept: list = []
    if subset:
        old_rows, old_notes = _previous()
        kept = [n for n in old_rows if n not in rows]
        order = _all_names()
        merged = {**{n: old_rows[n] for n in kept}, **rows}
        rows = {n: merged[n] for n in sorted(merged, key=lambda n: (order.index(n) if n in order else len(order), n))}
        notes = [x for n in old_notes if n in kept for x in old_notes[n]] + notes
    rows_l = list(rows.values())
    proofs_held = all(not (float(r.split("|")[-2].split(":")[1]) <= 0.0) for r in rows_l)
    text = ("Certified: `collision_matrix(model, workers=2)` (analytic distances at box centres, at most 2*10^5 "
            "evaluations per pair); sampled: MoveIt's rule at 10^4 and 10^5 random configurations. A sampled-Never "
            "pair that the certified search witnesses colliding is one sampling would wrongly disable. The last column "
            "samples every proven-Never pair with coal: a distance <= 0 there would contradict a proof"
            + (" (none does)" if proofs_held else "") + "; `tests/test_srdf_never_sampled.py` goes to 10^6 on puma560, ur5 "
            "and panda.")
    coal = [n for n in rows if "(coal)" in rows[n].split("|")[3]]
    if coal:
        text += (f" The certified search of {', '.join(coal)} takes its distances from coal (marked): its convex hulls "
                 "have 800-4,900 vertices, where the analytic kernel's penetration depth falls back from EPA to the "
                 "exhaustive SAT, which does not return in minutes.")
    if kept:
        text += (f" Rows of {', '.join(kept)} are kept from an earlier run (this one measured "
                 f"{', '.join(n for n in rows if n not in kept)}: `ARMGUARD_BENCH_ROBOTS`); their times are that run's, "
                 "on its machine and load.")
    text += "\n\n" + HEAD + "\n" + "\n".join(rows_l)
    seen = list(dict.fromkeys(notes))
    if seen:
        text += "\n\n" + "\n".join(f"- {n}" for n in seen)
    summary = _summary(rows_l)
    if summary:
        text += "\n\n" + summary
    return text
