"""``armguard demo`` (the job ``make run`` runs) and the words it reports verdicts in.

A stopping distance depends on speed (Hermes ``001_…`` §4: a stepwise function of speed; zero at
rest), so an arm starting from rest is not charged the top-speed distance at t = 0; a violation of
the stopping distance by shapes still apart is reported as such, beside a real contact.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from armguard.cli import main
from armguard.cli._demo import AT_REST, HERMES_MAX_STOPPING_DISTANCE, hermes_table
from armguard.scene import load_scene
from armguard.verify import CollisionKind, StoppingDistance, Subdivided, Verifier, VerificationStatus


def test_hermes_table_is_zero_at_rest_and_steps_to_its_top():
    sd = hermes_table(2.0)
    assert sd.at(0.0) == 0.0 and sd.at(AT_REST) == 0.0
    assert sd.at(2 * AT_REST) == pytest.approx(HERMES_MAX_STOPPING_DISTANCE / 10)
    assert sd.at(2.0) == pytest.approx(HERMES_MAX_STOPPING_DISTANCE)
    values = [sd.at(v) for v in np.linspace(0.0, 2.0, 401)]
    assert np.all(np.diff(values) >= 0.0)
    with pytest.raises(Exception, match="at_rest"):
        StoppingDistance.hermes(1.0, 0.1, 10, at_rest=0.2)  # not inside the first range


def _puma():
    sc = load_scene("puma560")
    traj = sc.trajectories["pick_and_place"]
    v = Verifier(sc, robot=traj.robot_name)
    return sc, traj, v


def test_speed_dependent_stopping_distance_violation_is_worded_as_such():
    sc, traj, v = _puma()
    plain = v.verify(traj)
    assert plain.status is VerificationStatus.SAFE  # as planned the arm never touches
    r = v.verify(Subdivided(traj, 8), stopping_distance=hermes_table(plain.details.max_speed))
    assert r.status is VerificationStatus.COLLISION  # Hermes's rule: closer than the stopping distance
    c = r.first_collision
    assert c.kind is CollisionKind.STOPPING_DISTANCE
    assert c.time > 0.0  # at rest at t = 0: no stopping distance there
    lever = v.model.lever  # the named link is the one that moves; the still base is the obstacle
    assert lever[v.model._part_index[c.a]].any() and not lever[v.model._part_index[c.b]].any()
    assert c.link == c.a.split("/", 1)[1] and c.obstacle == c.b
    assert 0.0 < c.distance < c.stopping_distance <= HERMES_MAX_STOPPING_DISTANCE + 1e-12
    assert c.describe() == f"within stopping distance {c.stopping_distance * 1e3:.0f} mm: {c.distance * 1e3:.1f} mm"
    assert "UNSAFE: within the stopping distance, no contact" in r.summary() and r.verdict() == "unsafe (stopping distance)"
    assert "first stopping-distance violation" in r.summary()
    doc = json.loads(r.to_json())
    assert doc["first_collision"]["kind"] == "stopping distance"
    assert doc["first_collision"]["stopping_distance"] == pytest.approx(c.stopping_distance)


def test_a_constant_stopping_distance_applies_from_t0_and_a_contact_is_a_contact():
    sc, traj, v = _puma()
    r = v.verify(traj, stopping_distance=0.1)
    assert r.first_collision.kind is CollisionKind.STOPPING_DISTANCE and r.first_collision.time == 0.0
    assert r.first_collision.stopping_distance == 0.1
    hermes = load_scene("hermes")
    t = hermes.trajectories["stow_misaligned"]
    hit = Verifier(hermes, robot=t.robot_name).verify(t)
    assert hit.first_collision.kind is CollisionKind.CONTACT
    assert hit.first_collision.describe().startswith("contact (distance")
    assert "first contact at" in hit.summary()


def test_demo_reports_every_trajectory_with_its_words(tmp_path):
    res = CliRunner().invoke(main, ["demo", "--scene", "puma560", "--scene", "hermes", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    rows = {}
    for line in res.output.splitlines():
        cells = [c.strip() for c in line.split("│")]
        if len(cells) > 5 and cells[1] in ("puma560", "hermes"):
            rows[(cells[2], cells[3])] = cells[4:6]
    assert rows[("pick_and_place", "0 mm")][0] == "SAFE"
    verdict, first = rows[("pick_and_place", "Hermes ≤ 100 mm")]
    assert verdict == "UNSAFE (stopping distance)" and first.startswith("within stopping distance")
    verdict, first = rows[("stow_misaligned", "0 mm")]
    assert verdict == "COLLISION" and first.startswith("contact (distance")
    reports = sorted(p.name for p in tmp_path.glob("*.json"))
    assert "puma560__pick_and_place__hermes100mm.json" in reports and len(reports) == 8
    doc = json.loads((tmp_path / "puma560__pick_and_place__hermes100mm.json").read_text())
    assert doc["status"] == "collision" and doc["first_collision"]["kind"] == "stopping distance"


def test_demo_keeps_one_report_per_stopping_distance(tmp_path):
    """0 and 0.4 mm were both "sd0mm": the second verification's report and plot overwrote the first's (and 0.6 /
    1.4 mm both "sd1mm"); a value given twice is verified once."""
    args = ["demo", "--scene", "puma560", "--out", str(tmp_path)]
    for sd in ("0", "0.0004", "0.0004", "0.0006", "0.0014"):
        args += ["--stopping-distance", sd]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    stems = sorted(p.stem for p in tmp_path.glob("puma560__pick_and_place__*.json"))
    assert stems == sorted(f"puma560__pick_and_place__sd{v}mm" for v in ("0", "0.4", "0.6", "1.4"))
    assert sorted(p.stem for p in tmp_path.glob("puma560__pick_and_place__*.png")) == stems
    labels = [c.strip() for line in res.output.splitlines() if "pick_and_place" in line
              for c in line.split("│")[3:4]]
    assert labels == ["0 mm", "0.4 mm", "0.6 mm", "1.4 mm"]


def test_demo_names_stopping_distances_alike_to_6_digits_by_their_exact_value():
    from armguard.cli._demo import _mode_names

    names = _mode_names([("fixed", 0.1), ("fixed", 0.1000000001), ("hermes", 0.1)])
    assert names == [("0.1 m", "sd0.1m"), ("0.1000000001 m", "sd0.1000000001m"), ("Hermes ≤ 100 mm", "hermes100mm")]


def test_verify_cli_speed_dependent():
    res = CliRunner().invoke(main, ["verify", "puma560", "pick_and_place", "--stopping-distance", "0.1", "--speed-dependent"])
    assert res.exit_code == 1 and "UNSAFE (stopping distance)" in res.output
    assert "[link-link]" in res.output  # the summary is printed as text, not as rich markup
    bad = CliRunner().invoke(main, ["verify", "puma560", "pick_and_place", "--speed-dependent"])
    assert bad.exit_code == 2 and "--stopping-distance > 0" in bad.output


def test_the_clearance_column_brackets_the_least_clearance_up_to_the_first_collision():
    """The column is the verification's own interval [proven lower bound, least evaluated]: a dense sampling
    of the moving arm's clearance up to the first collision lies inside it (a sampled figure over the whole
    trajectory counted the depths past the contact)."""
    from armguard.cli._demo import clearance_text
    from armguard.detect import Detector

    for scene, name in (("hermes", "unstow"), ("hermes", "stow_misaligned"), ("rover", "place_instrument")):
        sc = load_scene(scene)
        traj = sc.trajectories[name]
        r = Verifier(sc, robot=traj.robot_name).verify(traj)
        end = r.first_collision.time if r.first_collision is not None else traj.duration
        base = sc.default_q()
        rows = []
        for q in np.asarray(traj.at(np.linspace(0.0, end, 2000))):
            base[traj.robot_name] = q
            rows.append(sc.flat_q(base))
        sampled = float(np.min(Detector(sc, 0.05, active=traj.robot_name).check_many(np.array(rows)).min_distance))
        assert r.min_clearance_lower_bound - 1e-9 <= sampled <= r.min_clearance + 1e-9, (scene, name)
        text = clearance_text(r)
        assert text.startswith(f"in [{r.min_clearance_lower_bound * 1e3:.1f}, {r.min_clearance * 1e3:.1f}] mm")
        assert ("before t = " in text) == (r.first_collision is not None)


def test_demo_checks_its_files_before_the_work_and_writes_them_as_one_set(tmp_path, monkeypatch):
    """A folder at one report's name was found after the verifications (the verdicts not printed, the previous run's
    files mixed with the new ones); a full disk now leaves the previous set whole, and the verdicts are printed."""
    import armguard._io as io_mod
    import armguard.cli._demo as demo

    args = ["demo", "--scene", "gmf_s480", "--stopping-distance", "0", "--out", str(tmp_path)]
    assert CliRunner().invoke(main, args).exit_code == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    victim = sorted(before)[-1]
    (tmp_path / victim).unlink()
    (tmp_path / victim).mkdir()

    def no_work(*a, **k):
        raise AssertionError("verified before the outputs were checked")

    monkeypatch.setattr(demo, "_demo_rows", no_work)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 3 and f"{victim}: it exists and is a folder" in res.output, res.output
    (tmp_path / victim).rmdir()
    (tmp_path / victim).write_bytes(before[victim])
    monkeypatch.undo()
    n = [0]

    def full_after_one(fd, blob, real=io_mod._write_all):
        n[0] += 1
        if n[0] > 1:
            raise OSError(28, "No space left on device")
        real(fd, blob)

    monkeypatch.setattr(io_mod, "_write_all", full_after_one)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 3 and "No space left" in res.output and "│ gmf_s480 │" in res.output, res.output
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # the previous set, whole
