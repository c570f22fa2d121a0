"""The console's *Tasks* tab (WORKMATE's task menu) and the *jog the tool* folder, on viser.

The logic is in :mod:`._tasks` (the program) and :mod:`._jog` (the jog); here only widgets.  A
click on a static body in the 3-D view answers the task's prompt in turn (PLACE: the object, then
what it goes onto; MOVE: the frame); the dropdowns answer the same prompts without the view.
*run* runs the program on the cell (every motion verified, certified, then emulated) and puts its
motions on the time line with the run's report; the FIND-bound frames are drawn beside the
nominal ones.  Errors go to the panel's message, never to the server.
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np

from .._errors import ArmguardError
from ._parse import ConsoleInputError, parse_number
from ._tasks import (DEFAULT_GRASP, DEFAULT_LIFT, PROMPTS, TASK_KINDS, TaskComposer, carried, held_intervals,
                     program_timeline, task_ends)
from ._views import TrainingViews  # noqa: F401  (the app imports the WORKMATE widgets from here)

__all__ = ["TasksPanel", "JogPanel", "TrainingViews", "make_cell", "FRAME_AXES", "FIELD_KINDS"]

FIELD_KINDS = {"grasp height (m)": ("PICKUP",), "approach lift (m)": ("PICKUP", "PLACE")}
"""The tasks each typed field applies to, shown for these only: a PICKUP's grasp height (a PLACE
releases at the height its PICKUP grasped), the approach lift of a PICKUP and a PLACE (FIND and
MOVE have neither)."""

FRAME_AXES = (0.08, 0.004)
"""Drawn frames: axis length and radius (m) of a FIND's bound frame (its nominal frame: half)."""


def _note(state, message: str) -> None:
    """Show ``message`` in the panel (not an error)."""
    with state._lock:
        state._message, state._message_is_error = message, False
        state._version += 1


def make_cell(state):
    """``(cell, cell_ref)`` the task menu programs: the console's cell (started on a cell file), else
    one made of its model for the active arm; ``(None, reason)`` without a model."""
    cell = getattr(state, "cell", None)
    ref = getattr(state, "cell_source", None)
    if cell is not None:
        return cell, ref
    if state.model is None:
        return None, "the task menu needs a model (a built-in name, a model or cell file), not a bare scene"
    from ..program import Cell

    try:
        return Cell(state.model, state.snapshot().active), ref
    except ArmguardError as exc:
        return None, f"no cell for the task menu: {exc}"


