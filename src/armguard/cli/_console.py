"""``armguard console SCENE``: the operator console in the browser."""

from __future__ import annotations

import click

from . import main


@main.command("console")
@click.argument("scene")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; the default serves this machine only.")
@click.option("--port", default=8080, show_default=True, type=click.IntRange(0, 65535),
              help="TCP port (0: any free port). A port in use is an error.")
@click.option("--threshold", default=0.05, show_default=True, type=float, help="Initial detection threshold (m).")
@click.option("--watch", is_flag=True, help="Reload the model when its files change, keeping the configuration.")
def console_cmd(scene: str, host: str, port: int, threshold: float, watch: bool) -> None:
    """Serve the operator console for SCENE (a built-in scene name or a scene file)."""
    from ..console import ConsoleApp, ConsoleState
    from ..console._serve import ModelWatcher, load_for_console, watched_files
    from ._compile import warm_up

    warm_up()
    sc, model = load_for_console(scene)
    app = ConsoleApp(ConsoleState(sc, threshold=threshold, model=model), host=host, port=port).start()
    if watch:
        files = watched_files(scene, model)
        ModelWatcher(app, scene, files).start()
        click.echo(f"watching for changes: {', '.join(str(f) for f in files)}", err=True)
    click.echo(f"armguard console: {app.url}  (Ctrl-C to stop)")
    app.serve_forever()
