"""Backend agreement: analytic, coal and python-fcl on built-in and public robots, through ``armguard compare``.

For each model, ``run_compare`` (the harness behind ``armguard compare``) answers the same seeded
random in-limit configurations (plus the canned trajectories' samples at 1 Hz) with every backend
and compares them pair by pair.  Per backend pair: verdict and sign disagreements, the distance
differences on separated and on penetrating entries, and the witness-contract violations on each
side (``docs/backends.md`` defines them); per backend: µs per configuration with distances and
yes/no configurations per second, measured in the same process.  python-fcl is left out where it
is not installed.  One model per ``run_compare`` call, one after another, in this process.
"""

from __future__ import annotations

import time

TITLE = "Backend agreement: analytic, coal and python-fcl through armguard compare"
MODELS = ("ranger", "hermes", "panda", "ur5", "kuka_iiwa", "z1")
"""Two built-ins (capsules, boxes, hulls; Hermes's payload and vehicle) and four public robots:
panda and ur5 (example-robot-data, mesh hulls), the iiwa (pybullet_data, mesh hulls) and z1
(example-robot-data: cylinders and two gripper hulls of 3,193 and 6,877 vertices)."""


def _e(x) -> str:
    return "—" if x is None else f"{x:.1e}"


def _judged(p: dict) -> str:
    """The reference's word on a backend pair's worst distance entries beyond tolerance: how many, and
    each side's largest error against it (``harness._compare.reference_distance``)."""
    refs = [w["slow_reference"] for w in p["worst"] if w.get("slow_reference", {}).get("distance") is not None]
    if not refs:
        return "— (none beyond tolerance)"
    return f"{len(refs)}: " + ", ".join(f"{b} off ≤ {max(r['error'][b] for r in refs):.1e}" for b in (p["a"], p["b"]))


def run(quick: bool) -> str:
    return tables(MODELS, 1000 if quick else 10_000)


def tables(models, n: int) -> str:
    """The timings and agreement tables (Markdown) over ``models`` at ``n`` random configurations each."""
    from armguard.backends import available
    from armguard.harness import run_compare
    from armguard.model import known_models

    installed = {m.name for m in known_models() if m.available}
    backends = ("analytic", "coal", "fcl") if "fcl" in available() else ("analytic", "coal")
    times = ["| model | configurations | pairs | " + " | ".join(f"{b} µs/config" for b in backends) + " | "
             + " | ".join(f"{b} yes/no per s" for b in backends) + " | wall |",
             "|---|---|---|" + "---|" * (2 * len(backends)) + "---|"]
    agree = ["| model | backends | verdicts ≠ (outside band / in band) | sign ≠ | separated |Δd| max / p99 (m) "
             "| penetrating |Δd| max / p99 (m) | witness contract ✗ (a; b) | the slow reference on the worst entries |",
             "|---|---|---|---|---|---|---|---|"]
    for name in models:
        if name not in installed:
            times.append(f"| {name} | not installed |" + " |" * (2 * len(backends) + 2))
            continue
        t0 = time.perf_counter()
        comp = run_compare(name, backends, n_configs=n, seed=0, trajectories="all", plots=False)
        wall = time.perf_counter() - t0
        s = comp.summary
        b = s["backends"]
        n_pairs = next(iter(s["pairs"].values()))["categories"]["all"]["pairs"]
        times.append(f"| {name} | {s['configs']['total']} | {n_pairs} | "
                     + " | ".join(f"{b[x]['us_per_config']:.1f}" for x in backends) + " | "
                     + " | ".join(f"{b[x]['yes_no_configs_per_s'] / 1e3:.1f} k" for x in backends) + f" | {wall:.0f} s |")
        for key, p in s["pairs"].items():
            c = p["categories"]["all"]
            wc = c["witness_contract"]
            agree.append(
                f"| {name} | {key} | {p['verdict_disagreements']} / {p['verdict_disagreements_in_band']} "
                f"| {c['sign_disagreements']} | {_e(c['separated']['max'])} / {_e(c['separated']['p99'])} "
                f"| {_e(c['penetrating']['max'])} / {_e(c['penetrating']['p99'])} "
                f"| {wc[p['a']]['violations']}/{wc[p['a']]['checked']}; {wc[p['b']]['violations']}/{wc[p['b']]['checked']} "
                f"| {_judged(p)} |")
    note = (f"\n\n{n} seeded random configurations per model (seed 0) plus the canned trajectories' samples at 1 Hz; "
            "|Δd| over (configuration, pair) entries, *separated* where both distances are above the contact band "
            "(1e-6 m), *penetrating* where both are below its negative. Reproduce one model: `armguard compare NAME "
            f"--backends {','.join(backends)} --configs {n}` (its per-category table and its worst configurations, "
            "each with a one-line command). What the columns mean: [backends.md](backends.md#what-is-measured). "
            "*The slow reference on the worst entries*: of the 5 largest |Δd| entries, those beyond the pair's "
            "tolerance, with each side's largest error against the support-function reference (no GJK, no EPA: "
            "[backends.md](backends.md#what-is-measured)), which says which side is off. "
            "The µs per configuration are each backend's `pair_distances` from Python: coal's is mostly the reading "
            "of its results through Pinocchio's bindings (its C++ core alone: the Backends section), fcl's yes/no "
            "computes each pair's distance until the first within the margin.")
    return "\n".join(times) + "\n\n" + "\n".join(agree) + note
