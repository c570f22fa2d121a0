"""``armguard compare MODEL`` (the backend harness) and ``armguard check-urdf PATH`` (the model linter)."""

from __future__ import annotations

import math
import sys

import click
import numpy as np

from . import main
from ._params import AT_LEAST_ONE, BACKENDS, COUNT, FilePath, POSITIVE, SAMPLES, SEED, refuse_unused
from ._exit import ExitCode, exit_epilog
from ._output import count, esc, json_text, output_console


def _floats(text: str) -> list:
    """--q's values; a value that is not a finite number is a usage error (exit status 2, as
    check's and fk's --q)."""
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise click.BadParameter(f"expected comma-separated numbers, got {text!r}", param_hint="--q") from None
    for k, v in enumerate(vals):
        if not math.isfinite(v):
            raise click.BadParameter(f"value {k + 1} of {len(vals)} = {v}: every value must be finite", param_hint="--q")
    return vals


def _pin_q(model, vals: list) -> list:
    """--q as Pinocchio's ``q``: its ``nq`` values as given, or, on a model with continuous joints, one angle
    a joint in the scene's order (as check's --q) turned into Pinocchio's (``Model.pin_q``); any other
    count is a usage error naming the layout (exit status 2, as check's --q)."""
    if len(vals) == model.nq:
        q = vals
    elif model.has_continuous_joints and len(vals) == len(model.q_index):
        q = model.pin_q(vals).tolist()
    else:
        raise click.BadParameter(f"expected {model.q_layout(len(vals))}, got {len(vals)} values", param_hint="--q")
    from .._errors import ArmguardError

    try:  # outside the limits: a usage error as check's --q (it was exit 3 here)
        model.check_pin_limits(np.asarray(q, dtype=np.float64), "q")
    except ArmguardError as exc:
        raise click.BadParameter(str(exc).removeprefix("q: "), param_hint="--q") from None
    return q


@main.command("compare", epilog=exit_epilog(ok="the backends agree (--q: answered)", unsafe="a backend pair differs",
                                           incomplete="a backend refused some configurations; the others agree"))
@click.argument("model")
@click.option("--backends", type=BACKENDS, default="analytic,coal", show_default=True, help="Comma-separated backends to compare.")
@click.option("--configs", "n_configs", type=SAMPLES, default=1000, show_default=True, help="Seeded random in-limit configurations.")
@click.option("--trajectory", "trajectories", multiple=True, default=("all",), show_default=True,
              help="Canned trajectories whose samples are added: a name (repeatable), 'all' or 'none'.")
@click.option("--frequency", type=POSITIVE, default=1.0, show_default=True, help="Trajectory sampling rate (Hz).")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of the random configurations.")
@click.option("--out", "out_dir", type=FilePath(file_okay=False), default=None, help="Write compare.json and PNGs here.")
@click.option("--backend-option", "backend_options", multiple=True, metavar="B.KEY=VALUE",
              help="An option of one backend, e.g. analytic.fidelity=paper (repeatable).")
@click.option("--workers", type=AT_LEAST_ONE, default=None, help="Spread the configurations over a Dask LocalCluster of N processes.")
@click.option("--scheduler", default=None, help="... or over an existing Dask cluster (scheduler address).")
@click.option("--no-plots", is_flag=True, help="Skip the PNGs.")
@click.option("--worst", "n_worst", type=COUNT, default=5, show_default=True, help="Worst configurations listed per backend pair.")
@click.option("--q", "q_text", default=None, help="Answer at this one configuration instead: Pinocchio's q (comma-separated), or one angle a joint in "
              "the scene's order where joints are continuous.")
