"""``armguard fk SCENE --q ...``: the world poses of a robot's links at a configuration."""

from __future__ import annotations

import click
import numpy as np

from .._errors import SceneError
from . import main
from ._output import esc, output_console


@main.command("fk")
@click.argument("scene")
@click.option("--q", "q_text", default=None,
              help="Joint values, comma- or space-separated (default: home). Revolute in rad, or deg with --deg; prismatic in m.")
@click.option("--robot", "robot_name", default=None, help="Robot of the scene (default: the only or first robot).")
@click.option("--deg", is_flag=True, help="--q gives revolute joints in degrees; rpy is printed in degrees.")
def fk_cmd(scene: str, q_text: str | None, robot_name: str | None, deg: bool) -> None:
    """Print the world pose (xyz in m, rpy) of every link of a robot of SCENE at --q."""
    from rich.table import Table

    from ..kinematics import xyz_rpy_from_pose
    from ..model import kinematics_of
    from ..scene import load_scene

    s = load_scene(scene)
    if not s.robots:
        raise SceneError(f"scene {s.name!r} has no robot")
    name = robot_name or next(iter(s.robots))
    if name not in s.robots:
        raise SceneError(f"--robot: unknown robot {name!r}; robots are {list(s.robots)}")
    robot = s.robots[name]
    if q_text is None:
        q = s.home(name)
    else:
        try:
            vals = [float(x) for x in q_text.replace(",", " ").split()]
        except ValueError:
            raise click.BadParameter(f"expected numbers, got {q_text!r}", param_hint="--q") from None
        if len(vals) != robot.n_joints:
            raise click.BadParameter(f"robot {name!r} has {robot.n_joints} joints {list(robot.joint_names)}, got {len(vals)} "
                                     "values", param_hint="--q")
        q = np.array(vals)
        bad = np.flatnonzero(~np.isfinite(q))
        if len(bad):  # a usage error, as check's --q (exit status 2), naming the joint
            k = int(bad[0])
            raise click.BadParameter(f"{name}/{robot.joint_names[k]} (value {k + 1} of {len(q)}) = {q[k]}: every value "
                                     "must be finite", param_hint="--q")
        if deg:
            rev = np.array([jt.value == "revolute" for jt in robot.joint_types])
            q = np.where(rev, np.radians(q), q)
    q = robot.check_q(q)
    X = kinematics_of(s).robot_link_poses(name, q)  # the Model's kinematics (pin_model)
    unit = "deg" if deg else "rad"
    t = Table(title=f"{esc(s.name)}: robot {esc(name)}, link frames in W (xyz m, rpy {unit})")
    for col in ("link", "x", "y", "z", "roll", "pitch", "yaw"):
        t.add_column(col, justify="right" if col != "link" else "left")
    for i, ln in enumerate(robot.link_names):
        xyz, rpy = xyz_rpy_from_pose(X[i])
        if deg:
            rpy = np.degrees(rpy)
        t.add_row(esc(ln), *(f"{v: .6f}" for v in xyz), *(f"{v: .4f}" for v in rpy))
    outside = [robot.joint_names[k] for k in range(robot.n_joints) if not (robot.lower[k] <= q[k] <= robot.upper[k])]
    output_console().print(t)
    if outside:
        click.secho(f"warning: joints outside their limits: {', '.join(outside)}", fg="yellow", err=True)
