"""What the panel says besides the active arm's readout: refusals tied to a field, and other arms.

Mixed into :class:`~._state.ConsoleState` (its lock, scene, configuration and settings).

**Refusals** (:meth:`NoticesMixin.note_error` with a ``source``, :meth:`NoticesMixin.clear_error`):
a refused value's message names its field; the next value that field accepts takes the message
away, also when accepting it changes nothing in the state (a jog step, a threshold typed equal
to the one in force).

**Other arms** (:meth:`NoticesMixin._evaluate_others`): the panel is the active arm's (Ranger:
the active arm against everything), so selecting another arm hid a near miss of the arm left
behind.  After each update every other arm is checked against everything at the current
configuration by a :class:`armguard.detect.Detector` of its own (the console's detector's
settings, that arm active; built once per model and arm, the terrain not included); those
within the threshold or in collision are listed in :attr:`Snapshot.others` and shown in the
panel, named moving link first as the panel's pair.  The cost is one detector check per other
arm and update (Ranger's four arms: three checks, about 0.2 ms beside the panel's own 20-70 µs;
:attr:`NoticesMixin.others_us`), and building the detectors at a model's first update (~5 ms).
"""

from __future__ import annotations

import html
import time
from dataclasses import dataclass

from ._readout import PanelStatus, _fmt_m, _status_of

__all__ = ["NoticesMixin", "OtherArm", "others_html"]


@dataclass(frozen=True)
class OtherArm:
    """An arm other than the active one within the threshold (or in collision): its nearest pair."""

    robot: str
    status: PanelStatus
    distance: float
    link: str
    obstacle: str


class NoticesMixin:
    """Refusals tied to their field, and the other arms' near misses."""

    _error_source: tuple | None = None
    _others: tuple = ()
    _other_detectors: dict | None = None
    others_us: float = 0.0
    """How long the last update's check of the other arms took (µs; 0 with one arm or detection off)."""

    # ------------------------------------------------------------------ refusals
    def note_error(self, message: str, source: str | None = None) -> None:
        """Show ``message`` (an input the GUI rejected before it reached a command, or a command's
        refusal); ``source`` names the field it refused, so that field's next accepted value
        clears it (:meth:`clear_error`)."""
        with self._lock:
            self._message = message
            self._message_is_error = True
            self._error_source = None if source is None else (source, message)
            self._version += 1

    def clear_error(self, source: str) -> bool:
        """Field ``source`` accepted a value: the refusal it caused, if the panel still shows it, goes.

        Returns whether a message was cleared (another field's error, or a newer message, stays)."""
        with self._lock:
            if not (self._message_is_error and self._error_source == (source, self._message)):
                return False
            self._message, self._message_is_error, self._error_source = "", False, None
            self._version += 1
            return True

    # ------------------------------------------------------------------ other arms
    @property
    def others(self) -> tuple[OtherArm, ...]:
        """The arms other than the active one within the threshold or in collision (last update)."""
        return self._others

    def _other_detector(self, robot: str):
        from ..detect import Detector

        cache = self._other_detectors
        if cache is None or cache.get("") is not self._detector:  # a new model or scene: new detectors
            cache = self._other_detectors = {"": self._detector}
        det = cache.get(robot)
        if det is None:
            det = cache[robot] = Detector(self._scene, self._threshold, stopping_distance=self._stopping,
                                          active=robot, tol=self._tol)
        if det.threshold != self._threshold:
            det.set_threshold(self._threshold)
        if det.stopping_distance != self._stopping:
            det.set_stopping_distance(self._stopping)
        return det

    def _evaluate_others(self) -> None:
        """Check every arm but the active one (lock held); keep those within the threshold or in collision."""
        self._others, self.others_us = (), 0.0
        if not self._detection or len(self._scene.robots) < 2:
            return
        t0 = time.perf_counter()
        out = []
        for robot in self._scene.robots:
            if robot == self._active:
                continue
            rep = self._other_detector(robot).check(self._q)
            near, status = rep.nearest, _status_of(rep)
            if near is None or status not in (PanelStatus.WARNING, PanelStatus.COLLISION, PanelStatus.INCOMPLETE):
                continue
            link, obstacle = str(near.link), str(near.obstacle)
            if self._is_static(link) and not self._is_static(obstacle):  # a pedestal is the obstacle
                link, obstacle = obstacle, link
            out.append(OtherArm(robot, status, float(near.distance), link, obstacle))
        self._others = tuple(out)
        self.others_us = (time.perf_counter() - t0) * 1e6


def others_html(others) -> str:
    """The panel's notice of the other arms within the threshold (``id="armguard-others"``,
    ``data-arms`` their names); empty when there are none."""
    if not others:
        return ""
    e = html.escape
    worst = any(o.status is PanelStatus.COLLISION for o in others)
    lines = "".join(
        f"<div><b>{e(o.robot)}</b> (not active): {e(o.status.value.upper())} {e(_fmt_m(o.distance))} "
        f"{e(o.link)} / {e(o.obstacle)}</div>" for o in others)
    return (f'<div id="armguard-others" data-arms="{e(" ".join(o.robot for o in others))}" '
            f'style="border:2px solid {"#d62828" if worst else "#c99a00"};border-radius:6px;padding:4px;'
            'margin-top:4px;font-family:sans-serif;font-size:0.9em;overflow-wrap:anywhere;word-break:break-word">'
            "<div><b>other arms within the threshold</b></div>" + lines + "</div>")
