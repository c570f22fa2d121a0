"""WORKMATE's training views in the console (Smith 1986, seed 004: motions were trained with "top,
front and side views at once" and an "eye in the hand").

viser gives each browser tab one 3-D view with one camera, so the views shown *at once* are
insets: small pictures the tab renders from other cameras (``ClientHandle.get_render`` with a
camera pose), shown in the *Views* tab beside each other — top, front, side (the cameras of
:func:`armguard.console.view_pose`) and the eye in the hand.  The *eye in the hand* camera sits
at the active arm's tool origin looking along the tool's z axis (its approach direction), the
tool's y axis pointing down in the picture; *main view: eye in the hand* makes the tab's own
camera follow it as the arm moves.  The top / front / side buttons above put the main camera
at those views.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np

__all__ = ["TrainingViews", "VIEWS", "VISTA_POINTS", "view_pose", "INSET_VIEWS", "INSET_SIZE", "camera_wxyz", "eye_in_hand", "inset_camera",
           "INSET_FOV_DEG", "EYE_FOV_DEG", "REFRESH_S", "urdf_hints", "canvas_of"]

INSET_VIEWS = ("top", "front", "side", "eye in the hand")
INSET_SIZE = (180, 240)
"""Inset pictures: (height, width) pixels."""
INSET_FOV_DEG = 40.0
"""Vertical field of view of the top / front / side insets (deg)."""
EYE_FOV_DEG = 70.0
"""Vertical field of view of the eye in the hand (deg): wide, as a wrist camera's."""
REFRESH_S = 2.0
"""With *keep the insets current*, at most one refresh this often (s): each is four renders in the tab."""
_RENDER_TIMEOUT_S = 60.0
_VIEW_DISTANCE = 2.5
"""Camera distance for the standard views, in scene radii."""

VISTA_POINTS = tuple((60.0 * k - 30.0, 30.0) for k in range(1, 7)) + tuple((90.0 * k, -30.0) for k in range(4))
"""Ranger's ten vista points (seed 000 section 6: "buttons that allow the user to select from ten
vista points for viewing the simulation"), as ``(azimuth, elevation)`` degrees about the scene
centre.  The seed gives no directions; these are chosen: six from above (elevation 30 deg, every
60 deg of azimuth from 30 deg) and four from below (elevation -30 deg, azimuths 0, 90, 180,
270 deg), where the grapple arm and the underside of the vehicle show."""

VIEWS = ("top", "front", "side") + tuple(f"vista {k}" for k in range(1, len(VISTA_POINTS) + 1))
"""The camera presets offered: three orthogonal views and the ten vista points."""


def canvas_of(client) -> dict:
    """``{"fov_rad": ..., "aspect": ...}`` of a tab's camera, as its browser last reported them; the
    defaults (75 deg, :data:`~._view.DEFAULT_ASPECT`) where it has not reported yet."""
    from ._view import DEFAULT_ASPECT

    out = {"fov_rad": math.radians(75.0), "aspect": DEFAULT_ASPECT}
    try:
        cam = client.camera
        if cam.image_width > 0 and cam.image_height > 0:
            out["aspect"] = float(cam.aspect)
        if 0.0 < float(cam.fov) < math.pi:
            out["fov_rad"] = float(cam.fov)
    except (AssertionError, AttributeError, TypeError, ValueError, ZeroDivisionError):
        pass  # no report yet (viser asserts it has one)
    return out


def urdf_hints(model, loaded: bool, has_visual: bool) -> tuple[str, str]:
    """The hints of the Views tab's "URDF visual geometry" and "URDF collision geometry" checkboxes:
    what each draws, or, where it is greyed out, why. ``model`` the console's model (None: a bare
    scene), ``loaded`` whether its URDF is drawn, ``has_visual`` whether that URDF has visuals."""
    if loaded:
        collision = "the <collision> meshes of the model's URDF"
        if has_visual:
            return "the model's URDF meshes (its <visual> geometry)", collision
        return "unavailable: the model's URDF has no <visual> geometry", collision
    if any(str(f).endswith(".urdf") for f in getattr(model, "files", ())):
        why = "unavailable: the model's URDF could not be drawn (the message above said why)"
    else:
        why = "unavailable: this scene has no URDF (its model is not built from a URDF file), so no URDF visuals"
    return why, why


def view_pose(label: str, center: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Camera ``(position, look_at)``, each (3,) m in W, for a preset of :data:`VIEWS`.

    top: looking down -z; front: looking along -x from +x; side: looking along +y from -y;
    vista k: the k-th ``(azimuth, elevation)`` of :data:`VISTA_POINTS`.  All at
    ``_VIEW_DISTANCE`` radii from ``center``, looking at it.
    """
    d = _VIEW_DISTANCE * radius
    c = np.asarray(center, dtype=np.float64)
    if label == "top":
        return c + np.array([0.0, -1e-3 * d, d]), c
    if label == "front":
        return c + np.array([d, 0.0, 0.0]), c
    if label == "side":
        return c + np.array([0.0, -d, 0.0]), c
    if label in VIEWS and label.startswith("vista "):
        az, el = (math.radians(a) for a in VISTA_POINTS[int(label.split()[1]) - 1])
        return c + d * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]), c
    raise ValueError(f"unknown view {label!r}; views are {list(VIEWS)}")


def camera_wxyz(position, look_at, up) -> np.ndarray:
    """The quaternion (w, x, y, z) of a camera at ``position`` looking at ``look_at``, ``up`` up in
    the picture: viser's (OpenCV's) camera axes — x right, y down, z forward — as columns of R_WC."""
    from ._meshes import quat_wxyz_from_matrix

    z = np.asarray(look_at, dtype=np.float64) - np.asarray(position, dtype=np.float64)
    z /= np.linalg.norm(z)
    up = np.asarray(up, dtype=np.float64)
    x = np.cross(z, up)
    if np.linalg.norm(x) < 1e-9:  # looking along up: any right will do
        x = np.cross(z, [0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.asarray(quat_wxyz_from_matrix(np.stack([x, y, z], axis=1)), dtype=np.float64)


def eye_in_hand(X_WE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(position, look_at, up)`` of the eye in the hand for tool pose ``X_WE``: at the tool origin,
    looking 0.5 m along the tool's z axis, the tool's -y up (its y down in the picture)."""
    X = np.asarray(X_WE, dtype=np.float64)
    p = X[:3, 3]
    return p.copy(), p + 0.5 * X[:3, 2], -X[:3, 1]


