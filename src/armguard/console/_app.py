"""The viser binding of the console: widgets call :class:`ConsoleState` commands; a draw loop shows it.

No logic lives here beyond unit conversion for display (degrees for revolute joints).  Every
widget callback ignores server-side assignments (``event.client is None``), catches
ConsoleInputError (and any ArmguardError) and puts the message in the panel, then resets the
widget to the state's value, so a bad entry never crashes the server or loses state.  GUI
widgets are shared by every open tab (one console, one state); cameras are per tab, and a
closed tab leaves nothing behind.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np

from .._errors import ArmguardError
from ._avoid_panel import AvoidPanel
from ._draw import SceneDrawer
from ._fields import COMMIT_ON_BLUR_HTML, TypedField
from ._plot import PLOT_PERIOD
from ._parse import CONTINUOUS_SPAN_DEG
from ._readout import panel_html
from ._state import MAX_DISTANCE_SETTING, ConsoleState
from ._targets import MAX_ANGLE_DEG, MAX_COORDINATE
from ._tasks_panel import TasksPanel, TrainingViews
from ._timeline_panel import TimelinePanel
from ._views import VIEWS, canvas_of, urdf_hints, view_pose

__all__ = ["ConsoleApp", "PortInUseError", "FPS", "PLOT_PERIOD"]

FPS = 30.0
"""Rate of the draw / player loop (Hz)."""


class PortInUseError(ArmguardError):
    """The console's port is taken: it says so instead of moving to another port."""


def _check_port_free(host: str, port: int) -> None:
    """Bind ``host:port`` once and let it go: a port in use is :class:`PortInUseError`; an address this
    machine does not have, or a host name that does not resolve, is an :class:`ArmguardError` saying so
    (with ``--port 0`` viser retried such an address forever, silently; with a port it read "in use")."""
    import errno
    import socket

    try:  # "" is every interface (as 0.0.0.0): the socket's own reading, which getaddrinfo refuses
        family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0] if host else socket.AF_INET
    except (socket.gaierror, UnicodeError) as exc:
        raise ArmguardError(f"--host {host!r} does not resolve ({getattr(exc, 'strerror', None) or exc}): give an "
                            "address of this machine (127.0.0.1: this machine only; 0.0.0.0: every interface)") from None
    with socket.socket(family, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, port))
        except OSError as exc:
            if exc.errno == errno.EACCES:
                raise ArmguardError(f"port {port} on {host} needs privileges ({exc.strerror or exc}): pass a port "
                                    "from 1024 up, or --port 0 for any free port") from None
            if exc.errno == errno.EADDRINUSE:
                raise PortInUseError(f"port {port} on {host} is in use ({exc.strerror or exc}); stop what holds it "
                                     "or pass --port 0 for any free port") from None
            raise ArmguardError(f"cannot serve on {host} ({exc.strerror or exc}): --host names an address of this "
                                "machine (127.0.0.1: this machine only; 0.0.0.0: every interface)") from None


def run_line(snap) -> str:
    """The Tests tab's line: the canned test's state and when (``**test: done at t = 5.00 s**``)."""
    if not snap.run_state:
        return "test: none running"
    return f"**test: {' '.join(x for x in (snap.run_state, snap.run_detail) if x)}**"


def _fmt(x: float) -> str:
    """A value for a typed field: up to 6 significant digits, no trailing zeros, never ``-0``."""
    x = float(x)
    return f"{0.0 if x == 0.0 else x:.6g}"


JOINT_DECIMALS = {"deg": 2, "m": 4}
"""Decimals a joint field shows: 0.01 deg, 0.1 mm (finer than the sliders' steps); the state keeps
the exact value (an inverse-kinematics answer is not moved by showing it)."""


