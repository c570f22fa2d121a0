"""``armguard demo``: the main job of ``make run`` — verify every built-in scene's canned trajectories.

Each trajectory is verified as planned (stopping distance 0) and with Hermes's speed-dependent
stopping distance (001_…, §4: a stepwise function of speed, up to 100 mm "for maximum speed
movements", 10 ranges; zero at rest).  Hermes's table is looked up per interval from the peak
speed of the fastest point of the arm over it, so each trajectory segment is split into
:data:`SUBDIVISIONS` pieces of its own straight joint-space path: an arm starting from rest is
not charged the full-speed distance at t = 0.  The clearance is the verification's own: its
proven lower bound and the least clearance it evaluated, over the pairs that involve the moving
arm, up to the first collision.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from . import main
from ._params import FilePath, LENGTH
from ._output import esc, output_console
from .._errors import OutputError

#: Hermes (001_…, §4): "the maximum value of the stopping distance be 100 mm, i.e. the typical value
#: for maximum speed movements".
HERMES_MAX_STOPPING_DISTANCE = 0.1
HERMES_RANGES = 10
"""Speed ranges of Hermes's stepwise table."""
SUBDIVISIONS = 8
"""Pieces each trajectory segment is split into for the speed-dependent stopping distance."""
AT_REST = 1e-6
"""Speeds (m/s) up to this are at rest: stopping distance 0."""


def hermes_table(max_speed: float, max_distance: float = HERMES_MAX_STOPPING_DISTANCE, n_ranges: int = HERMES_RANGES):
    """Hermes's stepwise stopping distance up to ``max_speed`` (m/s), with 0 at rest (speeds up to
    :data:`AT_REST`): :meth:`armguard.verify.StoppingDistance.hermes`."""
    from ..verify import StoppingDistance

    vmax = max(float(max_speed), 2.0 * AT_REST * n_ranges)
    return StoppingDistance.hermes(vmax, max_distance, n_ranges, at_rest=AT_REST)


def clearance_text(r) -> str:
    """The clearance column from the verification itself: the proven lower bound over the verified path
    and the least clearance evaluated, both up to the first collision when there is one (a figure sampled
    along the whole trajectory would count depths past the contact, and a sampled minimum is never a bound)."""
    upto = f" before t = {r.first_collision.time:.2f} s" if r.first_collision is not None else ""
    if np.isfinite(r.min_clearance_lower_bound):
        return f"in [{r.min_clearance_lower_bound * 1e3:.1f}, {r.min_clearance * 1e3:.1f}] mm{upto}"
    return f"≤ {r.min_clearance * 1e3:.1f} mm{upto} (sampled: no lower bound)"


def first_collision_text(r) -> str:
    """The first collision, worded as a contact or as a stopping-distance violation."""
    c = r.first_collision
    if c is None:
        return "—"
    who = c.link or c.payload or c.a
    feat = f" {c.feature}" if c.feature is not None else ""
    p = c.p_W
    return f"{c.describe()}, {who} / {c.obstacle}{feat} at ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) m, t = {c.time:.2f} s"


def _file_stem(spec: str, scene) -> str:
    """A file-name stem for scene ``spec`` (a built-in name, or a scene file's own stem): never a path."""
    p = Path(spec)
    stem = p.stem if p.suffix.lower() in (".yaml", ".yml", ".urdf") or p.exists() else str(spec)
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in stem) or str(getattr(scene, "name", "scene"))


EXAMPLES = (
    ("python examples/workmate_demo.py",
     "WORKMATE's demonstration on the PUMA 560 cell: calibrate the camera to the robot, write the calibration "
     "file, stack a cylinder on another found by vision (every motion verified), generate the program; the "
     "placed cylinder's axis offset with and without calibration (docs/program.md)"),
    ("python examples/online_guard.py", "the on-line guard: a control loop that stops a 3-link arm before a thin rod, then lets a jog away through"),
    ("python examples/grasp_error.py",
     "the grasp error from a wrist force/torque sensor against noise and orientations (docs/program.md)"),
    ("python examples/prm_edges.py --plot prm_edges.png",
     "a probabilistic roadmap whose edges are certified, beside the same roadmap with sampled edges (edges through "
     "thin plates that sampling passes; docs/trajectory-format.md)"),
)
"""The demonstrations beside ``armguard demo`` (``armguard demo --list``): command, what it shows."""


def verdict_text(r) -> str:
    """The verdict column: SAFE, INCOMPLETE, COLLISION (a contact) or UNSAFE (stopping distance)."""
    v = r.verdict()
    colour = {"safe": "green", "collision": "red", "incomplete": "yellow"}.get(v, "dark_orange")
    head, _, tail = v.partition(" (")  # "unsafe (stopping distance)": the kind stays in lower case
    return f"[{colour}]{head.upper()}{' (' + tail if tail else ''}[/]"


def _mode_names(modes) -> list:
    """``(label, file-stem part)`` of each ``(mode, stopping distance)``: the distance in mm to 6 digits
    (``sd0.4mm``; ``sd0mm`` rounded 0.4 mm to 0 and overwrote the first report with the second), in m to
    the last digit where two would still read alike."""
    mm = [(mode, f"{sd * 1e3:.6g}") for mode, sd in modes]
    out = []
    for (mode, sd), (_, v) in zip(modes, mm):
        exact = mm.count((mode, v)) > 1
        unit = f"{sd!r} m" if exact else f"{v} mm"
        stem = f"{sd!r}m" if exact else f"{v}mm"
        out.append((f"Hermes ≤ {unit}", f"hermes{stem}") if mode == "hermes" else (unit, f"sd{stem}"))
    return out


