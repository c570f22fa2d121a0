"""Start the console on a scene: what ``armguard console SCENE`` runs, with ``--watch``."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

from ..model import scene_of
from ._app import ConsoleApp
from ._state import DEFAULT_THRESHOLD, ConsoleState

__all__ = ["serve", "make_state", "load_inputs", "ConsoleInputs", "load_for_console", "ModelWatcher"]


def load_for_console(name):
    """``(scene, model)`` for a built-in name or a file; ``model`` is None where no Model can be built."""
    from ..model import load_model
    from ..program._format import is_cell_file
    from ..scene import load_scene

    if is_cell_file(name):  # a cell file (armguard_cell: 1): its model
        from ..program import load_cell

        model = load_cell(name).model
        return model.scene, model
    try:
        model = load_model(name)
    except Exception:
        return load_scene(name), None
    return model.scene, model


def watched_files(name, model) -> list[Path]:
    """The files whose change reloads the model: the model's own files, or the scene file."""
    files = [Path(f) for f in getattr(model, "files", ())] if model is not None else []
    if not files and Path(str(name)).exists():
        files = [Path(str(name))]
    out = []
    for f in files:
        out.append(f.resolve())
        mesh_dir = f.parent / "meshes"
        if f.suffix == ".urdf" and mesh_dir.is_dir():
            out.append(mesh_dir.resolve())
    return out


class ModelWatcher:
    """Reload the console's model when its files change (``watchfiles``); a file that stops parsing
    leaves the last good model running, with the error in the panel."""

    def __init__(self, app: ConsoleApp, name, files) -> None:
        self.app = app
        self.name = name
        self.files = list(files)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="armguard-watch", daemon=True)

    def start(self) -> "ModelWatcher":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()

    def reload_now(self) -> str | None:
        """Load the files again and hand the result to the state; returns the change summary (None on error)."""
        try:
            scene, model = load_for_console(self.name)
            changes = self.app.state.reload(scene, model)
        except Exception as exc:
            self.app.state.note_error(f"model not reloaded, the last good one keeps running: "
                                      f"{type(exc).__name__}: {exc}")
            return None
        self.app.model_reloaded()
        return changes

    def _run(self) -> None:
        from watchfiles import watch

        paths = sorted({str(p if p.is_dir() else p.parent) for p in self.files})
        wanted = {str(p) for p in self.files}

        def relevant(_change, path: str) -> bool:
            return path in wanted or any(path.startswith(w + "/") for w in wanted)

        for _changes in watch(*paths, watch_filter=relevant, stop_event=self._stop, debounce=300):
            self.reload_now()


@dataclass(frozen=True)
class ConsoleInputs:
    """What the console reads from its files, read: the ``scene``, its ``model`` (or None), the
    ``cell`` of a cell file (or None) and ``source``, how a saved program names the cell."""

    scene: object
    model: object = None
    cell: object = None
    source: str | None = None


def load_inputs(scene, *, terrain=None) -> ConsoleInputs:
    """Read (and parse) the console's files before anything is checked: ``scene`` (a Scene, a Model,
    a built-in name, a scene, model or cell file) and that a ``terrain`` file exists.  No kernel is
    compiled here, so ``armguard console`` refuses a mistyped path at once, before it warms the
    kernels up, with the loaders' own message (ArmguardError)."""
    scene = scene_of(scene, "console")  # a Model: its scene
    model, cell, source = None, None, None
    if isinstance(scene, (str, Path)):
        from ..program._format import is_cell_file

        source = str(Path(scene).resolve()) if Path(str(scene)).exists() else str(scene)  # a saved program names it
        if is_cell_file(scene):  # the task menu programs this cell (its camera, its real layout)
            from ..program import load_cell

            cell = load_cell(scene)
            scene, model = cell.model.scene, cell.model
        else:
            scene, model = load_for_console(scene)
    if isinstance(terrain, (str, Path)):  # a file, or a shipped terrain's name ("rocky"): read later, with the scene's kernels
        from ..terrain import terrain_path

        terrain_path(terrain)  # a TerrainError naming it, and the shipped names, when neither
    return ConsoleInputs(scene, model, cell, source)


def make_state(scene, *, threshold: float = DEFAULT_THRESHOLD, terrain=None, uncertain=()) -> ConsoleState:
    """The console state for ``scene`` (a Scene or a built-in / file name; a cell file: its model, and
    the cell as ``state.cell`` for the Tasks tab; or the :class:`ConsoleInputs` of :func:`load_inputs`)
    with its model, a terrain (an ElevationMap, or a file for :func:`armguard.terrain.load_terrain`)
    and uncertain placements (UncertainPlacement objects or ``"BODY=SIGMA_M[,SIGMA_DEG]"`` texts)."""
    from ._overlays import parse_uncertain

    inputs = scene if isinstance(scene, ConsoleInputs) else load_inputs(scene, terrain=terrain)
    scene, model, cell, source = inputs.scene, inputs.model, inputs.cell, inputs.source
    state = ConsoleState(scene, threshold=threshold, model=model)
    state.cell, state.cell_source = cell, source  # read by the Tasks tab (._tasks_panel.make_cell)
    if terrain is not None:
        if isinstance(terrain, (str, Path)):
            from ..terrain import load_terrain

            terrain = load_terrain(terrain, state.scene)
        state.set_terrain(terrain)
    if uncertain:
        state.set_placements([parse_uncertain(state.scene, u) if isinstance(u, str) else u for u in uncertain])
    return state


def serve(scene, *, host: str = "127.0.0.1", port: int = 8080, threshold: float = DEFAULT_THRESHOLD,
          block: bool = True, watch: bool = False, terrain=None, uncertain=()) -> ConsoleApp:
    """Serve the console for ``scene`` (a Scene or a built-in / file name).

    Binds ``host`` (loopback by default) on ``port`` (0: a free port; one in use raises
    PortInUseError).  ``watch`` (names only) reloads the model when its files change; ``terrain``
    and ``uncertain`` as :func:`make_state`.  With ``block`` it serves until interrupted;
    otherwise it returns the started :class:`ConsoleApp`.
    """
    scene = scene_of(scene, "console")  # a Model: its scene
    name = scene
    app = ConsoleApp(make_state(scene, threshold=threshold, terrain=terrain, uncertain=uncertain),
                     host=host, port=port).start()
    if watch and isinstance(name, (str, Path)):
        app.watcher = ModelWatcher(app, name, watched_files(name, app.state.model)).start()
    if block:
        app.serve_forever()
    return app
