"""``armguard verify SCENE TRAJECTORY...``: verify trajectories (certified or sampled) and write reports."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from . import main
from ._params import AT_LEAST_ONE, LENGTH, PATH, PATH_OR_DASH, POSITIVE
from ._exit import ExitCode, exit_epilog
from ._output import esc, output_console
from .._errors import OutputError


def resolve_trajectories(scene, specs):
    """``(name, Trajectory)`` for each spec: a ``.yaml`` file, a canned trajectory or canned test of
    the scene, or ``all`` (every canned trajectory of the scene)."""
    from .._errors import VerificationError
    from ..verify import load_trajectory

    out = []
    for spec in specs:
        p = Path(spec)
        if spec == "all":
            out.extend((n, t) for n, t in scene.trajectories.items())
        elif p.suffix.lower() in (".yaml", ".yml") or p.exists():
            out.append((p.stem, load_trajectory(scene, p)))  # checked against the scene, errors located
        elif spec in scene.trajectories:
            out.append((spec, scene.trajectories[spec]))
        elif spec in scene.canned_tests:
            out.append((spec, scene.canned_tests[spec].trajectory(scene)))
        else:
            names = sorted(scene.trajectories) + sorted(scene.canned_tests)
            raise VerificationError(f"trajectory {spec!r}: not a .yaml file nor a canned trajectory of scene "
                                    f"{scene.name!r} (it has: {', '.join(names) or 'none'}; or 'all')")
    if not out:
        raise VerificationError(f"scene {scene.name!r} has no canned trajectory: give trajectory files "
                                "(.yaml, docs/trajectory-format.md; Trajectory.save_yaml writes one)")
    return _unique_names(out)


def _unique_names(items):
    """``items`` with a name repeated (two files ``a/ok.yaml``, ``b/ok.yaml``) made unique, ``ok``,
    ``ok_2``, ...: a report and a plot file per trajectory, none written over another's."""
    seen, out = set(), []
    for name, traj in items:
        new, k = name, 1
        while new in seen:
            k += 1
            new = f"{name}_{k}"
        seen.add(new)
        out.append((new, traj))
    return out


@main.command("verify", epilog=exit_epilog(
    ok="every trajectory safe", unsafe="a trajectory collides or violates the stopping distance",
    incomplete="none collides, but one could not be verified (incomplete)"))
@click.argument("scene")
@click.argument("trajectories", nargs=-1, required=True)
@click.option("--method", type=click.Choice(["certified", "sampled"]), default="certified", show_default=True,
              help="certified: proven between samples (never misses); sampled: Hermes's discrete checks.")
@click.option("--frequency", type=POSITIVE, default=None, help="Sampled mode: checks per second along the time law (Hz).")
@click.option("--joint-step", type=POSITIVE, default=None, help="Sampled mode: joint-space step (rad; default 0.05).")
@click.option("--stopping-distance", type=LENGTH, default=0.0, show_default=True, help="Obstacles grow by this (m).")
@click.option("--speed-dependent", is_flag=True,
              help="Hermes's stepwise stopping distance instead of a constant one: 10 speed ranges reaching "
                   "--stopping-distance at the trajectory's top speed, 0 at rest; each segment is split in 8 and "
                   "each eighth holds the distance of its own top speed (so a move from rest has its first "
                   "eighth's distance from t = 0).")
@click.option("--threshold", type=LENGTH, default=None, help="Warning threshold drawn on the plot (m; default 0.05).")
@click.option("--robot", default=None, help="The moving robot (default: the trajectory's).")
@click.option("--report", "report_path", type=PATH_OR_DASH, default=None,
              help="Write the JSON report here; '-': to standard output (the summaries then go to standard error).")
@click.option("--plot", "plot_path", type=PATH, default=None, help="Write a plot of clearance vs time here (.png, or .pdf, .svg; one file per trajectory, "
              "FILE_<trajectory>.png, when there are several).")
@click.option("--workers", type=AT_LEAST_ONE, default=None, help="Run on a Dask LocalCluster with N worker processes.")
@click.option("--scheduler", default=None, help="Run on an existing Dask cluster (scheduler address).")
@click.option("--terrain", "terrain_file", type=PATH, default=None,
              help="Also verify against a sensed terrain file (armguard.terrain.load_terrain; or a shipped terrain by "
                   "name: gentle, rocky, rough): the terrain sweep is "
                   "certified whatever --method (the scene's check follows --method), the trajectories verified here one "
                   "after another (not with --workers or --scheduler).")
