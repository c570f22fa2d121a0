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
