"""The console's terrain and uncertain placements (state, panel, meshes), without a browser."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from armguard.console import ConsoleInputError, ConsoleState, panel_html
from armguard.console._draw_overlays import box_edges, ellipsoid_mesh, terrain_meshes
from armguard.console._overlays import MAX_TERRAIN_BOXES, parse_uncertain
from armguard.console._overlays import tested_boxes as replay_descent
from armguard.console._serve import load_for_console, make_state

TERRAIN = "reference/terrain/rocky.npz"
LOW = np.deg2rad([0, 30, 20, 30, 0])  # the turret down in front of the wheels (docs/terrain.md)


@pytest.fixture(scope="module")
def rover():
    return load_for_console("rover")


def _terrain_state(rover):
    from armguard.terrain import load_terrain

    scene, model = rover
    st = ConsoleState(scene, model=model)
    st.set_terrain(load_terrain(TERRAIN, st.scene))
    return st


def test_terrain_category_and_tested_boxes(rover):
    st = _terrain_state(rover)
    st.set_joints("arm", LOW)
    snap = st.snapshot()
    rows = {r.category: r for r in snap.readout.rows}
    assert "terrain" in rows and rows["terrain"].distance < 0  # the turret in the ground
    assert snap.readout.status.value == "collision"
    tv = snap.terrain
    assert tv is not None and tv.report.status.value == "collision"
    # the replayed descent visits exactly the boxes the pyramid's own check counted
    assert tv.visited == tv.report.boxes_tested
    assert len(tv.boxes) == min(tv.visited, MAX_TERRAIN_BOXES)
    assert tv.levels[0] == 0 and tv.levels.max() == tv.n_levels - 1 and tv.hit[0]
    pyr = st._pyramid
    for box, lvl in zip(tv.boxes, tv.levels):  # every drawn box is a box of its level
        level_boxes = pyr.levels[lvl].boxes
        assert np.any(np.all(np.abs(level_boxes - box) < 1e-12, axis=1))
    html = panel_html(snap.readout, terrain=tv)
    assert 'id="armguard-terrain"' in html and f'data-boxes="{tv.visited}"' in html
    # high above the ground: clear, far fewer boxes
    st.set_joints("arm", np.deg2rad([0, -20, 10, 0, 45]))
    high = st.snapshot().terrain
    assert high.report.status.value == "clear" and high.visited < tv.visited


def test_tested_boxes_cap_and_detach(rover):
    st = _terrain_state(rover)
    st.set_joints("arm", LOW)
    guard = st.detector.terrain
    boxes, levels, hit, visited = replay_descent(guard, st.scene.flat_q(st.snapshot().q), 0.05, 0.0, cap=5)
    assert len(boxes) == 5 and visited > 5 and list(levels[:2]) == [0, 1]
    st.set_terrain(None)
    snap = st.snapshot()
    assert snap.terrain is None and "terrain" not in {r.category for r in snap.readout.rows}
    with pytest.raises(ConsoleInputError):
        st.set_terrain("not a map")


def test_terrain_mesh_seen_and_unseen(rover):
    from armguard.terrain import load_terrain

    m = load_terrain(TERRAIN, rover[0])
    meshes = terrain_meshes(m)
    n_unknown = int((~m.known).sum())
    assert 0 < n_unknown < m.known.size
    for seen, (V, F) in meshes.items():
        n_cells = int(m.known.sum()) if seen else n_unknown
        assert len(F) >= 2 * n_cells  # a top per cell, walls beyond
        assert F.max() < len(V)
        assert V[:, 2].min() >= min(m.floor, m.heights.min()) - 1e-12 and V[:, 2].max() <= m.heights.max() + 1e-12
    # one unseen cell's top quad is in the unseen mesh at its height
    r, c = map(int, np.argwhere(~m.known)[0])
    V = meshes[False][0]
    x, y = m.origin + (np.array([c, r]) + 0.5) * m.cell
    top = V[(np.abs(V[:, 2] - m.heights[r, c]) < 1e-12)]
    assert np.any(np.linalg.norm(top[:, :2] - [x, y], axis=1) <= math.sqrt(0.5) * m.cell + 1e-12)


def test_box_edges_and_ellipsoid_mesh():
    e = box_edges([[0, 0, 0, 1, 2, 3]])
    assert e.shape == (12, 2, 3)
    assert np.allclose(np.abs(e).reshape(-1, 3).max(axis=0), [1, 2, 3])
    assert np.allclose(sorted(np.linalg.norm(e[:, 1] - e[:, 0], axis=1)), [2] * 4 + [4] * 4 + [6] * 4)
    axes = np.diag([0.1, 0.2, 0.3])
    V, _ = ellipsoid_mesh([1, 2, 3], axes)
    u = (V - [1, 2, 3]) / [0.1, 0.2, 0.3]
    assert np.allclose(np.linalg.norm(u, axis=1), 1.0, atol=1e-4)


def test_uncertain_placement_sigmas_and_ellipsoids(rover):
    from armguard.uncertainty import clearance_sigmas

    scene, model = rover
    st = ConsoleState(scene, model=model)
    assert st.snapshot().sigmas is None
    st.add_uncertain("chassis", 0.02, 1.0)
    snap = st.snapshot()
    rep = snap.sigmas
    direct = clearance_sigmas(st.detector, st.scene.flat_q(snap.q), st.placements, samples=0)
    assert rep.overall.nearest.sigmas == pytest.approx(direct.overall.nearest.sigmas, rel=1e-12)
    assert rep.overall.p_bound == pytest.approx(direct.overall.p_bound, rel=1e-12)
    p = rep.overall.nearest
    assert p.sigmas == pytest.approx(p.distance / p.sigma)
    html = panel_html(snap.readout, sigmas=rep)
    assert 'id="armguard-sigmas"' in html and f'data-sigmas="{p.sigmas:.3g}"' in html and "P(collision)" in html
    ells = st.ellipsoids()
    at_origin = [e for e in ells if e.name == "chassis"]
    assert [e.confidence for e in at_origin] == [0.9, 0.999]
    for e in at_origin:  # an isotropic 2 cm spread of the origin: a sphere of radius 2 cm * k
        k = math.sqrt(stats.chi2.ppf(e.confidence, 3))
        assert np.allclose(np.linalg.norm(e.axes, axis=0), 0.02 * k, rtol=1e-6)
    at_witness = [e for e in ells if e.name == "chassis @ nearest"]
    assert at_witness and np.allclose(at_witness[0].center, p.p_WB if p.b == "chassis" else p.p_WA)
    # the witness point is off the origin: the 1 deg rotation's lever arm makes its ellipsoid larger
    assert np.linalg.norm(at_witness[0].axes, axis=0).max() > np.linalg.norm(at_origin[0].axes, axis=0).max()
    st.set_placements(())
    assert st.snapshot().sigmas is None and st.ellipsoids() == ()


@pytest.mark.parametrize("text, words", [("chassis", "BODY=SIGMA_M"), ("nope=0.1", "not a body or robot"),
                                         ("chassis=abc", "numbers"), ("chassis=0.1,2,3", "SIGMA_M,SIGMA_DEG"),
                                         ("chassis=-1", ">= 0"), ("chassis=0,0", "both 0")])
def test_parse_uncertain_refuses_bad_text(rover, text, words):
    with pytest.raises(ConsoleInputError, match=words):
        parse_uncertain(rover[0], text)


def test_make_state_from_cli_words():
    st = make_state("rover", terrain=TERRAIN, uncertain=["arm=0.01,0.5", "mast=0.03"])
    assert st.terrain is not None and [p.name for p in st.placements] == ["arm", "mast"]
    snap = st.snapshot()
    assert snap.terrain is not None and snap.sigmas is not None


def test_console_cli_refuses_bad_uncertain():
    from click.testing import CliRunner

    from armguard.cli import main

    res = CliRunner().invoke(main, ["console", "rover", "--port", "0", "--uncertain", "nope=0.1"])
    assert res.exit_code == 3 and "not a body or robot" in res.output  # a value refused (armguard.cli.ExitCode)


def test_terrain_collision_is_the_headline_with_every_backend(rover):
    """The terrain is checked by the detector only: with another backend the panel still shows
    its row, and the headline is the worst of every category (red, the terrain's depth)."""
    st = _terrain_state(rover)
    st.set_joints("arm", LOW)
    ref = st.snapshot().terrain.report
    assert ref.status.value == "collision" and ref.distance < 0
    others = [b for b in st.backends if b in ("coal", "fcl")]
    assert others, "coal is a dependency: the rover must offer it"
    for backend in ["analytic"] + others:
        st.set_backend(backend)
        r = st.snapshot().readout
        rows = {row.category: row for row in r.rows}
        assert r.backend == backend and r.status.value == "collision", backend
        assert rows["terrain"].distance == pytest.approx(ref.distance, abs=1e-9), backend
        assert r.distance <= min(row.distance for row in r.rows) + 1e-12, backend  # the nearest of all
        assert r.alarm and r.reason == "contact"
    st.set_joints("arm", np.deg2rad([0, -20, 10, 0, 45]))  # high: the terrain row stays, clear
    r = st.snapshot().readout
    assert "terrain" in {row.category for row in r.rows} and r.status.value != "collision"


def _srgb_to_lab(rgb) -> np.ndarray:
    """CIELAB (D65) of an 8-bit sRGB colour: the textbook formulas, written out."""
    c = np.asarray(rgb, dtype=np.float64) / 255.0
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    M = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                  [0.0193339, 0.1191920, 0.9503041]])
    xyz = M @ c / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_unseen_cells_cannot_be_confused_with_the_feature_outline():
    """Unseen terrain is far (CIELAB ΔE76) from the magenta nearest-feature outline, and from
    every other colour of the view's shapes and lines."""
    from armguard.console._draw import COLORS, COMPARE_COLOR, FEATURE_COLOR
    from armguard.console._draw_overlays import TERRAIN_COLOR, UNKNOWN_COLOR

    de = lambda a, b: float(np.linalg.norm(_srgb_to_lab(a) - _srgb_to_lab(b)))  # noqa: E731
    assert de((255, 255, 255), (0, 0, 0)) == pytest.approx(100.0, abs=0.01)  # the reference itself
    assert de(UNKNOWN_COLOR, FEATURE_COLOR) >= 60.0
    for other in (*COLORS.values(), COMPARE_COLOR, TERRAIN_COLOR):
        assert de(UNKNOWN_COLOR, other) >= 30.0, other


