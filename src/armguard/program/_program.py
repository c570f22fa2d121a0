"""A task program: its tasks expanded into workcell primitives (the listing), run on an emulated
cell, or exported as a Python program that calls the same primitives.

The listing is one list of steps ``(op, args, comment)``: ``frame`` (``F = wc.frame(name)``,
evaluated when the task starts: the object's frame as bound then), ``find``, ``move`` (a tool
pose ``F @ pose(xyz, rpy)``), ``move_joints``, ``home``, ``grasp``, ``release``.  :func:`run_program`
interprets it; :func:`export_program` writes it as Python — so both run the same motions.
"""

from __future__ import annotations

import copy
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import SceneError, SceneFileError
from ._cell import Cell, load_cell
from ._format import ProgramFile, read_program
from ._workcell import ProgramRun, ProgramStopped, Workcell

__all__ = ["Program", "Step", "load_program", "run_program", "export_program", "workcell_main"]


@dataclass(frozen=True)
class Step:
    """One primitive: ``op``, its ``args`` (plain values), the task it comes from (``where``, ``line``)
    and a ``label`` (task and phase) for reports."""

    op: str
    args: tuple
    label: str
    where: str
    line: int | None


def _xyz_rpy(X: np.ndarray) -> tuple[list, list]:
    from ..kinematics import xyz_rpy_from_pose

    xyz, rpy = xyz_rpy_from_pose(X)
    return [float(v) for v in xyz], [float(v) for v in rpy]


def _joint_problems(t, robot, angle: tuple, allowance: float) -> list:
    """A ``move: joints`` task's joint values against ``robot``: their count, then each within its limits
    (``allowance``: ``Tolerances.joint_limit``), said in the file's angle unit (``angle``: its value in rad
    and its name) at ``tasks[i].joints[k]``."""
    if len(t.q) != robot.n_joints:
        return [(f"{t.where}.joints", f"expected {robot.n_joints} joint values, got {len(t.q)}")]
    out = []
    for k, (x, lo, hi) in enumerate(zip(t.q, robot.lower, robot.upper)):
        if not lo - allowance <= x <= hi + allowance:
            s, unit = angle  # as the file's joints are read (every value in its angle unit)
            out.append((f"{t.where}.joints[{k}]", f"joint {robot.joint_names[k]!r} = {x / s:.10g} {unit} is outside "
                                                  f"its limits [{lo / s:.10g}, {hi / s:.10g}] {unit}"))
    return out


class Program:
    """A parsed task program (:func:`load_program`): ``name``, ``tasks``, ``cell`` (as the file names
    it), ``speed`` (m/s), ``confidence``; :meth:`steps` is its listing of primitives."""

    def __init__(self, spec: ProgramFile) -> None:
        self.spec = spec
        self.name, self.tasks, self.file = spec.name, spec.tasks, spec.file
        self.speed, self.confidence = spec.speed, spec.confidence

    @property
    def cell(self) -> str | None:
        """The cell the file names (a relative path resolved against the file's folder only), or None.  A name
        with no folder and no suffix that is not a file there is a model name (``puma560``).  A path missing
        beside the program file was looked up in the working directory: another folder's cell ran."""
        c = self.spec.cell
        if c is None:
            return None
        p = Path(c)
        if p.is_absolute():
            return c
        if (self.spec.base / p).exists() or p.suffix or len(p.parts) > 1:
            return str(self.spec.base / p)
        return c

    def check(self, cell: Cell) -> None:
        """Every object and frame the tasks name exists in ``cell``; else a located SceneFileError."""
        objects = set(cell.objects)
        frames = objects | {"world", "base", "tool"}
        problems = []
        if self.spec.robot is not None and self.spec.robot != cell.robot:
            problems.append(("robot", f"{self.spec.robot!r} is not the robot of cell {cell.name!r} (its robot: "
                                      f"{cell.robot!r})"))
        for t in self.tasks:
            names = []
            if t.object is not None:
                names.append(("find" if t.kind == "find" else t.kind, t.object, objects))
            if t.kind == "place":
                names.append(("onto", t.target, objects))
                if t.target == t.object:
                    problems.append((f"{t.where}.onto", f"cannot place {t.object!r} onto itself"))
            for m in t.motions if t.kind == "move" else ():
                names.append(("frame", m.frame, frames))
            if t.q is not None:
                problems += _joint_problems(t, cell.model.scene.robots[cell.robot], self.spec.angle, cell.model.tol.joint_limit)
            for key, name, known in names:
                if name not in known:
                    problems.append((f"{t.where}.{key}", f"{name!r} is not in cell {cell.name!r}; "
                                                         f"expected one of {sorted(known)}"))
        if problems:
            from .._errors import list_problems
            from .._lines import lines_for

            with lines_for(self.file):  # each problem's line in the file
                raise SceneFileError(self.file, *list_problems(problems))

    def steps(self) -> list[Step]:
        """The listing: every task expanded into workcell primitives, in order."""
        out: list[Step] = []
        for t in self.tasks:
            head = f"{t.where} {t.kind.upper()}" + (f" {t.object}" if t.object else "")
            if t.kind == "find":
                out.append(Step("find", (t.object,), head, t.where, t.line))
                continue
            if t.kind == "move":
                if t.q is not None:
                    out.append(Step("move_joints", ([float(v) for v in t.q],), head + " joints", t.where, t.line))
                elif t.target == "home":
                    out.append(Step("home", (), head + " home", t.where, t.line))
                else:
                    m = t.motions[0]
                    out.append(Step("frame", (m.frame,), head, t.where, t.line))
                    out.append(Step("move", (*_xyz_rpy(m.X_FE), m.mode, ()), f"{head} to {m.frame}", t.where, t.line))
                continue
            frame = t.object if t.kind == "pickup" else t.target
            out.append(Step("frame", (frame,), head, t.where, t.line))
            phases = ("approach", "grasp", "depart") if t.kind == "pickup" else ("approach", "release", "depart")
            for phase, m in zip(phases, t.motions):
                touching = (t.target,) if phase == "release" else ()
                out.append(Step("move", (*_xyz_rpy(m.X_FE), m.mode, touching), f"{head} {phase}", t.where, t.line))
                if phase == "grasp":
                    out.append(Step("grasp", (t.object,), f"{head} close hand", t.where, t.line))
                if phase == "release":
                    out.append(Step("release", (t.object,), f"{head} open hand", t.where, t.line))
        return out


