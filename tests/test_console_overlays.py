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