def test_terrain_block_gives_the_distance_when_clear(rover):
    """Clear beyond the check's reach, the terrain block still gives the least distance and the
    link: the same as the least exact distance over every column (a plain loop)."""
    from armguard.geometry import distance

    st = _terrain_state(rover)
    st.set_joints("arm", np.deg2rad([0, -20, 10, 0, 45]))
    tv = st.snapshot().terrain
    assert tv.report.status.value == "clear" and math.isinf(tv.report.distance)
    d, link, limit = tv.far
    assert math.isfinite(d) and tv.report.reach < d <= limit
    guard = st.detector.terrain
    _, shapes = guard.posed(st.scene.flat_q(st._q))
    m = guard.pyramid.map
    best = (math.inf, None)
    for k, s in enumerate(shapes):
        for r in range(m.shape[0]):
            for c in range(m.shape[1]):
                x = distance(s, guard.pyramid.cell_box(r, c)).distance
                if x < best[0]:
                    best = (x, guard.owners[k])
    assert d == pytest.approx(best[0], abs=1e-6) and link == best[1]
    html = panel_html(st.snapshot().readout, terrain=tv)
    assert f"clear: {d * 1000:.1f} mm ({link};" in html and "— (—)" not in html


def test_terrain_depth_is_true_or_said_to_be_a_lower_bound(rover):
    """A shallow contact's depth is the link's true depth (moving it out by the depth frees it);
    deeper, the column depth stays put while the link sinks, and the block says it is a bound."""
    from armguard.geometry import distance

    st = _terrain_state(rover)
    guard = st.detector.terrain

    def moved_out(tv):  # the nearest link moved out by the depth (+2 mm) along the witness: least distance
        rep = tv.report
        n = (rep.p_WB - rep.p_WA) / np.linalg.norm(rep.p_WB - rep.p_WA)
        X = np.eye(4)
        X[:3, 3] = n * (-rep.distance + 2e-3)
        _, shapes = guard.posed(st.scene.flat_q(st._q))
        mine = [s.transformed(X) for s, o in zip(shapes, guard.owners) if o == rep.link]
        m = guard.pyramid.map
        return min(distance(s, guard.pyramid.cell_box(r, c)).distance
                   for s in mine for r in range(m.shape[0]) for c in range(m.shape[1]))

    st.set_joints("arm", np.deg2rad([0, 18, 8, 0, 0]))
    shallow = st.snapshot().terrain
    assert -0.03 < shallow.report.distance < 0 and shallow.depth_resolved
    assert moved_out(shallow) > 0
    html = panel_html(st.snapshot().readout, terrain=shallow)
    assert f": {shallow.report.distance * 1000:.1f} mm (" in html and "≤" not in html

    depths = []
    for wrist in (30, 50):
        st.set_joints("arm", np.deg2rad([0, 30, 20, wrist, 0]))
        deep = st.snapshot().terrain
        assert deep.report.distance < 0 and not deep.depth_resolved
        assert moved_out(deep) < 0  # still in the ground: the true depth is larger
        html = panel_html(st.snapshot().readout, terrain=deep)
        assert f"≤ {deep.report.distance * 1000:.1f} mm" in html and "deeper not resolved" in html
        depths.append(deep.report.distance)
    assert depths[0] == pytest.approx(depths[1], abs=1e-9)  # one column's depth does not grow


