"""Package-level contracts: lazy top-level names, the error hierarchy, the tolerance dataclass, the CLI entry."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import pytest

import armguard
from armguard import _errors


def test_import_is_lazy_and_compiles_nothing():
    code = "import sys, armguard; print(sorted(m for m in sys.modules if m.startswith(('numba', 'armguard.geometry'))))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("name", sorted(armguard._LAZY), ids=str)
def test_lazy_names_resolve(name):
    assert getattr(armguard, name) is not None


def test_unknown_attribute_raises():
    with pytest.raises(AttributeError):
        armguard.no_such_thing  # noqa: B018


@pytest.mark.parametrize("cls", [c for c in vars(_errors).values() if isinstance(c, type) and issubclass(c, Exception)
                                 and not issubclass(c, Warning)], ids=lambda c: c.__name__)
def test_every_error_is_an_armguard_error_with_a_docstring(cls):
    assert issubclass(cls, armguard.ArmguardError)
    assert cls.__doc__ and cls.__doc__.strip()


@pytest.mark.parametrize("cls", [c for c in vars(_errors).values() if isinstance(c, type) and issubclass(c, Warning)],
                         ids=lambda c: c.__name__)
def test_every_warning_is_an_armguard_warning_with_a_docstring(cls):
    assert issubclass(cls, _errors.ArmguardWarning) and issubclass(cls, UserWarning)
    assert cls.__doc__ and cls.__doc__.strip()


def test_scene_file_error_names_file_place_and_expectation():
    err = armguard.SceneFileError("cell.yaml", "robots[0].joints[3].limits", "expected [lower, upper] with lower < upper")
    assert str(err) == "cell.yaml: robots[0].joints[3].limits: expected [lower, upper] with lower < upper"
    assert (err.file, err.where) == ("cell.yaml", "robots[0].joints[3].limits")


def test_tolerances_are_frozen_and_documented():
    tol = armguard.Tolerances()
    with pytest.raises(dataclasses.FrozenInstanceError):
        tol.length = 1.0  # type: ignore[misc]
    doc = armguard.Tolerances.__doc__
    for f in dataclasses.fields(tol):
        assert f.name in doc, f"tolerance {f.name} is not documented"
        assert getattr(tol, f.name) > 0


@pytest.mark.parametrize("module", ["armguard.cli", "armguard"])
def test_cli_help_lists_commands(module):
    out = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "distance" in out.stdout
