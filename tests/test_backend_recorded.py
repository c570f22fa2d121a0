"""Which backend gave the distances is on record: ``check --json`` and the verification report
(``details.backend``, its summary and JSON); they said "the detector" alone."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main
from armguard.kinematics import Trajectory


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_check_json_and_the_verification_report_name_the_backend(backend):
    r = CliRunner().invoke(main, ["-q", "--backend", backend, "check", "puma560", "--json"])
    assert json.loads(r.output)["backend"] == backend, r.output
    m = armguard.load_model("puma560")
    q0 = m.scene.home("puma560")
    traj = Trajectory.joint_interpolated(m.scene.robots["puma560"], np.array([q0, q0 + 0.05]))
    rep = armguard.verify(m, traj, backend=backend)
    assert rep.details.source == "detector" and rep.details.backend == backend
    assert f"distances from the detector ({backend} backend)" in rep.summary()
    assert json.loads(rep.to_json())["details"]["backend"] == backend