def test_line_buried_in_the_terrain():
    """A segment through a column's top is buried; one above the surface, under the floor or off
    the map is not; the ends (trimmed) do not count."""
    from types import SimpleNamespace

    from armguard.console._draw_overlays import line_buried

    h = np.zeros((4, 4))
    h[1, 2] = 0.3  # one rock at x in [0.2, 0.3), y in [0.1, 0.2)
    m = SimpleNamespace(heights=h, origin=np.array([0.0, 0.0]), cell=0.1, floor=-0.1)
    assert line_buried(m, [[0.25, 0.15, 0.5], [0.25, 0.15, 0.1]])  # down into the rock
    assert line_buried(m, [[0.05, 0.15, 0.2], [0.38, 0.15, 0.2]])  # sideways through it
    assert not line_buried(m, [[0.05, 0.15, 0.4], [0.38, 0.15, 0.4]])  # over it
    assert not line_buried(m, [[0.05, 0.05, 0.05], [0.35, 0.05, 0.05]])  # over the flat ground
    assert not line_buried(m, [[0.05, 0.05, -0.5], [0.35, 0.05, -0.5]])  # under the floor
    assert not line_buried(m, [[1.5, 1.5, -0.05], [2.5, 1.5, -0.05]])  # off the map
    assert not line_buried(m, [[0.25, 0.15, 0.31], [0.25, 0.15, 0.5]])  # ends on the top face
    assert not line_buried(m, [[0.25, 0.15, np.nan], [0.25, 0.15, 0.1]])


def test_terrain_is_seen_through_while_the_line_is_buried(rover):
    """The rover's turret in the ground: its nearest line lies in a column, so the drawer makes the
    terrain translucent; high above, opaque again."""
    from types import SimpleNamespace

    from armguard.console._draw_overlays import TERRAIN_SEE_THROUGH_OPACITY, OverlayDrawer, line_buried

    st = _terrain_state(rover)
    drawer = OverlayDrawer(server=None)
    drawer.terrain_handles = {True: SimpleNamespace(opacity=None), False: SimpleNamespace(opacity=None)}
    st.set_joints("arm", LOW)
    snap = st.snapshot()
    r = snap.readout
    assert r.obstacle == "terrain" and line_buried(st.terrain, [r.p_WA, r.p_WB])
    drawer._see_through_terrain(snap, st)
    assert all(h.opacity == TERRAIN_SEE_THROUGH_OPACITY for h in drawer.terrain_handles.values())
    st.set_joints("arm", np.deg2rad([0, -20, 10, 0, 45]))
    snap = st.snapshot()
    assert not line_buried(st.terrain, [snap.readout.p_WA, snap.readout.p_WB])
    drawer._see_through_terrain(snap, st)
    assert all(h.opacity is None for h in drawer.terrain_handles.values())
