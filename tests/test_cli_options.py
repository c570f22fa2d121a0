"""Numbers a command cannot use are refused where click reads them (exit status 2, the option named),
not deep in the library as an internal error (``--frequency 0`` was a ZeroDivisionError, exit 4),
nor used as given (``--configs 0`` printed "0 configurations - agree"; ``--max-evaluations 0`` ran
258 evaluations; ``--workers 0`` was accepted by one command and refused by another)."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from armguard.cli import ExitCode, main
from armguard.cli._params import LENGTH, POSITIVE

BAD = [
    (["compare", "puma560", "--frequency", "0"], "--frequency"),
    (["compare", "puma560", "--frequency", "nan"], "--frequency"),
    (["compare", "ur5", "--configs", "-3"], "--configs"),
    (["compare", "ur5", "--configs", "0"], "--configs"),
    (["compare", "ur5", "--worst", "-1"], "--worst"),
    (["compare", "ur5", "--workers", "0"], "--workers"),
    (["compare", "ur5", "--pair", "a,b"], "--pair"),
    (["check-urdf", "ur5", "--configs", "0"], "--configs"),
    (["check", "hermes", "--threshold", "nan"], "--threshold"),
    (["check", "hermes", "--budget-us", "-1"], "--budget-us"),
    (["check", "hermes", "--stopping-distance", "inf"], "--stopping-distance"),
    (["verify", "puma560", "pick_and_place", "--workers", "0"], "--workers"),
    (["verify", "puma560", "pick_and_place", "--frequency", "-2"], "--frequency"),
    (["verify", "puma560", "pick_and_place", "--joint-step", "0"], "--joint-step"),
    (["srdf", "puma560", "--out", "x.srdf", "--max-evaluations", "0"], "--max-evaluations"),
    (["srdf", "puma560", "--out", "x.srdf", "--margin", "nan"], "--margin"),
    (["check-srdf", "puma560", "--workers", "0"], "--workers"),
    (["cspace", "build", "hermes", "--out", "x.agmap", "--max-depth", "-1"], "--max-depth"),
    (["demo", "--stopping-distance", "-0.1"], "--stopping-distance"),
]


@pytest.mark.parametrize("args,option", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_a_number_the_command_cannot_use_is_a_usage_error(args, option, tmp_path):
    r = CliRunner().invoke(main, args)
    assert r.exit_code == ExitCode.USAGE, r.output
    assert option in r.output and "Traceback" not in r.output, r.output


def test_finite_types():
    assert LENGTH.convert("0", None, None) == 0.0 and POSITIVE.convert("2.5", None, None) == 2.5
    for t, value in ((LENGTH, "-1e-9"), (LENGTH, "nan"), (LENGTH, "-inf"), (POSITIVE, "0"), (POSITIVE, "abc")):
        with pytest.raises(Exception) as e:
            t.convert(value, None, None)
        assert type(e.value).__name__ == "BadParameter", (value, e.value)


def test_demo_refuses_a_scene_with_nothing_to_verify(tmp_path):
    """``demo --scene ur5`` (a public robot: no canned trajectories) printed an empty table and "reports and
    plots in out/" with the folder empty, exit 0."""
    r = CliRunner().invoke(main, ["demo", "--scene", "ur5", "--out", str(tmp_path / "d")])
    assert r.exit_code == ExitCode.USAGE and "'ur5' has no canned trajectory" in r.output, r.output
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("args,said", [
    (["--method", "sampled", "--frequency", "0.1", "--joint-step", "0.05"], "not both"),
    (["--frequency", "20"], "--frequency goes with --method sampled"),
    (["--joint-step", "0.05"], "--joint-step goes with --method sampled"),
])
def test_verify_refuses_a_sampling_option_it_would_drop(args, said):
    """``--method sampled --frequency 0.1 --joint-step 0.05`` checked at 0.1 Hz alone (2 configurations) and
    said SAFE past a collision the joint step finds; with the certified method either option was ignored."""
    r = CliRunner().invoke(main, ["verify", "puma560", "pick_and_place", *args])
    assert r.exit_code == ExitCode.USAGE and said in r.output, r.output


def test_verify_in_python_refuses_them_too():
    import armguard
    from armguard import VerificationError

    sc = armguard.load_scene("puma560")
    traj = sc.trajectories["pick_and_place"]
    for kwargs, said in ((dict(method="sampled", frequency=0.1, joint_step=0.05), "not both"),
                         (dict(frequency=20.0), "frequency: sampled mode's option"),
                         (dict(joint_step=0.05), "joint_step: sampled mode's option")):
        with pytest.raises(VerificationError, match=said):
            armguard.verify(sc, traj, **kwargs)
    r = armguard.verify(sc, traj, method="sampled", joint_step=0.05)
    assert r.details.method == "sampled" and r.details.joint_step == 0.05 and r.details.frequency is None


def test_a_sampled_safe_verdict_says_it_is_unproven_between_samples():
    import armguard

    sc = armguard.load_scene("puma560")
    traj = sc.trajectories["pick_and_place"]
    sampled, certified = armguard.verify(sc, traj, method="sampled"), armguard.verify(sc, traj)
    assert sampled.status.value == certified.status.value == "safe"
    assert "verdict: SAFE at the samples (sampled: not proven between them" in sampled.summary()
    assert "verdict: SAFE\n" in certified.summary() + "\n" and "at the samples" not in certified.summary()


def _path_params(group=main, prefix=()):
    import click

    for name, cmd in group.commands.items():
        if isinstance(cmd, click.Group):
            yield from _path_params(cmd, (*prefix, name))
        for p in cmd.params:
            if isinstance(p.type, click.Path):
                yield " ".join((*prefix, name, p.name)), p


