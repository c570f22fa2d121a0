"""``armguard console SCENE``: the operator console in the browser."""

from __future__ import annotations

import click

from . import main


@main.command("console")
@click.argument("scene")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; the default serves this machine only.")
@click.option("--port", default=8080, show_default=True, type=click.IntRange(0, 65535),
              help="TCP port (0: any free port).")
@click.option("--threshold", default=0.05, show_default=True, type=float, help="Initial detection threshold (m).")
def console_cmd(scene: str, host: str, port: int, threshold: float) -> None:
    """Serve the operator console for SCENE (a built-in scene name or a scene file)."""
    from ..console import ConsoleApp, ConsoleState
    from ..scene import load_scene

    click.echo("loading scene and compiling kernels (first run only)...", err=True)
    state = ConsoleState(load_scene(scene), threshold=threshold)
    app = ConsoleApp(state, host=host, port=port).start()
    click.echo(f"armguard console: {app.url}  (Ctrl-C to stop)")
    app.serve_forever()
