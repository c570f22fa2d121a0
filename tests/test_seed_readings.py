"""How armguard reads the seeds where a figure is easy to misread (issue: the seeds as published).

* Hermes's memory table (seed 001, §4) is *central memory*: the 3 × 3 substructures the loading
  strategy keeps, 13.5 KB at 1°, scaled by (1°/n)² with n = Ed / 11.4 (eq. 4-5); formula 4-3 is the
  whole structure, 600 KB at 1°.
* Eq. 4-5's 11.4 cm/deg is the paper's arm; armguard's HERA gives its own from L2 and L3.
* The Hermes seed carries no date.
* Ranger's workspace box is "centered on the Ranger manipulator module" and encloses the arms.
"""

from __future__ import annotations

import re

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

import armguard
from armguard.cspace import PAPER_CM_PER_DEGREE, ed_constant

ROOT = Path(__file__).resolve().parent.parent
REF = yaml.safe_load((ROOT / "reference" / "seeds" / "hermes_forbidden_map.yaml").read_text(encoding="utf-8"))


def test_hermes_memory_table_is_the_loaded_neighbourhood():
    per_deg = REF["discretization_error"]["cm_per_degree"]
    sub = REF["substructures"]
    assert sub["loaded"] * sub["kbyte_each"] == pytest.approx(sub["loaded_kbyte"])  # 9 x 1.5 = 13.5 KB
    scaled = [sub["loaded_kbyte"] * (per_deg / r["ed_cm"]) ** 2 for r in REF["memory_table"]["rows"]]
    assert scaled == pytest.approx([70.2, 17.5, 7.8, 4.4], abs=0.05)
    for r, kb in zip(REF["memory_table"]["rows"], scaled):
        assert abs(kb - r["kbyte"]) <= 0.5  # the table is this, to the KB it prints
    # formula 4-3 is the whole structure, not central memory: 75 N / (1 * 1) = 600 KB at 1 degree
    d43 = REF["memory_formula"]["kbyte_per_obstacle"] * REF["obstacles"]["value"]
    assert d43 == REF["full_structure_1deg"]["memory_kbyte"] == 600


def _pin_lengths():
    """L2, L3 of HERA from pinocchio's joint placements (an independent reading of the URDF)."""
    pm = armguard.load_model("hermes").pin_model
    names = list(pm.names)
    place = {n: np.asarray(pm.jointPlacements[names.index(n)].translation) for n in names if n.startswith("hera")}
    return float(np.linalg.norm(place["hera_elbow"])), float(np.linalg.norm(place["hera_wrist_pitch"]))


def test_ed_constant_comes_from_the_model():
    c = ed_constant(armguard.load_scene("hermes"), "hera")
    l2, l3 = _pin_lengths()
    assert (c.l2, c.l3) == pytest.approx((l2, l3), abs=1e-12)
    assert c.cm_per_degree == pytest.approx(math.hypot(l2, l3) * math.pi / 180 * 100, rel=1e-12)
    assert round(c.cm_per_degree, 1) == 10.4 and PAPER_CM_PER_DEGREE == REF["discretization_error"]["cm_per_degree"]
    assert c.resolution_deg(c.cm_per_degree) == pytest.approx(1.0)
    # the paper's 11.4 would need (L2^2 + L3^2)^(1/2) = 6.53 m
    assert PAPER_CM_PER_DEGREE / (math.pi / 180 * 100) == pytest.approx(6.53, abs=0.005)


def test_ed_constant_refuses_an_unknown_robot():
    with pytest.raises(armguard.ArmguardError, match="not in the scene"):
        ed_constant(armguard.load_scene("hermes"), "nope")


def test_the_hermes_seed_is_not_dated():
    for doc in ("docs/paper-fidelity.md", "docs/performance.md", "docs/cspace.md"):
        text = (ROOT / doc).read_text(encoding="utf-8")
        # a year, as the old text had it ("Hermes (1990)", "1990 paper"); a measured rate such as
        # "1990 k/s" in a benchmark table is not a date
        years = re.findall(r"(?<![\d.,])1990(?!\d|[.,]\d|\s*(?:k/s|µs|ms|s\b|KB|B\b|configurations))", text)
        assert not years, doc