def verify_cmd(scene, trajectories, method, frequency, joint_step, stopping_distance, speed_dependent, threshold, robot,
               report_path, plot_path, workers, scheduler, terrain_file) -> None:
    """Verify TRAJECTORIES (.yaml files, canned names of SCENE, or 'all') in SCENE."""
    import json

    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .._errors import ArmguardError, VerificationError
    from .._io import atomic_write, check_writable, figure_format
    from ..scene import load_scene
    from ..verify import verify_many

    from ._compile import warm_up
    from ._demo import verdict_text

    console = output_console()
    to_stdout = report_path == "-"
    if to_stdout:  # stdout is the JSON alone: the summaries and progress go to stderr
        from rich.console import Console

        console = Console(stderr=True)
    if frequency is not None and joint_step is not None:  # a usage error here (2), before the work
        raise click.UsageError("give --frequency or --joint-step, not both: --method sampled checks at one or the other")
    if method == "certified" and (frequency is not None or joint_step is not None):
        raise click.UsageError(f"{'--frequency' if frequency is not None else '--joint-step'} goes with --method sampled "
                               "(certified bounds every instant, with no step to choose)")
    if terrain_file is not None and (workers or scheduler):  # accepted and ignored before: said, before the work
        raise click.UsageError(f"{'--workers' if workers else '--scheduler'} does not go with --terrain: the terrain "
                               "sweep runs here, one trajectory after another; drop it, or verify without --terrain "
                               "on the cluster")
    if plot_path:
        figure_format(plot_path)  # a format matplotlib cannot write: refused before the work
    inputs = [t for t in trajectories if Path(t).is_file()] + [scene, terrain_file]
    sc = load_scene(scene)
    items = resolve_trajectories(sc, trajectories)
    planned = ([("--report", Path(report_path))] if report_path and not to_stdout else []) + \
        ([("--plot", _plot_file(plot_path, name, len(items))) for name, _ in items] if plot_path else [])
    seen: dict = {}
    for option, out in planned:  # every file the run writes: checked before the work, not after it
        other = seen.setdefault(out.resolve(), (option, out))
        if other != (option, out):
            raise click.UsageError(f"{other[0]} and {option} both write {out}: one would replace the other")
        check_writable(out, inputs)  # a folder that cannot be written, an input file: refused before the work
    warm_up(console=console)
    kwargs = dict(stopping_distance=stopping_distance, method=method, frequency=frequency, joint_step=joint_step,
                  robot=robot, threshold=threshold)
    if speed_dependent:
        if terrain_file is not None or workers or scheduler:
            raise click.UsageError("--speed-dependent runs here, serially: not with --terrain, --workers or --scheduler")
        if stopping_distance <= 0.0:
            raise click.UsageError("--speed-dependent needs --stopping-distance > 0 (m): the value at the top speed")
        reports = _speed_dependent(sc, items, kwargs)
    elif terrain_file is not None:  # the terrain category (armguard.terrain), trajectory by trajectory
        from ..terrain import verify_items

        reports = verify_items(sc, items, terrain_file, **kwargs)
    elif len(items) > 1 or workers or scheduler:
        done = [0]

        def step(n, total):
            done[0] = n
            bar.update(task, completed=n)

        try:
            with Progress(TextColumn("verifying"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                          console=console, transient=True) as bar:
                task = bar.add_task("verify", total=len(items))
                reports = verify_many(sc, items, workers=workers, scheduler=scheduler, progress=step, **kwargs)
        except KeyboardInterrupt:  # no verdict for the run: said with how far it got
            click.echo(f"\n{done[0]} of {len(items)} trajectories verified when interrupted; no report written, and no "
                       "verdict for the run", err=True)
            raise
        except ArmguardError as exc:  # which trajectory could not be verified (verify_many keeps the others' reports)
            i = getattr(exc, "failed_index", None)
            if i is None:
                raise
            done_n = sum(r is not None for r in exc.reports)
            raise VerificationError(f"trajectory {items[i][0]}: {exc} ({done_n} of {len(items)} verified; no report written, "
                                    "and no verdict for the run)") from None
    else:
        with console.status(f"verifying {items[0][0]}"):  # on a terminal a spinner (a long sampled run said nothing)
            reports = verify_many(sc, items, **kwargs)
    written = []  # the files first: a reader that closes the pipe early (| head) must not cost them
    if report_path:  # an output that cannot be written: OutputError, one line, exit status 3
        doc = reports[0].to_dict() if len(reports) == 1 else [r.to_dict() for r in reports]
        if to_stdout:
            click.echo(json.dumps(doc, indent=2))
        else:
            p = Path(report_path)
            atomic_write(p, json.dumps(doc, indent=2), parents=True)
            written.append(f"report: {p}")
    if plot_path:
        p = Path(plot_path)
        for r in reports:
            out = _plot_file(p, r.trajectory, len(reports))
            try:
                r.plot(out)
            except OutputError as exc:  # the files written before it stay: say which, never leave it to a guess
                if written:
                    raise OutputError(f"{exc}; written before it: {', '.join(w.split(': ', 1)[1] for w in written)}") \
                        from None
                raise
            written.append(f"plot: {out}")
    for r in reports:
        console.rule(f"[bold]{esc(r.trajectory)}[/] — {verdict_text(r)}")
        console.print(r.summary(), highlight=False, markup=False)
    for line in written:
        console.print(line)
    sys.exit(int(verify_exit_code(reports)))


def _plot_file(plot_path, trajectory: str, n: int) -> Path:
    """The plot of ``trajectory``: ``--plot FILE`` itself for one, ``FILE_<trajectory>`` for several."""
    p = Path(plot_path)
    return p if n == 1 else p.with_name(f"{p.stem}_{trajectory}{p.suffix or '.png'}")


def verify_exit_code(reports) -> ExitCode:
    """OK when every report is safe, UNSAFE when one found a collision (a stopping-distance violation
    included), else INCOMPLETE (one could not finish): a known collision outranks a missing verdict."""
    from ..verify import VerificationStatus

    if all(r.safe for r in reports):
        return ExitCode.OK
    if any(r.status is VerificationStatus.COLLISION for r in reports):
        return ExitCode.UNSAFE
    return ExitCode.INCOMPLETE


def _speed_dependent(sc, items, kwargs):
    """Each trajectory verified with Hermes's stepwise stopping distance up to ``kwargs``'s at its
    top speed (found by a plain verification first), on its segments split as ``armguard demo`` does."""
    from ..verify import Verifier
    from ..verify import Subdivided
    from ._demo import SUBDIVISIONS, hermes_table

    top = kwargs.pop("stopping_distance")
    reports = []
    for name, traj in items:
        v = Verifier(sc, robot=kwargs.get("robot") or traj.robot_name)
        plain = v.verify(traj, name=name, **kwargs)
        reports.append(v.verify(Subdivided(traj, SUBDIVISIONS), stopping_distance=hermes_table(plain.details.max_speed, top), name=name,
                                **kwargs))
    return reports

