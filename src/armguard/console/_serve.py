"""Start the console on a scene: what ``armguard console SCENE`` runs."""

from __future__ import annotations

from ._app import ConsoleApp
from ._state import DEFAULT_THRESHOLD, ConsoleState

__all__ = ["serve"]


def serve(scene, *, host: str = "127.0.0.1", port: int = 8080, threshold: float = DEFAULT_THRESHOLD,
          block: bool = True) -> ConsoleApp:
    """Serve the console for ``scene`` (a Scene or a built-in / file name for ``load_scene``).

    Binds ``host`` (loopback by default) on ``port`` (0: a free port).  With ``block`` it serves
    until interrupted; otherwise it returns the started :class:`ConsoleApp` (call ``stop()``).
    """
    if isinstance(scene, str):
        from ..scene import load_scene

        scene = load_scene(scene)
    app = ConsoleApp(ConsoleState(scene, threshold=threshold), host=host, port=port).start()
    if block:
        app.serve_forever()
    return app
