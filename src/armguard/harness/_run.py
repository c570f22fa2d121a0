"""``run_compare``: configurations -> every backend's answers -> the comparison -> compare.json, table, plots."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .._errors import ArmguardError
from ._compare import Comparison, compare_answers, judged, reference_distance, reference_of
from ._configs import build_configs
from ._evaluate import (answers_distances, build_checkers, check_finite, checked_distances, checked_verdicts, evaluate,
                        verdict_detail, where_of)
from ._models import resolve_model
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._verdicts import NA, code_names, verdict_tables

__all__ = ["run_compare", "write_outputs", "summary_table", "compare_at"]


def run_compare(spec, backends=("analytic", "coal"), *, n_configs: int = 1000, seed: int = 0, trajectories="all",
                frequency: float = 1.0, options=None, workers: int | None = None, scheduler: str | None = None,
                out_dir=None, plots: bool = True, progress=None, tol: Tolerances = DEFAULT_TOLERANCES,
                n_worst: int = 5, model=None) -> Comparison:
    """Compare ``backends`` on model ``spec`` (a built-in or public robot name -- ``panda``, ``ur10``,
    ``iiwa``... -- or a file path).

    Parameters
    ----------
    n_configs : int — seeded random in-limit configurations (``model.random_q(n_configs, seed)``)
    trajectories : "all" | None | name | names — canned trajectories whose samples (``frequency`` Hz) are added
    options : {backend: {key: value}} — each backend's options (``--backend-option b.key=value``)
    workers, scheduler : a fresh Dask LocalCluster of N single-threaded workers, or an existing scheduler
    out_dir : where ``compare.json`` and the PNGs go (None: nothing written)
    progress : callable(done, total) — configurations answered so far
    model : the loaded Model of ``spec`` (saves loading it again)

    Returns the :class:`Comparison`; ``summary["timing"]`` holds the wall times of the stages (s).
    """
    if isinstance(backends, str):  # "analytic,coal" (the CLI's text), not its characters
        backends = [b.strip() for b in backends.split(",") if b.strip()]
    backends = tuple(backends)
    if isinstance(n_configs, bool) or not isinstance(n_configs, (int, np.integer)) or n_configs < 0:
        raise ArmguardError(f"n_configs: expected an integer >= 0, got {n_configs!r}")
    if len(backends) < 2:
        raise ArmguardError(f"--backends: give at least two backends to compare, got {list(backends)}")
    if len(set(backends)) != len(backends):
        raise ArmguardError(f"--backends: each backend once, got {list(backends)}")
    options = {b: dict(v) for b, v in (options or {}).items()}
    for b in options:
        if b not in backends:
            raise ArmguardError(f"--backend-option for {b!r}, which is not among --backends {list(backends)}")
    if out_dir is not None:  # refused before the work, not after it (an unwritable --out lost the whole comparison)
        import itertools

        from .._io import check_target, check_writable

        check_writable(Path(out_dir) / "compare.json")
        if plots:  # a folder or FIFO at a plot's name failed the set's move after the whole comparison
            for a, b in itertools.combinations(backends, 2):
                for kind in ("scatter", "hist", "verdicts"):
                    check_target(Path(out_dir) / f"{kind}_{a}_{b}.png")
            check_target(Path(out_dir) / "timing.png")
    t0 = time.perf_counter()
    model = model if model is not None else resolve_model(spec)
    configs = build_configs(model, n_configs, seed, trajectories, frequency)
    if len(configs.Q) == 0:  # "agree" from no configuration is no verdict
        raise ArmguardError(f"no configuration to compare: n_configs = {n_configs} and no trajectory samples (give "
                            "--configs >= 1 or a trajectory)")
    t1 = time.perf_counter()
    refused: list = []  # configurations a backend refused: left out of the comparison, reported, never "agree" alone
    answers = evaluate(model, configs.Q, backends, options, spec=str(spec), workers=workers, scheduler=scheduler,
                       progress=progress, refused=refused)
    drawn = len(configs)
    if refused:
        configs = configs.dropping([r["config"] for r in refused])
    t2 = time.perf_counter()
    comp = compare_answers(model, configs, answers, spec=str(spec), options=options, tol=tol, n_worst=n_worst)
    comp.summary["configs"].update(drawn=drawn, refused=len(refused))  # random, trajectories: as drawn
    comp.summary["refused"] = refused[:n_worst]  # the first few, with their messages
    comp.summary["complete"] = not refused  # "agree" over some configurations only is not a whole comparison
    t3 = time.perf_counter()
    comp.summary["timing"] = {"load_and_configs_s": t1 - t0, "answers_s": t2 - t1, "compare_s": t3 - t2,
                              "workers": int(workers) if workers else None, "scheduler": scheduler}
    if out_dir is not None:
        _write_set(comp, out_dir, plots=plots, t_start=t3)
    return comp


def _jsonable(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    raise TypeError(f"not JSON: {type(x)}")


def write_outputs(comp: Comparison, out_dir, *, plots: bool = True) -> list:
    """``compare.json`` and (``plots``) the PNGs into ``out_dir``, as one set; returns the paths.

    All are written into a staging folder first and then renamed into place
    (:func:`armguard._io.output_set`): an interrupted or failed write leaves the previous run's
    set as it was, never a new ``compare.json`` beside old plots; the files of the previous set
    (its ``compare.json``'s ``outputs``) that this one lacks are removed.  OutputError names the
    path and the reason when the folder cannot be written."""
    return _write_set(comp, out_dir, plots=plots)


def _previous_outputs(out: Path) -> tuple:
    """The file names the ``compare.json`` in ``out`` lists as its set (none when it cannot be read,
    or is not a regular file: a FIFO there would block the read; output_set refuses it)."""
    try:
        if not (out / "compare.json").is_file():
            return ()
        names = json.loads((out / "compare.json").read_text(encoding="utf-8")).get("outputs", [])
    except (OSError, ValueError, AttributeError):
        return ()
    return tuple(n for n in names if isinstance(n, str)) if isinstance(names, list) else ()


def _non_finite(x, where: str = ""):
    """``(path, value)`` of the first NaN or infinite float in the summary ``x`` (dicts, lists), or None."""
    if isinstance(x, (float, np.floating)):
        return None if math.isfinite(x) else (where, float(x))
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, (list, tuple)) else ()
    for k, v in items:
        found = _non_finite(v, f"{where}[{k!r}]")
        if found is not None:
            return found
    return None


def _write_set(comp: Comparison, out_dir, *, plots: bool, t_start: float | None = None) -> list:
    from .._io import atomic_write, output_set
    from ._plots import write_plots

    out = Path(out_dir)
    for b in comp.summary["backends"].values():  # inf (an empty batch) is not JSON
        for k, v in list(b.items()):
            if isinstance(v, float) and not math.isfinite(v):
                b[k] = None
    bad = _non_finite(comp.summary)
    if bad is not None:  # refused before the folder is touched: the previous set stays as it was
        where, value = bad
        raise ArmguardError(f"{out / 'compare.json'}: summary{where} = {value!r} is not a finite number (JSON holds "
                            "none); nothing written")
    with output_set(out, stale=_previous_outputs(out)) as staging:
        names = [p.name for p in write_plots(comp, staging)] if plots else []
        comp.summary["outputs"] = ["compare.json", *names]
        if t_start is not None:
            comp.summary["timing"]["outputs_s"] = time.perf_counter() - t_start
        text = json.dumps(comp.summary, indent=1, allow_nan=False, default=_jsonable) + "\n"
        atomic_write(staging / "compare.json", text)
    return [out / n for n in comp.summary["outputs"]]


def _fmt(x, unit=1.0) -> str:
    return "—" if x is None else f"{x / unit:.2e}"


def summary_table(comp: Comparison):
    """Rich renderables: per backend pair and category, then per backend timings."""
    from rich.table import Table

    s = comp.summary
    tables = []
    for key, p in s["pairs"].items():
        if p.get("answers") == "verdicts":
            tables += verdict_tables(s, p)
            continue
        t = Table(title=f"{s['model']}: {p['a']} vs {p['b']} (reference {p['reference']}), {s['configs']['total']} "
                        f"configurations — {p['status']}", title_justify="left")
        for col in ("category", "pairs", "verdicts ≠", "sign ≠", "sep |Δd| max", "p99", "median", "pen |Δd| max",
                    "p99", "median", "unique |Δp| max", f"contract ✗ {p['a']}", f"contract ✗ {p['b']}"):
            t.add_column(col, justify="right" if col != "category" else "left")
        for c, r in p["categories"].items():
            up = r["unique_points"]
            upmax = max((v for v in (up["p_WA"]["max"], up["p_WB"]["max"]) if v is not None), default=None)
            wc = r["witness_contract"]
            t.add_row(c, str(r["pairs"]), str(r["verdict_disagreements"]), str(r["sign_disagreements"]),
                      _fmt(r["separated"]["max"]), _fmt(r["separated"]["p99"]), _fmt(r["separated"]["median"]),
                      _fmt(r["penetrating"]["max"]), _fmt(r["penetrating"]["p99"]), _fmt(r["penetrating"]["median"]),
                      _fmt(upmax), f"{wc[p['a']]['violations']}/{wc[p['a']]['checked']}",
                      f"{wc[p['b']]['violations']}/{wc[p['b']]['checked']}")
        t.caption = (f"yes/no verdict disagreements outside the contact band: {p['verdict_disagreements']} "
                     f"(inside: {p['verdict_disagreements_in_band']}); max |Δd| {p['max_abs_distance_error']:.3e} m; "
                     f"{p['b']}/{p['a']} time: distances {p['speed_ratio']['distances']:.2f}×, yes/no "
                     f"{p['speed_ratio']['yes_no']:.2f}×")
        tables.append(t)
    t = Table(title="timings (one process)", title_justify="left")
    for col in ("backend", "µs / configuration (distances)", "× fastest", "yes/no configurations/s", "× fastest"):
        t.add_column(col, justify="right" if col != "backend" else "left")
    for b, r in s["backends"].items():
        yn = r["yes_no_configs_per_s"]
        dist = (NA, "—") if r.get("answers") == "verdicts" else (f"{r['us_per_config']:.1f}", f"{r['distances_vs_fastest']:.2f}")
        t.add_row(b, *dist, "—" if yn is None else f"{yn:,.0f}",
                  "—" if r["yes_no_vs_fastest"] is None else f"{r['yes_no_vs_fastest']:.2f}")
    tables.append(t)
    return tables


def compare_at(spec, backends, q, *, options=None, pair=None, model=None) -> list:
    """Every backend's answer at one configuration ``q`` (pin order): rows ``{pair, category, backend: answer}``
    for ``pair`` (two GeometryObject names) or every pair.

    A distance backend's answer is ``(d, p_WA, p_WB)`` (m); a verdicts-only backend's is
    ``{"collides": bool, "verdict": name or None, "pair_verdict": name or None}`` (its three-valued
    answer for the configuration and for the row's pair, where it exposes them).  With ``pair``, the
    row also holds ``slow_reference``: the slow support-function reference's signed distance and each
    distance backend's error against it (:func:`._compare.reference_distance`).
    """
    from ..backends import check_q

    model = model if model is not None else resolve_model(spec)
    q = check_q(model, q)  # q="abc" was a raw ValueError; every backend's rule (shape, finite, limits) before any is built
    checkers = build_checkers(model, backends, options)
    res = {}
    n = len(model.pairs)
    for b, c in checkers.items():  # each answer checked as the comparison checks it (shape, type, finite)
        if answers_distances(c):
            d, pa, pb = checked_distances(b, c.pair_distances(q), n, None, q)
            check_finite(b, model, d[None], pa[None], pb[None], q[None], None)
            res[b] = SimpleNamespace(distance=d, p_WA=pa, p_WB=pb)
        else:
            det = verdict_detail(c, q[None], backend=b, where=where_of(None, q))
            res[b] = (bool(checked_verdicts(b, c.collides(q[None]), q[None], None)[0]), det)
    names = model.pairs.names
    rows = []
    for k in range(len(names)):
        if pair is not None and {names[k, 0], names[k, 1]} != set(pair):
            continue
        row = {"pair": (names[k, 0], names[k, 1]), "category": model.pairs.category[k]}
        for b, r in res.items():
            if isinstance(r, tuple):
                hit, det = r
                labels = code_names("map_forbidden" in det)
                row[b] = {"collides": hit, "verdict": labels[int(det["codes"][0])] if "codes" in det else None,
                          "pair_verdict": labels[int(det["pair_codes"][0, k])] if "pair_codes" in det else None}
            else:
                row[b] = (float(r.distance[k]), r.p_WA[k].tolist(), r.p_WB[k].tolist())
        if pair is not None:  # one pair asked for: the slow reference's word too (~20 ms), each backend's error
            row["slow_reference"] = judged(reference_distance(model, q, k),
                                      {b: row[b][0] for b in res if not isinstance(res[b], tuple)})
        rows.append(row)
    if pair is not None and not rows:
        raise ArmguardError(f"pair {tuple(pair)} is not an active pair of model {model.name!r}")
    return rows


# re-exported for callers that want the reference rule
reference_of = reference_of
