"""The papers' minimalist checkers measured against coal: how often and by how much they differ.

For Ranger and Hermes, over 10^4 uniform in-limit configurations (``model.random_q(N, seed)``):
per pair category, the paper checker's nearest distance (``armguard.checker(model, "analytic",
{"fidelity": "paper"})``) against coal's (``armguard.checker(model, "coal")``): |Δd| quantiles,
the share of configurations whose nearest distance or nearest pair is wrong, verdict
disagreements at the model's thresholds, Hermes's yes/no (its four modules) against coal's, the worst
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


# ---------------------------------------------------------------- Hermes's modules, pair by pair (seed 001 §3-4)
HERMES_N = 10_000
HERMES_COUNT_RANDOM = 1000  # the paper's sample: "1,000 configurations, randomly chosen in the working area"
HERMES_CHECK_HZ = 1.7  # the paper's activation frequency; the trajectories are sampled at it
PAPER_OPS = {"mean": 1651, "sd": 195, "max": 6064, "flop": 11_000, "kflops": 18, "hz": 1.7, "growing": 325}
_HMARK = re.compile(r"<!-- paper_fidelity:hermes -->.*?<!-- /paper_fidelity:hermes -->", re.S)


def _hermes_modules(n: int):
    """Each Hermes module's per-pair verdicts against coal's distance <= margin, over ``n`` configurations."""
    import armguard
    from armguard_analytic._paper_hermes import BRANCHES

    m = armguard.load_model("hermes")
    paper = armguard.checker(m, "analytic", {"fidelity": "paper"})
    coal = armguard.checker(m, "coal")
    Q = m.random_q(n, SEEDS["hermes"])
    Dc = np.array([coal.pair_distances(q).distance for q in Q])
    mods = np.asarray(paper.hermes_modules)
    rad = paper._E[13]  # the elements' radii (m), as the kernels read them
    radii = rad[paper._H[1]] + rad[paper._H[2]]
    rows = []
    for margin in (0.0, HERMES_MAX_STOPPING):
        hit, d, br = paper.pair_verdicts_many(Q, margin=margin)
        per_cfg = (hit.any(axis=1), (Dc <= margin).any(axis=1))
        for mod in ("link-obstacle", "link-link", "payload-link", "payload-obstacle"):
            k = mods == mod
            h, c = hit[:, k], Dc[:, k] <= margin
            dd = d[:, k] - radii[k]  # the module's distance, less both radii (link-link, payload-link)
            ok = np.isfinite(dd)
            err = np.abs(dd[ok] - Dc[:, k][ok]) if ok.any() else np.zeros(0)
            exits = np.bincount(br[:, k].ravel(), minlength=len(BRANCHES[mod]))
            rows.append((mod, int(k.sum()), margin, h.size, int(c.sum()), int(h.sum()), int((c & ~h).sum()),
                         int((h & ~c).sum()), float((h == c).mean()), err,
                         ", ".join(f"{b} {x / h.size * 100:.3g} %" for b, x in zip(BRANCHES[mod], exits) if x)))
        rows.append(("all (collides)", len(mods), margin, n, int(per_cfg[1].sum()), int(per_cfg[0].sum()),
                     int((per_cfg[1] & ~per_cfg[0]).sum()), int((per_cfg[0] & ~per_cfg[1]).sum()),
                     float((per_cfg[0] == per_cfg[1]).mean()), np.zeros(0), ""))
    return m, paper, rows


def _hermes_counts(m, paper, n_random: int):
    """Operation counts per check (every pair of the four modules, margin 0) over the built-in
    trajectories sampled at the paper's 1.7 Hz and over ``n_random`` random configurations."""
    from armguard_analytic._paper_count import FIELDS, count_rows, flop

    sets = {}
    Qt = []
    for name, tr in m.scene.trajectories.items():
        Qt.append(m.pin_q(tr.sample(frequency=HERMES_CHECK_HZ)[1]))
    sets[f"trajectories ({', '.join(m.scene.trajectories)}; {HERMES_CHECK_HZ} Hz)"] = np.vstack(Qt)
    sets[f"random ({n_random}, seed {SEEDS['hermes']})"] = m.random_q(n_random, SEEDS["hermes"])
    out = {}
    for label, Q in sets.items():
        counts, _ = count_rows(paper, Q)
        buckets = sorted({b for c in counts for b in c})
        tab = {b: np.array([[c.get(b, {}).get(f, 0) for f in FIELDS] for c in counts]) for b in buckets}
        fl = {b: np.array([flop(c.get(b, {})) for c in counts]) for b in buckets}
        out[label] = (len(Q), tab, fl)
    return out


def _mults(a):  # multiplications (divisions counted as multiplications, as the paper's count does)
    return a[:, 0] + a[:, 1]


