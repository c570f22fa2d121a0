"""An output is never written over a file the command read: ``verify t.yaml --report t.yaml`` replaced the
trajectory with its report, ``program export p.yaml --out p.yaml`` the program with Python, ``program run
--save cell.yaml`` the cell with a run record, ``cspace build m.yaml --out m.yaml`` the model with a map, the
console's task menu the cell with a program.  Each is refused before the work (exit 3), the input unchanged."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from armguard import OutputError
from armguard.cli import ExitCode, main

ROOT = Path(__file__).resolve().parents[1]
TRAJ = """format: armguard.trajectory
version: 1
robot: hera
joint_names: [shoulder_yaw]
times: [0.0, 2.0]
waypoints:
  - [0.0]
  - [0.1]
"""


@pytest.fixture()
def folder(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples" / "workmate", tmp_path, dirs_exist_ok=True)
    (tmp_path / "t.yaml").write_text(TRAJ)
    np.savez(tmp_path / "e.npz", Q0=np.zeros(6), Q1=np.full(6, 0.1))
    monkeypatch.chdir(tmp_path)
    return tmp_path


CASES = [
    (["verify", "hermes", "t.yaml", "--report", "t.yaml"], "t.yaml"),
    (["verify", "hermes", "./t.yaml", "--report", "t.yaml"], "t.yaml"),  # another spelling of the same file
    (["edges", "hermes", "e.npz", "--out", "e.npz"], "e.npz"),
    (["program", "export", "stack.yaml", "--out", "stack.yaml"], "stack.yaml"),
    (["program", "run", "stack.yaml", "--save", "cell.yaml"], "cell.yaml"),  # the cell the program names
    (["program", "run", "stack.yaml", "--save", "calibration.yaml"], "calibration.yaml"),  # the cell's calibration
    (["program", "calibrate", "cell.yaml", "--out", "cell.yaml"], "cell.yaml"),
]


@pytest.mark.parametrize("args,victim", CASES, ids=[" ".join(a) for a, _ in CASES])
def test_an_output_over_an_input_is_refused_before_the_work(folder, args, victim):
    before = (folder / victim).read_bytes()
    res = CliRunner().invoke(main, args)
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "it is the input file" in res.output and "name another file" in res.output
    assert (folder / victim).read_bytes() == before


def test_verify_refuses_one_file_for_report_and_plot(folder):
    """One trajectory: its plot is --plot itself; several: FILE_<trajectory>, which the report may name too (the
    report was lost, exit 0); --report r.png --plot r.png with several trajectories writes three files: fine."""
    res = CliRunner().invoke(main, ["verify", "hermes", "t.yaml", "--report", "r.png", "--plot", "r.png"])
    assert res.exit_code == ExitCode.USAGE and "--report and --plot both write r.png" in res.output, res.output
    assert not (folder / "r.png").exists()
    res = CliRunner().invoke(main, ["verify", "hermes", "unstow", "payload_sweep", "--report", "p_unstow.png",
                                    "--plot", "p.png"])
    assert res.exit_code == ExitCode.USAGE and "both write p_unstow.png" in res.output, res.output
    res = CliRunner().invoke(main, ["verify", "hermes", "unstow", "payload_sweep", "--report", "q.png", "--plot", "q.png"])
    assert res.exit_code == ExitCode.OK, res.output
    assert {p.name for p in folder.glob("q*.png")} == {"q.png", "q_unstow.png", "q_payload_sweep.png"}


def test_a_map_over_its_model_file_and_a_program_over_its_cell_are_refused(folder):
    import math

    from armguard.console._tasks import TaskComposer
    from armguard.cspace import ForbiddenMap
    from armguard.models import builtin_path
    from armguard.program import load_cell

    shutil.copy(builtin_path("hermes"), folder / "h.yaml")
    before = (folder / "h.yaml").read_bytes()
    with pytest.raises(OutputError, match="it is the input file"):
        ForbiddenMap.build("h.yaml", out="h.yaml", resolution=math.radians(30), stopping_distance=0.1, max_depth=0)
    assert (folder / "h.yaml").read_bytes() == before
    tc = TaskComposer(load_cell("cell.yaml"), cell_ref="cell.yaml")
    tc.add("FIND", object="cylinder_a")
    cell_before = (folder / "cell.yaml").read_bytes()
    with pytest.raises(OutputError, match="it is the input file"):
        tc.save(folder / "cell.yaml")
    assert (folder / "cell.yaml").read_bytes() == cell_before
    assert tc.save(folder / "menu.yaml").is_file()


def _no_work(*args, **kwargs):
    raise AssertionError("the work ran before its outputs were checked")


def test_every_planned_plot_is_checked_before_the_work(tmp_path, monkeypatch):
    """``verify A B --plot p.png`` writes ``p_A.png`` and ``p_B.png``; ``compare --out D`` its plots: a folder at one
    of those names was found after the whole verification or comparison (its verdicts lost)."""
    import armguard.harness._run as run
    import armguard.verify as verify

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(verify, "verify_many", _no_work)
    (tmp_path / "v" / "p_payload_sweep.png").mkdir(parents=True)
    res = CliRunner().invoke(main, ["verify", "hermes", "unstow", "payload_sweep", "--plot", "v/p.png"])
    assert res.exit_code == ExitCode.INPUT and "p_payload_sweep.png: it exists and is a folder" in res.output, res.output
    monkeypatch.setattr(run, "build_configs", _no_work)
    for name in ("timing.png", "scatter_analytic_coal.png"):
        (tmp_path / "c" / name).mkdir(parents=True)
        res = CliRunner().invoke(main, ["compare", "hermes", "--backends", "analytic,coal", "--configs", "5", "--out", "c"])
        assert res.exit_code == ExitCode.INPUT and f"{name}: it exists and is a folder" in res.output, res.output
        (tmp_path / "c" / name).rmdir()