def load_program(path) -> Program:
    """The task program in ``path`` (``armguard_program: 1``, ``docs/program.md``)."""
    return Program(read_program(path))


def execute(wc: Workcell, steps) -> None:
    """Run ``steps`` on ``wc`` (raises ProgramStopped when a motion is refused)."""
    from ._workcell import pose

    F = np.eye(4)
    for s in steps:
        wc.label = s.label
        if s.op == "find":
            wc.find(*s.args)
        elif s.op == "frame":
            F = wc.frame(*s.args)
        elif s.op == "move":
            xyz, rpy, mode, touching = s.args
            wc.move(F @ pose(xyz, rpy), mode=mode, touching=touching)
        elif s.op == "move_joints":
            wc.move_joints(s.args[0])
        elif s.op == "home":
            wc.home()
        elif s.op == "grasp":
            wc.grasp(*s.args)
        elif s.op == "release":
            wc.release(*s.args)
        else:  # pragma: no cover - the listing has no other ops
            raise SceneError(f"unknown step {s.op!r}")


def run_program(program: Program | str | Path, cell: Cell | str | None = None, *, seed: int = 0,
                method: str = "certified", calibration=None) -> ProgramRun:
    """Run ``program`` on the emulated ``cell`` (a Cell, a cell file, a model name; default the one
    the program names): every motion verified, then emulated.  ``calibration`` (a calibration file
    or Calibration) regenerates the cell from it first.  Returns the :class:`ProgramRun`;
    ``run.ok`` is False when a motion was refused (the run stops there)."""
    if not isinstance(program, Program):
        program = load_program(program)
    cell = _cell_of(program, cell, calibration)
    program.check(cell)
    wc = Workcell(cell, seed=seed, speed=program.speed, confidence=program.confidence, method=method, name=program.name)
    try:
        execute(wc, program.steps())
    except ProgramStopped:
        pass
    except SceneError as exc:
        if isinstance(exc, SceneFileError):
            raise
        s = wc.label.split(" ")[0] if wc.label else ""
        task = next((t for t in program.tasks if t.where == s), None)
        raise SceneFileError(program.file, s, str(exc), line=task.line if task is not None else None) from None
    return wc.finish()


def _cell_of(program: Program, cell, calibration=None) -> Cell:
    if isinstance(cell, Cell):
        if calibration is not None:
            cell = copy.copy(cell)
            cell.calibrate(calibration)
        return cell
    if cell is not None:
        return load_cell(cell, calibration)
    if program.cell is None:
        raise SceneFileError(program.file, "cell", "the program names no cell: give 'cell:' in the file or --cell")
    return _named_cell(program, calibration)


def _named_cell(program: Program, calibration=None) -> Cell:
    """The cell the program's ``cell:`` names; a cell file that is not there is the program's error at
    that key (it named the cell file alone)."""
    try:
        return load_cell(program.cell, calibration)
    except SceneFileError as exc:
        if exc.where or Path(exc.file) != Path(program.cell):
            raise
        from .._lines import lines_for

        with lines_for(program.file):
            raise SceneFileError(program.file, "cell", f"{program.spec.cell}: {exc.message}") from None


def _py(v) -> str:
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (list, tuple)):
        inner = ", ".join(_py(x) for x in v)
        return f"[{inner}]" if isinstance(v, list) else (f"({inner},)" if len(v) == 1 else f"({inner})")
    return repr(v)