class TasksPanel:
    """The Tasks tab of a :class:`~._app.ConsoleApp` (build inside the tab)."""

    @classmethod
    def build(cls, app, tabs) -> tuple["TasksPanel", "JogPanel"]:
        """The Tasks tab and the jog folder (in the Control tab, after the Cartesian panel)."""
        with tabs.add_tab("Tasks"):
            panel = cls(app)
        with app._tab_control:
            jog = JogPanel(app, panel.cell, order=app._joints_order + 1.5)
        return panel, jog

    def __init__(self, app) -> None:
        self.app = app
        st = app.state
        gui = app.server.gui
        self.cell, ref = make_cell(st)  # ref: how a saved program names the cell, or why there is none
        self.composer = None if self.cell is None else TaskComposer(self.cell, cell_ref=ref)
        self.run_result = None
        self._running = threading.Lock()
        self._bound_items = None
        self._frames: list = []
        self._asking = 0
        self._track = None  # (the program's player, its held intervals)
        self._moved: set = set()
        if self.composer is None:
            gui.add_markdown(ref)
            return
        objs = self.composer.objects or ("(none)",)
        self.w_kind = gui.add_dropdown("task", TASK_KINDS, initial_value=TASK_KINDS[0])
        self.w_prompt = gui.add_markdown("")
        self.w_object = gui.add_dropdown("object", objs)
        self.w_onto = gui.add_dropdown("onto", objs, visible=False)
        self.w_frame = gui.add_dropdown("frame", self.composer.frames, visible=False)
        self.w_to = gui.add_dropdown("to", ("home", "tool pose now"), visible=False,
                                     hint="the tool pose now in the frame: jog the tool there first")
        self.w_mode = gui.add_dropdown("motion", ("joint", "line"), visible=False)
        self.grasp, self.lift = DEFAULT_GRASP, DEFAULT_LIFT
        self.f_grasp = app._field("grasp height (m)", f"{self.grasp:g}", self._set_grasp,
                                  "the tool above the object's frame origin at the grasp; -2 to 2 m")
        self.f_lift = app._field("approach lift (m)", f"{self.lift:g}", self._set_lift,
                                 "approach and depart this far above the grasp / release; 0 to 2 m")
        self.b_add = gui.add_button("add task")
        self.w_list = gui.add_markdown("")
        self.w_edit = gui.add_button_group("program", ("remove last", "clear"))
        self.b_run = gui.add_button("run: verify, emulate, play on the time line")
        self.w_path = gui.add_text("save as", "console_program.yaml", hint="a .yaml path (relative: the console's folder)")
        self.b_save = gui.add_button("save program")
        self.w_report = gui.add_html("")
        self.w_kind.on_update(lambda e: self._kind_changed())
        self.b_add.on_click(lambda e: self._do(self._add))
        self.w_edit.on_click(lambda e: self._do(self._edit, e.target.value))
        self.b_run.on_click(lambda e: self._do(self.run))
        self.b_save.on_click(lambda e: self._do(self.save))
        self._kind_changed()
        self._show_list()

    # ------------------------------------------------------------------ helpers
    def _do(self, fn, *args):
        try:
            return fn(*args)
        except ArmguardError as exc:
            self.app.state.note_error(str(exc))
            return None

    def _set_grasp(self, text) -> None:
        self.grasp = parse_number(text, "grasp height", lo=-2.0, hi=2.0, unit="m")
        self.f_grasp.show(f"{self.grasp:g}")  # the box shows the value in force

    def _set_lift(self, text) -> None:
        self.lift = parse_number(text, "approach lift", lo=0.0, hi=2.0, unit="m")
        self.f_lift.show(f"{self.lift:g}")

    def _show_list(self, playing: int | None = None) -> None:
        """The program list; the task the time line is in now marked ▶ (``playing``: its index)."""
        lines = [f"{x} ▶" if k == playing else x for k, x in enumerate(self.composer.lines())]
        text = "**program**\n\n" + ("\n".join(f"{x}  " for x in lines) if lines else "(no tasks yet)")
        if self.w_list.content != text:
            self.w_list.content = text

    def prompts(self) -> tuple[str, ...]:
        return PROMPTS[self.w_kind.value]

    def _show_prompt(self) -> None:
        kind, prompts = self.w_kind.value, self.prompts()
        k = min(self._asking, len(prompts) - 1)
        self.w_prompt.content = (f"**{kind}**: click the *{prompts[k]}* in the 3-D view (or choose it below)")

    def _kind_changed(self) -> None:
        kind = self.w_kind.value
        self._asking = 0
        self.w_object.visible = kind in ("FIND", "PICKUP", "PLACE")
        self.w_onto.visible = kind == "PLACE"
        for w in (self.w_frame, self.w_to, self.w_mode):
            w.visible = kind == "MOVE"
        for f in (self.f_grasp, self.f_lift):
            f.visible = kind in FIELD_KINDS[f.label]
        self._show_prompt()

    # ------------------------------------------------------------------ picking in the 3-D view
    def bind_clicks(self) -> None:
        """Make every static body's mesh answer the prompt when clicked (again after a rebuild)."""
        items = getattr(self.app.drawer, "items", None)
        if items is None or items is self._bound_items:
            return
        self._bound_items = items
        for item in items:
            owner, kind, h = item[0], item[1], item[4]
            if kind == "body":
                h.on_click(lambda e, o=owner: self._do(self.picked, o))

    def picked(self, name: str) -> str:
        """A click on body ``name``: answers the prompt asked now; returns the prompt it answered."""
        if self.composer is None:
            raise ConsoleInputError("task menu: no cell to program")
        prompts = self.prompts()
        prompt = prompts[min(self._asking, len(prompts) - 1)]
        if name not in self.composer.objects:
            raise ConsoleInputError(f"{prompt}: {name!r} is not an object of the cell; objects are {list(self.composer.objects)}")
        {"object": self.w_object, "onto": self.w_onto, "frame": self.w_frame}[prompt].value = name
        self._asking = (self._asking + 1) % len(prompts)
        self._show_prompt()
        _note(self.app.state, f"{self.w_kind.value} {prompt}: {name} (picked in the 3-D view)")
        return prompt

    # ------------------------------------------------------------------ the program
    def _add(self) -> None:
        kind = self.w_kind.value
        kw = {"grasp": self.grasp, "lift": self.lift}
        if kind == "MOVE":
            if self.w_to.value == "home":
                kw["home"] = True
            else:
                from ..kinematics._frames import xyz_rpy_from_pose
                from ._jog import frame_pose

                # the cell's arm, whichever arm the panel has active (the active arm's pose was recorded)
                arm = self.cell.robot
                X_FE = np.linalg.inv(frame_pose(self.app.state, self.w_frame.value, self.cell, robot=arm)) @ \
                    self.app.state.ee_pose(arm)
                xyz, rpy = xyz_rpy_from_pose(X_FE)
                kw.update(frame=self.w_frame.value, xyz=xyz, rpy_deg=np.degrees(rpy), mode=self.w_mode.value)
        else:
            kw.update(object=self.w_object.value, onto=self.w_onto.value)
        e = self.composer.add(kind, **kw)
        self._asking = 0
        self._show_prompt()
        self._show_list()
        _note(self.app.state, f"added {e.line}")

    def _edit(self, what: str) -> None:
        if what == "remove last":
            self.composer.remove_last()
        else:
            self.composer.clear()
        self._show_list()

    def save(self) -> Path:
        text = str(self.w_path.value).strip()
        if not text or Path(text).suffix not in (".yaml", ".yml"):
            raise ConsoleInputError(f"save as: expected a path ending in .yaml or .yml, got {text!r}; nothing written")
        out = self.composer.save(Path(text).expanduser())
        _note(self.app.state, f"saved the task program to {out}")
        return out

    def run(self, *, seed: int = 0):
        """Run the program (verified, emulated), put it on the time line; returns the ProgramRun."""
        from ._app import report_html

        if not self._running.acquire(blocking=False):
            raise ConsoleInputError("run: the program is already running")
        try:
            _note(self.app.state, f"running {self.composer.name}: verifying each motion before it is emulated ...")
            run = self.composer.run(seed=seed)
        finally:
            self._running.release()
        self.run_result = run
        self.w_report.content = report_html(run.summary()).replace('id="armguard-report"', 'id="armguard-program-report"')
        self._draw_frames(run)
        tl = program_timeline(run)
        head = f"program {run.name}: " + ("every motion verified and ran" if run.ok else "STOPPED: " + run.stopped)
        if tl is None:
            self.app.state.note_error(head) if not run.ok else _note(self.app.state, head)
            return run
        traj, times, clearance = tl
        player = self.app.state.show_verified(run.name, traj, times, clearance, run, head)
        self._track = (player, held_intervals(run), task_ends(run), self.composer.lines())
        if not run.ok:
            self.app.state.note_error(head)
        return run

    def _draw_frames(self, run) -> None:
        from ._meshes import quat_wxyz_from_matrix

        sc = self.app.server.scene
        for h in self._frames:
            h.remove()
        self._frames = []
        L, r = FRAME_AXES
        for f in run.finds:
            for kind, X, scale in (("nominal", f.nominal, 0.5), ("found", f.found, 1.0)):
                self._frames.append(sc.add_frame(f"/program/{kind}/{f.object}", wxyz=quat_wxyz_from_matrix(X[:3, :3]),
                                                 position=tuple(float(v) for v in X[:3, 3]), axes_length=L * scale,
                                                 axes_radius=r * scale))

    def on_redraw(self, snap) -> None:
        if self.composer is None:
            return
        self.bind_clicks()
        p = snap.player
        if self._track is not None and p is self._track[0]:
            robot = self.app.state.scene.robots[p.robot]
            self._carry(carried(self._track[1], lambda t: robot.link_pose(p.trajectory.at(t)), p.timeline.t))
            if self._track[3] == self.composer.lines():  # the list is the program that ran
                self._show_list(playing=next((k for t_end, k in self._track[2] if p.timeline.t <= t_end), None))
        elif self._moved:
            self._carry({})
            self._show_list()

    def _carry(self, moves: dict) -> None:
        """Draw each object the program carries where the hand has taken it (``moves``: object -> D_W);
        the others where they stand.  Display only: the console's checks keep the scene as it is."""
        from ._meshes import quat_wxyz_from_matrix

        for owner, kind, _P0, c0, h, *_ in self.app.drawer.items:
            if kind != "body" or (owner not in moves and owner not in self._moved):
                continue
            D = moves.get(owner, np.eye(4))
            h.position = D[:3, :3] @ c0 + D[:3, 3]
            h.wxyz = quat_wxyz_from_matrix(D[:3, :3])
        self._moved = set(moves)