@click.option("--pair", "pair_text", default=None, help="With --q: only this pair (A,B GeometryObject names).")
@click.option("--json", "as_json", is_flag=True, help="Print compare.json (or the --q answers) instead of tables.")
def compare_cmd(model, backends, n_configs, trajectories, frequency, seed, out_dir, backend_options, workers, scheduler,
                no_plots, n_worst, q_text, pair_text, as_json) -> None:
    """Compare BACKENDS on MODEL (a built-in or public robot name -- `armguard info` lists them -- or a
    .urdf/.yaml path): verdicts, distances, nearest points and timings on the same configurations.
    With --out, compare.json and the PNGs are written as one set: an interrupted or failed run leaves
    the previous run's set as it was."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from ..harness import compare_at, parse_backend_options, run_compare, summary_table
    from ..harness._models import resolve_model

    from .._errors import ArmguardError

    console = output_console()
    names = tuple(b.strip() for b in backends.split(",") if b.strip())
    try:  # a malformed option is a usage error (2), as every other bad option, not a refused file (3)
        options = parse_backend_options(backend_options)
    except ArmguardError as exc:
        raise click.BadParameter(str(exc).removeprefix("--backend-option "), param_hint="--backend-option") from None
    if pair_text is not None and q_text is None:  # it was ignored: the whole comparison ran
        raise click.UsageError("--pair answers one pair at one configuration: give --q as well")
    if q_text is not None and out_dir is not None:  # nothing was written, and nothing said so
        raise click.UsageError("--out writes a comparison's compare.json and plots; --q answers one configuration on "
                               "the terminal (add --json for JSON): drop --out, or --q")
    if q_text is not None:  # one configuration: the comparison's own options do not apply
        refuse_unused(click.get_current_context(), ["n_configs", "trajectories", "frequency", "seed", "workers",
                                                    "scheduler", "no_plots", "n_worst"],
                      "belongs to a comparison over many configurations; --q answers one")
    if q_text is None and (len(names) < 2 or len(set(names)) != len(names)):
        raise click.BadParameter(f"give at least two backends to compare, each once, got {list(names)}",
                                 param_hint="--backends")
    if workers is not None and scheduler is not None:
        raise click.UsageError("give --workers (a new LocalCluster) or --scheduler (an existing cluster), not both")
    if q_text is not None:
        pair = tuple(p.strip() for p in pair_text.split(",")) if pair_text else None
        the_model = resolve_model(model)
        rows = compare_at(model, names, _pin_q(the_model, _floats(q_text)), options=options, pair=pair, model=the_model)
        if as_json:
            click.echo(json_text(rows, indent=1))
            return
        for r in rows:
            console.print(f"[bold]{esc(r['pair'][0])} / {esc(r['pair'][1])}[/bold] ({r['category']})")
            for b in names:
                ans = r[b]
                if isinstance(ans, dict):  # a verdicts-only backend answers a verdict, not a distance
                    console.print(f"  {b:10s} " + "  ".join(f"{k} = {v}" for k, v in ans.items()), soft_wrap=True)
                    continue
                d, pa, pb = ans
                console.print(f"  {b:10s} d = {d!r} m  p_WA = {pa}  p_WB = {pb}", soft_wrap=True)
            if "slow_reference" in r:
                console.print(f"  {_reference_line(r['slow_reference'], exact=True)}", soft_wrap=True, markup=False)
        return
    traj = list(dict.fromkeys(trajectories))  # a name given twice is sampled once
    for word in ("all", "none"):
        if word in traj and len(traj) > 1:
            raise click.BadParameter(f"'{word}' stands alone, got {traj}", param_hint="--trajectory")
    traj = "all" if traj == ["all"] else (None if traj == ["none"] else traj)
    with Progress(TextColumn("answering"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), TimeRemainingColumn(),
                  console=console, transient=True, disable=as_json) as bar:
        task = bar.add_task("configs", total=None)
        comp = run_compare(model, names, n_configs=n_configs, seed=seed, trajectories=traj, frequency=frequency,
                           options=options, workers=workers, scheduler=scheduler, out_dir=out_dir, plots=not no_plots,
                           n_worst=n_worst, progress=lambda done, total: bar.update(task, completed=done, total=total))
    if as_json:
        click.echo(json_text(comp.summary, indent=1, default=str))
    else:
        for t in summary_table(comp):
            console.print(t)
        for key, p in comp.summary["pairs"].items():
            bad = [w for w in p["worst"] if w["why"] == "verdict"] + [w for w in p["worst"] if w["why"] == "distance"][:n_worst]
            if bad:
                console.print(f"[bold]{key}: worst configurations[/bold]")
            for w in bad:
                a, b = p["a"], p["b"]
                console.print(f"  {w['why']:8s} #{w['config']} ({w['source']}) {esc(w['pair'][0])} / {esc(w['pair'][1])}: "
                              f"{a} {w[a]['distance']:.6e} m, {b} {w[b]['distance']:.6e} m")
                if "slow_reference" in w:  # the slow reference's word on who is off (harness._compare)
                    console.print(f"    {_reference_line(w['slow_reference'])}", markup=False)
                console.print(f"    {w['reproduce']}", style="dim", soft_wrap=True, markup=False)
        tm = comp.summary["timing"]
        console.print(f"{comp.summary['configs']['total']} configurations: answers {tm['answers_s']:.1f} s, "
                      f"comparison {tm['compare_s']:.1f} s" + (f", outputs {tm['outputs_s']:.1f} s in {out_dir}" if out_dir else ""))
    refused = comp.summary["configs"].get("refused", 0)
    if refused and not as_json:
        console.print(f"[bold]{refused} of {comp.summary['configs']['drawn']} configurations refused by a backend, left "
                      "out of the comparison[/bold]; the first:")
        for r in comp.summary["refused"]:
            console.print(f"  #{r['config']}: {r['message']}", markup=False, soft_wrap=True)
    if any(p["status"] != "agree" for p in comp.summary["pairs"].values()):
        sys.exit(int(ExitCode.UNSAFE))
    if refused:  # the others agree: not a whole comparison
        sys.exit(int(ExitCode.INCOMPLETE))


def _reference_line(ref: dict, exact: bool = False) -> str:
    """The terminal line of the slow reference's answer (``harness.reference_distance``, judged)."""
    if ref["distance"] is None:
        return f"reference  not available ({ref['why']})"
    d = repr(ref["distance"]) if exact else f"{ref['distance']:.6e}"
    errs = ", ".join(f"{b} off {e:.1e} m" for b, e in ref["error"].items()) or "no backend here answers distances"
    return f"reference  d = {d} m ({ref['method']}): {errs}"