def _hermes_text(rows, counts) -> tuple[str, str]:
    mods_t = ["| module | pairs | margin | pair-checks | coal: within | paper: hits | misses | false alarms "
              "| verdict agreement | distance abs Δd median | max | exits (share of pair-checks) |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for mod, k, margin, N, c, h, miss, false, agree, err, exits in rows:
        dm = (_mm(float(np.median(err))), _mm(float(err.max()))) if len(err) else ("–", "–")
        mods_t.append(f"| {mod} | {k} | {margin:g} m | {N} | {c} | {h} | {miss} | {false} | {agree * 100:.3f} % "
                      f"| {dm[0]} | {dm[1]} | {exits} |")
    P = PAPER_OPS
    ops = ["| configurations | multiplications per check: mean | SD | max | with kinematics: mean | SD | max "
           "| FLOP per check: mean | max | with kinematics: max | per-module-maximum bound | 18 kFLOPS → checks/s |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|",
           f"| Hermes §4 (1,000 random) | {P['mean']} | {P['sd']} | {P['max']} | – | – | – | – | ≈ {P['flop']:,} "
           f"(worst case) | – | – | {P['hz']} Hz |"]
    per_mod = ["| configurations | module | multiplications mean | max | sums mean | square roots mean "
               "| FLOP mean | max |", "|---|---|---|---|---|---|---|---|"]
    for label, (n, tab, fl) in counts.items():
        mods = [b for b in tab if b != "kinematics"]
        mul = sum(_mults(tab[b]) for b in mods)
        mulk = mul + _mults(tab["kinematics"])
        f = sum(fl[b] for b in mods)
        fk = f + fl["kinematics"]
        bound = sum(fl[b].max() for b in mods) + fl["kinematics"].max()
        ops.append(f"| {label}: {n} | {mul.mean():.0f} | {mul.std():.0f} | {mul.max()} | {mulk.mean():.0f} "
                   f"| {mulk.std():.0f} | {mulk.max()} | {f.mean():.0f} | {f.max():.0f} | {fk.max():.0f} "
                   f"| {bound:.0f} | {P['kflops'] * 1e3 / fk.max():.1f} Hz |")
        for b in ["kinematics"] + mods:
            t = tab[b]
            per_mod.append(f"| {label} | {b} | {_mults(t).mean():.0f} | {_mults(t).max()} | {t[:, 2].mean():.0f} "
                           f"| {t[:, 3].mean():.1f} | {fl[b].mean():.0f} | {fl[b].max():.0f} |")
    doc = ("### Hermes's four modules, pair by pair, against coal\n\n"
           f"`collides` with `verdicts = \"hermes\"`; {rows[0][3] // rows[0][1]} configurations "
           f"`model.random_q({rows[0][3] // rows[0][1]}, {SEEDS['hermes']})`, each pair's module verdict "
           "(`PaperChecker.pair_verdicts_many`) against coal's distance ≤ margin; Δd is the module's own "
           "distance less both radii against coal's (link–link: every pair-check; payload–link: where the "
           "sphere pre-test let it compute one); the last row of each margin is the per-configuration "
           "yes/no.\n\n" + "\n".join(mods_t) +
           "\n\n### Operation counts per check beside Hermes §4\n\n"
           "Every pair of the four modules at each configuration (margin 0, no early stop), counted by "
           "running the compiled kernels' own source on counting floats (`armguard_analytic._paper_count`; "
           "a division counts as a multiplication; FLOP weights as the paper's: multiplication 1, sum 1/3, "
           "square root 3, transcendental 7). *With kinematics* adds armguard's forward kinematics "
           "(generic 4×4 products, not the paper's DH matrices) and moving the end-points into W. The "
           "per-module-maximum bound adds each module's (and the kinematics') most expensive observed check, "
           "as if they coincided. "
           f"The paper: C = 11·f kFLOPS, so 18 kFLOPS run {P['kflops'] / 11:.2f} ≈ {P['hz']} checks/s; "
           f"its obstacle growing costs {P['growing']} FLOP (armguard's is one sum per face tested, inside "
           "the link–obstacle count).\n\n" + "\n".join(ops) + "\n\nPer module:\n\n" + "\n".join(per_mod))
    return doc, "\n".join(ops)


def run_hermes(quick: bool) -> str:
    """The Hermes module table and operation counts; writes them into docs/paper-fidelity.md (between
    its ``paper_fidelity:hermes`` markers) unless ``quick``; returns the counts table."""
    n = 300 if quick else HERMES_N
    m, paper, rows = _hermes_modules(n)
    counts = _hermes_counts(m, paper, 30 if quick else HERMES_COUNT_RANDOM)
    doc, ops = _hermes_text(rows, counts)
    if not quick:
        text = PAGE.read_text(encoding="utf-8")
        block = f"<!-- paper_fidelity:hermes -->\n{doc}\n<!-- /paper_fidelity:hermes -->"
        text = _HMARK.sub(lambda _: block, text) if _HMARK.search(text) else text.rstrip() + "\n\n" + block + "\n"
        PAGE.write_text(text, encoding="utf-8")
    return ops + "\n\nThe Hermes module table and the per-module counts: [docs/paper-fidelity.md](paper-fidelity.md)."
