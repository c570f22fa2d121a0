"""Every robot the two robot packages install, not only the arms: does it load, does it agree with coal.

The public-robot table (``bench robots``) measures the arms in depth.  This sweep takes every URDF
of example-robot-data and every URDF of pybullet_data with at least two movable joints (its
``random_urdfs`` objects left out): legged robots, humanoids, hands, grippers, mobile bases.  Each
runs in its own process (``python -m bench.sweep PATH N`` prints one JSON line):

* **load**: ``armguard.load_model(path)`` with the SRDF the search finds (the hull cache is the
  bench's own, filled by the process's first load);
* **fault**: where it does not load, the first line of the error (the file, the element, what is
  wrong there: a fault in the files, never a smaller model);
* **agreement**: on ``N`` random in-limit configurations, the verdicts (distance <= 0) where the
  analytic backend and coal differ, and the largest ``|d_analytic - d_coal|`` over pairs apart;
* **µs**: ``pair_distances(q)`` for each backend over the ``N`` configurations, thread CPU time,
  median of 3 interleaved runs.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

TITLE = "Every robot of example-robot-data and pybullet_data: load and agreement with coal"
REFERENCE_PER_KIND = 2
"""Pairs of each kind (per robot) whose depths differ by more than 1 mm that the slow reference checks."""


def _files() -> list[tuple[str, str]]:
    """``(package, path)`` of every URDF swept, in a stable order."""
    import xml.etree.ElementTree as ET
    from pathlib import Path

    from armguard.model._public import EXAMPLE_ROBOT_DATA, PYBULLET_DATA, package_root

    out = []
    for pkg in (EXAMPLE_ROBOT_DATA, PYBULLET_DATA):
        root = package_root(pkg)
        if root is None:
            continue
        for p in sorted(Path(root).rglob("*.urdf")):
            if pkg == PYBULLET_DATA:
                if "random_urdfs" in p.parts:
                    continue
                try:
                    joints = ET.parse(p).getroot().iter("joint")
                    if sum(j.get("type") in ("revolute", "prismatic", "continuous") for j in joints) < 2:
                        continue
                except ET.ParseError:
                    pass  # a robot file that does not parse is swept: its error is the finding
            out.append((pkg, str(p)))
    return out


def measure(path: str, n: int) -> dict:
    import warnings

    import numpy as np

    import armguard
    from armguard.geometry._support_reference import reference_signed_distance
    from armguard.model._shapes import placed_shapes

    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        try:
            m = armguard.load_model(path)
        except armguard.ArmguardError as exc:
            return {"fault": str(exc).splitlines()[0]}
    out = {"load_s": time.perf_counter() - t, "nq": m.pin_model.nq, "pairs": len(m.pairs)}
    if not len(m.pairs):
        return out
    a, c = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
    kind = {go.name: type(go.geometry).__name__ for go in m.collision_model.geometryObjects}
    Q = m.random_q(n, 7)
    dis, worst, depths, off, off_kinds, checked, ref_rows = 0, 0.0, 0, 0, set(), {}, []
    for q in Q:
        ra, rc = a.pair_distances(q), c.pair_distances(q)
        da, dc = ra.distance, rc.distance
        dis += int((da.min() <= 0) != (dc.min() <= 0))
        apart = (da > 1e-6) & (dc > 1e-6)
        worst = max(worst, float(np.abs(da - dc)[apart].max(initial=0.0)))
        inside = (da < -1e-6) & (dc < -1e-6)
        depths += int(inside.sum())
        for k in np.flatnonzero(inside & (np.abs(da - dc) > 1e-3)):
            off += 1
            kk = "-".join(sorted(kind.get(x, "?") for x in ra.pairs[k]))
            off_kinds.add(kk)
            if checked.get(kk, 0) < REFERENCE_PER_KIND:  # the slow reference decides (armguard.geometry._support_reference)
                checked[kk] = checked.get(kk, 0) + 1
                ref = reference_signed_distance(*placed_shapes(m, q, ra.pairs[k]))
                ref_rows.append((float(abs(da[k] - ref)), float(abs(dc[k] - ref))))
    ts = {"a": [], "c": []}
    for _ in range(3):
        for k, ch in (("a", a), ("c", c)):
            t = time.thread_time()
            for q in Q:
                ch.pair_distances(q)
            ts[k].append((time.thread_time() - t) / len(Q))
    return {**out, "disagree": dis, "max_dd": worst, "depths": depths, "depths_off": off,
            "off_kinds": sorted(off_kinds), "ref": ref_rows, "us_a": float(np.median(ts["a"])) * 1e6, "us_c": float(np.median(ts["c"])) * 1e6}


def _ref_cell(rows) -> str:
    """``n pairs: analytic at most x, coal y to z`` over the reference checks of ``rows``."""
    refs = [x for r in rows for x in r["ref"]]
    if not refs:
        return "—"
    a, c = [x[0] for x in refs], [x[1] for x in refs]
    return f"{len(refs)} pairs: at most {max(a):.0e} m; {min(c) * 1e3:.1f} mm to {max(c):.2f} m"


def run(quick: bool) -> str:
    import shutil
    import tempfile

    from bench.robots import _env

    n = 10 if quick else 50
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cache = tempfile.mkdtemp(prefix="armguard-bench-cache-")
    results = []
    try:
        for pkg, path in _files():
            proc = subprocess.run([sys.executable, "-m", "bench.sweep", path, str(n)], capture_output=True, text=True,
                                  timeout=900, cwd=root, env=_env(cache))
            lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
            r = json.loads(lines[-1]) if lines else {"crash": (proc.stderr.strip().splitlines() or ["no output"])[-1]}
            results.append((pkg, path, r))
            print(f"  {path}: {r}", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    summary = ["| package | URDFs | load | fault named in the files | crash | configurations | verdicts differing "
               "| max \\|Δd\\| apart | depths off > 1 mm (pair kinds) | of those, against the slow reference: analytic "
               "off by, coal off by | coal / analytic (median over robots) |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = ["| robot | package | nq | pairs | load | disagree (of N) | max \\|Δd\\| apart | depths off > 1 mm | analytic "
            "| coal | coal / analytic |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    import numpy as np

    for pkg in sorted({p for p, _, _ in results}):
        rs = [(path, r) for p, path, r in results if p == pkg]
        ok = [r for _, r in rs if "load_s" in r]
        checked = [r for r in ok if "disagree" in r]
        ratio = np.median([r["us_c"] / r["us_a"] for r in checked]) if checked else float("nan")
        summary.append(f"| {pkg} | {len(rs)} | {len(ok)} | {sum('fault' in r for _, r in rs)} "
                       f"| {sum('crash' in r for _, r in rs)} | {n * len(checked)} | {sum(r['disagree'] for r in checked)} "
                       f"| {max((r['max_dd'] for r in checked), default=0.0):.1e} m "
                       f"| {sum(r['depths_off'] for r in checked)} of {sum(r['depths'] for r in checked)} "
                       f"({', '.join(sorted({k for r in checked for k in r['off_kinds']})) or 'none'}) | {_ref_cell(checked)} "
                       f"| {ratio:.1f}× |")
        for path, r in rs:
            name = path.split("/robots/")[-1] if "/robots/" in path else path.split(f"{pkg}/")[-1]
            if "crash" in r or "fault" in r:
                what = r.get("fault") or f"crash: {r['crash']}"
                what = what.replace(path, "…")[:160].replace("|", "\\|")
                rows.append(f"| {name} | {pkg} | — | — | {what} ||||||")
            elif "disagree" not in r:
                rows.append(f"| {name} | {pkg} | {r['nq']} | 0 | {r['load_s']:.2f} s | no pair ||||||")
            else:
                rows.append(f"| {name} | {pkg} | {r['nq']} | {r['pairs']} | {r['load_s']:.2f} s | {r['disagree']} "
                            f"| {r['max_dd']:.1e} m | {r['depths_off']} of {r['depths']} | {r['us_a']:.1f} µs "
                            f"| {r['us_c']:.1f} µs | {r['us_c'] / r['us_a']:.1f}× |")
    note = (f"\n\nN = {n} random in-limit configurations a robot. *load*: `load_model(path)` in a fresh process, its "
            "first (every mesh hulled, `bench robots` times the later ones); a robot whose SRDF disables every pair, "
            "or with no collision shapes, has no pair to check. *fault*: the first line of the `SceneFileError`, "
            "which names the file, the element and what is wrong there; each was read in the file by hand "
            "(`tests/test_example_robot_data.py` lists example-robot-data's). *analytic*, *coal*: `pair_distances(q)` "
            "over the N configurations, thread CPU time, median of 3 interleaved runs (the humanoids' hundreds of "
            "pairs include many that never come near, which a Detector's culls skip). *depths off*: pairs both "
            "backends find overlapping whose depths differ by more than 1 mm, of all such pairs, and their kinds; up to "
            f"{REFERENCE_PER_KIND} of each kind a robot are checked against the slow support-function reference "
            "(`armguard.geometry._support_reference`: no GJK, no EPA), which gives each backend's error "
            "(`tests/test_example_robot_data.py` keeps romeo_laas_small's).\n\n")
    return "\n".join(summary) + note + "\n".join(rows)


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 50)))
