"""The console's task menu without a browser: WORKMATE's off-line programming (Smith 1986, seed 004,
§III.D) — tasks pasted from a menu (FIND, PICKUP, PLACE, MOVE), their prompts answered by naming
objects (the panel: by clicking them in the 3-D view), the program run through
:func:`armguard.program.run_program` (each motion verified, certified, before it is emulated) and
put on the time line, or saved as a task-program file (``docs/program.md``).

A :class:`TaskComposer` holds the tasks as the file's own mappings (lengths in m, angles in deg:
the file's ``units: {angle: deg, length: m}``), so the program that runs and the file that is saved
are parsed by the same reader from the same values.  PICKUP and PLACE poses are made from the
objects' sizes (hand pointing down, ``rpy = (180, 0, 0)`` deg, as in ``examples/workmate/stack.yaml``):

* PICKUP ``o``: grasp ``g`` above ``o``'s frame origin, approach and depart ``lift`` above that;
* PLACE ``o`` onto ``t``: release where ``o``'s bottom rests on ``t``'s top —
  ``z = (top(t) - origin(t)) + (origin(o) - bottom(o)) + g`` in ``t``'s frame — approach and
  depart ``lift`` above it (``g`` the grasp height of the PICKUP of ``o`` before it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._parse import ConsoleInputError, parse_number

__all__ = ["TASK_KINDS", "PROMPTS", "TaskComposer", "DEFAULT_GRASP", "DEFAULT_LIFT", "DOWN_RPY_DEG",
           "program_timeline", "held_intervals", "carried", "task_ends"]

TASK_KINDS = ("FIND", "PICKUP", "PLACE", "MOVE")
PROMPTS = {"FIND": ("object",), "PICKUP": ("object",), "PLACE": ("object", "onto"), "MOVE": ("frame",)}
"""What each task asks, in order: the prompts a click in the 3-D view answers."""
DEFAULT_GRASP = 0.02
"""m: the tool's height above an object's frame origin at the grasp (examples/workmate/stack.yaml)."""
DEFAULT_LIFT = 0.10
"""m: approach and depart stand this far above the grasp / release pose."""
DOWN_RPY_DEG = (180.0, 0.0, 0.0)
"""The hand pointing down (the tool's z along -z of the object's frame)."""
MAX_HEIGHT = 2.0
"""m: the largest grasp height or lift a prompt accepts."""


def _num(x: float) -> str:
    x = float(x)
    return repr(0.0 if x == 0.0 else x)


def _vec(v) -> str:
    return "[" + ", ".join(_num(x) for x in v) + "]"


@dataclass(frozen=True)
class Entry:
    """One task as its file mapping (``raw``, m and deg) and the line the program list shows."""

    raw: dict
    line: str


class TaskComposer:
    """A task program composed in the console, for ``cell`` (:class:`armguard.program.Cell`).

    ``cell_ref`` is how the saved file names the cell (a cell file's path, or a model name).
    :meth:`add` appends a task after checking its answers (unknown objects, a PLACE of an object
    the program does not hold, bad heights raise ConsoleInputError and add nothing)."""

    def __init__(self, cell, *, cell_ref: str | None = None, name: str = "console_program", speed: float = 0.1,
                 confidence: float = 0.999) -> None:
        self.cell = cell
        self.cell_ref = cell_ref
        self.name, self.speed, self.confidence = name, float(speed), float(confidence)
        self.entries: list[Entry] = []

    # ------------------------------------------------------------------ reading
    @property
    def objects(self) -> tuple[str, ...]:
        return tuple(self.cell.objects)

    @property
    def frames(self) -> tuple[str, ...]:
        return ("world", "base") + self.objects

    def lines(self) -> list[str]:
        """The program list: ``1. FIND cylinder_a`` ..."""
        return [f"{k + 1}. {e.line}" for k, e in enumerate(self.entries)]

    def _extent(self, obj: str) -> tuple[float, float]:
        """``(below, above)`` m: how far ``obj``'s shapes reach below and above its frame origin (W's z)."""
        z0 = float(self.cell.objects[obj][2, 3])
        lo, hi = math.inf, -math.inf
        for s in self.cell.model.scene.bodies[obj].shapes:
            b = np.asarray(s.aabb(), dtype=np.float64).reshape(2, 3)
            lo, hi = min(lo, b[0, 2]), max(hi, b[1, 2])
        return z0 - lo, hi - z0

    def _held(self) -> dict:
        """Objects held at the end of the program so far -> their grasp height (m)."""
        held: dict = {}
        for e in self.entries:
            if "pickup" in e.raw:
                held[e.raw["pickup"]] = float(e.raw["grasp"]["xyz"][2])
            elif "place" in e.raw:
                held.pop(e.raw["place"], None)
        return held

    def _object(self, name, prompt: str) -> str:
        if name not in self.cell.objects:
            raise ConsoleInputError(f"{prompt}: {name!r} is not an object of cell {self.cell.name!r}; "
                                    f"objects are {list(self.objects)}")
        return str(name)

    # ------------------------------------------------------------------ composing
    def add(self, kind: str, *, object=None, onto=None, frame=None, xyz=(0.0, 0.0, 0.0), rpy_deg=(0.0, 0.0, 0.0),
            home: bool = False, mode: str = "joint", grasp=DEFAULT_GRASP, lift=DEFAULT_LIFT) -> Entry:
        """Append a task (``FIND``, ``PICKUP``, ``PLACE``, ``MOVE``) with its answers; returns it."""
        kind = str(kind).upper()
        if kind not in TASK_KINDS:
            raise ConsoleInputError(f"task: expected one of {list(TASK_KINDS)}, got {kind!r}")
        g = parse_number(grasp, "grasp height", lo=-MAX_HEIGHT, hi=MAX_HEIGHT, unit="m")
        h = parse_number(lift, "approach lift", lo=0.0, hi=MAX_HEIGHT, unit="m")
        g = round(g, 9)  # nm: 0.12, not 0.12000000000000001
        held = self._held()
        down = list(DOWN_RPY_DEG)
        if kind == "FIND":
            o = self._object(object, "FIND object")
            if o in held:
                raise ConsoleInputError(f"FIND {o}: the program holds {o} at that point (the camera finds objects on the table)")
            e = Entry({"find": o}, f"FIND {o}")
        elif kind == "PICKUP":
            o = self._object(object, "PICKUP object")
            if held:
                raise ConsoleInputError(f"PICKUP {o}: the hand already holds {next(iter(held))}; PLACE it first")
            e = Entry({"pickup": o, "approach": {"xyz": [0.0, 0.0, round(g + h, 9)], "rpy": down},
                       "grasp": {"xyz": [0.0, 0.0, g], "rpy": down}, "depart": {"xyz": [0.0, 0.0, round(g + h, 9)], "rpy": down}},
                      f"PICKUP {o}")
        elif kind == "PLACE":
            o = self._object(object, "PLACE object")
            t = self._object(onto, "PLACE onto")
            if o not in held:
                raise ConsoleInputError(f"PLACE {o}: the hand does not hold {o} there; add a PICKUP {o} first")
            if t == o:
                raise ConsoleInputError(f"PLACE {o}: an object is not placed onto itself")
            z = round(self._extent(t)[1] + self._extent(o)[0] + held[o], 9)
            e = Entry({"place": o, "onto": t, "approach": {"xyz": [0.0, 0.0, round(z + h, 9)], "rpy": down},
                       "release": {"xyz": [0.0, 0.0, z], "rpy": down}, "depart": {"xyz": [0.0, 0.0, round(z + h, 9)], "rpy": down}},
                      f"PLACE {o} onto {t}")
        else:
            if home:
                e = Entry({"move": "home"}, "MOVE home")
            else:
                if frame not in self.frames:
                    raise ConsoleInputError(f"MOVE frame: {frame!r} is not a frame; frames are {list(self.frames)}")
                if mode not in ("line", "joint"):
                    raise ConsoleInputError(f"MOVE mode: expected line or joint, got {mode!r}")
                p = [float(v) for v in np.asarray(xyz, dtype=np.float64).reshape(3)]
                a = [float(v) for v in np.asarray(rpy_deg, dtype=np.float64).reshape(3)]
                if not all(math.isfinite(v) for v in p + a):
                    raise ConsoleInputError("MOVE: the pose has a non-finite value; nothing added")
                e = Entry({"move": "pose", "frame": str(frame), "xyz": p, "rpy": a, "mode": mode},
                          f"MOVE to {frame} " + ", ".join(f"{v:.3f}" for v in p) + f" m ({mode})")
        self.entries.append(e)
        return e

    def remove_last(self) -> None:
        if not self.entries:
            raise ConsoleInputError("program: no task to remove")
        self.entries.pop()

    def clear(self) -> None:
        self.entries.clear()

    # ------------------------------------------------------------------ the program
    def text(self, folder=None) -> str:
        """The task-program file (``armguard_program: 1``, docs/program.md) of the tasks so far, to be saved in
        ``folder``: a cell file is named relative to it (a program file's ``cell`` is read relative to the
        program file; written as the console was given it, it was found only from the console's folder);
        without ``folder``, by its whole path."""
        if not self.entries:
            raise ConsoleInputError("program: no tasks yet; add one from the task menu")
        out = ["# A task program composed in the armguard console's task menu.", "armguard_program: 1",
               f"name: {self.name}"]
        if self.cell_ref is not None:
            out.append(f"cell: {_quote(self._cell_for(folder))}")
        out += ["units: {angle: deg, length: m}", f"speed: {_num(self.speed)}", f"confidence: {_num(self.confidence)}",
                "tasks:"]
        for e in self.entries:
            items = list(e.raw.items())
            for k, (key, v) in enumerate(items):
                lead = "  - " if k == 0 else "    "
                if isinstance(v, dict):
                    v = "{" + ", ".join(f"{a}: {_vec(b)}" for a, b in v.items()) + "}"
                elif isinstance(v, list):
                    v = _vec(v)
                out.append(f"{lead}{key}: {v}")
        return "\n".join(out) + "\n"

    def program(self):
        """The tasks as an :class:`armguard.program.Program`, parsed by the file reader's own code."""
        from ..program import Program
        from ..program._format import ProgramFile, _task

        if not self.entries:
            raise ConsoleInputError("program: no tasks yet; add one from the task menu")
        file = "<console task menu>"
        tasks = tuple(_task(dict(e.raw), i, 1.0, math.pi / 180.0, file, {}) for i, e in enumerate(self.entries))
        return Program(ProgramFile(self.name, "", self.cell_ref, self.cell.robot, self.speed, self.confidence, tasks,
                                   file, Path.cwd()))

    def save(self, path) -> Path:
        """Write the task-program file to ``path`` (whole or not at all); returns the path."""
        from .._io import atomic_write

        from .._io import check_not_input

        check_not_input(path, [self.cell_ref, getattr(self.cell, "file", None)])  # never over the cell file
        text = self.text(Path(path).resolve().parent)
        return atomic_write(Path(path), text)

    def _cell_for(self, folder) -> str:
        """``cell_ref`` as a file saved in ``folder`` names it: a cell file relative to ``folder`` (its whole path
        where no relative one exists: another drive), a model name as it is."""
        import os

        ref = Path(self.cell_ref)
        if not ref.is_file():
            return self.cell_ref  # a model name (puma560)
        ref = ref.resolve()
        if folder is None:
            return str(ref)
        try:
            return os.path.relpath(ref, folder)
        except ValueError:
            return str(ref)

    def run(self, *, seed: int = 0):
        """Run the program on the cell (:func:`armguard.program.run_program`: every motion verified,
        certified, before it is emulated); returns the :class:`~armguard.program.ProgramRun`."""
        from ..program import run_program

        return run_program(self.program(), self.cell, seed=seed)


def _quote(s: str) -> str:
    import json

    return json.dumps(str(s))  # a YAML double-quoted scalar


def program_timeline(run):
    """``(trajectory, times, clearance)`` of a program run for the time line: its motions (those that
    ran and a refused one that has a trajectory) joined end to start, and the clearance profile of
    each motion's verification report on the believed cell, shifted to match; None when no motion has
    a trajectory."""
    from ..kinematics import Trajectory

    parts, times, clear = [], [], []
    t0 = 0.0
    for m in run.motions:
        if m.trajectory is None:
            continue
        parts.append(m.trajectory)
        prof = getattr(m.report, "profile", None)
        if prof is not None and len(prof.time):
            times.append(np.asarray(prof.time, dtype=np.float64) - float(m.trajectory.times[0]) + t0)
            clear.append(np.asarray(prof.overall, dtype=np.float64))
        t0 += float(m.trajectory.duration)
    if not parts:
        return None
    traj = Trajectory.concatenate(parts)
    if times:
        return traj, np.concatenate(times), np.concatenate(clear)
    return traj, np.array([0.0, traj.duration]), np.full(2, np.nan)


def held_intervals(run) -> list[tuple[str, float, float]]:
    """``(object, t_grasp, t_release)`` s on the program's time line (:func:`program_timeline`): the
    object is in the hand from the end of its PICKUP's grasp motion to the end of its PLACE's
    release motion (``inf``: still held at the end)."""
    t, held, out = 0.0, {}, []
    for m in run.motions:
        if m.trajectory is None:
            continue
        t += float(m.trajectory.duration)
        words = m.label.split()  # "tasks[2] PICKUP cylinder_a grasp" (Program.steps)
        if m.status != "ran" or len(words) < 4:
            continue
        if words[1] == "PICKUP" and words[-1] == "grasp":
            held[words[2]] = t
        elif words[1] == "PLACE" and words[-1] == "release" and words[2] in held:
            out.append((words[2], held.pop(words[2]), t))
    return out + [(o, tg, math.inf) for o, tg in held.items()]


def carried(intervals, tool_pose_at, t: float) -> dict:
    """object -> ``D_W`` (4, 4): how far each object the program picks up has been carried at time
    ``t`` (applied in W to where it stood): ``X_WE(t) X_WE(t_grasp)^-1`` while held, frozen at the
    release after it, the identity before the grasp.  ``tool_pose_at(t)`` is ``X_WE`` at ``t``."""
    out = {}
    for obj, tg, tr in intervals:
        D = np.eye(4) if t < tg else tool_pose_at(min(t, tr)) @ np.linalg.inv(tool_pose_at(tg))
        out[obj] = D @ out.get(obj, np.eye(4))  # picked up again: after the earlier carry
    return out


def task_ends(run) -> list[tuple[float, int]]:
    """``(t_end, task index)`` s of each motion on the program's time line, in order: which task
    (``tasks[k]`` of the program) the time line is in at a time."""
    t, out = 0.0, []
    for m in run.motions:
        if m.trajectory is None:
            continue
        t += float(m.trajectory.duration)
        out.append((t, int(m.label.split("]", 1)[0].split("[", 1)[1])))
    return out
