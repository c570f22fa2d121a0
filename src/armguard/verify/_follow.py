"""What :class:`~armguard.verify.Verifier` and :class:`~armguard.verify.Guard` share: a state built from
the scene (its :class:`~armguard.verify.ClearanceModel` and what goes with it), published whole, rebuilt
once after a scene edit however many threads find it stale, and a call that runs on one state or
starts again on the scene as it is now."""

from __future__ import annotations

import threading

from .._errors import StaleModelError

__all__ = ["FollowsScene", "VerifierState"]


class FollowsScene:
    """Mixin.  The subclass defines ``_build()`` (an object with a ``model`` attribute, a
    ClearanceModel) and calls :meth:`_follow` at the end of its ``__init__``."""

    def _follow(self) -> None:
        self._lock = threading.Lock()  # one rebuild after an edit, however many threads find it
        self._st = self._build()

    def __getstate__(self):  # a lock does not pickle: each copy gets its own
        return {k: v for k, v in self.__dict__.items() if k != "_lock"}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._lock = threading.Lock()

    @property
    def model(self):
        """The clearance model of the scene as the last call found it."""
        return self._st.model

    def _current(self):
        """The state to call with: the last one, or a new one if the scene changed since (a call on
        another thread keeps the one it read)."""
        st = self._st
        if st.model.is_stale():  # the scene changed since the model was built: never answer with the old one
            with self._lock:
                st = self._st
                if st.model.is_stale():
                    st = self._st = self._build()
        return st

    def _on_one_state(self, fn, attempts: int, what: str):
        """``fn(state)`` on the current state; where the scene changed during the call (any error it
        raised then counts as that: :class:`StaleModelError` or rows of another scene), again on the
        scene as it is now, up to ``attempts`` times; then :class:`StaleModelError`.  A result is
        returned only if the scene was still the state's when ``fn`` returned."""
        for _ in range(attempts):
            st = self._current()
            try:
                out = fn(st)
            except Exception:
                if not st.model.is_stale():
                    raise
                continue
            if not st.model.is_stale():
                return out
        raise StaleModelError(f"the scene changed during each of {attempts} attempts to {what}: no verdict")


class VerifierState:
    """What one verification reads (:meth:`Verifier._build`): the clearance model and every robot's configuration
    (and, per thread and robot, the record ``check_edges`` reuses: not pickled)."""

    __slots__ = ("model", "base", "edge_bases", "edge_records")

    def __init__(self, model, base: dict) -> None:
        self.model, self.base = model, base
        self.edge_bases: dict = {}  # per robot: its flat base configuration (read only)
        self.edge_records = threading.local()  # per thread and robot: check_edges' record

    def __getstate__(self):
        return {"model": self.model, "base": self.base}

    def __setstate__(self, state) -> None:
        self.__init__(state["model"], state["base"])