PATH_PARAMS = list(_path_params())


@pytest.mark.parametrize("where,param", PATH_PARAMS, ids=[w for w, _ in PATH_PARAMS])
def test_every_path_refuses_an_empty_one_and_a_dash_it_would_write_as_a_file(where, param):
    import click

    from armguard.cli._params import FilePath

    assert isinstance(param.type, FilePath), f"{where}: a plain click.Path lets '' through as 'not given'"
    with pytest.raises(click.BadParameter, match="empty path"):
        param.type.convert("", param, None)
    if where == "verify report_path":  # '-': the JSON report on standard output
        assert param.type.convert("-", param, None) == "-"
    else:
        with pytest.raises(click.BadParameter, match="name a file"):
            param.type.convert("-", param, None)
    assert param.type.convert("some/file.x", param, None) == "some/file.x"


def test_calibrate_with_an_empty_out_writes_nothing(tmp_path):
    """``--out ''`` was read as "not given": the cell's own calibration file was overwritten."""
    import shutil
    from pathlib import Path

    src = Path(__file__).resolve().parents[1] / "examples" / "workmate"
    for f in src.iterdir():
        if f.is_file():
            shutil.copy(f, tmp_path / f.name)
    before = {f.name: f.read_bytes() for f in tmp_path.iterdir()}
    for out in ("", "   "):
        res = CliRunner().invoke(main, ["program", "calibrate", str(tmp_path / "cell.yaml"), "--out", out])
        assert res.exit_code == ExitCode.USAGE, res.output
        assert "empty path" in res.output
    assert {f.name: f.read_bytes() for f in tmp_path.iterdir()} == before


def test_a_plot_to_a_dash_is_refused_not_a_file_named_dash(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, ["verify", "hermes", "all", "--plot", "-"])
    assert res.exit_code == ExitCode.USAGE and "--plot" in res.output
    assert not (tmp_path / "-").exists()


@pytest.mark.parametrize("args", [["check", "hermes", "--threshold", "1e300"],
                                  ["check", "hermes", "--stopping-distance", "2e9"],
                                  ["verify", "hermes", "unstow", "--stopping-distance", "1e300"]])
def test_a_length_beyond_a_scene_files_bound_is_a_usage_error(args):
    """``verify --stopping-distance 1e300`` printed the stopping distance as 300 digits of millimetres."""
    res = CliRunner().invoke(main, args)
    assert res.exit_code == ExitCode.USAGE and "must be <= 1e+09" in res.output, res.output


def test_the_library_bounds_those_lengths_too():
    import armguard
    from armguard import DetectionError, VerificationError
    from armguard.verify._stopping import check_stopping_distance

    with pytest.raises(DetectionError, match=r"threshold: expected a finite number in \[0, 1e\+09\]"):
        armguard.Detector(armguard.load_scene("gmf_s480"), threshold=1e300)
    with pytest.raises(VerificationError, match="stopping_distance"):
        check_stopping_distance(1e10)
    assert check_stopping_distance(1e9) == 1e9


def test_compare_lists_as_many_worst_configurations_as_asked():
    """``--worst 10`` printed 3 distance entries (a fixed cap), compare.json held 10."""
    import re

    for n in (1, 5):
        res = CliRunner().invoke(main, ["compare", "hermes", "--configs", "60", "--worst", str(n), "--no-plots"])
        assert res.exit_code == ExitCode.OK, res.output
        assert len(re.findall(r"(?m)^  distance #", res.output)) == n, res.output


@pytest.mark.parametrize("args,said", [
    (["srdf", "puma560", "--out", "x.srdf", "--samples", "100"], "--samples goes with --method sampled"),
    (["srdf", "puma560", "--out", "x.srdf", "--method", "sampled", "--max-evaluations", "5"],
     "--max-evaluations goes with --method certified"),
    (["srdf", "puma560", "--out", "x.srdf", "--method", "sampled", "--workers", "2"], "--workers goes with --method certified"),
    (["compare", "hermes", "--q", "0,0,0,0,0,0", "--configs", "7"], "--configs belongs to a comparison over many"),
    (["compare", "hermes", "--q", "0,0,0,0,0,0", "--seed", "3"], "--seed belongs to a comparison over many"),
])
def test_an_option_that_does_not_apply_is_a_usage_error(args, said, tmp_path, monkeypatch):
    """``srdf --method certified --samples 100``, ``compare --q ... --configs 7``: accepted and silently ignored."""
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == ExitCode.USAGE and said in res.output, res.output
    assert not (tmp_path / "x.srdf").exists()


def test_srdf_update_judges_the_options_by_the_files_method(tmp_path, monkeypatch):
    """``--update`` of a sampled SRDF runs sampled (the file's method): its --samples was refused as certified's,
    its --workers accepted and ignored."""
    monkeypatch.chdir(tmp_path)
    run = CliRunner().invoke
    assert run(main, ["srdf", "gmf_s480", "--method", "sampled", "--samples", "200", "--out", "p.srdf"]).exit_code == 0
    res = run(main, ["srdf", "gmf_s480", "--out", "p.srdf", "--update", "--samples", "300"])
    assert res.exit_code == 0 and "method sampled" in res.output, res.output
    res = run(main, ["srdf", "gmf_s480", "--out", "p.srdf", "--update", "--workers", "2"])
    assert res.exit_code == ExitCode.USAGE and "--workers goes with --method certified" in res.output, res.output


def test_a_time_budget_is_not_bounded_as_a_length():
    """``check --budget-us 2e9`` (2000 s) was refused by the 1e9 m bound of lengths."""
    res = CliRunner().invoke(main, ["check", "puma560", "--budget-us", "2e9"])
    assert res.exit_code == ExitCode.OK and "CLEAR" in res.output, res.output
