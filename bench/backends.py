"""The backend plugins side by side: analytic vs coal vs python-fcl on the same Models.

Per model: µs per configuration for every pair's signed distance and witness points
(``checker.pair_distances(q)``), and yes/no configurations per second (``checker.collides(Q)``,
each backend's own batch path: the analytic one multi-threaded numba, coal's
``computeCollisionsInParallel`` over a GeometryPool, fcl one configuration at a time).
"""

from __future__ import annotations

import sysconfig
from pathlib import Path


from .timing import fmt_ns, median_seconds

TITLE = "Backends: analytic vs coal vs python-fcl on the same Model"

_ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"


def _models():
    import armguard

    out = [(n, lambda n=n: armguard.load_model(n)) for n in ("ranger", "hermes", "puma560", "gmf_s480", "rover")]
    panda = _ROBOTS / "panda_description"
    if panda.is_dir():
        out.append(("panda (hulls)", lambda: armguard.load_model(panda / "urdf/panda.urdf", srdf=panda / "srdf/panda.srdf")))
    return out


def run(quick: bool) -> str:
    import armguard

    n_pd = 50 if quick else 300
    n_yn = 2000 if quick else 20000
    rows = ["| model | pairs | analytic distances | coal distances | fcl distances | analytic yes/no | coal yes/no "
            "| fcl yes/no | coal / analytic (distances, yes/no) |",
            "|---|---|---|---|---|---|---|---|---|"]
    for name, load in _models():
        m = load()
        Q = m.random_q(n_pd, 1)
        Qy = m.random_q(n_yn, 2)
        t_pd, t_yn = {}, {}
        for b in ("analytic", "coal", "fcl"):
            c = armguard.checker(m, b)
            it = iter(range(10**9))
            t_pd[b] = median_seconds(lambda c=c: c.pair_distances(Q[next(it) % len(Q)]), repeat=5, number=len(Q) // 5)
            Qb = Qy if b != "fcl" else Qy[: max(50, len(Qy) // 50)]
            t_yn[b] = median_seconds(lambda c=c, Qb=Qb: c.collides(Qb), repeat=3) / len(Qb)
        rows.append(
            f"| {name} | {len(m.pairs)} | {fmt_ns(t_pd['analytic'])} | {fmt_ns(t_pd['coal'])} | {fmt_ns(t_pd['fcl'])} "
            f"| {1 / t_yn['analytic'] / 1e3:.0f} k/s | {1 / t_yn['coal'] / 1e3:.0f} k/s | {1 / t_yn['fcl'] / 1e3:.1f} k/s "
            f"| {t_pd['coal'] / t_pd['analytic']:.1f}×, {t_yn['coal'] / t_yn['analytic']:.1f}× |")
    note = (f"\n\nDistances: one `pair_distances(q)` per configuration ({n_pd} random in-limit configurations, "
            f"median of 5 runs), every active pair with witness points, from Python. Yes/no: `collides(Q)` "
            f"on {n_yn} configurations (fcl on a fiftieth of them). coal's reference runs GJK without guesses "
            "carried between configurations (see `plugins/armguard_coal`).")
    return "\n".join(rows) + note
