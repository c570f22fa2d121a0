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


def _names() -> list[str]:
    """Every built-in model, then every public robot found installed (the public-robot table's set);
    ``ARMGUARD_BENCH_ROBOTS=a,b`` (environment) for a subset, in the same order."""
    import os

    from armguard.model import known_models

    only = [n for n in os.environ.get("ARMGUARD_BENCH_ROBOTS", "").split(",") if n]
    ms = [m for m in known_models() if m.available and (not only or m.name in only)]
    return [m.name for m in ms if m.source == "built-in"] + [m.name for m in ms if m.source != "built-in"]


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
    from armguard.model._public import public_robot, public_robot_files
    from armguard.model._srdf import read_srdf
    from armguard.srdfgen import collision_matrix, pair_setup

    n_check = 10_000 if quick else 100_000
    rows = []
    notes = []
    for name in (QUICK_ROBOTS if quick else _names()):
        print(f"bench srdf: {name} ...", file=sys.stderr, flush=True)
        model = armguard.load_model(name, srdf=False)
        t = time.perf_counter()
        cm = collision_matrix(model, workers=2)
        t_cert = time.perf_counter() - t
        c = cm.counts()
        witnessed = {frozenset((e.link1, e.link2)) for e in cm.entries if e.status == "witnessed"}
        sampled = {}
        for n in ((10_000,) if quick else (10_000, 100_000)):
            sm = collision_matrix(model, method="sampled", samples=n)
            never = {frozenset((e.link1, e.link2)) for e in sm.entries if e.reason == "Never"}
            sampled[n] = (len(never), len(never & witnessed))
        shipped = "-"
        if public_robot(name) is not None:
            _, srdf = public_robot_files(name)
            if srdf is not None:
                dis = {frozenset((a, b)) for a, b, _ in read_srdf(srdf).disabled}
                bad = sorted(tuple(sorted(p)) for p in dis & witnessed)
                shipped = f"{len(bad)} of {len(dis)}"
                if bad:
                    notes.append(f"{name}: the shipped SRDF disables {', '.join(f'{a}-{b}' for a, b in bad)}, "
                                 "which the search witnesses colliding")
        setup = pair_setup(model)
        never_pairs = [p for p, e in zip(setup.pairs, cm.entries) if e.reason == "Never"]
        dmin = _coal_check(model, setup, never_pairs, n_check) if never_pairs else float("nan")
        s10 = sampled[10_000]
        s100 = sampled.get(100_000)
        rows.append(f"| {name} | {c['pairs']} | {t_cert:.1f} | {c['Adjacent']} / {c['Default']} / {c['Never']} | "
                    f"{c['witnessed']} | {c['undecided']} | {shipped} | {s10[0]} ({s10[1]}) | "
                    + (f"{s100[0]} ({s100[1]})" if s100 else "-") + f" | {n_check:.0e}: {dmin:.4f} |")
    head = ("| robot | link pairs | certified (s, 2 threads) | Adjacent / Default / Never (proven) | witnessed | undecided | "
            "shipped SRDF disables, witnessed colliding | sampled Never at 10^4 (of them witnessed) | at 10^5 | "
            "coal on proven-Never pairs: samples, least distance (m) |\n|---|---|---|---|---|---|---|---|---|---|")
    text = ("Certified: `collision_matrix(model, workers=2)` (analytic distances at box centres, at most 2*10^5 "
            "evaluations per pair); sampled: MoveIt's rule at 10^4 and 10^5 random configurations. A sampled-Never "
            "pair that the certified search witnesses colliding is one sampling would wrongly disable. The last column "
            "samples every proven-Never pair with coal: a distance <= 0 there would contradict a proof.\n\n"
            + head + "\n" + "\n".join(rows))
    if notes:
        text += "\n\n" + "\n".join(f"- {n}" for n in notes)
    return text
