"""Where the console's answers come from: the backend of the panel, a compared backend, model reloads.

Mixed into :class:`~._state.ConsoleState` (uses its lock, scene, model and ``_changed``):
:meth:`SourcesMixin.set_backend` and :meth:`SourcesMixin.set_compare` pick the backends
(the installed ones that answer distances: :func:`distance_backends`), :meth:`SourcesMixin.reload` replaces the model
(``armguard console --watch``) keeping the configuration.
"""

from __future__ import annotations

import typing

from ._backends import BackendView
from ._parse import ConsoleInputError

__all__ = ["SourcesMixin", "BackendFailed", "distance_backends", "declared_capabilities"]


class BackendFailed(ConsoleInputError):
    """A backend plugin raised while computing the panel: it is no longer offered until the model is reloaded."""


def declared_capabilities(backend) -> frozenset | None:
    """What a backend plugin says its checkers answer, without building one (None: it does not say).

    The backend's own ``capabilities``, else those of the checker class its ``build`` is declared
    to return.
    """
    caps = getattr(backend, "capabilities", None)
    if caps is None:
        try:
            hint = typing.get_type_hints(type(backend).build).get("return")
        except Exception:  # noqa: BLE001 - an unresolvable annotation says nothing
            hint = None
        caps = getattr(hint, "capabilities", None)
    return None if caps is None else frozenset(caps)


def distance_backends() -> tuple[str, ...]:
    """The installed backends besides ``analytic`` that answer distances (``Capability.DISTANCES``).

    A backend that declares verdicts only (``clip``, ``forbidden``) is left out; one that declares
    nothing is listed, and refused when its checker turns out not to answer distances.
    """
    from ..backends import Capability, available, get_backend

    out = []
    for name in available():
        if name == "analytic":
            continue
        try:
            caps = declared_capabilities(get_backend(name))
        except Exception:  # noqa: BLE001 - a plugin that does not load is not offered
            continue
        if caps is None or Capability.DISTANCES in caps:
            out.append(name)
    return tuple(out)


