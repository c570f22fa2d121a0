"""What an operator reads: reports and messages that named the wrong thing or too little.

A trajectory verified as :class:`Subdivided` (``armguard verify --speed-dependent``) reports segment numbers and
the name of the trajectory as given: puma560's pick_and_place violated its stopping distance at t = 0.156 s, in
its segment 0 (knots 0, 1.247 s, ...), and the report said "segment 1" (the second eighth of segment 0) and named
the trajectory "trajectory"."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main
from armguard.verify import Subdivided


@pytest.fixture(scope="module")
def puma():
    return armguard.load_scene("puma560")


def test_a_subdivided_trajectorys_collision_names_the_given_segment_and_trajectory(puma):
    traj = puma.trajectories["pick_and_place"]
    whole = armguard.verify(puma, traj, stopping_distance=0.1)
    pieces = armguard.verify(puma, Subdivided(traj, 8), stopping_distance=0.1)
    c = pieces.first_collision
    knots = np.asarray(traj.times)
    assert c is not None and knots[c.segment] <= c.time <= knots[c.segment + 1], (c.segment, c.time, knots)
    assert c.segment == whole.first_collision.segment == 0
    assert pieces.trajectory == whole.trajectory == "pick_and_place"


def test_verify_speed_dependent_prints_the_given_segment(tmp_path, puma):
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", "pick_and_place", "--stopping-distance", "0.1",
                                  "--speed-dependent", "--report", str(tmp_path / "sd.json")])
    assert r.exit_code == 1 and "(segment 0)" in r.output, r.output
    rep = json.loads((tmp_path / "sd.json").read_text())
    text = json.dumps(rep)
    assert '"segment": 0' in text and '"segment": 1' not in text


@pytest.mark.parametrize("d, text", [(2e-6, "2 µm"), (-4.5e-6, "-4.5 µm"), (0.0, "0.00 mm"), (0.01234, "12.34 mm"),
                                     (-0.0221, "-22.10 mm"), (1e-5, "0.01 mm")])
def test_a_clearance_under_a_hundredth_of_a_millimetre_prints_in_micrometres(d, text):
    """A SAFE verdict 2 µm clear printed "minimum clearance 0.00 mm" beside it."""
    from armguard.verify._report import _mm

    assert _mm(d) == text


def test_held_joints_are_not_called_home_when_q_others_holds_them():
    """A Verifier's ``q_others`` may hold the moving robot's own joints left out of an edge (a gripper open):
    the summary called the value "home" (0.04 where panda's home is 0.001)."""
    from armguard.verify import Verifier

    m = armguard.load_model("panda")
    q = m.scene_q(m.neutral())
    q2 = q.copy()
    q2[7] = 0.04
    e = Verifier(m.scene, q_others={"panda": q2}).check_edges(q[:7], q[:7] + 0.05, joints="arm")
    assert e.held == {"panda_finger_joint1": 0.04}
    assert "held at home" not in e.summary() and "held still (the Verifier's home, or its q_others): " \
        "panda_finger_joint1 = 0.04" in e.summary()


def test_a_joint_limit_refusal_shows_the_excess_and_names_float32_rounding():
    """panda's joint 1 at its upper limit, given as float32 (5e-9 rad past it): the message printed the value and
    the limit as the same 2.8973."""
    m = armguard.load_model("panda")
    c = armguard.checker(m)
    q = m.neutral()
    q[0] = m.pin_model.upperPositionLimit[0]
    assert not c.collides(q[None])[0]  # float64 at the limit: answered
    with pytest.raises(armguard.JointLimitError) as ei:
        c.collides(q[None].astype(np.float32))
    msg = str(ei.value)
    assert "= 2.8973000049591064 is outside its limits [-2.8973, 2.8973]: 4.959e-09 above the upper (as small as " \
           "float32's rounding: clip a float32 configuration to the limits, or give it as float64)" in msg, msg
    q[0] = 3.0
    with pytest.raises(armguard.JointLimitError, match=r"= 3 is outside its limits \[-2.8973, 2.8973\]: 0.1027 above the "
                                                       r"upper \(allowance"):
        c.collides(q[None])


def test_verify_report_dash_writes_the_json_to_stdout_and_the_summary_to_stderr(tmp_path, monkeypatch):
    """``--report -`` wrote a file named '-' and printed "report: -"."""
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", "pick_and_place", "--report", "-"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["status"] == "safe" and doc["trajectory"] == "pick_and_place"
    assert "verdict: SAFE" in r.stderr and "report:" not in r.stderr
    assert not (tmp_path / "-").exists()


def test_a_q_mapping_by_joint_names_is_told_the_mappings_form():
    """``det.check({"panda/panda_joint1": ..., ...})`` said only "q names unknown robots [...]"."""
    m = armguard.load_model("panda")
    det = armguard.Detector(m)
    qs = m.scene_q(m.neutral())
    with pytest.raises(armguard.SceneError, match=r"robots are \['panda'\] \(a mapping goes robot -> that robot's joint "
                                                  r"values; these are joint names"):
        det.check(dict(zip(m.scene.joint_names, qs)))
    with pytest.raises(armguard.SceneError, match=r"q names unknown robots \['pand'\]; robots are \['panda'\]$"):
        det.check({"pand": qs})
    assert det.check({"panda": qs}).status.value in ("clear", "warning")


def test_the_check_tables_payload_row_names_the_payload():
    """hermes, the payload 0.71 m from the tail: the row read "hera/link6 | tail" as if the link were."""
    r = CliRunner().invoke(main, ["-q", "check", "hermes", "--q", "3.30,0.0618,-0.0309,0,0,0"])
    row = next(line for line in r.output.splitlines() if line.strip("│ ").startswith("payload"))
    assert "payload (on hera/link6)" in row and "tail" in row, r.output


def test_an_interrupted_map_build_says_where_the_finished_part_is_and_how_to_go_on(tmp_path, monkeypatch):
    """Ctrl-C in ``cspace build`` printed "interrupted" alone, though the journal OUT.partial was kept and the
    same command resumes from it."""
    from armguard.cspace import ForbiddenMap

    out = tmp_path / "maps" / "h.agmap"

    def interrupted(*args, **kwargs):
        out.parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "maps" / "h.agmap.partial").write_bytes(b"journal")
        raise KeyboardInterrupt

    monkeypatch.setattr(ForbiddenMap, "build", interrupted)
    r = CliRunner().invoke(main, ["-q", "cspace", "build", "hermes", "--out", str(out)])
    assert r.exit_code == 130 and not out.exists(), r.output
    text = " ".join(r.stderr.split())
    assert f"{out} not written; the finished substructures are kept in {out}.partial: the same command resumes" in text
    r = CliRunner().invoke(main, ["-q", "cspace", "build", "hermes", "--out", str(out), "--no-resume"])
    assert "the same command without --no-resume resumes from them" in " ".join(r.stderr.split())


