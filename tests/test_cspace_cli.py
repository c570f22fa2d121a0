"""``armguard cspace build | info | plot`` on a coarse map."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from armguard.cli import main


def test_build_info_plot(tmp_path):
    out = tmp_path / "maps" / "hermes.agmap"
    runner = CliRunner()
    r = runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "12deg", "--max-depth", "1",
                             "--stopping-distance", "0.1", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert out.exists() and "bytes" in r.output
    r = runner.invoke(main, ["cspace", "info", str(out), "--samples", "2000", "--json"])
    assert r.exit_code == 0, r.output
    info = json.loads(r.output)
    assert info["size_bytes"] == out.stat().st_size and info["n_cells"] == 30 * 20
    assert info["exactness"]["allowed_but_colliding"] == 0 and info["exactness"]["status"] == "conservative"
    r = runner.invoke(main, ["cspace", "info", str(out), "--samples", "0"])
    assert r.exit_code == 0 and "substructures" in r.output
    png = tmp_path / "slice.png"
    r = runner.invoke(main, ["cspace", "plot", str(out), "--q2", "30", "--q", "180,30,-20", "--out", str(png)])
    assert r.exit_code == 0, r.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_other_model_is_refused(tmp_path):
    out = tmp_path / "h.agmap"
    runner = CliRunner()
    assert runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                                "--out", str(out)]).exit_code == 0
    r = runner.invoke(main, ["cspace", "info", str(out), "--model", "ranger", "--samples", "0"])
    assert r.exit_code == 3 and "built for other model files" in r.output  # ExitCode.INPUT


def test_info_exits_1_when_the_map_allows_a_colliding_configuration(tmp_path, monkeypatch):
    """``cspace info`` says "unsafe" (exit 1) when its own sampled check finds configurations the map allows
    that collide -- a map that is not conservative is not a success (it exited 0 before)."""
    import dataclasses

    import armguard.cspace as cspace

    out = tmp_path / "h.agmap"
    runner = CliRunner()
    assert runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                                "--out", str(out)]).exit_code == 0
    real = cspace.check_exactness

    def leaky(fmap, model=None, n=10_000):  # the real check, then three configurations it let through
        rep = real(fmap, model, n=n)
        return dataclasses.replace(rep, allowed_but_colliding=3)

    monkeypatch.setattr(cspace, "check_exactness", leaky)
    for extra in ([], ["--json"]):
        r = runner.invoke(main, ["cspace", "info", str(out), "--samples", "200", *extra])
        assert r.exit_code == 1, (extra, r.output)
        assert ("3 allowed but colliding" in r.output) if not extra else json.loads(r.output)["exactness"]["allowed_but_colliding"] == 3
    r = runner.invoke(main, ["cspace", "info", str(out), "--samples", "0"])
    assert r.exit_code == 0


def test_plot_refuses_what_it_cannot_mark_and_writes_the_format_asked(tmp_path):
    """A NaN or unreadable angle (a usage error, exit 2, as every command's bad option value: it was 3), or a
    ``--q`` whose joint 2 is on another slice than ``--q2``'s (its marker would show this slice's verdict where it
    does not hold: exit 3), is refused with no file; ``--out`` writes the format its suffix names (it wrote PNG bytes into a .pdf)."""
    out = tmp_path / "h.agmap"
    runner = CliRunner()
    assert runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                                "--out", str(out)]).exit_code == 0
    png = tmp_path / "s.png"
    for args, said, code in ((["--q2", "30", "--q", "nan,30,-20"], "not a finite angle", 2),  # option values: usage
                             (["--q2", "30", "--q", "1,abc,3"], "--q: 'abc' is not a finite angle", 2),  # (2), as
                             (["--q2", "abc"], "--q2: 'abc' is not a finite angle", 2),  # every command's
                             (["--q2", "30", "--q", "1,2"], "expected three angles", 2),
                             (["--q2", "30", "--q", "180,90,-20"], "is not in the slice's cell", 3),  # the map's
                             (["--q2", "30", "--q", "999,30,-20"], "its joint 1 (999°) is outside the map's limits", 3),
                             (["--q2", "9999"], "(9999 deg) is outside joint 2's limits", 3)):  # the unit given
        r = runner.invoke(main, ["cspace", "plot", str(out), *args, "--out", str(png)])
        assert r.exit_code == code and said in r.output, (args, r.output)
        assert not png.exists()
    r = runner.invoke(main, ["cspace", "plot", str(out), "--q2", "30", "--q", "180,30,-20", "--out", str(tmp_path / "s.pdf")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "s.pdf").read_bytes()[:5] == b"%PDF-"
    r = runner.invoke(main, ["cspace", "plot", str(out), "--q2", "30", "--out", str(tmp_path / "s.xyz")])
    assert r.exit_code == 3 and "matplotlib writes no .xyz plots" in r.output, r.output
    assert not (tmp_path / "s.xyz").exists()


def test_build_on_a_robot_without_bodies_says_what_the_map_lacks(tmp_path):
    """ur5 has 17 checked pairs but no static body: the map has nothing to map, and says so (it said
    "model 'ur5' has no pair to check ... enable a pair", which ur5 has)."""
    r = CliRunner().invoke(main, ["cspace", "build", "ur5", "--resolution", "10deg", "--cell", "40deg",
                                  "--out", str(tmp_path / "x.agmap")])
    assert r.exit_code == 3, r.output
    assert "no pair of a mapped link (links 1-3) against a static body" in r.output and "enable a pair" not in r.output
    assert not (tmp_path / "x.agmap").exists()


def test_build_refuses_what_it_cannot_hold_and_leaves_no_empty_journal(tmp_path):
    """A 0.0001 deg resolution asked numpy for 298 GiB (an internal error, exit 4, and a .partial left
    behind); a scheduler that is no address was an internal error and left an empty journal."""
    runner = CliRunner()
    tiny = tmp_path / "tiny.agmap"
    r = runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "0.0001deg", "--j3-resolution", "10deg",
                             "--out", str(tiny)])
    assert r.exit_code == 3 and "more than 1073741824 (MAX_MAP_BINS)" in r.output, r.output
    assert not tiny.exists() and not tiny.with_name("tiny.agmap.partial").exists()
    sch = tmp_path / "sch.agmap"
    r = runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--scheduler", "nonsense",
                             "--out", str(sch)])
    assert r.exit_code == 3 and "'nonsense' is not a Dask scheduler's address" in r.output, r.output
    assert not sch.exists() and not sch.with_name("sch.agmap.partial").exists()


def test_map_queries_refuse_cells_it_does_not_have(tmp_path):
    """forbidden_intervals(-1, 0) answered the last cell's intervals (a plausible answer for no cell);
    (60, 0) and substructure_mask(1000) were raw IndexErrors; check_exactness(n=0) called a map it never
    sampled CONSERVATIVE."""
    import pytest

    from armguard._errors import ForbiddenMapError
    from armguard.cspace import ForbiddenMap, check_exactness

    out = tmp_path / "h.agmap"
    fmap = ForbiddenMap.build("hermes", out=out, resolution="30deg", max_depth=0)
    n1, n2 = (int(c) for c in fmap.grid.counts[:2])
    assert fmap.forbidden_intervals(n1 - 1, n2 - 1).shape[1] == 2
    for i1, i2 in ((-1, 0), (0, -1), (n1, 0), (0, n2), (1.5, 0)):
        with pytest.raises(ForbiddenMapError, match="is not a cell of this map"):
            fmap.forbidden_intervals(i1, i2)
    for s in (-1, fmap.grid.n_substructures, "0"):
        with pytest.raises(ForbiddenMapError, match="substructure"):
            fmap.substructure_mask(s)
    for n in (0, -1, 2.5):
        with pytest.raises(ForbiddenMapError, match="n: expected a number of configurations >= 1"):
            check_exactness(fmap, n=n)
    with pytest.raises(ForbiddenMapError, match="M >= 1"):
        check_exactness(fmap, Q=np.zeros((0, 6)))
    for q in ("abc", None, [[0.1, 0.2, 0.3]]):
        with pytest.raises(ForbiddenMapError, match="q: expected"):
            fmap.allowed(q)
    with pytest.raises(ForbiddenMapError, match="stopping_distance"):
        ForbiddenMap.build("hermes", out=tmp_path / "x.agmap", resolution="30deg", stopping_distance="x")


def test_a_missing_or_folder_map_exits_3_like_every_missing_input(tmp_path):
    """``cspace info``/``plot`` of a missing map exited 2 (click's path check: a usage error) where every other
    missing input file is refused with 3, naming the file."""
    runner = CliRunner()
    for args in (["cspace", "info", str(tmp_path / "none.agmap")],
                 ["cspace", "plot", str(tmp_path / "none.agmap"), "--q2", "0", "--out", str(tmp_path / "s.png")]):
        r = runner.invoke(main, args)
        assert r.exit_code == 3 and "none.agmap: no such map file" in r.output, r.output
    r = runner.invoke(main, ["cspace", "info", str(tmp_path)])
    assert r.exit_code == 3 and "is a directory, not a map file" in r.output, r.output
    assert not (tmp_path / "s.png").exists()
    r = runner.invoke(main, ["cspace", "info", ""])  # Path('') is the working directory
    assert r.exit_code == 3 and "an empty path names no map file" in r.output, r.output


def test_a_fifo_is_refused_not_waited_on(tmp_path):
    """``cspace info`` on a FIFO blocked in open() until killed; a pipe read as a truncated map."""
    import os

    fifo = tmp_path / "map.agmap"
    os.mkfifo(fifo)
    r = subprocess.run([sys.executable, "-m", "armguard", "cspace", "info", str(fifo)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 3 and "not a regular file (a FIFO, pipe or device)" in r.stderr, r.stderr


def test_a_bare_grid_step_over_half_a_radian_is_refused_with_both_readings(tmp_path):
    """``--resolution 5`` built a map of 286-degree cells (a bare number is rad), where ``--q2 1`` of
    ``cspace plot`` is 1 degree: a bare step that large is refused, naming both readings."""
    for opt in ("--resolution", "--cell", "--j3-resolution"):
        r = CliRunner().invoke(main, ["cspace", "build", "hermes", opt, "5", "--out", str(tmp_path / "m.agmap")])
        assert r.exit_code == 2 and "5 is read as 5 rad (286.5 deg)" in r.output and "'5deg'" in r.output, r.output
        assert not (tmp_path / "m.agmap").exists()


def test_a_map_that_forbids_nearly_everything_says_so(tmp_path):
    """A 10 m stopping distance forbids the whole joint box: build and info warn (the map was written
    with exit 0 and no word, and info called it conservative); a usable map says nothing of it."""
    runner = CliRunner()
    out = tmp_path / "all.agmap"
    r = runner.invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                             "--stopping-distance", "10", "--out", str(out)])
    assert r.exit_code == 0 and "forbids 100.00% of the joint box" in r.output and "(10 m)" in r.output, r.output
    r = runner.invoke(main, ["cspace", "info", str(out), "--samples", "0"])
    assert r.exit_code == 0 and "forbids 100.00% of the joint box" in r.output
    r = runner.invoke(main, ["cspace", "build", "gmf_s480", "--resolution", "20deg", "--out", str(tmp_path / "ok.agmap")])
    assert r.exit_code == 0 and "warning" not in r.output, r.output  # 93 % forbidden: no warning


@pytest.mark.parametrize("opt, value", [("--resolution", "nan"), ("--resolution", "abc"), ("--cell", "0deg")])
def test_a_bad_grid_option_is_a_usage_error(tmp_path, opt, value):
    """``--resolution nan`` or ``--cell 0deg`` exited 3 (a file or value refused) where every other command's bad
    option value exits 2; and nothing is written."""
    out = tmp_path / "h.agmap"
    r = CliRunner().invoke(main, ["cspace", "build", "hermes", opt, value, "--out", str(out)])
    assert r.exit_code == 2 and f"Invalid value for {opt}" in r.output, r.output
    assert not out.exists()
