"""``armguard check SCENE --q ...``: one detector check, printed per category (or as JSON).

Exit status (:class:`armguard.cli.ExitCode`): 0 clear or warning, 1 collision, 5 incomplete (as
``armguard verify``: a check that could not finish is never read as clear, nor as a collision),
2 bad input (a value outside the joint limits is refused with the joint, the value and the
limits in the units typed), 3 a file refused.
"""

from __future__ import annotations

import math
import sys

import click

from . import main
from ._params import DURATION, LENGTH, PATH, scene_of, srdf_option
from ._exit import ExitCode, exit_epilog
from ._output import esc, json_text, output_console

_STATUS_EXIT = {"clear": ExitCode.OK, "warning": ExitCode.OK, "collision": ExitCode.UNSAFE,
                "incomplete": ExitCode.INCOMPLETE}
_COLOUR = {"clear": "green", "warning": "yellow", "collision": "red", "incomplete": "magenta"}


def _fmt(p) -> str:
    return "[" + ", ".join(f"{float(x):.4f}" for x in p) + "]"


def parse_q(sc, q_text: str, deg: bool):
    """``q`` flat over ``sc.joint_names`` from text; with ``deg`` revolute joints are in degrees.

    A value outside its joint's limits raises click.BadParameter naming the joint, the value
    and the limits in the units typed.
    """
    import numpy as np

    try:
        q = np.array([float(x) for x in q_text.replace(" ", ",").split(",") if x], dtype=np.float64)
    except ValueError as exc:
        raise click.BadParameter(f"expected comma-separated numbers, got {q_text!r}", param_hint="--q") from exc
    n = len(sc.joint_names)
    if len(q) != n:
        raise click.BadParameter(f"expected {n} values (over {', '.join(sc.joint_names)}), got {len(q)}",
                                 param_hint="--q")
    bad = np.flatnonzero(~np.isfinite(q))
    if len(bad):
        k = int(bad[0])
        raise click.BadParameter(f"{sc.joint_names[k]} (value {k + 1} of {n}) = {float(q[k])}: every value must be finite",
                                 param_hint="--q")
    k = 0
    for rname, robot in sc.robots.items():
        types = getattr(robot, "joint_types", None) or ("revolute",) * robot.n_joints
        for j in range(robot.n_joints):
            revolute = "prismatic" not in str(getattr(types[j], "value", types[j])).lower()
            scale = math.pi / 180.0 if (deg and revolute) else 1.0
            unit = "deg" if (deg and revolute) else ("rad" if revolute else "m")
            lo, hi = float(robot.lower[j]), float(robot.upper[j])
            x = q[k] * scale
            from .._tolerance import DEFAULT_TOLERANCES

            slack = DEFAULT_TOLERANCES.joint_limit
            if not (lo - slack <= x <= hi + slack):
                hint = " (degrees? add --deg)" if unit == "rad" and abs(x) > 2.0 * math.pi else ""
                raise click.BadParameter(
                    f"{rname}/{robot.joint_names[j]} = {q[k]:.10g} {unit} is outside its limits "
                    f"[{lo / scale:.10g}, {hi / scale:.10g}] {unit}{hint}", param_hint="--q")
            q[k] = x
            k += 1
    return q


@main.command("check", epilog=exit_epilog(ok="clear or warning", unsafe="collision",
                                           incomplete="incomplete: the budget ran out before a verdict"))
@click.argument("scene")
@click.option("--q", "q_text", default=None,
              help="Joint values, comma-separated, in the scene's joint order (`armguard info SCENE` lists it; "
                   "default: the home pose).")
@click.option("--deg", is_flag=True, help="--q gives revolute joints in degrees (prismatic stay in m).")
@click.option("--threshold", type=LENGTH, default=0.05, show_default=True, help="Detection threshold (m).")
@click.option("--stopping-distance", type=LENGTH, default=0.0, show_default=True, help="Stopping distance (m).")
@click.option("--active", default=None, help="Check only this robot against everything (default: all arms).")
@click.option("--budget-us", type=DURATION, default=None, help="Anytime mode: time budget in microseconds.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--terrain", "terrain_file", type=PATH, default=None,
              help="Add the terrain category: a sensed terrain file (armguard.terrain.load_terrain), or a shipped "
                   "terrain by name (gentle, rocky, rough).")
@srdf_option("SCENE")
def check_cmd(scene, q_text, deg, threshold, stopping_distance, active, budget_us, as_json, terrain_file, srdf) -> None:
    """Check SCENE (a built-in name or a scene file) at one configuration."""
    from rich.table import Table

    from ..detect import Detector
    from ._compile import warm_up

    sc = scene_of(scene, srdf)
    q = sc.flat_q(sc.default_q()) if q_text is None else parse_q(sc, q_text, deg)
    warm_up()
    terrain = None
    if terrain_file is not None:  # the terrain category (armguard.terrain), whatever the backend
        from ..terrain import load_terrain

        terrain = load_terrain(terrain_file, sc, robot=active)
    det = Detector(sc, threshold=threshold, stopping_distance=stopping_distance, active=active, terrain=terrain)
    rep = det.check(q, budget_us=budget_us)
    code = _STATUS_EXIT.get(rep.status.value, ExitCode.INCOMPLETE)  # never a success exit without a verdict
    if as_json:
        click.echo(json_text({**rep.to_dict(), "backend": getattr(det, "backend", None)}, indent=2))  # features as data
        sys.exit(int(code))
    out = output_console()
    colour = _COLOUR[rep.status.value]
    near = ""  # Ranger's collision status covers the stopping distance: said where nothing touches
    least = min((r.distance for r in rep.by_category.values()), default=math.inf)
    if rep.status.value == "collision" and stopping_distance > 0.0 and least > 0.0:
        touch = "" if rep.not_evaluated else ", no contact"  # a pair the budget left may touch
        near = f" [{colour}](within the stopping distance{touch})[/{colour}]"
    stop = f", stopping distance {stopping_distance} m" if stopping_distance > 0.0 else ""
    out.print(f"[bold]{esc(sc.name)}[/bold]  status: [bold {colour}]{rep.status.value.upper()}[/bold {colour}]{near}  "
              f"(threshold {threshold} m{stop}, {rep.elapsed_us:.1f} µs, {rep.n_evaluated} of {det.n_pairs} pairs evaluated)")
    table = Table("category", "distance (m)", "link", "object", "feature", "p_WA (m)", "p_WB (m)")
    for cat, r in rep.by_category.items():
        feat = "" if r.feature is None else str(r.feature)
        style = "red" if r.distance <= max(0.0, stopping_distance) else ("yellow" if r.distance <= threshold else "")
        side_a = r.link if r.a == r.link else f"{r.a} (on {r.link})"  # a payload is side A: named, with its link
        table.add_row(cat, f"{r.distance:.6f}", esc(side_a), esc(r.obstacle), esc(feat), _fmt(r.p_WA), _fmt(r.p_WB), style=style)
    out.print(table)
    if rep.not_evaluated:
        lb = min(n.lower_bound for n in rep.not_evaluated)
        bound = f"least lower bound {lb:.4f} m" if math.isfinite(lb) else "no lower bound on some of them yet"
        out.print(f"{len(rep.not_evaluated)} pairs not evaluated within the budget; {bound}")
    sys.exit(int(code))