def inset_camera(label: str, center, radius: float, X_WE=None) -> tuple[np.ndarray, np.ndarray, float]:
    """``(position, wxyz, fov rad)`` of an inset of :data:`INSET_VIEWS`."""
    if label == "eye in the hand":
        p, look, up = eye_in_hand(X_WE)
        return p, camera_wxyz(p, look, up), math.radians(EYE_FOV_DEG)
    p, look = view_pose(label, center, radius)
    d = p - look  # the preset's direction, at the distance where the scene's sphere fills the inset
    p = look + d / np.linalg.norm(d) * radius / math.sin(math.radians(0.5 * INSET_FOV_DEG))
    return p, camera_wxyz(p, look, (0.0, 0.0, 1.0) if label != "top" else (0.0, 1.0, 0.0)), math.radians(INSET_FOV_DEG)


class TrainingViews:
    """The Views tab's training views for a :class:`~._app.ConsoleApp` (build inside its tab)."""

    def __init__(self, app) -> None:
        self.app = app
        gui = app.server.gui
        self.images: dict = {}
        self.rendered_version = -1
        self._busy = threading.Lock()
        self._last = 0.0
        self._eye_pose = None
        with gui.add_folder("training views (WORKMATE)"):
            gui.add_markdown("Top, front and side at once, and the eye in the hand: pictures of this tab's "
                             "scene from those cameras.")
            self.w_eye = gui.add_checkbox("main view: eye in the hand", False,
                                          hint="the main camera rides on the active arm's tool, looking along its z axis")
            self.b_show = gui.add_button("render the training views")
            self.w_keep = gui.add_checkbox("keep the insets current", False,
                                           hint=f"re-render after a change, at most every {REFRESH_S:g} s")
            self.w_images = {}
            blank = np.full((INSET_SIZE[0], INSET_SIZE[1], 3), 235, dtype=np.uint8)
            for label in INSET_VIEWS:
                gui.add_markdown(f"*{label}*")
                self.w_images[label] = gui.add_image(blank, format="jpeg")
        self.b_show.on_click(lambda e: self._render_async(e.client))
        self.w_eye.on_update(lambda e: self._follow_eye(force=True))

    # ------------------------------------------------------------------ the eye in the hand
    def _follow_eye(self, force: bool = False) -> None:
        if not self.w_eye.value:
            self._eye_pose = None
            return
        X = self.app.state.ee_pose()
        if not force and self._eye_pose is not None and np.array_equal(X, self._eye_pose):
            return
        self._eye_pose = X
        p, look, up = eye_in_hand(X)
        for client in self.app.server.get_clients().values():
            try:
                with client.atomic():
                    client.camera.up_direction = tuple(float(v) for v in up)
                    client.camera.position = tuple(float(v) for v in p)
                    client.camera.look_at = tuple(float(v) for v in look)
                    client.camera.fov = math.radians(EYE_FOV_DEG)
            except Exception:  # the tab closed meanwhile
                pass

    # ------------------------------------------------------------------ insets
    def render(self, client) -> dict:
        """Render the four insets in ``client`` (blocking); returns label -> (H, W, 3) uint8."""
        snap = self.app.state.snapshot()
        d = self.app.drawer
        out = {}
        for label in INSET_VIEWS:
            p, wxyz, fov = inset_camera(label, d.center, d.radius, snap.ee_pose)
            img = client.get_render(INSET_SIZE[0], INSET_SIZE[1], wxyz=wxyz, position=p, fov=fov,
                                    transport_format="jpeg", timeout=_RENDER_TIMEOUT_S)
            out[label] = np.asarray(img)[..., :3]
            self.w_images[label].image = out[label]
        self.images = out
        self.rendered_version = snap.version
        return out

    def _render_async(self, client) -> None:
        if client is None:
            clients = list(self.app.server.get_clients().values())
            if not clients:
                return
            client = clients[0]
        if not self._busy.acquire(blocking=False):
            return

        def work():
            try:
                self.render(client)
            except Exception as exc:  # the tab closed, or it timed out: say so, keep serving
                self.app.state.note_error(f"training views: not rendered ({type(exc).__name__}: {exc})")
            finally:
                self._last = time.monotonic()
                self._busy.release()

        threading.Thread(target=work, name="armguard-insets", daemon=True).start()

    def on_redraw(self, snap) -> None:
        """After each change: move the eye-in-hand camera; refresh the insets when asked to."""
        self._follow_eye()
        if (self.w_keep.value and snap.version != self.rendered_version
                and time.monotonic() - self._last >= REFRESH_S):
            self._render_async(None)
