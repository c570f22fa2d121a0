"""A shipped terrain loads by its name (``load_terrain("rocky")``, ``--terrain rocky``) from any folder:
run here from a temporary directory, so the checkout's ``reference/terrain/`` is not on the relative path.
An unknown name is refused naming it and listing the shipped names."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from armguard._errors import TerrainError
from armguard._resources import data_dir
from armguard.terrain import load_terrain, shipped_terrains, terrain_path
from armguard.terrain.generate import REFERENCE

SHIPPED = data_dir("reference") / "terrain"


def test_the_shipped_terrains_are_listed_by_name():
    assert shipped_terrains() == tuple(sorted(REFERENCE)) == ("gentle", "rocky", "rough")


def test_a_shipped_name_loads_from_another_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert terrain_path("rocky") == SHIPPED / "rocky.npz"
    by_name, by_path = load_terrain("rocky"), load_terrain(SHIPPED / "rocky.npz")
    np.testing.assert_array_equal(by_name.heights, by_path.heights)
    np.testing.assert_array_equal(by_name.origin, by_path.origin)
    import armguard

    scene = armguard.load_scene("rover")  # centred under the arm, as the file would be
    np.testing.assert_array_equal(load_terrain("rocky", scene).origin, load_terrain(SHIPPED / "rocky.npz", scene).origin)


def test_a_file_of_that_name_here_wins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rocky").write_text("mine")
    assert terrain_path("rocky") == Path("rocky")


@pytest.mark.parametrize("given", ["rockyy", "nosuch"])
def test_an_unknown_name_is_refused_listing_the_shipped_ones(tmp_path, monkeypatch, given):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TerrainError, match=rf"terrain file '{given}' does not exist.*gentle, rocky, rough"):
        load_terrain(given)


@pytest.mark.parametrize("given", ["rocky.npz", "terrain/rocky", "./rocky"])
def test_only_a_bare_name_is_taken_for_a_shipped_terrain(tmp_path, monkeypatch, given):
    """A path with a folder or a suffix is a file: missing here, it is refused (the shipped names listed)."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TerrainError, match=r"does not exist.*gentle, rocky, rough") as err:
        terrain_path(given)
    assert f"terrain file '{given}' does not exist" in str(err.value)  # named as given


def test_the_command_line_takes_a_shipped_name(tmp_path, monkeypatch):
    from armguard.cli import main

    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, ["check", "rover", "--q", "0,30,20,30,0", "--deg", "--terrain", "rocky"])
    assert res.exit_code == 1, res.output  # docs/terrain.md: the terrain category collides
    res = CliRunner().invoke(main, ["check", "rover", "--terrain", "nosuch"])
    assert res.exit_code == 3
    assert "terrain file 'nosuch' does not exist" in res.output and "gentle, rocky, rough" in res.output


def test_the_console_takes_a_shipped_name_before_compiling(tmp_path, monkeypatch):
    import armguard.cli._compile as compile_mod
    import armguard.console._serve as serve_mod
    from armguard.cli import main

    monkeypatch.chdir(tmp_path)
    warmed, seen = [], []
    monkeypatch.setattr(compile_mod, "warm_up", lambda *a, **k: warmed.append(1))
    res = CliRunner().invoke(main, ["console", "puma560", "--terrain", "nosuch", "--port", "0"])
    assert res.exit_code == 3 and "gentle, rocky, rough" in res.output and warmed == []

    class Stop(Exception):  # an unexpected error: the command line's exit status 4
        pass

    def inputs(scene, *, terrain=None):
        seen.append(terrain)
        raise Stop

    monkeypatch.setattr(serve_mod, "load_inputs", inputs)
    res = CliRunner().invoke(main, ["console", "rover", "--terrain", "rocky", "--port", "0"])
    assert seen == [str(SHIPPED / "rocky.npz")], res.output  # handed on resolved (then stopped: exit 4)


def test_the_console_api_takes_a_shipped_name(tmp_path, monkeypatch):
    """``make_state(..., terrain="rocky")`` and ``serve``: the name is checked as the command line checks it
    (``load_inputs``, before any kernel), and an unknown one is named with the shipped names."""
    from armguard import TerrainError
    from armguard.console._serve import load_inputs

    monkeypatch.chdir(tmp_path)
    assert load_inputs("rover", terrain="rocky").model is not None
    with pytest.raises(TerrainError, match="gentle, rocky, rough"):
        load_inputs("rover", terrain="nosuch")
