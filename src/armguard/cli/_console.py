"""``armguard console SCENE``: the operator console in the browser."""

from __future__ import annotations

import click

from . import main
from ._params import LENGTH, PATH


class _Uncertain(click.ParamType):
    """``BODY=SIGMA_M[,SIGMA_DEG]``: its form and numbers checked where click reads it (a usage error, exit
    status 2, as every option's value); the body's name against the scene when the console loads it (3)."""

    name = "uncertain"

    def convert(self, value, param, ctx):
        from .._errors import ArmguardError
        from ..console._overlays import split_uncertain

        try:
            split_uncertain(value)
        except ArmguardError as exc:
            self.fail(str(exc).removeprefix("--uncertain").lstrip(": "), param, ctx)
        return value


@main.command("console")
@click.argument("scene")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; the default serves this machine only.")
@click.option("--port", default=8080, show_default=True, type=click.IntRange(0, 65535),
              help="TCP port (0: any free port). A port in use is an error.")
@click.option("--threshold", default=0.05, show_default=True, type=LENGTH, help="Initial detection threshold (m).")
@click.option("--watch", is_flag=True, help="Reload the model when its files change, keeping the configuration.")
@click.option("--terrain", "terrain_file", type=PATH, default=None,
              help="Check against a sensed terrain file or shipped name (as armguard check --terrain) and draw it with the "
                   "pyramid boxes each check tests.")
@click.option("--uncertain", multiple=True, type=_Uncertain(), metavar="BODY=SIGMA_M[,SIGMA_DEG]",
              help="Place a body (or a robot's base) with an isotropic uncertainty (m, deg); repeatable. "
                   "Draws its 90 % / 99.9 % ellipsoids; the panel shows the clearance in sigmas.")
def console_cmd(scene: str, host: str, port: int, threshold: float, watch: bool, terrain_file, uncertain) -> None:
    """Serve the operator console for SCENE (a built-in scene name, a scene file, or a cell file for the
    Tasks tab: armguard_cell: 1)."""
    from ..console import ConsoleApp
    from ..console._serve import ModelWatcher, load_inputs, make_state, watched_files
    from ._compile import warm_up

    # a scene, terrain or --uncertain body refused: one line, exit status 3 (as every command); the
    # files read first, so a mistyped path is refused at once, not after the kernels compiled
    if terrain_file is not None:  # a file, or a shipped terrain's name (rocky), as armguard check --terrain
        from ..terrain import terrain_path

        terrain_file = str(terrain_path(terrain_file))
    inputs = load_inputs(scene, terrain=terrain_file)
    warm_up()
    state = make_state(inputs, threshold=threshold, terrain=terrain_file, uncertain=uncertain)
    app = ConsoleApp(state, host=host, port=port).start()
    if watch:
        files = watched_files(scene, state.model)
        ModelWatcher(app, scene, files).start()
        click.echo(f"watching for changes: {', '.join(str(f) for f in files)}", err=True)
    click.echo(f"armguard console: {app.url}  (Ctrl-C to stop)")
    app.serve_forever()