def program_text(program: Program, *, cell: str | None = None, calibration: str | None = None) -> str:
    """The program as Python that calls armguard's workcell primitives (docs/program.md, "Exported programs")."""
    cell = cell if cell is not None else program.cell
    lines = [
        "#!/usr/bin/env python3",
        f'"""{program.name}: a workcell program exported by `armguard program export` from {Path(program.file).name}.',
        "",
        "Every motion is a tool pose relative to a frame bound at execution time: F = wc.frame(NAME) is",
        "the object's frame as the last FIND bound it (its nominal frame before any FIND), and",
        "pose(xyz, rpy) a relation in m and rad (rot(z, yaw) rot(y, pitch) rot(x, roll)).  Each motion",
        "is verified before it runs; a refused one stops the program (exit status 1).",
        "",
        "Run: python THIS.py [--cell CELL] [--calibration FILE] [--seed N] [--save RUN.json]",
        '"""',
        "from armguard.program import pose, workcell_main",
        "",
        "",
        "def program(wc):",
    ]
    last = None
    for s in program.steps():
        if s.where != last:
            at = f" (line {s.line})" if s.line is not None else ""
            lines.append(f"    # {s.label.split(' ', 1)[0]}{at}: {s.label.split(' ', 1)[1] if ' ' in s.label else ''}".rstrip())
            last = s.where
        lab = f"wc.label = {s.label!r}"
        if s.op == "frame":
            lines.append(f"    F = wc.frame({s.args[0]!r})")
        elif s.op == "move":
            xyz, rpy, mode, touching = s.args
            extra = f", touching={_py(tuple(touching))}" if touching else ""
            lines.append(f"    {lab}; wc.move(F @ pose({_py(xyz)}, {_py(rpy)}), mode={mode!r}{extra})")
        elif s.op == "move_joints":
            lines.append(f"    {lab}; wc.move_joints({_py(s.args[0])})")
        else:
            args = ", ".join(repr(a) for a in s.args)
            lines.append(f"    {lab}; wc.{s.op}({args})")
    lines += [
        "",
        "",
        'if __name__ == "__main__":',
        f"    raise SystemExit(workcell_main(program, cell={cell!r}, name={program.name!r}, "
        f"speed={program.speed!r}, confidence={program.confidence!r}"
        + (f", calibration={calibration!r}" if calibration is not None else "") + "))",
        "",
    ]
    return "\n".join(lines)


def export_program(program: Program | str | Path, out, *, cell: str | None = None, calibration=None) -> Path:
    """Write ``program`` as a Python program to ``out`` (see :func:`program_text`); returns the path.
    ``calibration``: the calibration file the exported program regenerates its cell from by default."""
    if not isinstance(program, Program):
        program = load_program(program)
    if cell is not None:
        cell = str(Path(cell).resolve()) if Path(cell).exists() else str(cell)
    elif program.cell is not None and Path(program.cell).exists():
        cell = str(Path(program.cell).resolve())
    if calibration is not None:
        from ._calibfile import read_calibration

        read_calibration(calibration)  # a bad file is refused now, not when the exported program runs
        calibration = str(Path(calibration).resolve())
    # what run refuses (an object or frame not in the cell, another robot, a joint target outside the limits) is
    # not exported: checked against the cell given, or the one the program names (a file, or a built-in's name)
    if cell is not None or program.cell is not None:
        program.check(load_cell(cell, calibration) if cell is not None else _named_cell(program, calibration))
    text = program_text(program, cell=cell, calibration=calibration)
    from .._io import atomic_write, check_not_input

    check_not_input(out, [program.file, cell, calibration])  # the program written over itself: refused
    return atomic_write(Path(out), text)  # whole or not at all; a FIFO or a full disk is an OutputError


def workcell_main(program, *, cell: str | None, name: str = "program", speed: float = 0.1,
                  confidence: float = 0.999, calibration: str | None = None, argv=None) -> int:
    """Entry point of an exported program: ``program(wc)`` on the emulated cell; prints the run's
    summary, writes ``--save`` (JSON), returns 0 when every motion verified and ran, 1 otherwise."""
    import argparse
    import json

    ap = argparse.ArgumentParser(description=f"workcell program {name} (exported by armguard)")
    ap.add_argument("--cell", default=cell)
    ap.add_argument("--calibration", default=calibration)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--save", default=None)
    a = ap.parse_args(argv)
    if a.cell is None:
        ap.error("no cell: give --cell")
    from .._errors import ArmguardError
    from .._io import atomic_write, check_writable

    try:
        if a.save:  # refused before the run, as armguard program run --save (it failed after it: a traceback, exit 1)
            check_writable(a.save, [a.cell, a.calibration, sys.argv[0] if sys.argv else None])
        wc = Workcell(load_cell(a.cell, a.calibration), seed=a.seed, speed=speed, confidence=confidence, name=name)
        program(wc)
    except ProgramStopped:
        pass
    except ArmguardError as exc:  # a cell that does not load, an object the program names that it lacks: one line
        print(f"error: {exc}", file=sys.stderr)
        return 3  # as armguard's exit status for a file or value refused (1 is "a motion was refused")
    run = wc.finish()
    print(run.summary())
    if a.save:
        try:
            atomic_write(Path(a.save), json.dumps(run.to_dict()), parents=True)
        except ArmguardError as exc:  # a full disk: the run was printed; its record could not be written
            print(f"error: {exc}", file=sys.stderr)
            return 3
    return 0 if run.ok else 1
