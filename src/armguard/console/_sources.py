"""Where the console's answers come from: the backend of the panel, a compared backend, model reloads.

Mixed into :class:`~._state.ConsoleState` (uses its lock, scene, model and ``_changed``):
:meth:`SourcesMixin.set_backend` and :meth:`SourcesMixin.set_compare` pick the backends
(``armguard.backends.available()``), :meth:`SourcesMixin.reload` replaces the model
(``armguard console --watch``) keeping the configuration.
"""

from __future__ import annotations

from ._backends import BackendView
from ._parse import ConsoleInputError

__all__ = ["SourcesMixin"]


class SourcesMixin:
    """Backends and model updates of the console state."""

    def _readout_of(self, backend: str):
        from ._readout import readout_from_report

        if backend == "analytic":
            self._last_report = self._detector.check(self._q)
            return readout_from_report(self._last_report)
        view = self._views.get(backend)
        if view is None:
            view = self._views[backend] = BackendView(self._model, backend)
        return view.readout(self._scene, self._q, self._active, threshold=self._threshold,
                            stopping_distance=self._stopping, contact=self._tol.length)

    # ------------------------------------------------------------------ model updates
    @property
    def model(self):
        return self._model

    def reload(self, scene, model=None) -> str:
        """Replace the scene (and model) by a new version, keeping the configuration; returns what changed.

        Arms whose joints are unchanged keep their values (clipped into the new limits); the active
        arm, settings and backends stay when they still exist.  Any failure leaves the old model
        running and raises.
        """
        from ._reload import carry_q, describe_changes

        if not scene.robots:
            raise ConsoleInputError(f"scene {scene.name!r} has no robot to drive")
        with self._lock:
            old = (self._scene, self._model, self._q, self._active, self._detector, self._views, self._backend,
                   self._compare_with)
            new_scene = scene.copy()
            new_q = carry_q(self._q, self._scene, new_scene)
            try:
                changes = describe_changes(self._scene, new_scene, self._q, new_q, self._model, model)
                self._scene, self._model, self._q, self._views = new_scene, model, new_q, {}
                if self._active not in new_scene.robots:
                    self._active = next(iter(new_scene.robots))
                if self._backend not in self.backends:
                    self._backend = "analytic"
                if self._compare_with not in self.backends:
                    self._compare_with = None
                self._stop_player()
                self._rebuild_detector()
                self._changes = f"model reloaded: {changes}"
                self._changed(self._changes)
            except Exception:
                (self._scene, self._model, self._q, self._active, self._detector, self._views, self._backend,
                 self._compare_with) = old
                self._evaluate()
                raise
            return changes

    # ------------------------------------------------------------------ backends
    @property
    def backends(self) -> tuple[str, ...]:
        """The backends the panel can use: ``analytic`` (the detector) and, with a model, every installed one."""
        if self._model is None:
            return ("analytic",)
        from ..backends import available

        return ("analytic",) + tuple(b for b in available() if b != "analytic")

    def _check_backend(self, name: str) -> str:
        if name not in self.backends:
            raise ConsoleInputError(f"backend: {name!r} is not installed here; backends are {list(self.backends)}")
        return name

    def set_backend(self, name: str) -> None:
        """Compute the panel with backend ``name`` (the configuration and settings stay)."""
        with self._lock:
            self._check_backend(name)
            old = self._backend
            self._backend = name
            try:
                self._changed(f"backend: {name}")
            except Exception:
                self._backend = old
                self._evaluate()
                raise

    def set_compare(self, name: str | None) -> None:
        """Compare mode: also compute the nearest pair with backend ``name`` (None: off) and show Δd."""
        with self._lock:
            if name is not None:
                self._check_backend(name)
            old = self._compare_with
            self._compare_with = name
            try:
                self._changed("" if name is None else f"comparing {self._backend} with {name}")
            except Exception:
                self._compare_with = old
                self._evaluate()
                raise

