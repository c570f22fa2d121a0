"""The workcell runtime a program runs on: WORKMATE's emulation of a task program, one primitive at a time.

:class:`Workcell` holds two copies of the cell: the *believed* one (the nominal model with every
frame a FIND has bound moved to where the camera found it) and the emulated *real* one (the true
object poses).  Each motion is expanded through the robot's IK, verified (certified) on the
believed cell — with the bound frames' covariance, at ``confidence`` (the uncertainty module's
:func:`~armguard.uncertainty.verify_with_confidence`) — and only then emulated: run in the real
cell, where it is checked again.  A motion refused by either check stops the program
(:class:`ProgramStopped`, with the verification report).

The primitives (``find``, ``frame``, ``move``, ``move_joints``, ``home``, ``grasp``,
``release``) are what a task program expands into and what an exported program calls
(:mod:`._export`): the same calls with the same seed give the same motions.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._errors import ArmguardError, SceneError
from ._cell import Cell, _inv, move_body
from ._supports import CONTACT_TOLERANCE, SINK, support_scene

__all__ = ["Workcell", "ProgramStopped", "MotionRecord", "FindRecord", "ProgramRun", "pose", "CONTACT_TOLERANCE"]

_UNCALIBRATED = ("FIND used the camera at a pose without covariance (nominal, or a calibration that gives none): the "
                 "motions' confidence covers FIND's noise, not an error in the camera's placement; `armguard program "
                 "calibrate` measures both")


def pose(xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)) -> np.ndarray:
    """``trans(x, y, z) rot(z, yaw) rot(y, pitch) rot(x, roll)`` (4, 4): m and rad (the scene files' relation)."""
    from ..kinematics import pose_from_xyz_rpy

    return pose_from_xyz_rpy(np.asarray(xyz, dtype=np.float64), np.asarray(rpy, dtype=np.float64))


class ProgramStopped(ArmguardError):
    """A program stopped: a motion refused (``record.status``: ``collision`` or ``incomplete`` on
    the believed cell, ``real collision`` in the emulated real cell, ``unreachable``) or a FIND
    the camera cannot answer.  ``record`` is the :class:`MotionRecord` (None for a FIND)."""

    def __init__(self, message: str, record=None) -> None:
        self.record = record
        super().__init__(message)


@dataclass
class MotionRecord:
    """One expanded motion: ``label`` (task and phase), ``trajectory``, ``status`` (``ran`` or why
    it was refused), ``report`` (the certified VerificationReport on the believed cell, grown by
    the bound frames' confidence ellipsoids when there are any), ``k`` (their Mahalanobis radius,
    0 without), ``real_report`` (the check in the emulated real cell)."""

    label: str
    trajectory: object
    status: str
    report: object = None
    k: float = 0.0
    real_report: object = None

    nominal_clearance: float | None = None  # a refusal at confidence k > 0: the clearance of the objects not grown
    notes: list = field(default_factory=list)  # what else the motion's checks found (a held object sunk into its support)

    @property
    def min_clearance(self) -> float:
        return float(self.report.min_clearance) if self.report is not None else float("nan")

    def why(self) -> list:
        """For a refused or stopped motion, what hit what and when (the report's first collision), and for a
        refusal of grown bound objects the clearance they have as found; else ``[]``."""
        if self.status == "ran":
            return list(self.notes)
        rep = self.real_report if self.status.startswith("stopped") else self.report
        c = getattr(rep, "first_collision", None)
        out = []
        if c is not None:
            where = f" at ({', '.join(f'{x:.4f}' for x in c.p_W)}) m" if c.p_W is not None else ""
            feat = f" {c.feature}" if c.feature is not None else ""
            out.append(f"{c.describe()}: {c.link or c.payload or c.a} with {c.obstacle}{feat}{where}, t = {c.time:.4f} s")
        if self.nominal_clearance is not None:
            out.append(f"not verified at the confidence asked: the bound objects grown by up to {self.k:.2f} sigma touch; as "
                       f"found they are {1e3 * self.nominal_clearance:.1f} mm clear (calibrate the camera, or ask less "
                       "confidence)" if self.nominal_clearance > 0.0 else
                       "the bound objects collide as found, without their growth")
        return out + list(self.notes)


@dataclass
class FindRecord:
    """A FIND: the object's ``nominal`` frame, the ``found`` (bound) frame, its ``true`` pose in the
    emulated cell and the bound frame's ``uncertain`` relation (UncertainPose3)."""

    object: str
    nominal: np.ndarray
    found: np.ndarray
    true: np.ndarray
    uncertain: object


@dataclass
class ProgramRun:
    """A program's run: ``motions`` and ``finds`` in order, ``ok`` (every motion verified and ran),
    ``stopped`` (the reason when not), and the objects' final poses, ``believed`` and ``real``."""

    name: str
    motions: list = field(default_factory=list)
    finds: list = field(default_factory=list)
    ok: bool = True
    stopped: str = ""
    believed: dict = field(default_factory=dict)
    real: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)  # what the verdicts rest on that the cell does not know

    def axis_offset(self, obj: str, target: str) -> float:
        """m: the horizontal distance (in W's x-y plane) between ``obj``'s and ``target``'s frame
        origins in the emulated real cell — for stacked cylinders, how far the placed one's axis
        landed from the other's."""
        d = self.real[obj][:3, 3] - self.real[target][:3, 3]
        return float(np.hypot(d[0], d[1]))

    def summary(self) -> str:
        """A text report: each FIND (nominal, found, true) and each motion (status, clearance)."""
        out = [f"program {self.name}: {'every motion verified and ran' if self.ok else 'STOPPED: ' + self.stopped}"]
        out += [f"  warning: {w}" for w in self.warnings]
        for f in self.finds:
            dn = 1e3 * np.linalg.norm(f.found[:3, 3] - f.nominal[:3, 3])
            dt = 1e3 * np.linalg.norm(f.found[:3, 3] - f.true[:3, 3])
            out.append(f"  FIND {f.object}: found at {np.round(f.found[:3, 3], 4).tolist()} m "
                       f"({dn:.1f} mm from nominal, {dt:.1f} mm from true)")
        for m in self.motions:
            clear = "" if m.report is None else f", clearance {1e3 * m.min_clearance:.1f} mm{_between(m.report)}"
            k = f" beyond {m.k:.2f} sigma" if m.k > 0.0 else ""
            real = "" if m.real_report is None else f", real cell {1e3 * float(m.real_report.min_clearance):.1f} mm"
            out.append(f"  {m.label}: {m.status} ({m.trajectory.duration:.2f} s{clear}{k}{real})"
                       if m.trajectory is not None else f"  {m.label}: {m.status}")
            for line in m.why():
                out.append(f"    {line}")
        return "\n".join(out)

    def to_dict(self) -> dict:
        """Plain form (JSON): each motion's label, status, times and waypoints; each FIND's frames."""
        return {"name": self.name, "ok": self.ok, "stopped": self.stopped, "warnings": list(self.warnings),
                "motions": [{"label": m.label, "status": m.status, "why": m.why(),
                             "times": None if m.trajectory is None else m.trajectory.times.tolist(),
                             "waypoints": None if m.trajectory is None else m.trajectory.waypoints.tolist()}
                            for m in self.motions],
                "finds": [{"object": f.object, "nominal": f.nominal.tolist(), "found": f.found.tolist(),
                           "true": f.true.tolist()} for f in self.finds]}


