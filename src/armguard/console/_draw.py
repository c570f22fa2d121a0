"""The console's 3-D view on viser: shapes, the nearest-obstacle lines, the feature, the URDF robots.

:class:`SceneDrawer` draws each checked shape once as a mesh and afterwards only moves and
recolours it.  The nearest-obstacle line is drawn in screen-space pixels (:data:`LINE_PX`), so it
keeps its width at every zoom, also in software WebGL, with a marker sphere at each nearest point
(sized to the line: :func:`~._view.marker_radius`) and the distance as a label at its middle; a compared backend's line is cyan, drawn beside the first (shifted
sideways by :data:`COMPARE_OFFSET` scene radii, so two equal answers stay two visible lines; its
label below the line, the first one's above: :func:`label_place`).
The nearest link is red within the threshold; the obstacle's nearest face or edge is outlined
in magenta.  A shape the nearest line runs through (a link wrapped around it, say: no camera sees
past it), or that stands between a browser tab's camera and the line (:mod:`._sight`), is drawn
translucent (:data:`SEE_THROUGH_OPACITY`), so the line stays in sight; viser offers no
depth-test switch for line segments.  In a contact the obstacle the line runs inside is drawn
translucent too, so the red link inside it stays in sight, whichever backend computed the pair.  Robots from a URDF are also drawn from it (viser's ``ViserUrdf`` over yourdfpy):
its visual geometry where it has one, its collision geometry as a toggle.
"""

from __future__ import annotations

import io
import math
import threading
import time
from pathlib import Path

import numpy as np

from ._draw_overlays import OverlayDrawer
from ._meshes import item_frames, link_poses, mesh_of, quat_wxyz_from_matrix
from ._nodes import PosedItems, ShapeNode
from ._readout import no_negative_zero
from ._sight import SIGHT_PERIOD, hidden_from
from ._view import DEFAULT_ASPECT, feature_segments, follow_view, marker_radius, pair_view, see_through

__all__ = ["SceneDrawer", "grid_segments", "grid_step", "GRID_COLOR", "LINE_PX", "COMPARE_OFFSET", "COLORS", "COMPARE_COLOR", "FEATURE_COLOR", "SEE_THROUGH_OPACITY"]

COLORS = {"body": (150, 160, 175), "link": (235, 150, 60), "payload": (90, 180, 110), "hot": (230, 20, 20),
          "active": (245, 120, 30)}
COMPARE_COLOR = (0, 200, 220)
FEATURE_COLOR = (230, 0, 230)
LINE_PX = 5.0
"""Width of the nearest-obstacle line (screen pixels)."""
COMPARE_OFFSET = 0.015
"""Sideways shift of the compared backend's line, in scene radii."""
SEE_THROUGH_OPACITY = 0.3
"""Opacity of a shape the nearest line runs through (the others are opaque)."""
LABEL_RISE = 0.3
"""The distance label stands this many line lengths above the line's middle (not over the line)."""


def label_place(key: str, pa, pb) -> tuple[tuple[float, float, float], str]:
    """Where a nearest line's distance label stands, and its anchor: the first backend's
    (``"primary"``) :data:`LABEL_RISE` line lengths above the line's middle, resting on that
    point; a compared backend's (``"compare"``) as far below it, hanging from it -- the two never
    stack over one another, however short the line."""
    pa, pb = np.asarray(pa, dtype=np.float64), np.asarray(pb, dtype=np.float64)
    up = 1.0 if key == "primary" else -1.0
    p = 0.5 * (pa + pb) + np.array([0.0, 0.0, up * LABEL_RISE * float(np.linalg.norm(pb - pa))])
    return tuple(float(x) for x in p), ("bottom-center" if up > 0 else "top-center")


GRID_COLOR = (185, 185, 190)
"""The floor grid's lines (thin screen-space lines: viser's shaded grid plane cost more than half of
a software-WebGL frame)."""