class SourcesMixin:
    """Backends and model updates of the console state."""

    def _readout_of(self, backend: str):
        """The panel from ``backend``, its nearest pair named moving link first (:func:`moving_link_first`)."""
        from ._readout import moving_link_first

        return moving_link_first(self._backend_readout(backend), self._is_static)

    def _is_static(self, owner: str) -> bool:
        """True for an arm link no joint moves (a pedestal, a base plate): a static body, not a link."""
        robot_name, _, link = owner.partition("/")
        robot = self._scene.robots.get(robot_name) if link else None
        if robot is None or link not in robot.link_names:
            return False
        while link is not None:
            spec = robot.joint_of_link(link)
            if spec is not None and spec.joint_type.value != "fixed":
                return False
            link = robot.parent_link(link)
        return True

    def _backend_readout(self, backend: str):
        """The panel from ``backend``; the terrain, which only the detector checks, is added to
        every other backend's answer (its row, and the headline the worst of both)."""
        from ._readout import readout_from_report, with_terrain

        if backend == "analytic":
            self._last_report = self._detector.check(self._q)
            return readout_from_report(self._last_report)
        view = self._views.get(backend)
        if view is None:
            view = self._views[backend] = self._view_of(backend)
        try:
            r = view.readout(self._scene, self._q, self._active, threshold=self._threshold,
                             stopping_distance=self._stopping, contact=self._tol.length)
        except Exception as exc:  # noqa: BLE001 - a plugin's failure is said, never a traceback in a log
            self._views.pop(backend, None)
            self._refused[backend] = f"{backend!r} failed ({type(exc).__name__}: {exc}) and is no longer offered"
            raise BackendFailed(f"backend: {self._refused[backend]} until the model is reloaded") from None
        guard = getattr(self._detector, "terrain", None)
        if guard is None:
            return r
        rep = guard.check(self._scene.flat_q(self._q), threshold=self._threshold, stopping_distance=self._stopping)
        if backend == self._backend:
            self._backend_terrain = rep
        return with_terrain(r, rep)

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
        from ._overlays import reanchored
        from ._reload import carry_q, describe_changes

        if not scene.robots:
            raise ConsoleInputError(f"scene {scene.name!r} has no robot to drive")
        with self._lock:
            old = (self._scene, self._model, self._q, self._active, self._detector, self._views, self._backend,
                   self._compare_with, self._refused, self._placements)
            new_scene = scene.copy()
            new_q = carry_q(self._q, self._scene, new_scene)
            try:
                changes = describe_changes(self._scene, new_scene, self._q, new_q, self._model, model)
                self._placements, dropped = reanchored(self._placements, self._scene, new_scene)
                if dropped:
                    changes += f"; uncertain placements dropped (gone or moved in the plane): {', '.join(dropped)}"
                self._scene, self._model, self._q, self._views = new_scene, model, new_q, {}
                self._refused = {}
                self._ws_draft = (None, None)
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
                 self._compare_with, self._refused, self._placements) = old
                self._evaluate()
                raise
            return changes

    # ------------------------------------------------------------------ backends
    @property
    def backends(self) -> tuple[str, ...]:
        """The backends the panel can use: ``analytic`` (the detector) and, with a model, every
        installed one that answers distances (:func:`distance_backends`), less any refused here."""
        if self._model is None:
            return ("analytic",)
        if self._distance_backends is None:
            self._distance_backends = distance_backends()
        return ("analytic",) + tuple(b for b in self._distance_backends if b not in self._refused)

    def _check_backend(self, name: str) -> str:
        if name in self._refused:
            raise ConsoleInputError(f"backend: {self._refused[name]}; backends are {list(self.backends)}")
        if name not in self.backends:
            raise ConsoleInputError(f"backend: {name!r} is not installed here or does not answer distances; "
                                    f"backends are {list(self.backends)}")
        return name

    def _view_of(self, name: str) -> BackendView:
        """Build backend ``name``'s checker on the model; a checker without distances, or one that
        cannot be built, is refused (and left out of :attr:`backends` from then on)."""
        from ..backends import Capability

        try:
            view = BackendView(self._model, name)
            caps = getattr(view.checker, "capabilities", None)
            if caps is not None and Capability.DISTANCES not in caps:
                raise ConsoleInputError(f"{name!r} answers {sorted(str(getattr(c, 'value', c)) for c in caps)}, "
                                        "not distances")
        except Exception as exc:
            self._refused[name] = f"{name!r} cannot compute the panel ({exc})"
            raise ConsoleInputError(f"backend: {self._refused[name]}; kept {self._backend}; "
                                    f"backends are {list(self.backends)}") from None
        return view

    def _prepare(self, name: str) -> None:
        """Build ``name``'s checker before taking the lock (it may take seconds; other commands wait less)."""
        if name == "analytic" or name in self._views:
            return
        model = self._model
        view = self._view_of(name)
        with self._lock:
            if self._model is model:
                self._views.setdefault(name, view)

    def set_backend(self, name: str) -> None:
        """Compute the panel with backend ``name`` (the configuration and settings stay).

        A refusal (not a distance backend, or its checker cannot be built) leaves the backend,
        the panel and its message as they were, and raises.
        """
        self._check_backend(name)
        self._prepare(name)
        with self._lock:
            old, message = (self._backend, self._compare_with), (self._message, self._message_is_error)
            self._backend = name
            note = ""
            if self._compare_with == name:  # never compared with itself
                self._compare_with, note = None, "; comparison off"
            try:
                self._changed(f"backend: {name}{note}")
            except Exception:
                self._backend, self._compare_with = old
                self._message, self._message_is_error = message
                self._evaluate()
                raise

    def set_compare(self, name: str | None) -> None:
        """Compare mode: also compute the nearest pair with backend ``name`` (None: off) and show Δd."""
        if name is not None:
            self._check_backend(name)
            if name == self._backend:
                raise ConsoleInputError(f"compare with: {name!r} is the panel's backend; a backend is not compared "
                                        "with itself (pick another)")
            self._prepare(name)
        with self._lock:
            old, message = self._compare_with, (self._message, self._message_is_error)
            self._compare_with = name
            try:
                self._changed("" if name is None else f"comparing {self._backend} with {name}")
            except Exception:
                self._compare_with = old
                self._message, self._message_is_error = message
                self._evaluate()
                raise