def test_an_interrupted_verification_of_several_trajectories_says_how_far_it_got(tmp_path, monkeypatch):
    import armguard.verify as v

    def interrupted(scene, items, *, progress=None, **kwargs):
        progress(1, len(items))
        raise KeyboardInterrupt

    monkeypatch.setattr(v, "verify_many", interrupted)
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", "pick_and_place", "pick_and_place", "--report",
                                  str(tmp_path / "r.json")])
    assert r.exit_code == 130 and not (tmp_path / "r.json").exists(), r.output
    assert "1 of 2 trajectories verified when interrupted; no report written, and no verdict" in r.stderr


def test_a_subdivided_trajectorys_waypoint_outside_its_limits_is_named_as_given(puma):
    """Waypoint 1 outside its limits: verified as Subdivided(8) the error named "waypoints[3]" and an
    interpolated value (the fourth knot of the pieces)."""
    from armguard.kinematics import Trajectory

    t = puma.trajectories["pick_and_place"]
    W = np.array(t.waypoints, dtype=float)
    W[1, 1] = 10.0
    bad = Trajectory(t.robot_name, t.joint_names, t.times, W)
    msgs = []
    for traj in (bad, Subdivided(bad, 8)):
        with pytest.raises(armguard.VerificationError) as ei:
            armguard.verify(puma, traj)
        msgs.append(str(ei.value))
    assert msgs[0] == msgs[1] and msgs[0].startswith("trajectory waypoints[1]: ") and "= 10 is outside" in msgs[0], msgs
