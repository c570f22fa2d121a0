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
from ._meshes import mesh_of, quat_wxyz_from_matrix, rigid_motion
from ._plot import ClearancePlot
from ._readout import panel_html
from ._state import ConsoleState

__all__ = ["ConsoleApp", "FPS", "PLOT_PERIOD"]

FPS = 30.0
"""Rate of the draw / player loop (Hz)."""
PLOT_PERIOD = 0.2
"""Seconds between clearance-plot marker refreshes while playing."""
_COLORS = {"body": (150, 160, 175), "link": (235, 150, 60), "payload": (90, 180, 110), "hot": (220, 30, 30)}
_VIEW_DISTANCE = 2.5
"""Camera distance for the standard views, in scene radii."""


def _deg_scale(robot) -> np.ndarray:
    """Per joint: display units per SI unit (180/pi for revolute, 1 for prismatic)."""
    types = getattr(robot, "joint_types", None) or ("revolute",) * robot.n_joints
    return np.array([1.0 if "prismatic" in str(getattr(t, "value", t)).lower() else 180.0 / math.pi for t in types])


class ConsoleApp:
    """Serve a :class:`ConsoleState` on viser at ``http://host:port``.

    ``start()`` opens the server and the draw loop; ``stop()`` closes both.  ``host`` defaults to
    the loopback address: the console exposes arm control and must be opened wider on purpose.
    """

    def __init__(self, state: ConsoleState, *, host: str = "127.0.0.1", port: int = 8080) -> None:
        self.state = state
        self.host = host
        self.port = int(port)
        self.server = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._shown_version = -1
        self._plot: ClearancePlot | None = None
        self._plot_player = None
        self._plot_last = 0.0
        self._ws_shown = None

    @property
    def url(self) -> str:
        port = self.server.get_port() if self.server is not None else self.port
        return f"http://{self.host}:{port}"

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> "ConsoleApp":
        import viser

        self.server = viser.ViserServer(host=self.host, port=self.port, verbose=False)
        self.server.gui.configure_theme(control_width="large", dark_mode=False, show_logo=False)
        self.server.scene.set_up_direction("+z")
        # No shadows: they cost much and add nothing to judging clearances (and software
        # WebGL, as in headless browsers, renders far faster without them).
        self.server.scene.configure_default_lights(cast_shadow=False)
        self._build_scene()
        self._build_gui()
        self._redraw(force=True)
        self.server.on_client_connect(lambda client: self._set_view(client, "vista 5"))
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

    def _loop(self) -> None:
        last = time.perf_counter()
        period = 1.0 / FPS
        while not self._stop.is_set():
            now = time.perf_counter()
            try:
                self.state.tick(now - last)
                self._redraw()
            except Exception as exc:  # keep serving; show what went wrong
                self.state.note_error(f"display error: {type(exc).__name__}: {exc}")
            last = now
            self._stop.wait(max(0.0, period - (time.perf_counter() - now)))

    # ------------------------------------------------------------------ guarded commands
    def _do(self, fn, *args, on_error=None):
        """Run a state command; on a bad input show the message and call ``on_error`` (reset widgets)."""
        try:
            return fn(*args)
        except ArmguardError as exc:
            self.state.note_error(str(exc))
            if on_error is not None:
                on_error()
            self._redraw(force=True)
            return None

    # ------------------------------------------------------------------ scene
    def _build_scene(self) -> None:
        sc = self.server.scene
        snap = self.state.snapshot()
        items = self.state.scene.shapes_at(snap.q)
        self._items = []
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for k, it in enumerate(items):
            v, f = mesh_of(it.shape)
            P0 = np.array(it.shape.core_points)
            c0 = P0.mean(axis=0)
            lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
            color = _COLORS.get(it.kind, _COLORS["body"])
            h = sc.add_mesh_simple(f"/scene/{k:03d}_{it.owner.replace('/', '.')}", v - c0, f, color=color,
                                   side="double" if len(f) < 8 else "front", position=c0,
                                   cast_shadow=False, receive_shadow=False)
            self._items.append((it.owner, it.kind, P0, c0, h, color))
        if not np.all(np.isfinite(lo)):
            lo, hi = -np.ones(3), np.ones(3)
        self._center = 0.5 * (lo + hi)
        self._radius = max(0.5, 0.5 * float(np.linalg.norm(hi - lo)))
        sc.add_grid("/grid", width=4 * self._radius, height=4 * self._radius, position=(self._center[0], self._center[1], lo[2]))
        seg = np.zeros((1, 2, 3), dtype=np.float32)
        self._line = sc.add_line_segments("/nearest/line", seg, (255, 210, 0), thickness=0.006, visible=False)
        self._dot_a = sc.add_icosphere("/nearest/a", radius=0.012, color=(255, 210, 0), visible=False)
        self._dot_b = sc.add_icosphere("/nearest/b", radius=0.012, color=(255, 210, 0), visible=False)
        self._ws = sc.add_line_segments("/workspace", seg, (60, 120, 220), thickness=0.004, visible=False)

    def _draw_workspace(self, ws) -> None:
        if ws is None:
            self._ws.visible = False
            return
        lo, hi = ws
        c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        edges = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
        self._ws.points = np.array([[c[a], c[b]] for a, b in edges], dtype=np.float32)
        self._ws.visible = True

    # ------------------------------------------------------------------ GUI
    def _build_gui(self) -> None:
        gui = self.server.gui
        st = self.state
        snap = st.snapshot()
        self._panel = gui.add_html(panel_html(snap.readout))
        tabs = gui.add_tab_group()

        # -- control: Ranger's main control panel ------------------------------------------
        with tabs.add_tab("Control"):
            self._w_active = gui.add_dropdown("active arm", st.robots, initial_value=snap.active)
            self._w_mode = gui.add_dropdown("mode", ("joint", "cartesian"), initial_value=snap.mode)
            self._w_detect = gui.add_checkbox("detection", snap.detection)
            self._w_thr = gui.add_number("threshold (m)", snap.threshold, step=0.001)
            self._w_stop = gui.add_number("stopping distance (m)", snap.stopping_distance, step=0.001)
            self._w_joint_folders = {}
            self._w_joints = {}
            for name in st.robots:
                robot = st.scene.robots[name]
                scale = _deg_scale(robot)
                lo, hi = st.joint_limits(name)
                with gui.add_folder(f"joints {name}", visible=name == snap.active) as folder:
                    sliders = []
                    for j, jn in enumerate(robot.joint_names):
                        a = float(lo[j] * scale[j]) if math.isfinite(lo[j]) else -360.0
                        b = float(hi[j] * scale[j]) if math.isfinite(hi[j]) else 360.0
                        unit = "deg" if scale[j] != 1.0 else "m"
                        v = float(np.clip(snap.q[name][j] * scale[j], a, b))
                        s = gui.add_slider(f"{jn} ({unit})", min=a, max=b, step=0.1 if unit == "deg" else 0.001,
                                           initial_value=v)
                        s.on_update(self._on_joint(name, j, scale[j]))
                        sliders.append(s)
                self._w_joint_folders[name] = folder
                self._w_joints[name] = (sliders, scale)
            with gui.add_folder("Cartesian", visible=False) as self._w_cart:
                self._w_pos = gui.add_vector3("tool position (m)", (0.0, 0.0, 0.0), step=0.001)
                self._w_rpy = gui.add_vector3("tool roll pitch yaw (deg)", (0.0, 0.0, 0.0), step=0.1)
                b_move = gui.add_button("move tool")
                b_read = gui.add_button("read tool pose")
                self._w_psi = gui.add_slider("arm angle (deg)", min=-180.0, max=180.0, step=0.5, initial_value=0.0)
            with gui.add_folder("workspace box", expand_by_default=False):
                ws = snap.workspace
                self._w_ws_lo = gui.add_vector3("lower corner (m)", tuple(ws[0]) if ws else (-1.0, -1.0, -1.0), step=0.01)
                self._w_ws_hi = gui.add_vector3("upper corner (m)", tuple(ws[1]) if ws else (1.0, 1.0, 1.0), step=0.01)
                b_ws = gui.add_button("apply limits")

        # -- tests: Ranger's test panel ----------------------------------------------------
        with tabs.add_tab("Tests"):
            if not st.canned_tests():
                gui.add_markdown("This scene has no canned tests.")
            for name in st.canned_tests():
                test = st.scene.canned_tests[name]
                gui.add_markdown(f"**{name}** — {test.description or test.robot}")
                gui.add_button(f"Setup {name}").on_click(self._guard(lambda _e, n=name: st.setup(n)))
                gui.add_button(f"Run {name}").on_click(self._guard(lambda _e, n=name: st.run(n)))
            gui.add_button("Stop").on_click(self._guard(lambda _e: st.stop()))

        # -- time line: WORKMATE's emulation -------------------------------------------------
        with tabs.add_tab("Time line"):
            trajs = st.trajectories()
            self._w_traj = gui.add_dropdown("trajectory", trajs or ("(none)",))
            b_load = gui.add_button("verify and load", disabled=not trajs)
            self._w_transport = gui.add_button_group("play", ("◀ back", "pause", "play ▶", "slower", "faster"))
            self._w_time = gui.add_slider("time (s)", min=0.0, max=1.0, step=0.01, initial_value=0.0)
            self._w_rate = gui.add_markdown("")
            self._w_plot = gui.add_image(np.full((20, 40, 3), 255, dtype=np.uint8), format="png", visible=False)
            self._w_report = gui.add_markdown("")

        # -- views ---------------------------------------------------------------------------
        with tabs.add_tab("Views"):
            for label in VIEWS:
                gui.add_button(label).on_click(lambda e, lb=label: self._set_view(e.client, lb))

        # -- callbacks -----------------------------------------------------------------------
        self._w_active.on_update(self._from_client(lambda v: st.set_active(v)))
        self._w_mode.on_update(self._from_client(lambda v: st.set_mode(v)))
        self._w_detect.on_update(self._from_client(lambda v: st.set_detection(v)))
        self._w_thr.on_update(self._from_client(lambda v: st.set_threshold(v)))
        self._w_stop.on_update(self._from_client(lambda v: st.set_stopping_distance(v)))
        self._w_psi.on_update(self._from_client(lambda v: st.set_arm_angle(math.radians(v))))
        self._w_time.on_update(self._from_client(lambda v: st.timeline_command("seek", v)))
        self._w_transport.on_click(self._from_client(self._transport))
        b_move.on_click(self._guard(lambda _e: st.move_ee(self._w_pos.value, np.radians(self._w_rpy.value))))
        b_read.on_click(lambda _e: self._read_tool_pose())
        b_ws.on_click(self._guard(lambda _e: st.set_workspace(self._w_ws_lo.value, self._w_ws_hi.value)))
        b_load.on_click(self._guard(lambda _e: st.load_trajectory(self._w_traj.value)))
        self._read_tool_pose()

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

    def _on_joint(self, robot: str, j: int, scale: float):
        return self._from_client(lambda v: self.state.set_joint(robot, j, float(v) / scale))

    def _transport(self, label: str) -> None:
        cmd = {"◀ back": "backward", "pause": "pause", "play ▶": "forward", "slower": "slower", "faster": "faster"}[label]
        self.state.timeline_command(cmd)
        if cmd in ("backward", "forward"):
            self.state.timeline_command("play")

    def _read_tool_pose(self) -> None:
        from ..kinematics._frames import xyz_rpy_from_pose

        xyz, rpy = xyz_rpy_from_pose(self.state.ee_pose())
        self._w_pos.value = tuple(float(x) for x in xyz)
        self._w_rpy.value = tuple(float(math.degrees(x)) for x in rpy)

    def _set_view(self, client, label: str) -> None:
        if client is None:
            return
        pos, look = view_pose(label, self._center, self._radius)
        try:
            with client.atomic():
                client.camera.up_direction = (0.0, 0.0, 1.0)
                client.camera.position = pos
                client.camera.look_at = look
        except Exception:  # the tab closed meanwhile: nothing to do
            pass

    # ------------------------------------------------------------------ drawing
    def _sync_widgets(self) -> None:
        snap = self.state.snapshot()
        self._w_active.value = snap.active
        self._w_mode.value = snap.mode
        self._w_detect.value = snap.detection
        self._w_thr.value = snap.threshold
        self._w_stop.value = snap.stopping_distance
        for name, (sliders, scale) in self._w_joints.items():
            for j, s in enumerate(sliders):
                v = float(np.clip(snap.q[name][j] * scale[j], s.min, s.max))
                if abs(s.value - v) > 1e-9:
                    s.value = v
            self._w_joint_folders[name].visible = name == snap.active and snap.mode == "joint"
        self._w_cart.visible = snap.mode == "cartesian"
        p = snap.player
        if p is not None:
            self._w_time.max = max(p.timeline.duration, 1e-3)
            self._w_time.value = float(min(p.timeline.t, self._w_time.max))

    def _redraw(self, force: bool = False) -> None:
        snap = self.state.snapshot()
        if snap.version == self._shown_version and not force:
            self._refresh_plot(snap, periodic=True)
            return
        self._shown_version = snap.version
        r = snap.readout
        items = self.state.scene.shapes_at(snap.q)
        with self.server.atomic():
            for it, (owner, kind, P0, c0, h, color) in zip(items, self._items):
                hot = r.within_threshold and owner == r.owner_a
                want = _COLORS["hot"] if hot else color
                if tuple(h.color) != want:
                    h.color = want
                if kind == "body":
                    continue
                R, t = rigid_motion(P0, np.asarray(it.shape.core_points))
                h.position = R @ c0 + t
                h.wxyz = quat_wxyz_from_matrix(R)
            if r.p_WA is not None:
                col = r.line_color
                self._line.points = np.array([[r.p_WA, r.p_WB]], dtype=np.float32)
                self._line.colors = np.array([[col, col]], dtype=np.uint8)
                self._dot_a.position, self._dot_b.position = r.p_WA, r.p_WB
                self._dot_a.color = self._dot_b.color = col
            for h in (self._line, self._dot_a, self._dot_b):
                h.visible = r.p_WA is not None
            if snap.workspace is not None:
                key = tuple(np.concatenate(snap.workspace))
            else:
                key = None
            if key != self._ws_shown:
                self._draw_workspace(snap.workspace)
                self._ws_shown = key
            self._panel.content = panel_html(r, snap.message, error=snap.message_is_error)
            self._sync_widgets()
            self._refresh_plot(snap, periodic=False)

    def _refresh_plot(self, snap, *, periodic: bool) -> None:
        p = snap.player
        if p is None or p.kind != "verified":
            if self._plot_player is not None:
                self._w_plot.visible = False
                self._w_report.content = ""
                self._plot_player = None
            return
        if p is not self._plot_player:
            rep = p.report
            fc = getattr(rep, "first_collision", None)
            self._plot = ClearancePlot(p.times, p.clearance, threshold=snap.threshold,
                                       first_collision=None if fc is None else float(fc.time))
            self._plot_player = p
            summary = rep.summary() if hasattr(rep, "summary") else str(rep)
            self._w_report.content = f"```\n{summary}\n```"
            self._w_plot.visible = True
            periodic = False
        now = time.perf_counter()
        if periodic and now - self._plot_last < PLOT_PERIOD:
            return
        self._plot_last = now
        tl = p.timeline.state
        self._w_plot.image = self._plot.image_at(tl.t)
        state = "playing" if tl.playing else "paused"
        self._w_rate.content = f"t = {tl.t:.2f} / {tl.duration:.2f} s · {state} {tl.direction} · speed ×{abs(tl.rate):g}"


VIEWS = ("top", "front", "side", "vista 1", "vista 2", "vista 3", "vista 4", "vista 5", "vista 6")
"""The camera presets offered: three orthogonal views and six oblique vista points."""


def view_pose(label: str, center: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Camera ``(position, look_at)``, each (3,) m in W, for a preset of :data:`VIEWS`.

    top: looking down -z; front: looking along -x from +x; side: looking along +y from -y;
    vista k: azimuth 60 k degrees, elevation 30 degrees.
    """
    d = _VIEW_DISTANCE * radius
    c = np.asarray(center, dtype=np.float64)
    if label == "top":
        return c + np.array([0.0, -1e-3 * d, d]), c
    if label == "front":
        return c + np.array([d, 0.0, 0.0]), c
    if label == "side":
        return c + np.array([0.0, -d, 0.0]), c
    if label.startswith("vista "):
        k = int(label.split()[1])
        az, el = math.radians(60.0 * k - 30.0), math.radians(30.0)
        return c + d * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]), c
    raise ValueError(f"unknown view {label!r}; views are {list(VIEWS)}")