def grid_step(half: float) -> float:
    """The floor grid's spacing (m) for a grid ``half`` m wide each way: 1, 2 or 5 times a power
    of ten, about a tenth of ``half``."""
    raw = max(float(half), 1e-6) / 10.0
    p = 10.0 ** math.floor(math.log10(raw))
    return min((m * p for m in (1.0, 2.0, 5.0, 10.0) if m * p >= raw), default=10.0 * p)


def grid_segments(center, half: float, z: float) -> np.ndarray:
    """``(n, 2, 3) float32``: the floor grid's lines at height ``z``, ``half`` m each way of
    ``center``'s x, y (rounded to the spacing :func:`grid_step`)."""
    step = grid_step(half)
    cx, cy = (round(float(c) / step) * step for c in np.asarray(center, dtype=np.float64)[:2])
    k = int(math.ceil(half / step))
    ticks = np.arange(-k, k + 1) * step
    x0, x1, y0, y1 = cx - k * step, cx + k * step, cy - k * step, cy + k * step
    segs = [[[cx + t, y0, z], [cx + t, y1, z]] for t in ticks] + [[[x0, cy + t, z], [x1, cy + t, z]] for t in ticks]
    return np.array(segs, dtype=np.float32)


def _strip_collision_checking(text: str) -> str:
    import re

    return re.sub(r"<collision_checking>.*?</collision_checking>", "", text, flags=re.S)


def _inside(p, shape) -> bool:
    from ..geometry import Sphere, distance

    return distance(Sphere(p, 1e-6), shape).distance < 0.0