class Workcell:
    """The runtime of a program on ``cell`` (:class:`~armguard.program.Cell`).

    ``seed`` seeds the camera's noise; ``speed`` (m/s) is the straight lines' speed;
    ``confidence`` the probability the bound frames' motions are verified at; ``method`` the
    verifier's (``certified``)."""

    def __init__(self, cell: Cell, *, seed: int = 0, speed: float = 0.1, confidence: float = 0.999,
                 method: str = "certified", name: str = "program") -> None:
        self.cell = cell
        self.robot = cell.robot
        self.believed = cell.nominal_scene()
        self.real = cell.real_scene()
        self.X_believed = {k: np.array(v) for k, v in cell.objects.items()}
        self.X_real = {k: np.array(v) for k, v in cell.real.items()}
        self.bound: dict = {}
        self.q = np.array(self.believed.home(self.robot))
        self.held = None  # (object, X_EO believed, X_EO real)
        self._held_unc = None  # the held object's FIND relation: (its covariance, X_WP at the grasp)
        self._supports: list = []
        self._sink_scenes: tuple = (None, None)
        self._rng = np.random.default_rng(seed)
        self.speed, self.confidence, self.method = float(speed), float(confidence), method
        self.run = ProgramRun(name)
        self.label = ""

    # ------------------------------------------------------------------ frames
    @property
    def _arm(self):
        return self.believed.robots[self.robot]

    def tool_pose(self) -> np.ndarray:
        """X_WE: the tool's pose now."""
        return self._arm.link_pose(self.q, self._arm.tool_link)

    def frame(self, name: str) -> np.ndarray:
        """X_WF of frame ``name``: ``world``, ``base`` (the robot's mount), ``tool`` (the tool now), or an
        object's frame as the last FIND bound it (its nominal frame before any FIND; where the hand
        holds it while held)."""
        if name == "world":
            return np.eye(4)
        if name == "base":
            return np.array(self._arm.X_WB)
        if name == "tool":
            return self.tool_pose()
        if self.held is not None and name == self.held[0]:
            return self.tool_pose() @ self.held[1]
        if name not in self.X_believed:
            raise SceneError(f"unknown frame {name!r}; frames are world, base, tool and the objects {list(self.X_believed)}")
        return np.array(self.X_believed[name])

    # ------------------------------------------------------------------ FIND
    def find(self, obj: str) -> np.ndarray:
        """Ask the camera for ``obj``: binds its frame (with the camera's covariance) and moves it in
        the believed cell; returns the found X_WO."""
        if obj not in self.X_real:
            raise SceneError(f"FIND {obj}: no object {obj!r} in the cell; objects are {list(self.X_real)}")
        if self.held is not None and self.held[0] == obj:
            raise SceneError(f"FIND {obj}: the object is in the hand")
        cam = self.cell.camera
        if not cam.sees(self.X_real[obj][:3, 3]):
            msg = f"FIND {obj}: the object is outside the camera's field of view"
            self.run.ok, self.run.stopped = False, msg
            raise ProgramStopped(msg)
        X_found = cam.measure(self.X_real[obj], self._rng)
        if not np.any(cam.cov_pose) and not any(w.startswith(_UNCALIBRATED[:40]) for w in self.run.warnings):
            self.run.warnings.append(_UNCALIBRATED)
        move_body(self.believed, obj, X_found @ _inv(self.X_believed[obj]))
        unc = cam.uncertain(X_found)
        self.run.finds.append(FindRecord(obj, np.array(self.cell.objects[obj]), X_found, np.array(self.X_real[obj]), unc))
        self.X_believed[obj] = X_found
        self.bound[obj] = unc
        return np.array(X_found)

    # ------------------------------------------------------------------ motions
    def move(self, X_WE, *, mode: str = "joint", touching=(), label: str | None = None) -> MotionRecord:
        """Move the tool to ``X_WE`` (a straight ``line`` or ``joint``-interpolated), verified first;
        ``touching`` names bodies the held object (or, with nothing held, the hand) may touch on
        this motion (PLACE's release: the object set down on its target)."""
        from .._errors import TrajectoryError
        from ..kinematics import Trajectory

        label = label or self.label or "move"
        try:
            traj = Trajectory.through_poses(self._arm, self.q, np.asarray(X_WE, dtype=np.float64)[None], mode=mode,
                                            speed=self.speed)
        except TrajectoryError as exc:
            return self._stop(MotionRecord(label, None, "unreachable"), f"{label}: {exc}")
        return self._run(traj, touching, label)

    def move_joints(self, q, *, label: str | None = None) -> MotionRecord | None:
        """Joint-interpolated move to ``q`` (rad), verified first; None when already there."""
        from ..kinematics import Trajectory

        q = np.asarray(q, dtype=np.float64)
        if np.array_equal(q, self.q):
            return None
        return self._run(Trajectory.trapezoidal(self._arm, self.q, q), (), label or self.label or "move joints")

    def home(self, *, label: str | None = None) -> MotionRecord | None:
        """Joint-interpolated move to the robot's home."""
        return self.move_joints(self.believed.home(self.robot), label=label or self.label or "move home")

    def _pairs(self, touching) -> list:
        who = self.held[0] if self.held is not None else f"{self.robot}/{self._arm.tool_link}"
        pairs = [(who, b) for b in touching]
        return pairs + [(self.held[0], b) for b in self._supports] if self.held is not None else pairs

    def _run(self, traj, touching, label: str) -> MotionRecord:
        from ..uncertainty import UncertainPlacement, UncertainPose3, verify_with_confidence
        from ..verify import verify

        for b in touching:
            if b not in self.believed.bodies:
                raise SceneError(f"{label}: touching names no body {b!r}; bodies are {list(self.believed.bodies)}")
        pairs = self._pairs(touching)
        added = _allow(self.believed, pairs), _allow(self.real, pairs)
        try:
            places = [UncertainPlacement(o, u) for o, u in self.bound.items() if o in self.believed.bodies and np.any(u.cov)]
            if self.held is not None and self._held_unc is not None and np.any(self._held_unc[0]):
                places.append(UncertainPlacement(self.held[0], UncertainPose3(self._held_unc[1], self._held_unc[0])))
            k = 0.0
            if places:
                cv = verify_with_confidence(self.believed, traj, places, self.confidence, method=self.method)
                report, k = cv.report, float(cv.k)
            else:
                report = verify(self.believed, traj, method=self.method)
            rec = MotionRecord(label, traj, "ran", report, k)
            if report.safe and self._supports:
                report = self._sink_check(rec, 0, traj) or report
            if not report.safe:
                rec.status = "refused: " + report.status.value
                if k > 0.0:  # said apart: a refusal of the grown objects from one of the objects as found
                    nominal = verify(self.believed, traj, method=self.method)
                    # unsafe as found: a contact (its clearance stops at the contact, 0.0 mm "clear" was said)
                    rec.nominal_clearance = float(nominal.min_clearance) if nominal.safe else min(0.0, float(nominal.min_clearance))
                return self._stop(rec, f"{label}: refused by verification ({report.verdict()})")
            rec.real_report = verify(self.real, traj, method=self.method)
            if rec.real_report.safe and self._supports:
                rec.real_report = self._sink_check(rec, 1, traj) or rec.real_report
            if not rec.real_report.safe:
                rec.status = "stopped: " + rec.real_report.status.value + " in the emulated real cell"
                return self._stop(rec, f"{label}: {rec.real_report.verdict()} in the emulated real cell")
        finally:
            _restore(self.believed, added[0]), _restore(self.real, added[1])
        self.q = np.array(traj.waypoints[-1])
        self._supports = []
        self._sink_scenes = (None, None)
        self.run.motions.append(rec)
        return rec

    def _sink_check(self, rec: MotionRecord, which: int, traj):
        """The motion after a grasp on the copy of the believed (0) or real (1) cell that checks the held object,
        eroded by SINK, against its supports (._supports): its report when it is not safe (the object pushed
        into what it rested on), else None; where the object cannot be eroded, a note on ``rec``."""
        from ..verify import verify

        sub = self._sink_scenes[which]
        if sub is None:
            if which == 0:
                rec.notes.append(f"{self.held[0]} cannot be eroded by {SINK * 1e3:g} mm (its shape): its supports "
                                 f"({', '.join(self._supports)}) were not checked during this motion")
            return None
        rep = verify(sub, traj, method=self.method)
        if rep.safe:
            return None
        rec.notes.append(f"{self.held[0]} sinks into {rep.first_collision.obstacle}, which it rested on, {SINK * 1e3:g} mm "
                         "deeper than at the grasp: a motion after a grasp must lift the object off")
        return rep

    def _stop(self, rec: MotionRecord, message: str):
        self.run.motions.append(rec)
        self.run.ok, self.run.stopped = False, message
        raise ProgramStopped(message, rec)

    # ------------------------------------------------------------------ the hand
    def grasp(self, obj: str) -> None:
        """Close the hand on ``obj``: it becomes a payload of the tool link, held where it is (in each
        cell); its pairs with every body are checked from now on, but those it rests on (its
        supports) only after the next motion."""
        if self.held is not None:
            raise SceneError(f"PICKUP {obj}: the hand already holds {self.held[0]!r}")
        if obj not in self.believed.bodies:
            raise SceneError(f"PICKUP {obj}: no body {obj!r} in the cell")
        supports = sorted(set(_touching(self.believed, obj)) | set(_touching(self.real, obj)))
        tool = self._arm.tool_link
        X_EW = _inv(self.tool_pose())
        # the next motion lifts it off its supports: checked on copies that hold only those pairs, the
        # object eroded by SINK (._supports); None where the object cannot be eroded (said at the motion)
        self._sink_scenes = tuple(support_scene(sc, obj, supports, self.robot, tool, self.q) if supports else None
                                  for sc in (self.believed, self.real))
        for scene in (self.believed, self.real):
            scene.grasp(obj, self.robot, tool, self.q)
            for b in scene.bodies:
                if frozenset((obj, b)) in scene.disabled_pairs:
                    scene.enable_pair(obj, b)
        self.held = (obj, X_EW @ self.X_believed[obj], X_EW @ self.X_real[obj])
        u = self.bound.pop(obj, None)  # carried with the hand: the payload is grown by it (uncertainty._confident)
        self._held_unc = None if u is None else (np.array(u.cov), self.believed.link_pose(self.q, self.robot, tool))
        self._supports = supports

    def release(self, obj: str) -> None:
        """Open the hand: ``obj`` becomes a static body where it is (in each cell)."""
        if self.held is None or self.held[0] != obj:
            raise SceneError(f"PLACE {obj}: the hand does not hold {obj!r}")
        X_WE = self.tool_pose()
        for scene in (self.believed, self.real):
            scene.release_payload(obj, self.q)
            for b in scene.bodies:
                if b != obj:
                    scene.disable_pair(obj, b)  # two static bodies: never checked
        self.X_believed[obj] = X_WE @ self.held[1]
        self.X_real[obj] = X_WE @ self.held[2]
        if self._held_unc is not None:  # set down where the hand took it: the FIND's displacement moved with it
            from ..uncertainty import UncertainPose3, se3

            cov, X_WP_grasp = self._held_unc
            T = self.believed.link_pose(self.q, self.robot, self._arm.tool_link) @ _inv(X_WP_grasp)
            Ad = se3.adjoint(T)
            self.bound[obj] = UncertainPose3(self.X_believed[obj], Ad @ cov @ Ad.T)
        self.held, self._held_unc = None, None

    def finish(self) -> ProgramRun:
        """The run so far, with the objects' final poses."""
        self.run.believed = {k: np.array(v) for k, v in self.X_believed.items()}
        self.run.real = {k: np.array(v) for k, v in self.X_real.items()}
        if self.held is not None:
            obj, X_EO_b, X_EO_r = self.held
            self.run.believed[obj] = self.tool_pose() @ X_EO_b
            self.run.real[obj] = self.tool_pose() @ X_EO_r
        return self.run


def _between(report) -> str:
    """`` between A and B`` of a report's least clearance (a fixed pair of the robot's own links says so)."""
    at = getattr(report, "min_clearance_at", None)
    return f" between {at.a} and {at.b}" if at is not None else ""


def _allow(scene, pairs) -> list:
    added = []
    for a, b in pairs:
        if frozenset((a, b)) not in scene.disabled_pairs:
            scene.disable_pair(a, b)
            added.append((a, b))
    return added


def _restore(scene, added) -> None:
    for a, b in added:
        scene.enable_pair(a, b)


def _touching(scene, obj: str) -> list:
    """The bodies of ``scene`` within :data:`CONTACT_TOLERANCE` of body ``obj``."""
    from ..geometry import distance

    out = []
    for b, body in scene.bodies.items():
        if b == obj:
            continue
        d = min(float(distance(s, t).distance) for s in scene.bodies[obj].shapes for t in body.shapes)
        if d <= CONTACT_TOLERANCE:
            out.append(b)
    return out
