"""``bench sweep`` reads a robot's row from ``measure`` in a child process: a changed error type or a
renamed field would stop the benchmark after every test had passed.  Its file list takes every URDF
of example-robot-data and only pybullet_data's robots."""

from __future__ import annotations

import pytest

from bench.sweep import _files, measure

from test_srdf import arm_urdf


def test_a_robot_row_has_its_agreement_and_timings(tmp_path):
    f = tmp_path / "arm.urdf"
    f.write_text(arm_urdf())
    r = measure(str(f), 3)
    assert r["nq"] == 3 and r["pairs"] > 0 and r["disagree"] == 0 and r["max_dd"] <= 1e-9
    assert r["us_a"] > 0 and r["us_c"] > 0 and r["load_s"] > 0


def test_a_fault_is_the_first_line_of_the_error_naming_the_file(tmp_path):
    f = tmp_path / "bad.urdf"
    f.write_text('<robot name="r"><link name="a"/><joint name="j" type="revolute"><parent link="a"/>'
                 '<child link="b"/></joint></robot>')
    r = measure(str(f), 3)
    assert set(r) == {"fault"} and r["fault"].startswith(str(f)) and "\n" not in r["fault"]


def test_the_file_list():
    files = _files()
    erd = [p for pkg, p in files if pkg == "example-robot-data"]
    pyb = [p for pkg, p in files if pkg == "pybullet_data"]
    if not erd:
        pytest.skip("example-robot-data is not installed")
    assert len(erd) >= 60 and any(p.endswith("tiago_dual.urdf") for p in erd)
    assert not any("random_urdfs" in p for p in pyb)
    if pyb:
        assert any(p.endswith("kuka_iiwa/model.urdf") for p in pyb) and not any(p.endswith("plane.urdf") for p in pyb)