class SceneDrawer:
    """Draw a console state's scene on a viser server (call :meth:`build` once, :meth:`draw` per change).

    Each shape is one mesh, added once by :meth:`build`; :meth:`draw` then only moves the meshes
    that moved (a pose from forward kinematics, :class:`~._nodes.PosedItems`) and sends a colour,
    an opacity or a line only when it changed.  The lighting is the default lights and a
    hemisphere light, without the environment map (image-based lighting made each frame in
    software WebGL several times slower).
    """

    def __init__(self, server, state) -> None:
        self.server = server
        self.state = state
        self.urdf = None
        self._urdf_index = None
        self._urdf_shown = False
        self._handles = []
        self._lock = threading.RLock()
        self._eyes: dict = {}
        self._sight_timer = None
        self._last_snap = None
        self._last_posed = None
        self.hidden = set()
        self.draw_ms: float | None = None
        try:
            server.on_client_connect(self._watch_camera)
            server.on_client_disconnect(self._forget_camera)
        except AttributeError:  # a stand-in server (tests): no tabs to watch
            pass

    # ------------------------------------------------------------------ build
    def configure_look(self) -> None:
        """Lights without the environment map (a software-WebGL frame costs several times more with it)."""
        sc = self.server.scene
        sc.configure_environment_map(None)
        self._hemi = sc.add_light_hemisphere("/lights/hemisphere", sky_color=(255, 255, 255),
                                             ground_color=(120, 120, 130), intensity=1.2, position=(0.0, 0.0, 1.0))

    def build(self) -> None:
        with self._lock:
            self._build()

    def _build(self) -> None:
        sc = self.server.scene
        if not hasattr(self, "_hemi"):
            self.configure_look()
        for h in self._handles:
            try:
                h.remove()
            except Exception:
                pass
        self._handles = []
        self._marker_r = {}
        snap = self.state.snapshot()
        scene = self.state.scene
        items = scene.shapes_at(snap.q, poses=link_poses(scene, snap.q))
        frames = item_frames(scene, snap.q)
        self.items: list[ShapeNode] = []
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for k, (it, X0) in enumerate(zip(items, frames)):
            v, f = mesh_of(it.shape)
            c0 = np.array(it.shape.core_points).mean(axis=0)
            lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
            color = COLORS.get(it.kind, COLORS["body"])
            h = sc.add_mesh_simple(f"/shapes/{k:03d}_{it.owner.replace('/', '.')}", v - c0, f, color=color,
                                   side="double" if len(f) < 8 else "front", position=c0,
                                   cast_shadow=False, receive_shadow=False)
            self._handles.append(h)
            bound = float(np.max(np.linalg.norm(v - c0, axis=1))) if len(v) else 0.0
            self.items.append(ShapeNode(it.owner, it.kind, it.robot, it.shape, c0, bound, np.linalg.inv(X0), h, color,
                                        shown_color=color))
        if not np.all(np.isfinite(lo)):
            lo, hi = -np.ones(3), np.ones(3)
        self.center = 0.5 * (lo + hi)
        self.radius = max(0.5, 0.5 * float(np.linalg.norm(hi - lo)))
        self._handles.append(sc.add_line_segments("/grid", grid_segments(self.center, 2.0 * self.radius, lo[2]),
                                                  GRID_COLOR, thickness=1.0, thickness_units="screen"))
        seg = np.zeros((1, 2, 3), dtype=np.float32)
        self.lines = {}
        self.labels = {}
        for key, col in (("primary", (255, 210, 0)), ("compare", COMPARE_COLOR)):
            line = sc.add_line_segments(f"/nearest/{key}/line", seg, col, thickness=LINE_PX,
                                        thickness_units="screen", visible=False)
            self.lines[key] = [line] + self._markers(key, col, 0.01)
            self.labels[key] = sc.add_label(f"/nearest/{key}/label", "", visible=False,
                                            anchor=label_place(key, np.zeros(3), np.zeros(3))[1], font_screen_scale=1.2)
            self._handles += [line, self.labels[key]] + self.lines[key][1:]
        self.feature = sc.add_line_segments("/nearest/feature", seg, FEATURE_COLOR, thickness=LINE_PX - 1.0,
                                            thickness_units="screen", visible=False)
        self.ws = sc.add_line_segments("/workspace", seg, (60, 120, 220), thickness=2.0, thickness_units="screen",
                                       visible=False)
        self._handles += [self.feature, self.ws]
        self._ws_shown = None
        self._feature_shown = None
        self._line_colors = {}
        self._last_snap = self._last_posed = None
        self.hidden = set()
        if not hasattr(self, "overlays"):
            self.overlays = OverlayDrawer(self.server)
        self.overlays.build(self.state)
        self._build_urdf()

    def _markers(self, key: str, col, radius: float) -> list:
        """(Re)create the two nearest-point marker spheres of line ``key`` with ``radius`` (m)."""
        sc = self.server.scene
        old = self.lines.get(key)
        if old is not None:
            for h in old[1:]:
                h.remove()
        self._marker_r[key] = radius
        return [sc.add_icosphere(f"/nearest/{key}/{end}", radius=radius, color=col, visible=False) for end in "ab"]

    def _build_urdf(self) -> None:
        """Load the model's URDF into viser (hidden until asked for); any failure leaves it out."""
        if self.urdf is not None:
            try:
                self.urdf.remove()
            except Exception:
                pass
        self.urdf = None
        model = self.state.model
        files = [Path(f) for f in getattr(model, "files", ()) if str(f).endswith(".urdf")]
        if not files:
            return
        try:
            import yourdfpy
            from viser.extras import ViserUrdf

            path = files[0]
            text = _strip_collision_checking(path.read_text(encoding="utf-8"))
            urdf = yourdfpy.URDF.load(io.BytesIO(text.encode("utf-8")), load_meshes=True,
                                      build_collision_scene_graph=True, load_collision_meshes=True,
                                      mesh_dir=str(path.parent))
            self.urdf = ViserUrdf(self.server, urdf, root_node_name="/urdf", load_meshes=True,
                                  load_collision_meshes=True, collision_mesh_color_override=(0.55, 0.6, 0.7, 0.6))
            names = list(self.urdf.get_actuated_joint_names())
            pin_names = list(model.joint_names)
            self._urdf_index = [pin_names.index(n) if n in pin_names else -1 for n in names]
            self.has_visual = any(link.visuals for link in urdf.robot.links)
            self.set_urdf(False, False)
        except Exception as exc:  # display only: the console runs without it
            self.state.note_error(f"URDF display unavailable: {type(exc).__name__}: {exc}")
            self.urdf = None

    def set_urdf(self, visual: bool, collision: bool) -> None:
        if self.urdf is None:
            return
        with self._lock:
            if self.has_visual:
                self.urdf.show_visual = bool(visual)
            self.urdf.show_collision = bool(collision)
            self._urdf_shown = bool(visual and self.has_visual) or bool(collision)
            if self._urdf_shown and self._last_snap is not None:
                self._pose_urdf(self._last_snap)

    def set_shapes_visible(self, on: bool) -> None:
        for item in self.items:
            item.handle.visible = bool(on)

    def set_boxes_visible(self, on: bool) -> None:
        """Show (or hide) the terrain pyramid boxes the last check tested (hidden by default)."""
        with self._lock:
            self.overlays.set_boxes_visible(on)

    def add_view_controls(self, gui) -> None:
        """The view's own checkboxes (in the caller's GUI container): the tested pyramid boxes, with a terrain."""
        self._w_boxes = None
        if getattr(self.state, "terrain", None) is None:
            return
        self._w_boxes = gui.add_checkbox("terrain: tested pyramid boxes", False,
                                         hint="the boxes each check visited, by level (slow to draw without a GPU)")
        self._w_boxes.on_update(lambda _e: self.set_boxes_visible(self._w_boxes.value))

    # ------------------------------------------------------------------ cameras
    def _watch_camera(self, client) -> None:
        client.camera.on_update(lambda cam, c=client: self._camera_moved(c))

    def _forget_camera(self, client) -> None:
        with self._lock:
            self._eyes.pop(client.client_id, None)

    def _camera_moved(self, client) -> None:
        try:
            eye = np.array(client.camera.position, dtype=np.float64)
        except Exception:  # the tab closed meanwhile
            return
        with self._lock:
            self._eyes[client.client_id] = eye
            if self._sight_timer is not None:
                return
            self._sight_timer = threading.Timer(SIGHT_PERIOD, self._refresh_sight)
            self._sight_timer.daemon = True
            self._sight_timer.start()

    def _refresh_sight(self) -> None:
        """A camera moved: draw translucent what now hides the nearest line, opaque what no longer does."""
        try:
            with self._lock:
                self._sight_timer = None
                if self._last_snap is not None and self._last_posed is not None:
                    with self.server.atomic():
                        self._apply_opacity(self._last_snap, self._last_posed)
                        self.overlays._see_through_terrain(self._last_snap, self.state, self.eyes())
        except Exception as exc:  # display only
            self.state.note_error(f"display error: {type(exc).__name__}: {exc}")

    def eyes(self) -> list[np.ndarray]:
        """The browser tabs' camera positions (m, W) the view knows."""
        return list(self._eyes.values())

    # ------------------------------------------------------------------ draw
    def see_through(self, snap, items=None) -> set[int]:
        """Indices (into the scene's shapes) of the shapes the nearest line runs through, other
        than the link's own; the obstacle's too only in a contact, where the line runs inside it
        and so does the red link (the obstacle translucent shows it; the link stays opaque)."""
        r = snap.readout
        if r.p_WA is None or r.p_WB is None:
            return set()
        posed = PosedItems(self.items, self.state.scene, snap.q) if items is None else items
        own = {r.owner_a} if not r.distance > 0.0 else {r.owner_a, r.owner_b or r.obstacle}
        L = np.array([r.p_WA, r.p_WB], dtype=np.float64)
        idx = [k for k in posed.near(L[0], L[1]) if self.items[k].owner not in own]
        hit = see_through(L, [posed.shape(k) for k in idx])
        return {idx[k] for k in hit}

    def line_hidden(self, snap, posed=None) -> set[int]:
        """Indices of the shapes standing between a tab's camera and the nearest line
        (:func:`~._sight.hidden_from`; in a contact the pair's own shapes are not counted: the
        line lies inside both, and :meth:`see_through` makes the obstacle translucent)."""
        r = snap.readout
        if r.p_WA is None or r.p_WB is None or not self._eyes:
            return set()
        posed = PosedItems(self.items, self.state.scene, snap.q) if posed is None else posed
        skip = set()
        if not r.distance > 0.0:
            skip = {k for k, n in enumerate(self.items) if n.owner in (r.owner_a, r.owner_b or r.obstacle)}
        line = np.array([r.p_WA, r.p_WB], dtype=np.float64)
        out: set[int] = set()
        for eye in self.eyes():
            out |= hidden_from(eye, line, posed, skip=skip | out)
        return out

    def _apply_opacity(self, snap, posed) -> None:
        clear = self.see_through(snap, posed) | self.line_hidden(snap, posed)
        self.hidden = clear
        for k, node in enumerate(self.items):
            opacity = SEE_THROUGH_OPACITY if k in clear else None
            if node.shown_opacity != opacity:
                node.handle.opacity = opacity
                node.shown_opacity = opacity

    def draw(self, snap) -> None:
        """Show ``snap`` (one batch of scene messages); :attr:`draw_ms` is how long it took."""
        t0 = time.perf_counter()
        with self._lock, self.server.atomic():
            self._draw(snap)
        self.draw_ms = (time.perf_counter() - t0) * 1e3

    def _draw(self, snap) -> None:
        r = snap.readout
        try:
            posed = PosedItems(self.items, self.state.scene, snap.q)
        except ValueError:  # the model was reloaded and the view not yet rebuilt (the draw loop's next frame)
            return
        for node, T in zip(self.items, posed.T):
            want = COLORS["hot"] if (r.alarm and node.owner == r.owner_a) else node.color
            if node.shown_color != want:
                node.handle.color = want
                node.shown_color = want
            if node.kind == "body":
                continue
            R = T[:3, :3]
            node.handle.position = R @ node.c0 + T[:3, 3]  # viser sends only a changed pose
            node.handle.wxyz = quat_wxyz_from_matrix(R)
        self._apply_opacity(snap, posed)
        self._line("primary", r)
        cmp = snap.compare
        self._line("compare", None if cmp is None else cmp.readout, offset=True, primary=r)
        self._draw_feature(r, posed)
        self._draw_workspace(snap.workspace)
        self.overlays.draw(snap, self.state, self.eyes())
        self._last_snap, self._last_posed = snap, posed
        if self._urdf_shown:
            self._pose_urdf(snap)

    def _pose_urdf(self, snap) -> None:
        if self.urdf is None or self._urdf_index is None:
            return
        qp = np.asarray(self.state.model.pin_q(self.state.scene.flat_q(snap.q)), dtype=np.float64)
        cfg = np.array([qp[i] if i >= 0 else 0.0 for i in self._urdf_index])
        self.urdf.update_cfg(cfg)

    def _line(self, key: str, r, *, offset: bool = False, primary=None) -> None:
        line, a, b = self.lines[key]
        label = self.labels[key]
        show = r is not None and r.p_WA is not None
        if show:
            pa, pb = np.asarray(r.p_WA, dtype=np.float64), np.asarray(r.p_WB, dtype=np.float64)
            if offset:
                pa, pb = pa + self._side(pa, pb), pb + self._side(pa, pb)
            col = r.line_color if key == "primary" else COMPARE_COLOR
            want = marker_radius(float(np.linalg.norm(pb - pa)), self.radius)
            if not 0.8 < want / self._marker_r[key] < 1.25:
                a.radius = b.radius = want  # the same spheres, resized
                self._marker_r[key] = want
            text = f"{no_negative_zero(r.distance * 1000.0, 1):.1f} mm" + (f" ({r.backend})" if key == "compare" else "")
            if label.text != text:
                label.text = text
            label.position = label_place(key, pa, pb)[0]
            if self._line_colors.get(key) != col:
                # one colour for the whole line (the uniform path: viser's per-vertex line colours
                # came out grey in software WebGL)
                line.colors = np.array(col, dtype=np.uint8)
                a.color = b.color = col
                self._line_colors[key] = col
            line.points = np.array([[pa, pb]], dtype=np.float32)  # viser sends only changed points
            a.position, b.position = tuple(pa), tuple(pb)
        for h in (line, a, b, label):
            if h.visible != show:
                h.visible = show

    def _side(self, pa, pb) -> np.ndarray:
        d = pb - pa
        n = np.cross(d, [0.0, 0.0, 1.0])
        if np.linalg.norm(n) < 1e-9 * max(1.0, np.linalg.norm(d)):
            n = np.cross(d, [1.0, 0.0, 0.0])
        if np.linalg.norm(n) < 1e-12:
            n = np.array([1.0, 0.0, 0.0])
        return COMPARE_OFFSET * self.radius * n / np.linalg.norm(n)

    def _draw_feature(self, r, posed) -> None:
        seg = np.zeros((0, 2, 3))
        if r.feature is not None and r.owner_b and r.p_WB is not None:
            ks = [k for k, n in enumerate(self.items) if n.owner == r.owner_b]
            if ks:
                k = min(ks, key=lambda k: float(np.min(np.linalg.norm(
                    np.asarray(posed.shape(k).core_points) - r.p_WB, axis=1))))
                seg = feature_segments(posed.shape(k), r.feature)
        key = None if not len(seg) else seg.round(9).tobytes()
        if key == self._feature_shown:
            return
        self._feature_shown = key
        if len(seg):
            self.feature.points = seg.astype(np.float32)
            self.feature.colors = np.array(FEATURE_COLOR, dtype=np.uint8)
        show = bool(len(seg))
        if self.feature.visible != show:
            self.feature.visible = show

    def _draw_workspace(self, ws) -> None:
        key = None if ws is None else tuple(np.concatenate(ws))
        if key == self._ws_shown:
            return
        self._ws_shown = key
        if ws is None:
            self.ws.visible = False
            return
        lo, hi = ws
        c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        edges = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
        self.ws.points = np.array([[c[a], c[b]] for a, b in edges], dtype=np.float32)
        self.ws.visible = True

    # ------------------------------------------------------------------ camera
    def follow_pose(self, snap, fov_rad: float = math.radians(75.0), *, focus: str = "arm",
                    aspect: float = DEFAULT_ASPECT):
        """``(position, look_at)`` framing the active arm and its nearest obstacle point
        (``focus="arm"``, left of the control panel on a canvas ``aspect`` wide per unit height),
        or only the nearest pair (``focus="pair"``: :func:`~._view.pair_view`, seen across the
        line past every shape)."""
        r = snap.readout
        items = self.state.scene.shapes_at(snap.q, poses=link_poses(self.state.scene, snap.q))
        line = None if r.p_WB is None else np.array([r.p_WA, r.p_WB], dtype=np.float64)
        if focus == "pair" and line is not None:
            return pair_view(line, [it.shape for it in items], fov_rad=fov_rad, min_radius=0.02 * self.radius)
        arm = [it for it in items if it.robot == snap.active]
        pts = [np.asarray(it.shape.core_points) for it in arm]
        if line is not None:
            pts.append(line[1].reshape(1, 3))
        P = np.concatenate(pts) if pts else self.center.reshape(1, 3)
        # the arm's points to keep in sight (its nearest link's count most), past the other
        # robots' and bodies' opaque shapes
        # (an obstacle translucent in a contact still hides the red link best not seen through it)
        clear = {k for k in self.see_through(snap) if self.items[k].owner != (r.owner_b or r.obstacle)}
        obstacles = [it.shape for k, it in enumerate(items) if it.robot != snap.active and k not in clear]
        targets, weights, radii, axis = [], [], [], None
        for it in arm:
            core = np.asarray(it.shape.core_points, dtype=np.float64)
            hot = it.owner == r.owner_a
            if hot and len(core) == 2:  # the nearest link: points along its axis
                axis = core[1] - core[0]
                core = core[0] + np.linspace(0.0, 1.0, 5)[:, None] * axis
            for p in (core if hot else core.mean(axis=0, keepdims=True)):
                if hot and any(_inside(p, sh) for sh in obstacles):
                    continue  # inside an obstacle: no camera sees it
                targets.append(p)
                weights.append(4.0 if hot else 1.0)
                radii.append(0.8 * float(getattr(it.shape, "radius", 0.0)))
        return follow_view(P, self.center, line=line, fov_rad=fov_rad, aspect=aspect, targets=np.array(targets).reshape(-1, 3),
                           weights=weights, target_radii=radii, obstacles=obstacles, axis=axis)