def joint_text(x: float, unit: str) -> str:
    """A joint value for its field, rounded to :data:`JOINT_DECIMALS` and never ``-0``: ``-47.0329`` deg
    shows ``"-47.03"``, ``45.0`` shows ``"45"``, ``-0.001`` deg shows ``"0"``."""
    v = round(float(x), JOINT_DECIMALS.get(unit, 4))
    return _fmt(v)


def signed(x: float, decimals: int) -> str:
    """``x`` with a sign and ``decimals`` places, never ``-0.0`` (``"+0.0"`` for a value that rounds to 0)."""
    v = round(float(x), decimals)
    return f"{0.0 if v == 0.0 else v:+.{decimals}f}"


def pose_line(arm: str, xyz, rpy) -> str:
    """The Cartesian panel's line for the tool pose now (m, and rad shown in deg), never ``-0.000``."""
    x, y, z = (signed(v, 3) for v in xyz)
    r, p, w = (signed(math.degrees(v), 1) for v in rpy)
    return f"tool now ({arm}): x y z = {x} {y} {z} m; roll pitch yaw = {r} {p} {w} deg"


def report_html(summary: str) -> str:
    """The verification report in the panel's width: monospace, long lines wrapped (a code block
    ran past the panel's right edge and was cut off)."""
    import html

    return ('<pre id="armguard-report" style="white-space:pre-wrap;overflow-wrap:anywhere;max-width:100%;'
            f'font-size:0.75em;margin:0">{html.escape(summary)}</pre>')


def _vec(v, decimals: int | None = None) -> str:
    """Three values for a typed field (``"0.3, -0.392, 0.5"``), rounded to ``decimals`` places when
    given (a target shows ``3.9e-16`` m as ``0``); empty for None (no box)."""
    if v is None:
        return ""
    return ", ".join(_fmt(x if decimals is None else round(float(x), decimals)) for x in v)


TARGET_DECIMALS = {"pos": 4, "rpy": 2}
"""Decimals the Cartesian target fields show: 0.1 mm (m) and 0.01 deg, as the joint fields; the
state keeps the exact target (:meth:`ConsoleState.target`), shown rounded only."""


def target_texts(p, rpy) -> tuple[str, str]:
    """The target position (m) and roll pitch yaw (rad, shown in deg) as their fields show them."""
    return _vec(p, TARGET_DECIMALS["pos"]), _vec(None if rpy is None else np.degrees(rpy), TARGET_DECIMALS["rpy"])


def compare_options(backends, backend: str) -> tuple[str, ...]:
    """The "compare with" choices: off and every backend but the panel's own (never compared with itself)."""
    return ("off",) + tuple(b for b in backends if b != backend)


def has_arm_angle(robot) -> bool:
    """Only a 7-DOF arm has an arm angle: one self-motion (a 6-DOF arm has none, more joints more than one)."""
    return robot.n_joints == 7


def arm_angle_label(psi: float) -> str:
    """The arm-angle slider's label with its value (the slider's number box is hidden): ``"arm angle +12.5 deg"``."""
    deg = round(math.degrees(float(psi)), 1)
    return f"arm angle {0.0 if deg == 0.0 else deg:+.1f} deg"


