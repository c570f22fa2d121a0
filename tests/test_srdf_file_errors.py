"""An ``srdf=`` that is not a readable file is a SceneFileError naming it, not a raw OSError."""

from __future__ import annotations

import pytest

import armguard
from armguard import SceneFileError
from armguard.harness import repo_root


def test_srdf_a_directory_is_a_located_error(tmp_path):
    urdf = repo_root() / "urdf" / "hermes" / "hermes.urdf"
    with pytest.raises(SceneFileError, match="expected an SRDF file, got a directory") as e:
        armguard.load_model(str(urdf), srdf=tmp_path)
    assert e.value.file == str(tmp_path)


def test_a_scene_srdf_that_is_a_directory_is_a_located_error(tmp_path):
    from armguard.model._scenefile import read_srdf_disabled

    with pytest.raises(SceneFileError, match="is a directory") as e:
        read_srdf_disabled(tmp_path)
    assert e.value.file == str(tmp_path)


def test_cli_srdf_a_directory_is_refused_in_one_line(tmp_path):
    """``--srdf DIR`` (a file armguard refuses, naming it: 3, as every input file that is a folder; click's own
    path check answered 2) and a scene file whose robot's ``srdf:`` is a folder (the scene file's error: its place
    and the folder, 3) -- never a traceback."""
    from click.testing import CliRunner

    from armguard.cli import ExitCode, main

    urdf = repo_root() / "urdf" / "hermes" / "hermes.urdf"
    res = CliRunner().invoke(main, ["info", str(urdf), "--srdf", str(tmp_path)])
    assert res.exit_code == ExitCode.INPUT and "expected an SRDF file, got a directory" in res.output, res.output
    assert str(tmp_path) in res.output and len(res.output.strip().splitlines()) == 1
    assert "Traceback" not in res.output and "IsADirectoryError" not in res.output
    (tmp_path / "srdf_dir").mkdir()
    scene = tmp_path / "cell.yaml"
    scene.write_text(f"armguard_scene: 1\nname: cell\nrobots:\n  - name: arm\n    urdf: {urdf}\n    srdf: srdf_dir\n")
    res = CliRunner().invoke(main, ["check", str(scene)])
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "Traceback" not in res.output and "IsADirectoryError" not in res.output
    assert str(scene) in res.output and "robots[0].srdf" in res.output and "is a directory" in res.output


def test_a_urdf_given_as_the_srdf_is_refused():
    """A URDF given where the SRDF goes read as an SRDF that disables nothing (``check-srdf ur5 ur5.urdf``
    linted it, exit 0): its top-level ``<link>`` says what it is."""
    from click.testing import CliRunner

    from armguard.cli import main

    urdf = repo_root() / "urdf" / "hermes" / "hermes.urdf"
    with pytest.raises(SceneFileError, match="this is a URDF, not an SRDF") as e:
        armguard.load_model(str(urdf), srdf=urdf)
    assert e.value.file == str(urdf) and "link[0]" in str(e.value)
    r = CliRunner().invoke(main, ["check-srdf", "hermes", str(urdf)])
    assert r.exit_code == 3 and "this is a URDF, not an SRDF" in r.output, r.output


@pytest.mark.parametrize("good, typo", [("group_state", "group_sate"), ("disable_collisions", "disable_colisions")])
def test_a_misspelt_srdf_element_is_refused_not_dropped(tmp_path, good, typo):
    """``<group_sate>`` was dropped without a word (the home pose read as all zeros) and ``<disable_colisions>``
    likewise (the pair checked after all): another model than the one written.  An element no reader knows
    and resembling none (a tool's ``<rotor_params>``) is left alone."""
    src = repo_root() / "urdf" / "puma560" / "puma560.srdf"
    text = src.read_text()
    assert f"<{good} " in text
    bad = tmp_path / "typo.srdf"
    bad.write_text(text.replace(f"<{good} ", f"<{typo} ", 1).replace(f"</{good}>", f"</{typo}>", 1))
    urdf = repo_root() / "urdf" / "puma560" / "puma560.urdf"
    with pytest.raises(SceneFileError, match=rf"<{typo}> is read by nothing: did you mean <{good}>\?") as e:
        armguard.load_model(str(urdf), srdf=bad)
    assert e.value.file == str(bad)
    other = tmp_path / "other.srdf"
    other.write_text(text.replace("</robot>", '<rotor_params><joint name="x" mass="0"/></rotor_params></robot>'))
    armguard.load_model(str(urdf), srdf=other)