@main.command("demo")
@click.option("--out", "out_dir", type=FilePath(file_okay=False), default="out", show_default=True,
              help="Where the JSON reports and PNG plots go.")
@click.option("--scene", "scenes", multiple=True, help="Only these built-in scenes (default: all).")
@click.option("--stopping-distance", "stopping_distances", type=LENGTH, multiple=True,
              help="Constant stopping distances to verify with (m); default: 0 and Hermes's speed-dependent table.")
@click.option("--list", "list_only", is_flag=True, help="List the demonstrations (this one and the examples) and exit.")
def demo_cmd(out_dir, scenes, stopping_distances, list_only) -> None:
    """Verify each built-in scene's canned trajectories (certified) and print a table.

    Each trajectory is verified as planned (stopping distance 0) and with Hermes's stopping
    distance, a stepwise function of speed up to 100 mm at the trajectory's top speed (0 at rest).
    ``--list`` names the other demonstrations (run from the source checkout).
    """
    if list_only:
        click.echo("armguard demo: certified verification of every built-in scene's canned trajectories")
        here = all((Path.cwd() / cmd.split()[1]).is_file() for cmd, _ in EXAMPLES)
        click.echo("the examples (from the root of the source checkout; a wheel installs none of them)"
                   + ("" if here else ": not found in this folder") + ":")
        for cmd, what in EXAMPLES:
            click.echo(f"{cmd}: {what}")
        return
    from rich.table import Table

    from .._io import check_target, check_writable, make_folder, output_set
    from ..models import builtin_names
    from ..scene import load_scene
    from ._compile import warm_up

    console = output_console()
    loaded = [(name, load_scene(name)) for name in scenes or builtin_names()]
    bare = [name for name, sc in loaded if not sc.trajectories]
    if scenes and bare:  # nothing to verify there: said, not an empty table and "reports and plots in out/"
        raise click.BadParameter(f"{', '.join(map(repr, bare))} has no canned trajectory to verify; the built-in scenes "
                                 f"have ({', '.join(builtin_names())}); for another model give trajectory files to "
                                 "`armguard verify` (docs/trajectory-format.md)", param_hint="--scene")
    out = make_folder(out_dir)  # OutputError (exit status 3) when it cannot be made
    table = Table(title="armguard: certified verification of the built-in scenes' canned trajectories")
    modes = [("fixed", sd) for sd in dict.fromkeys(float(x) for x in stopping_distances)]  # each value once
    modes = modes or [("fixed", 0.0), ("hermes", HERMES_MAX_STOPPING_DISTANCE)]
    names = _mode_names(modes)
    for col in ("scene", "trajectory", "stopping distance", "verdict",
                "first collision / stopping-distance violation: link / object feature at point, time",
                "least clearance (moving arm): [proven, evaluated]", "time"):
        table.add_column(col, overflow="fold")
    planned = [f"{_file_stem(name, sc)}__{tname}__{stem_sd}{ext}" for name, sc in loaded for tname in sc.trajectories
               for _, stem_sd in names for ext in (".json", ".png")]
    for k, f in enumerate(planned):  # a folder that cannot be written, a folder or FIFO at a name: refused now
        if k == 0:
            check_writable(out / f)
        else:
            check_target(out / f)
    warm_up(console=console)
    t_all = time.perf_counter()
    try:  # the files first (a reader closing the pipe early must not cost them), as one set: the previous run's
        with output_set(out) as staging:  # files are replaced at the end, whole, never half of them
            _demo_rows(loaded, modes, names, staging, table)
    except OutputError:
        console.print(table)  # the verdicts, then why their files could not be written
        raise
    console.print(table)
    console.print(f"reports and plots in {out}/ ({time.perf_counter() - t_all:.1f} s in all); "
                  "more demonstrations: armguard demo --list")


def _demo_rows(loaded, modes, names, out, table) -> None:
    """Verify every canned trajectory of ``loaded`` in each mode: a report and a plot in ``out``, a row of ``table``."""
    from ..verify import Subdivided, Verifier

    for name, sc in loaded:
        if not sc.trajectories:
            continue
        verifiers = {}
        for tname, traj in sc.trajectories.items():
            v = verifiers.get(traj.robot_name)
            if v is None:
                v = verifiers[traj.robot_name] = Verifier(sc, robot=traj.robot_name)
            for (mode, sd), (label, stem_sd) in zip(modes, names):
                t0 = time.perf_counter()
                if mode == "hermes":
                    plain = v.verify(traj, name=tname)
                    sdf = hermes_table(plain.details.max_speed, sd)
                    r = v.verify(Subdivided(traj, SUBDIVISIONS), stopping_distance=sdf, name=tname)
                else:
                    r = v.verify(traj, stopping_distance=sd, name=tname)
                dt = time.perf_counter() - t0
                table.add_row(esc(name), esc(tname), label, verdict_text(r), esc(first_collision_text(r)),
                              clearance_text(r), f"{dt * 1e3:.0f} ms")  # the row first: a failed write loses no verdict
                stem = f"{_file_stem(name, sc)}__{tname}__{stem_sd}"
                r.save_json(out / f"{stem}.json")  # each all or nothing (armguard._io.atomic_write)
                r.plot(out / f"{stem}.png")
