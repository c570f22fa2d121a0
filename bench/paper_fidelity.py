"""The papers' minimalist checkers measured against coal: how often and by how much they differ.

For Ranger and Hermes, over 10^4 uniform in-limit configurations (``model.random_q(N, seed)``):
per pair category, the paper checker's nearest distance (``armguard.checker(model, "analytic",
{"fidelity": "paper"})``) against coal's (``armguard.checker(model, "coal")``): |Δd| quantiles,
the share of configurations whose nearest distance or nearest pair is wrong, verdict
disagreements at the model's thresholds, Hermes's link–obstacle yes/no against coal's, the worst
configurations with a one-line reproduction, and the per-configuration cost of paper, exact and
coal.  Writes the tables into ``docs/paper-fidelity.md`` (between its ``paper_fidelity:tables``
markers) and returns the cost table for ``docs/performance.md``.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .timing import fmt_ns, median_seconds

TITLE = "Paper fidelity: the Ranger (1997) and Hermes minimalist checkers against coal"
PAGE = Path(__file__).resolve().parent.parent / "docs" / "paper-fidelity.md"
_MARK = re.compile(r"<!-- paper_fidelity:tables -->.*?<!-- /paper_fidelity:tables -->", re.S)
SEEDS = {"ranger": 1, "hermes": 2}
HERMES_MAX_STOPPING = 0.1  # m: "the maximum value of the stopping distance be 100 mm" (seed 001, §4)


def _thresholds(m) -> list[float]:
    tests = sorted({float(t.threshold) for t in m.scene.canned_tests.values()})
    return [0.0] + (tests if tests else [HERMES_MAX_STOPPING])


def _pct(x) -> str:
    x = float(np.mean(x)) * 100
    return "0" if x == 0 else (f"{x:.2f} %" if x < 10 else f"{x:.1f} %")


def _mm(x) -> str:
    return f"{x * 1e3:.3g} mm" if x >= 1e-6 else ("0" if x == 0 else f"{x * 1e6:.2g} µm")


def _measure(name: str, n: int, tol):
    import armguard

    m = armguard.load_model(name)
    paper = armguard.checker(m, "analytic", {"fidelity": "paper"})
    coal = armguard.checker(m, "coal")
    exact = armguard.checker(m, "analytic")
    seed = SEEDS[name]
    Q = m.random_q(n, seed)
    Dp = paper.paper_distances_many(Q)
    Dc = np.array([coal.pair_distances(q).distance for q in Q])
    cat = np.asarray(m.pairs.category)
    meth = np.asarray(paper.methods)
    stats, verdicts, worst = [], [], []
    for c in dict.fromkeys(m.pairs.category):
        idx = np.flatnonzero(cat == c)
        kp, kc = idx[Dp[:, idx].argmin(1)], idx[Dc[:, idx].argmin(1)]
        rows = np.arange(n)
        dp, dc = Dp[rows, kp], Dc[rows, kc]
        err = np.abs(dp - dc)
        wrong_d = err > tol
        wrong_pair = Dc[rows, kp] - dc > tol  # the paper's nearest pair is not a nearest pair for coal
        methods = sorted({s.split(" (")[0] for s in meth[idx]})
        sep = dc >= 0.0  # coal: the category is separated (proximity, not collision)
        es = err[sep] if sep.any() else np.zeros(1)
        stats.append((c, len(idx), methods, np.quantile(err, [0.5, 0.9, 0.99]), err.max(), wrong_d, wrong_pair,
                      dp < dc - tol, sep, wrong_d[sep], np.quantile(es, 0.99), es.max()))
        for T in _thresholds(m):
            verdicts.append((c, T, dc <= T, (dc <= T) & (dp > T), (dp <= T) & (dc > T)))
        k = int(err.argmax())
        worst.append((c, k, Q[k], m.pairs.names[kp[k]], dp[k], meth[kp[k]], m.pairs.names[kc[k]], dc[k],
                      Dp[k, kc[k]], meth[kc[k]]))
    yn = []
    for margin in sorted({0.0, HERMES_MAX_STOPPING}):
        hp, hc = paper.collides(Q, margin=margin), coal.collides(Q, margin=margin)
        yn.append((paper.verdicts, margin, hc, hp, hc & ~hp, hp & ~hc))
    # cost per configuration
    Qt = Q[: min(n, 2000)]
    it = iter(range(10**9))
    one = lambda c: (lambda: c.pair_distances(Qt[next(it) % len(Qt)]))  # noqa: E731
    cost = {
        "paper batch": median_seconds(lambda: paper.paper_distances_many(Qt), repeat=5) / len(Qt),
        "paper yes/no": median_seconds(lambda: paper.collides(Qt), repeat=5) / len(Qt),
        "paper q": median_seconds(one(paper), repeat=5, number=200),
        "exact q": median_seconds(one(exact), repeat=5, number=200),
        "exact batch": median_seconds(lambda: exact.min_distance_many(Qt), repeat=5) / len(Qt),
        "exact yes/no": median_seconds(lambda: exact.collides(Qt), repeat=5) / len(Qt),
        "coal q": median_seconds(one(coal), repeat=3, number=50),
        "coal yes/no": median_seconds(lambda: coal.collides(Qt), repeat=3) / len(Qt),
    }
    return dict(name=name, m=m, n=n, seed=seed, stats=stats, verdicts=verdicts, worst=worst, yn=yn, cost=cost)


def _tables(res, tol) -> str:
    out = [f"Configurations: {res[0]['n']} per model, `model.random_q({res[0]['n']}, seed)` (ranger seed "
           f"{SEEDS['ranger']}, hermes seed {SEEDS['hermes']}). A distance is *wrong* when it differs from coal's by "
           f"more than {tol * 1e6:g} µm (`Tolerances.paper_agreement`); the nearest *pair* is wrong when coal puts "
           "the paper's nearest pair more than that above coal's nearest distance.", "",
           "### Nearest distance per category: paper vs coal", "",
           "| model | category | pairs | paper's method | abs Δd median | p90 | p99 | max | distance wrong | pair wrong "
           "| paper below coal | coal separated | of those: distance wrong | p99 | max |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res:
        for c, npairs, methods, q, mx, wd, wp, below, sep, wds, q99s, mxs in r["stats"]:
            out.append(f"| {r['name']} | {c} | {npairs} | {'; '.join(methods)} | {_mm(q[0])} | {_mm(q[1])} | {_mm(q[2])} "
                       f"| {_mm(mx)} | {_pct(wd)} | {_pct(wp)} | {_pct(below)} | {_pct(sep)} "
                       f"| {_pct(wds) if len(wds) else '–'} | {_mm(q99s)} | {_mm(mxs)} |")
    out += ["", "### Verdicts at the model's thresholds (nearest distance of the category ≤ threshold)", "",
            "| model | category | threshold | coal: within | paper misses (coal within, paper clear) "
            "| paper false alarms |", "|---|---|---|---|---|---|"]
    for r in res:
        for c, T, within, miss, false in r["verdicts"]:
            out.append(f"| {r['name']} | {c} | {T:g} m | {_pct(within)} | {int(miss.sum())} ({_pct(miss)}) "
                       f"| {int(false.sum())} ({_pct(false)}) |")
    out += ["", "### Yes/no per configuration: `collides(Q, margin)`, paper vs coal", "",
            "| model | paper verdict rule | margin | coal: colliding | paper: misses | paper: false alarms |",
            "|---|---|---|---|---|---|"]
    for r in res:
        for rule, margin, hc, hp, miss, false in r["yn"]:
            out.append(f"| {r['name']} | {rule} | {margin:g} m | {_pct(hc)} | {int(miss.sum())} ({_pct(miss)}) "
                       f"| {int(false.sum())} ({_pct(false)}) |")
    out += ["", "### The worst configuration of each category", "",
            "| model | category | config | paper: nearest pair, distance (method) | coal: nearest pair, distance "
            "| paper on coal's pair (method) |", "|---|---|---|---|---|---|"]
    snippets = []
    for r in res:
        for c, k, q, pp, dp, mp, pc, dc, dpc, mc in r["worst"]:
            out.append(f"| {r['name']} | {c} | {k} | {pp[0]} / {pp[1]}: {dp:.4f} m ({mp}) | {pc[0]} / {pc[1]}: "
                       f"{dc:.4f} m | {dpc:.4f} m ({mc}) |")
            snippets.append(f"# {r['name']} {c}, configuration {k}: q = {np.array2string(q, precision=3, separator=', ', max_line_width=10**4)}\n"
                            f".venv/bin/python -c \"import armguard as a; m = a.load_model('{r['name']}'); "
                            f"q = m.random_q({r['n']}, {r['seed']})[{k}]; "
                            f"[print(c.pair_distances(q).nearest()['{c}']) for c in (a.checker(m, 'analytic', "
                            "{'fidelity': 'paper'}), a.checker(m, 'coal'))]\"")
    out += ["", "Reproduce any of them (q in pin_model's order, rad):", "", "```sh", *snippets, "```"]
    return "\n".join(out)


def _cost(res) -> str:
    rows = ["| model | pairs | paper, batch (all pair distances) | paper, yes/no batch | paper `pair_distances(q)` "
            "| exact `pair_distances(q)` | exact `min_distance_many` | exact yes/no batch | coal `pair_distances(q)` "
            "| coal yes/no batch |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in res:
        t = r["cost"]
        rows.append(f"| {r['name']} | {len(r['m'].pairs)} | {fmt_ns(t['paper batch'])} | {fmt_ns(t['paper yes/no'])} "
                    f"| {fmt_ns(t['paper q'])} | {fmt_ns(t['exact q'])} | {fmt_ns(t['exact batch'])} "
                    f"| {fmt_ns(t['exact yes/no'])} | {fmt_ns(t['coal q'])} | {fmt_ns(t['coal yes/no'])} |")
    return "\n".join(rows) + (
        "\n\nPer configuration, medians. The paper kernel is serial and evaluates every pair (the papers' static "
        "obstacle lists, no pruning); the exact batches are the analytic backend's multi-threaded, pruned paths; "
        "`pair_distances(q)` is one call from Python with witness points.")


def run(quick: bool) -> str:
    from armguard import DEFAULT_TOLERANCES

    n = 500 if quick else 10_000
    tol = DEFAULT_TOLERANCES.paper_agreement
    res = [_measure(name, n, tol) for name in ("ranger", "hermes")]
    cost = _cost(res)
    tables = f"<!-- paper_fidelity:tables -->\n{_tables(res, tol)}\n\n### Cost per configuration\n\n{cost}\n" \
             "<!-- /paper_fidelity:tables -->"
    if not quick:
        text = PAGE.read_text(encoding="utf-8") if PAGE.exists() else "# Paper fidelity\n\n"
        text = _MARK.sub(lambda _: tables, text) if _MARK.search(text) else text.rstrip() + "\n\n" + tables + "\n"
        PAGE.write_text(text, encoding="utf-8")
    return cost + "\n\nThe fidelity tables (Ranger and Hermes, 10⁴ configurations against coal): " \
                  "[docs/paper-fidelity.md](paper-fidelity.md)."
