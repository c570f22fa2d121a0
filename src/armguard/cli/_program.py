"""``armguard program run|export``: WORKMATE's off-line task programs (docs/program.md)."""

from __future__ import annotations

import json
import sys

import click

from . import main
from ._exit import ExitCode, exit_epilog


@main.group("program")
def program() -> None:
    """Task programs (FIND, PICKUP, PLACE, MOVE): run them on an emulated cell, export them."""


@program.command("run", epilog=exit_epilog(
    ok="every motion verified (certified) and ran in the emulated cell",
    unsafe="a motion was refused (it would collide, or could not be verified) or a FIND failed: the program stopped there"))
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--cell", default=None, metavar="CELL",
              help="A cell file (armguard_cell: 1), a model name or a scene file (default: the program's cell:).")
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the camera's FIND noise.")
@click.option("--save", default=None, type=click.Path(dir_okay=False),
              help="Write the run (each motion's times and waypoints, each FIND's frames) as JSON.")
def run_cmd(file: str, cell: str | None, seed: int, save: str | None) -> None:
    """Run the task program FILE: expand each task through IK, verify every motion, emulate it."""
    from ..program import run_program

    run = run_program(file, cell, seed=seed)
    click.echo(run.summary())
    if save:
        from .._io import atomic_write

        atomic_write(save, json.dumps(run.to_dict()))  # whole or not at all; a FIFO or a full disk: exit 3
    sys.exit(int(ExitCode.OK if run.ok else ExitCode.UNSAFE))


@program.command("export")
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--out", "out", required=True, type=click.Path(dir_okay=False),
              help="The program to write (Python that calls armguard's workcell primitives).")
@click.option("--cell", default=None, metavar="CELL", help="The cell the exported program runs on by default.")
def export_cmd(file: str, out: str, cell: str | None) -> None:
    """Export the task program FILE as a workcell program (Python) that reproduces its motions."""
    from ..program import export_program

    path = export_program(file, out, cell=cell)
    click.echo(f"wrote {path}")
