"""``armguard check``: JSON output matches the library report; bad input is a clean error."""

from __future__ import annotations

import json

from click.testing import CliRunner

from armguard.cli import main
from armguard.detect import Detector
from armguard.scene import load_scene


def test_check_json_matches_library():
    res = CliRunner().invoke(main, ["check", "ranger", "--json", "--threshold", "0.2"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    scene = load_scene("ranger")
    rep = Detector(scene, threshold=0.2).check(scene.default_q())
    assert data["status"] == rep.status.value
    assert set(data["by_category"]) == set(rep.by_category)
    for cat, r in rep.by_category.items():
        assert abs(data["by_category"][cat]["distance"] - r.distance) <= 1e-12


def test_check_table_shows_status():
    from armguard import Detector, load_scene

    res = CliRunner().invoke(main, ["check", "puma560"])
    assert res.exit_code == 0, res.output
    scene = load_scene("puma560")  # the command's defaults: threshold 0.05 m, the scene's default q
    det = Detector(scene, threshold=0.05)
    n = det.check(scene.flat_q(scene.default_q())).n_evaluated
    assert n > 0
    assert "status: CLEAR" in res.output and f"{n} of {det.n_pairs} pairs evaluated" in res.output


def test_check_bad_q_is_an_error():
    res = CliRunner().invoke(main, ["check", "puma560", "--q", "1,2"])
    assert res.exit_code == 2
    assert "q" in res.output
