"""``armguard demo``: the main job of ``make run`` — verify every built-in scene's canned trajectories."""

from __future__ import annotations

import time
from pathlib import Path

import click

from . import main

#: Hermes (001_…, §4): "the maximum value of the stopping distance be 100 mm, i.e. the typical value
#: for maximum speed movements".
HERMES_MAX_STOPPING_DISTANCE = 0.1


def _first_collision_text(r) -> str:
    c = r.first_collision
    if c is None:
        return "—"
    who = c.link or c.payload or c.a
    feat = ""
    if c.feature is not None:
        kind = getattr(getattr(c.feature, "kind", None), "value", None)
        feat = f" {kind} {getattr(c.feature, 'index', '')}".rstrip() if kind else f" {c.feature}"
    p = c.p_W
    return f"{who} / {c.obstacle}{feat} at ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) m, t = {c.time:.2f} s"


@main.command("demo")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="out", show_default=True,
              help="Where the JSON reports and PNG plots go.")
@click.option("--scene", "scenes", multiple=True, help="Only these built-in scenes (default: all).")
@click.option("--stopping-distance", "stopping_distances", type=float, multiple=True,
              help="Stopping distances to verify with (m; default: 0 and Hermes's largest, 0.1).")
def demo_cmd(out_dir, scenes, stopping_distances) -> None:
    """Verify each built-in scene's canned trajectories (certified) and print a table.

    Each trajectory is verified as planned (stopping distance 0) and with the obstacles grown by
    Hermes's largest stopping distance (100 mm), which brings out first collisions to report.
    """
    from rich.console import Console
    from rich.table import Table

    from ..models import builtin_names
    from ..scene import load_scene
    from ..verify import Verifier

    console = Console()
    if not console.is_terminal:  # piped or under make: don't fold the table into 80 columns
        console = Console(width=160)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    table = Table(title="armguard: certified verification of the built-in scenes' canned trajectories")
    stopping_distances = stopping_distances or (0.0, HERMES_MAX_STOPPING_DISTANCE)
    for col in ("scene", "trajectory", "stop dist", "verdict", "first collision: link / object feature at point, time", "min clearance", "time"):
        table.add_column(col, overflow="fold")
    colours = {"safe": "green", "collision": "red", "incomplete": "yellow"}
    console.print("compiling kernels (first run only)…", style="dim")
    t_all = time.perf_counter()
    for name in scenes or builtin_names():
        sc = load_scene(name)
        if not sc.trajectories:
            continue
        verifiers = {}
        for tname, traj in sc.trajectories.items():
            v = verifiers.get(traj.robot_name)
            if v is None:
                v = verifiers[traj.robot_name] = Verifier(sc, robot=traj.robot_name)
            for sd in stopping_distances:
                t0 = time.perf_counter()
                r = v.verify(traj, stopping_distance=sd, name=tname)
                dt = time.perf_counter() - t0
                stem = f"{name}__{tname}__sd{sd * 1e3:.0f}mm"
                r.save_json(out / f"{stem}.json")
                r.plot(out / f"{stem}.png")
                s = r.status.value
                table.add_row(name, tname, f"{sd * 1e3:.0f} mm", f"[{colours[s]}]{s.upper()}[/]", _first_collision_text(r),
                              f"{r.min_clearance * 1e3:.1f} mm", f"{dt * 1e3:.0f} ms")
    console.print(table)
    console.print(f"reports and plots in {out}/ ({time.perf_counter() - t_all:.1f} s in all)")
