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
