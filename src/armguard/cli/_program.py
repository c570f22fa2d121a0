"""``armguard program run|export|calibrate``: WORKMATE's off-line task programs (docs/program.md)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from . import main
from ._exit import ExitCode, exit_epilog
from ._params import PATH, SEED


@main.group("program")
def program() -> None:
    """Task programs (FIND, PICKUP, PLACE, MOVE): run them on an emulated cell, export them; calibrate the cell."""


@program.command("run", epilog=exit_epilog(
    ok="every motion verified (certified) and ran in the emulated cell",
    unsafe="a motion was refused (it would collide, or could not be verified) or a FIND failed: the program stopped there"))
@click.argument("file", type=PATH)
@click.option("--cell", default=None, metavar="CELL",
              help="A cell file (armguard_cell: 1), a model name or a scene file (default: the program's cell:).")
@click.option("--calibration", default=None, type=PATH,
              help="A calibration file (armguard_calibration: 1) to regenerate the cell from (default: the cell's).")
@click.option("--seed", default=0, show_default=True, type=SEED, help="Seed of the camera's FIND noise.")
@click.option("--save", default=None, type=PATH,
              help="Write the run (each motion's times and waypoints, each FIND's frames) as JSON.")
def run_cmd(file: str, cell: str | None, calibration: str | None, seed: int, save: str | None) -> None:
    """Run the task program FILE: expand each task through IK, verify every motion, emulate it."""
    from ..program import run_program

    if save:
        from .._io import check_writable

        check_writable(save, _inputs_of(file, cell, calibration))  # refused before the run (nothing is then lost)
    run = run_program(file, cell, seed=seed, calibration=calibration)
    click.echo(run.summary())
    if save:
        from .._io import atomic_write

        atomic_write(save, json.dumps(run.to_dict()), parents=True)  # whole or not at all; a FIFO or a full disk: exit 3
    sys.exit(int(ExitCode.OK if run.ok else ExitCode.UNSAFE))


@program.command("export")
@click.argument("file", type=PATH)
@click.option("--out", "out", required=True, type=PATH,
              help="The program to write (Python that calls armguard's workcell primitives).")
@click.option("--cell", default=None, metavar="CELL", help="The cell the exported program runs on by default.")
@click.option("--calibration", default=None, type=PATH,
              help="The calibration file the exported program regenerates its cell from by default.")
def export_cmd(file: str, out: str, cell: str | None, calibration: str | None) -> None:
    """Export the task program FILE as a workcell program (Python) that reproduces its motions."""
    from ..program import export_program

    from .._io import make_folder

    make_folder(Path(out).parent)  # a missing folder is made, as verify --report and compare --out make theirs
    path = export_program(file, out, cell=cell, calibration=calibration)
    click.echo(f"wrote {path}")


@program.command("calibrate", epilog=exit_epilog(
    ok="calibrated: every motion verified and ran, the camera saw every point, the calibration file written",
    unsafe="a motion was refused or the camera did not see the calibration object: nothing written"))
@click.argument("cell", type=PATH)
@click.option("--out", "out", default=None, type=PATH,
              help="The calibration file to write (default: the one the cell file names, updated in place).")
@click.option("--calibration", default=None, type=PATH,
              help="The calibration file to start from (default: the cell's; the nominal layout without one).")
@click.option("--points", default=12, show_default=True, type=click.IntRange(3, 200),
              help="Points of the trained trajectory in the camera's view.")
@click.option("--seed", default=0, show_default=True, type=SEED, help="Seed of the camera's FIND noise.")
def calibrate_cmd(cell: str, out: str | None, calibration: str | None, points: int, seed: int) -> None:
    """Calibrate the camera of the emulated cell CELL to its robot and write the calibration file.

    The arm takes the calibration object (the tool point) to POINTS poses in the camera's view,
    each motion verified before it runs; the camera FINDs it at each; the least-squares transform
    (Horn / Umeyama) with its covariance becomes the camera's relationship to the robot's base."""
    from ..program import calibrate_camera, load_cell, write_calibration

    c = load_cell(cell, calibration)
    target = out or (c.calibration.file if c.calibration is not None else None)
    if target is None:
        raise click.UsageError("the cell names no calibration file: give --out FILE")
    from .._io import check_writable

    check_writable(target, [cell])  # refused before the calibration, not after it (and never the cell file)
    result = calibrate_camera(c, n=points, seed=seed)
    click.echo(result.summary())
    if not result.ok:
        sys.exit(int(ExitCode.UNSAFE))
    from .._io import make_folder

    make_folder(Path(target).parent)
    path = write_calibration(result.calibration(), target)  # whole or not at all: a FIFO or a full disk is exit 3
    click.echo(f"wrote {path}")
    sys.exit(int(ExitCode.OK))


def _inputs_of(file, cell, calibration) -> list:
    """The files a run of the program ``file`` reads: the program, its cell file (``--cell``, else the one it
    names), the calibration file (``--calibration``, else the cell's); a file that does not read is left to the
    run to refuse."""
    from .._errors import ArmguardError

    inputs = [file, cell, calibration]
    try:
        from ..program import load_program
        from ..program._format import is_cell_file, read_cell

        named = cell if cell is not None else load_program(file).cell
        inputs.append(named)
        if calibration is None and named is not None and is_cell_file(named):
            inputs.append(read_cell(named).calibration)
    except (ArmguardError, OSError):
        pass
    return inputs