@main.command("check-urdf", epilog=exit_epilog(ok="no error-level finding", unsafe="an error-level finding"))
@click.argument("path")
@click.option("--configs", "n_configs", type=SAMPLES, default=200, show_default=True,
              help="Random configurations for the permanent-collision check.")
@click.option("--json", "as_json", is_flag=True, help="Print the findings as JSON.")
def check_urdf_cmd(path, n_configs, as_json) -> None:
    """Lint a model (a built-in name, .urdf or .yaml): dropped collision elements, non-convex meshes marked
    convex, zero-length capsules, SRDF names that match nothing, disabled pairs whose certificate (armguard srdf)
    an edit broke -- searched again, with the configuration where they now collide -- pairs in permanent collision,
    misspelt or repeated elements, joints a limit freezes, and values in other units (rpy or limits in degrees,
    a millimetre mesh read as metres)."""
    from rich.table import Table

    from pathlib import Path

    from .._errors import SceneFileError
    from ..harness import check_model_files

    if (Path(path).suffix or "/" in path) and not Path(path).exists():
        # nothing to lint is "could not check" (3), not an error-level finding (1)
        raise SceneFileError(str(path), "", "file not found")
    report = check_model_files(path, n_configs=n_configs)
    if as_json:
        click.echo(json_text(report.to_dict(), indent=1))
    else:
        console = output_console()
        if not report.findings:
            console.print(f"[green]{esc(report.target)}: clean[/green] ({esc(report.summary)})")
        else:
            t = Table(title=f"{esc(report.target)}: {count(len(report.findings), 'finding')}", title_justify="left")
            for col in ("severity", "check", "where", "finding", "suggestion"):
                t.add_column(col, overflow="fold")
            for f in report.findings:
                t.add_row(f.severity.value, f.check.value, esc(f.where), esc(f.message), esc(f.suggestion or ""))
            console.print(t)
    if report.status.value == "errors":
        sys.exit(int(ExitCode.UNSAFE))