class JogPanel:
    """*jog the tool*: steps along / about the axes of a chosen frame, through the arm's IK."""

    def __init__(self, app, cell=None, order: float | None = None) -> None:
        from ._jog import jog_frames

        self.app = app
        self.cell = cell
        gui = app.server.gui
        self.step, self.turn = 0.01, np.radians(5.0)
        with gui.add_folder("jog the tool", order=order, visible=False) as self.folder:
            self.w_frame = gui.add_dropdown("jog in", jog_frames(app.state, cell), initial_value="world",
                                            hint="the axes of: world, the arm's base, the tool (its own axes), an object")
            self.f_step = app._field("jog step (mm)", "10", self._set_step, "(0, 500] mm: more than 0, up to 500")
            self.f_turn = app._field("jog turn (deg)", "5", self._set_turn, "(0, 90] deg: more than 0, up to 90")
            self.w_move = gui.add_button_group("move along", ("-x", "+x", "-y", "+y", "-z", "+z"))
            self.w_turn = gui.add_button_group("turn about", ("-x", "+x", "-y", "+y", "-z", "+z"))
        self.w_move.on_click(lambda e: self.app._do(self.press, "move", e.target.value, on_error=self.app._sync_widgets))
        self.w_turn.on_click(lambda e: self.app._do(self.press, "turn", e.target.value, on_error=self.app._sync_widgets))

    def _set_step(self, text) -> None:
        from ._jog import parse_step_mm

        self.step = parse_step_mm(text)
        self.f_step.show(f"{self.step * 1e3:g}")  # the box shows the value in force

    def _set_turn(self, text) -> None:
        from ._jog import parse_turn_deg

        self.turn = parse_turn_deg(text)
        self.f_turn.show(f"{np.degrees(self.turn):g}")

    def press(self, what: str, label: str):
        """One jog: ``what`` "move" or "turn", ``label`` like ``"+x"``; returns the new joints."""
        from ._jog import jog

        sign = 1.0 if label[0] == "+" else -1.0
        kw = {"translate": sign * self.step} if what == "move" else {"turn": sign * self.turn}
        return jog(self.app.state, self.w_frame.value, label[1], cell=self.cell, **kw)

    def on_redraw(self, snap) -> None:
        want = snap.mode == "cartesian"  # beside the Cartesian panel
        if self.folder.visible != want:
            self.folder.visible = want
