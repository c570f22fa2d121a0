"""The terrain category merged into the Detector's report (composition: the fused kernel is untouched).

``Detector(scene, terrain=...)`` (or :func:`attach_terrain` on an existing detector) makes its
``check`` return a :class:`TerrainDetectionReport`: the detector's own report with a
``"terrain"`` entry in ``by_category`` (the link–terrain pair its TerrainReport names, from a
:class:`TerrainGuard` at the detector's threshold and stopping distance) and the status of both.
A detector without terrain is not touched: ``check`` stays the class's method, at no cost.
With terrain, the batches answer for it too: ``collides_many`` is the kernel's or the guard's
(:meth:`TerrainGuard.collides_many` at the detector's stopping distance), and ``check_many``'s
statuses and collisions are merged with the guard's per row (its ``min_distance`` keeps the
kernel's four categories); they used to be the kernel's alone, and said clear where ``check``
said collision.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..detect import DetectionReport, Status
from ..detect._report import STATUS_CODES, BatchReport
from ..detect._extras import register_extra
from ._guard import TERRAIN, TerrainGuard, TerrainReport

__all__ = ["TerrainDetectionReport", "attach_terrain", "check_with_terrain", "merge_status"]

_RANK = {Status.CLEAR: 0, Status.WARNING: 1, Status.INCOMPLETE: 2, Status.COLLISION: 3}


def merge_status(a: Status, b: Status) -> Status:
    """The verdict of two checks together: COLLISION over INCOMPLETE over WARNING over CLEAR
    (INCOMPLETE: one of them could not prove the threshold holds — never CLEAR by omission)."""
    return a if _RANK[a] >= _RANK[b] else b


@dataclass(frozen=True)
class TerrainDetectionReport(DetectionReport):
    """A :class:`armguard.DetectionReport` with the terrain category.

    ``status`` is the merged verdict (:func:`merge_status`) and ``detector_status`` the kernel's
    own; ``by_category["terrain"]`` the link–terrain pair its ``terrain`` report names (absent when every link is beyond
    the guard's ``reach``); ``within_threshold`` includes it when it is within the threshold;
    ``terrain`` the full :class:`TerrainReport`; ``elapsed_us`` both checks.
    """

    terrain: TerrainReport | None = None
    detector_status: Status | None = None

    @cached_property
    def by_category(self) -> dict:
        cats = dict(self._raw.by_category())
        pair = None if self.terrain is None else self.terrain.pair()
        if pair is not None:
            cats[TERRAIN] = pair
        return cats

    @cached_property
    def within_threshold(self) -> tuple:
        own = tuple(self._raw.within(self.threshold))
        pair = None if self.terrain is None else self.terrain.pair()
        if pair is None or pair.distance > self.threshold:
            return own
        return tuple(sorted(own + (pair,), key=lambda r: r.distance))

    def to_dict(self) -> dict:
        d = super().to_dict()
        d["detector_status"] = None if self.detector_status is None else self.detector_status.value
        d["terrain"] = None if self.terrain is None else self.terrain.to_dict()
        return d


def _merged(detector, rep: DetectionReport, terrain: TerrainReport) -> TerrainDetectionReport:
    r = TerrainDetectionReport._from_check(merge_status(rep.status, terrain.status), rep.threshold,
                                           rep.stopping_distance, rep.elapsed_us + terrain.elapsed_us, rep._raw)
    r.__dict__["terrain"] = terrain
    r.__dict__["detector_status"] = rep.status
    return r


def check_with_terrain(detector, guard: TerrainGuard, q, **kwargs) -> TerrainDetectionReport:
    """``detector.check(q, **kwargs)`` and ``guard.check(q)`` at the threshold and stopping distance that
    check used (its report's: another thread may change the detector's between the two), as one report;
    its ``terrain`` attribute is the guard's :class:`TerrainReport`.  Works with any Detector, terrain
    attached or not (the guard given here is the one used)."""
    check = type(detector).check  # the kernel's check, whatever is attached
    rep = check(detector, q, **kwargs)
    ter = guard.check(q, threshold=rep.threshold, stopping_distance=rep.stopping_distance)
    return _merged(detector, rep, ter)


def _guard_over(given: TerrainGuard, scene, robot: str | None) -> TerrainGuard:
    """``given``, or a guard over the same pyramid, reach and margins for ``robot`` (None: every robot)."""
    if robot == given.robot:
        return given
    return TerrainGuard(scene, given.pyramid, robot=robot, reach=given.reach, unknown_margin=given.unknown_margin,
                        tol=given.tol)


def _consistent(detector, run):
    """``run(guard)`` where neither the kernel's active arm nor the guard changed meanwhile: ``detector.switches``
    read before and after (a seqlock); a switch under way is waited out, and a run it overlapped runs again (a
    check and the terrain guard of another arm: 3,112 of 8,708 checks under a thread toggling ``set_active``);
    after three tries, under ``detector.switch_mutex()``."""
    for _ in range(3):
        s0 = detector.switches
        if s0 % 2:  # switching: the new build and guard are moments away
            continue
        out = run(detector.terrain)
        if detector.switches == s0:
            return out
    with detector.switch_mutex():  # no switch starts meanwhile
        return run(detector.terrain)


def attach_terrain(detector, terrain) -> TerrainGuard:
    """Attach ``terrain`` (a :class:`TerrainGuard`, :class:`TerrainPyramid` or :class:`ElevationMap`)
    to ``detector``: from now on ``detector.check(q)`` returns a :class:`TerrainDetectionReport`;
    ``detector.terrain`` is the guard.  A pyramid or map gets a guard over the detector's active
    robot (all robots when none); ``set_active`` moves it to the new active arm, and a guard given for
    one arm is followed by one over the same terrain for the new arm, or for every robot when none is
    active (it checked the old arm: a terrain collision of the new one read WARNING).  ``None``
    detaches.  Returns the guard."""
    if terrain is None:
        for name in ("check", "collides_many", "check_many", "_on_switch"):
            detector.__dict__.pop(name, None)
        detector.terrain = None
        return None
    if isinstance(terrain, TerrainGuard):
        given = terrain
    else:
        given = TerrainGuard(detector.scene, terrain, robot=detector.active)
    derived = not isinstance(terrain, TerrainGuard)
    made = {given.robot: given}
    detector.terrain = given

    def on_switch(name):  # before set_active changes anything: the new arm's guard (or its error); then install it
        keep = derived or not (given.robot is None or given.robot == name)
        robot = name if keep else given.robot
        guard = made.get(robot)
        if guard is None:
            guard = made.setdefault(robot, _guard_over(given, detector.scene, robot))

        def install() -> None:
            detector.terrain = guard

        return install

    def check(q, **kwargs):
        return _consistent(detector, lambda g: check_with_terrain(detector, g, q, **kwargs))

    def collides_many(Q):
        def run(guard):
            sd = detector.stopping_distance
            own = np.asarray(type(detector).collides_many(detector, Q))
            return own | guard.collides_many(Q, stopping_distance=sd)

        return _consistent(detector, run)

    def check_many(Q):
        def run(guard):
            own = type(detector).check_many(detector, Q)
            rows = np.asarray(Q, dtype=np.float64).reshape(len(own.status), -1)
            status, collision = own.status.copy(), own.collision.copy()
            for i, q in enumerate(rows):  # at the settings the batch used (its report's)
                ter = guard.check(q, threshold=own.threshold, stopping_distance=own.stopping_distance).status
                merged = merge_status(STATUS_CODES[int(status[i])], ter)
                status[i] = STATUS_CODES.index(merged)
                collision[i] |= ter is Status.COLLISION
            return BatchReport(own.min_distance, collision, status, own.threshold, own.stopping_distance)

        return _consistent(detector, run)

    check.__doc__ = type(detector).check.__doc__
    collides_many.__doc__ = type(detector).collides_many.__doc__
    check_many.__doc__ = type(detector).check_many.__doc__
    detector.check, detector.collides_many, detector.check_many = check, collides_many, check_many
    detector._on_switch = on_switch
    return given


register_extra("terrain", attach_terrain)  # Detector(..., terrain=...) attaches through it