def test_payload_is_checked_against_the_first_four_links():
    """Seed 001's payload-link module examines "the first four links"; its remark on "the last three
    links" would drop link 4.  The conservative reading: links 1-4 are checked, link 6 (holding it) is not."""
    P = armguard.load_model("hermes").pairs
    against = {a if b == "payload" else b for a, b in zip(P.owner_a, P.owner_b) if "payload" in (a, b)}
    links = {o for o in against if o.startswith("hera/")}
    assert links == {"hera/link1", "hera/link2", "hera/link3", "hera/link4"}


def test_ranger_box_is_centred_on_the_manipulator_module_and_encloses_every_arm_at_home():
    """Seed 000 §2: "a virtual rectangular box enclosing the arms and centered on the Ranger manipulator
    module"; the manipulator frame's origin is "at the center of the Manipulator Module"."""
    s = armguard.load_scene("ranger")
    box = s.workspace
    np.testing.assert_allclose((box.lo + box.hi) / 2, 0.0, atol=0.0)
    reach = np.full(3, -np.inf)
    for name, rob in s.robots.items():
        X_WL = rob.forward_kinematics(s.home(name))
        for ln, shapes in rob.link_shapes.items():
            X = X_WL[rob.link_names.index(ln)]
            for sh in shapes:  # a convex core (points) swept by a radius: every shape kind
                r = sh.core_radius
                for p_L in np.atleast_2d(sh.core_points):
                    p_W = X[:3, :3] @ p_L + X[:3, 3]
                    assert np.all(p_W - r > box.lo) and np.all(p_W + r < box.hi), (name, ln)
                    reach = np.maximum(reach, np.abs(p_W) + r)
    # the +-1.5 m box this replaced cut through the grapple arm at home (x = 2.07 m, yaml comment)
    assert 1.5 < reach[0] < box.hi[0]


def test_the_stored_timing_figures_are_compared():
    """Ranger §5's and the clipping paper's figures stand in performance.md beside armguard's, with the command."""
    text = (ROOT / "docs/performance.md").read_text(encoding="utf-8")
    section = text.split("<!-- bench:seeds -->")[1].split("<!-- /bench:seeds -->")[0]
    assert "`.venv/bin/python -m bench seeds`" in section
    ranger = yaml.safe_load((ROOT / "reference" / "seeds" / "ranger.yaml").read_text(encoding="utf-8"))
    for key, unit in (("segment_segment", "µs"), ("detection_cycle", "ms"), ("flight_estimate", "ms")):
        assert f"| {ranger[key]['value']:g} {unit} |" in section, key
    for figure in ("16 µs (65,000 per second)", "| 7 ms |", "(~6 per second)"):
        assert figure in section, figure


def test_paper_fidelity_quotes_the_seeds_bench_figures():
    """docs/paper-fidelity.md's readings table quotes armguard's side of the timing comparisons; each
    figure it quotes is the one ``bench seeds`` last wrote into performance.md (a rerun that moves
    them leaves this copy stale: it once quoted a cycle 15x slower than the bench measured)."""
    text = (ROOT / "docs/performance.md").read_text(encoding="utf-8")
    section = text.split("<!-- bench:seeds -->")[1].split("<!-- /bench:seeds -->")[0]
    ours = [ln.split("|")[-3].strip().split(" (")[0] for ln in section.splitlines()
            if ln.startswith("| segment–segment") or ln.startswith("| full detection cycle")]
    ours += [ln.split("|")[-3].strip().split(" (")[0] for ln in section.splitlines()
             if ln.startswith(("| one clipped coordinate", "| 100-vertex obstacle", "| PUMA 560 configuration"))]
    assert len(ours) == 6, ours
    fidelity = (ROOT / "docs/paper-fidelity.md").read_text(encoding="utf-8")
    rows = [ln for ln in fidelity.splitlines() if ln.startswith(("| `000` §5, timing", "| `004` clipping §V, timing"))]
    assert len(rows) == 2
    for figure in ours:
        assert figure in " ".join(rows), figure


def test_paper_fidelity_names_only_tests_that_exist():
    """docs/paper-fidelity.md's table of seed readings cites tests by file::name; each must exist."""
    import re

    text = (ROOT / "docs/paper-fidelity.md").read_text(encoding="utf-8")
    section = text.split("## The seeds as published")[1]
    cited = re.findall(r"tests/(test_\w+\.py)(?:::(\w+))?", section)
    assert len(cited) >= 8
    for name, func in cited:
        path = ROOT / "tests" / name
        assert path.is_file(), name
        if func:
            assert f"def {func}(" in path.read_text(encoding="utf-8"), f"{name}::{func}"
