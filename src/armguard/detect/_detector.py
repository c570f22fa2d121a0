"""``armguard.detect.Detector``: the public name, dispatching to the chosen backend's Detector.

``Detector(scene_or_model, threshold=..., active=..., backend=...)`` is what users construct.
The class here holds no algorithm: its ``__new__`` asks the backend (argument >
``$ARMGUARD_BACKEND`` > ``armguard.toml`` > ``"analytic"``) for the Detector class it declares
(``Backend.ranger_detector(options)``, the *fast path*, :func:`._ranger.fast_path`) and builds
that, else :class:`._ranger.RangerDetector` (Ranger's algorithm over the backend's Checker).
Both are subclasses, so ``isinstance(Detector(scene), Detector)`` holds whichever backend answers:

* ``"analytic"`` declares its fused numba Detector (``armguard_analytic._engine._detector.FusedDetector``,
  the plugin's own engine: one numba call per check), reached only through the backend registry,
  so the framework never imports the plugin;
* every other bundled backend gets :class:`~armguard.detect.RangerDetector`.

A declared class that is a subclass of this one is allocated here and initialised once by
Python with the caller's arguments; one that is not is called with them and returned as it is.
"""

from __future__ import annotations

__all__ = ["Detector"]


class Detector:
    """Ranger's virtual sensor for ``scene``: per category, the nearest pair and a status.

    Parameters
    ----------
    scene : armguard.Scene or armguard.Model
    threshold : float, m
        Detection threshold (Ranger's yellow): a pair within it gives WARNING.
    stopping_distance : float, m
        When > 0, a pair within it counts as COLLISION (Hermes's obstacle growing); 0: only
        contact / penetration (distance <= 0) is a collision.
    active : str or None
        A robot name: check that arm against everything (Ranger's active arm); None: all arms.
    tol : Tolerances
    backend, backend_options : str, mapping
        The backend whose distances the detector reports (argument > ``$ARMGUARD_BACKEND`` >
        ``armguard.toml`` > ``"analytic"``).  A backend that declares a Ranger cycle of its own
        (``Backend.ranger_detector``) gets it: ``"analytic"``'s is its fused numba kernel
        (``armguard_analytic._engine``); any other gives a
        :class:`~armguard.detect._ranger.RangerDetector`, Ranger's algorithm over the backend's
        Checker, with the same API.  Both are subclasses of this class.
    reach_margin : float, m
        Obstacle lists keep every obstacle a link can come within this margin of anywhere in
        its joint limits (conservative reach analysis, :mod:`armguard.detect._reach`); pairs
        farther are dropped.  ``inf`` (default) keeps every pair, so per-category nearest
        distances are exact at any range; a finite margin (at least the threshold and the
        stopping distance, raised to it if smaller) keeps the status and the within-threshold
        pairs exact and reports nearest pairs only among the listed ones.
    terrain : armguard.terrain.TerrainGuard, TerrainPyramid or ElevationMap, optional
        Adds the ``"terrain"`` category to ``check`` (:func:`armguard.terrain.attach_terrain`;
        composed outside the kernel, no cost without it).  ``detector.terrain`` is its guard.

    The API every subclass provides: ``check(q, budget_us=, lazy=, jacobian=)``,
    ``check_many(Q)``, ``collides_many(Q)``, ``pair_distances(q, robot=)``, ``prepare()``, ``warm_up(q)``,
    ``obstacle_list(link)``, ``set_threshold`` / ``set_stopping_distance`` / ``set_active``,
    ``threshold``, ``stopping_distance``, ``active``, ``n_pairs``, ``link_names``.

    Thread safety: several threads may call one Detector at once with the answers of
    single-threaded calls (the analytic one gives each thread its own scratch buffers and its
    kernels release the GIL; Ranger's over a Checker keeps per-thread state).  Changing the scene
    or the settings while other threads check is not synchronised.
    """

    terrain = None  # the attached armguard.terrain.TerrainGuard, if any

    def warm_up(self, q, *, jacobian: bool = True) -> None:
        """Run each mode of :meth:`check` once at ``q`` (the scene's joint order) on the calling thread,
        before a control loop's first cycle: the first call of a path compiles or loads its kernels and
        allocates the thread's scratch (tens of milliseconds with numba's cache warm, seconds without).
        The plain, lazy and budgeted checks, and with ``jacobian`` the Jacobian of the nearest pairs.
        Later statuses and exact answers are those of a Detector never warmed; the anytime mode's
        memory (``q``'s true distances, from which later bounds subtract the motion since) and its
        cost model learn from these calls, so which pairs a first budgeted check reaches may differ."""
        self.check(q)
        self.check(q, lazy=True)
        self.check(q, budget_us=0.0)
        if jacobian:
            self.check(q, jacobian=True)

    def _switch_active(self, name: str | None, lock) -> None:
        """``set_active``'s rule for every subclass: ``name`` (a robot of the scene, or None: all arms) becomes
        the active arm and the Detector builds again under ``lock``; a build refused (an arm without a pair)
        leaves the arm in use, and its build, as they were (the refused arm stayed named while checks ran on
        the old build, and a later edit raised)."""
        from .._errors import DetectionError

        if name is not None and name not in self.scene.robots:
            raise DetectionError(f"active: unknown robot {name!r}; robots are {list(self.scene.robots)}")
        hook = self.__dict__.get("_on_switch")  # what an extra attached follows (terrain: its guard's arm)
        with self.switch_mutex():
            install = hook(name) if hook is not None else None  # made before anything changes: a failure changes nothing
            with lock:
                self._switches = self.switches + 1  # odd while switching (an extra's reader waits, or checks again)
                try:
                    old, self._active = self._active, name
                    try:
                        self.prepare()
                    except BaseException:
                        self._active = old
                        raise
                    if install is not None:
                        install()
                finally:
                    self._switches += 1

    _switches = 0

    @property
    def switches(self) -> int:
        """Active-arm switches begun and finished, counted twice each: odd while ``set_active`` is switching.  A
        reader composing the kernel's check with state that follows the active arm (an attached terrain's guard)
        reads it before and after, and checks again when it changed (a seqlock); after a few tries it holds
        :meth:`switch_mutex` (no switch then starts: a thread switching without pause cannot starve it)."""
        return self._switches

    def switch_mutex(self):
        """The lock ``set_active`` holds for a whole switch (made at first use)."""
        import threading

        return self.__dict__.setdefault("_switch_mutex", threading.Lock())

    def __new__(cls, scene=None, *args, backend: str | None = None, backend_options=None, **kwargs):
        if cls is not Detector:  # a concrete Detector, built directly
            return super().__new__(cls)
        from ._ranger import RangerDetector, fast_path

        chosen = fast_path(backend, backend_options) or RangerDetector
        if isinstance(chosen, type) and issubclass(chosen, Detector):
            return super().__new__(chosen)  # Python then runs chosen.__init__ with the same arguments
        return chosen(scene, *args, backend=backend, backend_options=backend_options, **kwargs)