class ConsoleApp:
    """Serve a :class:`ConsoleState` on viser at ``http://host:port``.

    ``start()`` opens the server and the draw loop; ``stop()`` closes both.  ``host`` defaults to
    the loopback address: the console exposes arm control and must be opened wider on purpose.
    A ``port`` already in use is an error (:class:`PortInUseError`), never a silent move to
    another port; ``port=0`` asks for any free one.
    """

    def __init__(self, state: ConsoleState, *, host: str = "127.0.0.1", port: int = 8080) -> None:
        self.state = state
        self.host = host
        self.port = int(port)
        self.server = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._shown_version = -1
        self._framed_active = None
        self._model_generation = 0
        self._built_generation = 0
        self._draw_lock = threading.RLock()

    @property
    def url(self) -> str:
        port = self.server.get_port() if self.server is not None else self.port
        return f"http://{self.host}:{port}"

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> "ConsoleApp":
        import viser

        _check_port_free(self.host, self.port)  # port 0: the address alone (viser retried a foreign one forever)
        self.server = viser.ViserServer(host=self.host, port=self.port, verbose=False)
        if self.port != 0 and self.server.get_port() != self.port:
            got = self.server.get_port()
            self.server.stop()
            raise PortInUseError(f"port {self.port} on {self.host} is in use (the server would have moved to {got}); "
                                 "stop what holds it or pass --port 0 for any free port")
        self.server.gui.configure_theme(control_width="large", dark_mode=False, show_logo=False)
        self.server.scene.set_up_direction("+z")
        # No shadows: they cost much and add nothing to judging clearances (and software
        # WebGL, as in headless browsers, renders far faster without them).
        self.server.scene.configure_default_lights(cast_shadow=False)
        self.drawer = SceneDrawer(self.server, self.state)
        self.drawer.build()
        self._build_gui()
        self._redraw(force=True)
        self.server.on_client_connect(self._on_connect)
        self._thread = threading.Thread(target=self._loop, name="armguard-console", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        if self.server is not None:
            self.server.stop()

    def serve_forever(self) -> None:
        try:
            while not self._stop.is_set():
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            self.stop()

    def model_reloaded(self) -> None:
        """Tell the view the state's model was replaced (``--watch``): rebuild the meshes on the next frame."""
        self._model_generation += 1

    def _loop(self) -> None:
        last = time.perf_counter()
        period = 1.0 / FPS
        while not self._stop.is_set():
            now = time.perf_counter()
            try:
                generation = self._model_generation
                if self._built_generation != generation:
                    try:
                        self._refresh_model_widgets()
                        self.drawer.build()
                        self._redraw(force=True)
                    finally:  # built (or failed, said in the panel): the widgets are the new model's from here
                        self._built_generation = generation
                self.state.tick(now - last)
                self._redraw()
            except Exception as exc:  # keep serving; show what went wrong
                self.state.note_error(f"display error: {type(exc).__name__}: {exc}")
            last = now
            self._stop.wait(max(0.0, period - (time.perf_counter() - now)))

    # ------------------------------------------------------------------ guarded commands
    def _do(self, fn, *args, on_error=None, source: str | None = None):
        """Run a state command; on a bad input show the message (tied to field ``source``, if one)
        and call ``on_error`` (reset widgets)."""
        try:
            return fn(*args)
        except ArmguardError as exc:
            self.state.note_error(str(exc), source)
            if on_error is not None:
                on_error()
            self._redraw(force=True)
            return None

    # ------------------------------------------------------------------ GUI
    def _field(self, label: str, text: str, command, hint: str | None = None) -> TypedField:
        """A typed field whose commit runs ``command(text)``; a refusal reverts the box, an accepted
        value (also the value in force typed again) clears that field's refusal from the panel."""
        holder = {}

        def commit(typed: str) -> None:
            f = holder["f"]
            ok = self._do(lambda: (command(typed), True)[1], on_error=f.revert, source=label)
            if ok:
                self.state.clear_error(label)
                self._redraw(force=True)
                f.revert()  # show the value in force, as the state formats it

        holder["f"] = f = TypedField(self.server.gui, label, text, commit, hint=hint,
                                     on_same=lambda: self.state.clear_error(label))
        return f

    def _build_gui(self) -> None:
        import viser

        gui = self.server.gui
        st = self.state
        snap = st.snapshot()
        gui.add_html(COMMIT_ON_BLUR_HTML)
        self._panel = gui.add_html(panel_html(snap.readout))
        tabs = gui.add_tab_group()
        self._fields: dict = {}

        # -- control: Ranger's main control panel ------------------------------------------
        with tabs.add_tab("Control") as self._tab_control:
            self._w_active = gui.add_dropdown("active arm", st.robots, initial_value=snap.active)
            self._w_mode = gui.add_dropdown("mode", ("joint", "cartesian"), initial_value=snap.mode)
            self._w_detect = gui.add_checkbox("detection", snap.detection)
            self._w_backend = gui.add_dropdown("backend", st.backends, initial_value=snap.backend)
            self._w_compare = gui.add_dropdown("compare with", compare_options(st.backends, snap.backend),
                                               initial_value="off")
            hint = f"0 to {MAX_DISTANCE_SETTING:g} m; applies on Enter or on leaving the field"
            self._fields["thr"] = self._field("threshold (m)", _fmt(snap.threshold), st.set_threshold, hint)
            self._fields["stop"] = self._field("stopping distance (m)", _fmt(snap.stopping_distance),
                                               st.set_stopping_distance, hint)
            self._w_joint_folders = {}
            self._w_joints = {}
            self._joints_order = self._fields["stop"].form.order
            self._avoid = AvoidPanel(self).build_control(self._joints_order + 3.0)  # below the workspace box
            for k, name in enumerate(st.robots):
                self._build_joint_panel(name, snap, self._joints_order + (k + 1) / (len(st.robots) + 1))
            with gui.add_folder("Cartesian", visible=False, order=self._joints_order + 1.0) as self._w_cart:
                self._w_pose_now = gui.add_markdown("")
                pos_text, rpy_text = target_texts(*snap.target[:2])
                self._fields["pos"] = self._field("target position (m)", pos_text, st.set_target_position,
                                                  f"x, y, z within ±{MAX_COORDINATE:g} m; move tool to go there")
                self._fields["rpy"] = self._field("target roll pitch yaw (deg)", rpy_text,
                                                  st.set_target_rpy,
                                                  f"roll, pitch, yaw within ±{MAX_ANGLE_DEG:g} deg")
                b_move = gui.add_button("move tool")
                b_read = gui.add_button("target = tool pose now")
                self._w_psi = gui.add_slider(arm_angle_label(snap.arm_angle), min=-180.0, max=180.0, step=0.5,
                                             initial_value=math.degrees(snap.arm_angle),
                                             visible=has_arm_angle(st.scene.robots[snap.active]))
            with gui.add_folder("workspace box", expand_by_default=False, order=self._joints_order + 2.0):
                lo, hi = snap.workspace_corners
                hint = f"x, y, z within ±{MAX_COORDINATE:g} m; apply limits to use"
                self._fields["ws_lo"] = self._field("lower corner (m)", _vec(lo),
                                                    lambda t: st.set_workspace_corner("lower", t), hint)
                self._fields["ws_hi"] = self._field("upper corner (m)", _vec(hi),
                                                    lambda t: st.set_workspace_corner("upper", t), hint)
                b_ws = gui.add_button("apply limits")
                b_ws_off = gui.add_button("remove box")

        # -- tests: Ranger's test panel ----------------------------------------------------
        with tabs.add_tab("Tests") as self._tab_tests:
            # Stop first, red, beside the run's line: in reach without scrolling past the tests
            self._b_stop = gui.add_button("Stop", visible=bool(st.canned_tests()), color="red",
                                          icon=viser.Icon.PLAYER_STOP_FILLED, hint="stop the canned test running")
            self._b_stop.on_click(self._guard(lambda _e: st.stop()))
            self._w_run_state = gui.add_markdown("")
            self._build_tests_panel(self._w_run_state.order + 0.5)

        # -- time line: WORKMATE's emulation -------------------------------------------------
        with tabs.add_tab("Time line"):
            self._timeline = TimelinePanel(self)  # what is loaded, verify and load, play, the plot

        # -- views ---------------------------------------------------------------------------
        with tabs.add_tab("Views"):
            self._w_follow = gui.add_checkbox("follow the active arm", True,
                                              hint="frame the active arm and its nearest obstacle; re-frame on a change of arm")
            gui.add_button("frame the active arm").on_click(lambda e: self._frame(e.client))
            gui.add_button("frame the nearest pair").on_click(lambda e: self._frame(e.client, focus="pair"))
            self._w_shapes = gui.add_checkbox("checked shapes", True, hint="the shapes the distances are computed on")
            has_urdf = self.drawer.urdf is not None
            # a greyed-out checkbox says why in its hint
            vis_hint, col_hint = urdf_hints(st.model, has_urdf, getattr(self.drawer, "has_visual", False))
            self._w_urdf_vis = gui.add_checkbox("URDF visual geometry", bool(has_urdf and self.drawer.has_visual),
                                                disabled=not (has_urdf and self.drawer.has_visual), hint=vis_hint)
            self._w_urdf_col = gui.add_checkbox("URDF collision geometry", False, disabled=not has_urdf, hint=col_hint)
            self.drawer.add_view_controls(gui)
            for label in VIEWS:
                gui.add_button(label).on_click(lambda e, lb=label: self._set_view(e.client, lb))
            self._training = TrainingViews(self)  # WORKMATE's training views (top, front, side at once; the hand)
        self._tasks, self._jog = TasksPanel.build(self, tabs)  # WORKMATE's task menu (a tab), jog (Control tab)

        # -- callbacks -----------------------------------------------------------------------
        self._w_active.on_update(self._from_client(lambda v: st.set_active(v)))
        self._w_mode.on_update(self._from_client(lambda v: st.set_mode(v)))
        self._w_detect.on_update(self._from_client(lambda v: st.set_detection(v)))
        self._w_backend.on_update(self._from_client(lambda v: st.set_backend(v)))
        self._w_compare.on_update(self._from_client(lambda v: st.set_compare(None if v == "off" else v)))
        self._w_psi.on_update(self._from_client(lambda v: st.set_arm_angle(math.radians(v))))
        self._w_shapes.on_update(lambda e: self.drawer.set_shapes_visible(self._w_shapes.value))
        for w in (self._w_urdf_vis, self._w_urdf_col):
            w.on_update(lambda e: self.drawer.set_urdf(self._w_urdf_vis.value, self._w_urdf_col.value))
        b_move.on_click(self._guard(lambda _e: st.move_to_target()))
        b_read.on_click(self._guard(lambda _e: st.reset_target()))
        b_ws.on_click(self._guard(lambda _e: st.apply_workspace()))
        b_ws_off.on_click(self._guard(lambda _e: st.remove_workspace()))
        self._pose_shown = None

    def _build_joint_panel(self, name: str, snap, order: float) -> None:
        gui, st = self.server.gui, self.state
        robot = st.scene.robots[name]
        units = st.joint_units(name)
        scale = np.array([180.0 / math.pi if u == "deg" else 1.0 for u in units])
        lo, hi = st.joint_limits(name)
        fields, sliders = [], []
        step = 0.5 / (len(st.robots) + 1)
        with gui.add_folder(f"joints {name}", visible=name == snap.active, order=order) as folder:
            for j, jn in enumerate(robot.joint_names):
                a = float(lo[j] * scale[j]) if math.isfinite(lo[j]) else -CONTINUOUS_SPAN_DEG
                b = float(hi[j] * scale[j]) if math.isfinite(hi[j]) else CONTINUOUS_SPAN_DEG
                turn = "" if math.isfinite(lo[j]) or math.isfinite(hi[j]) else " (continuous: past it, wrapped)"
                fields.append(self._field(
                    f"{jn} ({units[j]})", joint_text(snap.q[name][j] * scale[j], units[j]),
                    lambda text, j=j: st.set_joint(name, j, text, deg=True),
                    hint=f"{a:g} to {b:g} {units[j]}{turn}; applies on Enter or on leaving the field"))
        with gui.add_folder(f"sliders {name}", visible=name == snap.active, expand_by_default=False,
                            order=order + step) as sfolder:
            for j, jn in enumerate(robot.joint_names):
                a = float(lo[j] * scale[j]) if math.isfinite(lo[j]) else -CONTINUOUS_SPAN_DEG
                b = float(hi[j] * scale[j]) if math.isfinite(hi[j]) else CONTINUOUS_SPAN_DEG
                v = float(np.clip(snap.q[name][j] * scale[j], a, b))
                s = gui.add_slider(f"{jn} slider ({units[j]})", min=a, max=b,
                                   step=0.1 if units[j] == "deg" else 0.001, initial_value=v)
                s.on_update(self._from_client(lambda x, j=j, k=scale[j]: st.set_joint(name, j, float(x) / k)))
                sliders.append(s)
        self._w_joint_folders[name] = (folder, sfolder)
        self._w_joints[name] = (fields, sliders, scale)

    def _build_tests_panel(self, order: float) -> None:
        """The canned tests' Setup / Run buttons, in one folder (rebuilt when the model is reloaded)."""
        gui, st = self.server.gui, self.state
        self._w_test_buttons = []
        with gui.add_folder("canned tests", order=order) as self._w_tests:
            if not st.canned_tests():
                gui.add_markdown("This scene has no canned tests.")
            for name in st.canned_tests():
                test = st.scene.canned_tests[name]
                gui.add_markdown(f"**{name}** — {test.description or test.robot}")
                for label, act in (("Setup", st.setup), ("Run", st.run)):
                    b = gui.add_button(f"{label} {name}")
                    b.on_click(self._guard(lambda _e, n=name, act=act: act(n)))
                    self._w_test_buttons.append(b)

    def _refresh_model_widgets(self) -> None:
        """After a model reload: the widgets that show the model (arms, joint fields and sliders
        with their limits and hints, backends, canned tests, trajectories, the workspace box) show
        the new one."""
        st, snap = self.state, self.state.snapshot()
        for folders in self._w_joint_folders.values():
            for folder in folders:
                folder.remove()
        self._w_joint_folders, self._w_joints = {}, {}
        with self._tab_control:
            for k, name in enumerate(st.robots):
                self._build_joint_panel(name, snap, self._joints_order + (k + 1) / (len(st.robots) + 1))
        self._w_active.options = st.robots
        order = self._w_tests.order
        self._w_tests.remove()
        with self._tab_tests:
            self._build_tests_panel(order)
        self._b_stop.visible = bool(st.canned_tests())
        self._timeline.model_reloaded()
        self._pose_shown = None

    def _guard(self, fn):
        def cb(event):
            self._do(fn, event, on_error=self._sync_widgets)
        return cb

    def _from_client(self, fn):
        """Wrap a widget callback: act only on a tab's edit, never on the server's own resets."""
        def cb(event):
            if event.client is None:
                return
            self._do(fn, event.target.value, on_error=self._sync_widgets)
        return cb

    # ------------------------------------------------------------------ camera
    def _on_connect(self, client) -> None:
        self._frame(client)

    def _frame(self, client, focus: str = "arm") -> None:
        if client is None:
            return
        # left of the control panel, as the tab's canvas is shaped (viser says its aspect, not the panel's place)
        pos, look = self.drawer.follow_pose(self.state.snapshot(), focus=focus, **canvas_of(client))
        self._place(client, pos, look)

    def _set_view(self, client, label: str) -> None:
        if client is None:
            return
        pos, look = view_pose(label, self.drawer.center, self.drawer.radius)
        self._place(client, pos, look)

    @staticmethod
    def _place(client, pos, look) -> None:
        try:
            with client.atomic():
                client.camera.up_direction = (0.0, 0.0, 1.0)
                client.camera.position = tuple(float(x) for x in pos)
                client.camera.look_at = tuple(float(x) for x in look)
        except Exception:  # the tab closed meanwhile: nothing to do
            pass

    # ------------------------------------------------------------------ drawing
    def _sync_widgets(self) -> None:
        snap = self.state.snapshot()
        backends = self.state.backends
        if tuple(self._w_backend.options) != backends:  # a backend refused here is no longer offered
            self._w_backend.options = backends
        if tuple(self._w_compare.options) != compare_options(backends, snap.backend):
            self._w_compare.options = compare_options(backends, snap.backend)
        self._w_active.value = snap.active
        self._w_mode.value = snap.mode
        self._w_detect.value = snap.detection
        self._w_backend.value = snap.backend
        cmp = snap.compare
        self._w_compare.value = "off" if cmp is None else cmp.other
        lo, hi = snap.workspace_corners
        self._fields["ws_lo"].show(_vec(lo))
        self._fields["ws_hi"].show(_vec(hi))
        self._fields["thr"].show(_fmt(snap.threshold))
        self._fields["stop"].show(_fmt(snap.stopping_distance))
        self._avoid.sync()
        for name, (fields, sliders, scale) in self._w_joints.items():
            units = self.state.joint_units(name)
            for j, (f, s) in enumerate(zip(fields, sliders)):
                f.show(joint_text(snap.q[name][j] * scale[j], units[j]))
                v = float(np.clip(snap.q[name][j] * scale[j], s.min, s.max))
                if abs(s.value - v) > 1e-9:
                    s.value = v
            for folder in self._w_joint_folders[name]:
                folder.visible = name == snap.active and snap.mode == "joint"
        self._w_cart.visible = snap.mode == "cartesian"
        self._w_psi.visible = has_arm_angle(self.state.scene.robots[snap.active])
        psi_deg = math.degrees(snap.arm_angle)
        if abs(self._w_psi.value - psi_deg) > 1e-9:  # reset to 0 by a move, a reload, another arm
            self._w_psi.value = psi_deg
        if self._w_psi.label != arm_angle_label(snap.arm_angle):
            self._w_psi.label = arm_angle_label(snap.arm_angle)
        self._sync_pose(snap)
        run = snap.run_state
        self._w_run_state.content = run_line(snap)
        self._timeline.sync(snap)

    def _sync_pose(self, snap) -> None:
        """The Cartesian panel: the tool pose now, and the target the state holds (the pose now until typed)."""
        from ..kinematics._frames import xyz_rpy_from_pose

        pos_text, rpy_text = target_texts(*snap.target[:2])
        self._fields["pos"].show(pos_text)
        self._fields["rpy"].show(rpy_text)
        xyz, rpy = xyz_rpy_from_pose(snap.ee_pose)
        key = (snap.active, tuple(np.round(xyz, 6)), tuple(np.round(rpy, 6)))
        if key == self._pose_shown:
            return
        self._pose_shown = key
        self._w_pose_now.content = pose_line(snap.active, xyz, rpy)

    def _redraw(self, force: bool = False) -> None:
        with self._draw_lock:  # the draw loop and a typed field's commit never draw at once
            snap = self.state.snapshot()
            if snap.version == self._shown_version and not force:
                self._refresh_plot(snap)
                return
            self._shown_version = snap.version
            with self.server.atomic():  # the panel first, alone: shown at once, not at the next WebGL frame
                self._panel.content = panel_html(snap.readout, snap.message, error=snap.message_is_error,
                                                 compare=snap.compare, update_us=snap.update_us, changes=snap.changes,
                                                 terrain=snap.terrain, sigmas=snap.sigmas, draw_ms=self.drawer.draw_ms,
                                                 active=snap.active, others=snap.others)
                self._sync_widgets()
                self._refresh_plot(snap)
            self.server.flush()
            self.drawer.draw(snap)
            for extra in (self._tasks, self._jog, self._training):
                extra.on_redraw(snap)
        if snap.active != self._framed_active:
            first = self._framed_active is None
            self._framed_active = snap.active
            if not first and self._w_follow.value:
                for client in self.server.get_clients().values():
                    self._frame(client)

    def _refresh_plot(self, snap) -> None:
        self._avoid.refresh(snap)
        self._timeline.refresh(snap)
