"""``armguard check SCENE --q ...``: one detector check, printed per category (or as JSON)."""

from __future__ import annotations

import json

import click

from . import main

_COLOUR = {"clear": "green", "warning": "yellow", "collision": "red", "incomplete": "magenta"}


def _fmt(p) -> str:
    return "[" + ", ".join(f"{float(x):.4f}" for x in p) + "]"


@main.command("check")
@click.argument("scene")
@click.option("--q", "q_text", default=None, help="Joint values over scene.joint_names, comma-separated (default: home).")
@click.option("--threshold", type=float, default=0.05, show_default=True, help="Detection threshold (m).")
@click.option("--stopping-distance", type=float, default=0.0, show_default=True, help="Stopping distance (m).")
@click.option("--active", default=None, help="Check only this robot against everything (default: all arms).")
@click.option("--budget-us", type=float, default=None, help="Anytime mode: time budget in microseconds.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
def check_cmd(scene, q_text, threshold, stopping_distance, active, budget_us, as_json) -> None:
    """Check SCENE (a built-in name or a scene file) at one configuration."""
    import numpy as np
    from rich.console import Console
    from rich.table import Table

    from ..detect import Detector
    from ..scene import load_scene

    sc = load_scene(scene)
    if q_text is None:
        q = sc.flat_q(sc.default_q())
    else:
        try:
            q = np.array([float(x) for x in q_text.replace(" ", ",").split(",") if x], dtype=np.float64)
        except ValueError as exc:
            raise click.BadParameter(f"expected comma-separated numbers, got {q_text!r}", param_hint="--q") from exc
    console = Console(stderr=True)
    if not as_json:
        console.print("[dim]compiling kernels (first run only)...[/dim]")
    det = Detector(sc, threshold=threshold, stopping_distance=stopping_distance, active=active)
    rep = det.check(q, budget_us=budget_us)
    if as_json:
        click.echo(json.dumps(rep.to_dict(), indent=2))
        return
    out = Console()
    colour = _COLOUR[rep.status.value]
    out.print(f"[bold]{sc.name}[/bold]  status: [bold {colour}]{rep.status.value.upper()}[/bold {colour}]  "
              f"(threshold {threshold} m, {rep.elapsed_us:.1f} µs, {rep.n_evaluated} pairs evaluated)")
    table = Table("category", "distance (m)", "link", "object", "feature", "p_WA (m)", "p_WB (m)")
    for cat, r in rep.by_category.items():
        feat = "" if r.feature is None else f"{getattr(r.feature.kind, 'value', r.feature.kind)} {r.feature.index}"
        style = "red" if r.distance <= max(0.0, stopping_distance) else ("yellow" if r.distance <= threshold else "")
        table.add_row(cat, f"{r.distance:.6f}", r.link, r.obstacle, feat, _fmt(r.p_WA), _fmt(r.p_WB), style=style)
    out.print(table)
    if rep.not_evaluated:
        out.print(f"{len(rep.not_evaluated)} pairs not evaluated (budget); least lower bound "
                  f"{min(n.lower_bound for n in rep.not_evaluated):.4f} m")
