"""A backend that is installed but does not import (its package's module, or a package it needs, is
missing) is a BackendError naming the backend and the module, whether the import fails when its entry
point is loaded or when its ``build`` imports the dependency; the command line answers it with the
exit status of a refused value (3), never an internal error (4).  The backends are installed for the
test as a real distribution's metadata in a folder put on ``sys.path``: nothing is uninstalled."""

from __future__ import annotations

import sys
import textwrap

import pytest
from click.testing import CliRunner

import armguard
from armguard import BackendError
from armguard import backends
from armguard.cli import ExitCode, main

MISSING = "armguard_test_no_such_dependency"


@pytest.fixture
def broken_backends(monkeypatch, tmp_path):
    """Three backends in one installed distribution: ``gone`` names a module that is not there,
    ``needs_dep`` imports a missing module when it builds a checker (as python-fcl's backend does),
    ``bad_import`` fails with an ImportError that is not a missing module."""
    info = tmp_path / "armguard_broken-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: armguard-broken\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(
        "[armguard.backends]\n"
        "gone = armguard_broken_not_there:Backend\n"
        "needs_dep = armguard_broken_mod:NeedsDep\n"
        "bad_import = armguard_broken_mod:BadImport\n"
        "misspelt = armguard_broken_mod:NeedsDepp\n"
        "raises_on_import = armguard_broken_raises:Backend\n"
        "build_raises = armguard_broken_mod:BuildRaises\n"
        "no_build = armguard_broken_mod:NoBuild\n"
        "needs_args = armguard_broken_mod:NeedsArgs\n")
    (tmp_path / "armguard_broken_raises.py").write_text("raise RuntimeError('no licence server')\n")
    (tmp_path / "armguard_broken_mod.py").write_text(textwrap.dedent(f"""
        class NeedsDep:
            name = "needs_dep"

            def build(self, model, options=None):
                import {MISSING}  # noqa: F401
                raise AssertionError("unreachable: the import above fails")


        class BadImport:
            name = "bad_import"

            def build(self, model, options=None):
                from math import no_such_function  # noqa: F401
                raise AssertionError("unreachable: the import above fails")


        class BuildRaises:
            name = "build_raises"

            def build(self, model, options=None):
                raise RuntimeError("cannot convert mesh link3.stl")


        class NoBuild:
            name = "no_build"


        class NeedsArgs:
            name = "needs_args"

            def __init__(self, path):
                self.path = path

            def build(self, model, options=None):
                raise AssertionError("unreachable: not made")
        """))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "armguard_broken_mod", raising=False)
    monkeypatch.delitem(sys.modules, "armguard_broken_raises", raising=False)
    yield tmp_path
    sys.modules.pop("armguard_broken_mod", None)
    sys.modules.pop("armguard_broken_raises", None)


def test_an_unimportable_backend_is_listed_but_get_backend_names_it(broken_backends):
    assert {"gone", "needs_dep", "bad_import", "analytic"} <= set(backends.available())
    with pytest.raises(BackendError) as e:
        backends.get_backend("gone")
    msg = str(e.value)
    assert msg.startswith("backend 'gone' could not be loaded: No module named 'armguard_broken_not_there'"), msg
    assert "its package or a dependency is not installed" in msg
    assert "armguard_broken_not_there:Backend" in msg  # where: the entry point it was loading
    assert isinstance(e.value.__cause__, ModuleNotFoundError)
    assert e.value.__cause__.name == "armguard_broken_not_there"
    # the same through checker(), and for a model given by name
    with pytest.raises(BackendError, match="^backend 'gone' could not be loaded: No module named"):
        armguard.checker("puma560", "gone")


def test_a_dependency_missing_at_build_is_a_backend_error(broken_backends):
    assert type(backends.get_backend("needs_dep")).__name__ == "NeedsDep"  # the package itself loads
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", "needs_dep")
    msg = str(e.value)
    assert msg.startswith(f"backend 'needs_dep' could not be loaded: No module named '{MISSING}'"), msg
    assert "its package or a dependency is not installed" in msg and "building its checker" in msg
    assert isinstance(e.value.__cause__, ModuleNotFoundError) and e.value.__cause__.name == MISSING


def test_an_import_error_that_is_not_a_missing_module_says_so(broken_backends):
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", "bad_import")
    msg = str(e.value)
    assert msg.startswith("backend 'bad_import' could not be loaded: cannot import name 'no_such_function'"), msg
    assert "does not import" in msg and "not installed" not in msg
    assert type(e.value.__cause__) is ImportError


def test_a_load_failure_is_not_blamed_on_the_configuration_file(broken_backends, tmp_path):
    """Options from armguard.toml are named with the file when the backend refuses them; a failed
    import is not the options' fault and keeps its own message and cause."""
    cfg = tmp_path / "armguard.toml"
    cfg.write_text('[backend]\nname = "needs_dep"\nthreads = 2\n')
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", config=cfg)
    assert str(e.value).startswith("backend 'needs_dep' could not be loaded"), str(e.value)
    assert str(cfg) not in str(e.value) and isinstance(e.value.__cause__, ModuleNotFoundError)


def test_a_working_backend_is_unaffected(broken_backends):
    c = armguard.checker("puma560", "analytic")
    assert c.pair_distances(c.model.neutral()).distance.shape == (len(c.model.pairs),)


def test_python_fcl_missing_is_a_backend_error(monkeypatch):
    """The real fcl backend imports python-fcl when it builds: with the module unimportable (None in
    sys.modules blocks the import), it is named, not a bare ModuleNotFoundError."""
    if "fcl" not in backends.available():
        pytest.skip("the fcl backend is not installed")
    monkeypatch.setitem(sys.modules, "fcl", None)
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", "fcl")
    assert str(e.value).startswith("backend 'fcl' could not be loaded: import of fcl halted"), str(e.value)
    assert "building its checker" in str(e.value) and isinstance(e.value.__cause__, ModuleNotFoundError)


@pytest.mark.parametrize("name, module", [("gone", "armguard_broken_not_there"), ("needs_dep", MISSING)])
def test_compare_exits_with_the_backend_error_code(broken_backends, tmp_path, name, module):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["compare", "puma560", "--backends", f"analytic,{name}", "--configs", "2",
                                    "--trajectory", "none", "--no-plots", "--out", str(out)])
    assert res.exit_code == ExitCode.INPUT, res.output
    line = res.output.strip()
    assert line.count("\n") == 0 and "internal error" not in line, line
    assert line.startswith(f"error: backend '{name}' could not be loaded: No module named '{module}'"), line
    assert not out.exists()


def test_check_with_an_unloadable_backend_exits_with_the_backend_error_code(broken_backends):
    res = CliRunner().invoke(main, ["--backend", "needs_dep", "check", "puma560"])
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "backend 'needs_dep' could not be loaded" in res.output and "internal error" not in res.output



@pytest.mark.parametrize("name, words", [
    ("misspelt", "backend 'misspelt' could not be loaded: AttributeError: module 'armguard_broken_mod' has no attribute "
                 "'NeedsDepp' (raised while loading its entry point misspelt = 'armguard_broken_mod:NeedsDepp'"),
    ("raises_on_import", "backend 'raises_on_import' could not be loaded: RuntimeError: no licence server (raised while "
                         "loading its entry point"),
    ("no_build", "backend 'no_build': its entry point no_build = 'armguard_broken_mod:NoBuild' gives a NoBuild, which "
                 "has no build(model, options) method"),
    ("needs_args", "backend 'needs_args': its entry point needs_args = 'armguard_broken_mod:NeedsArgs' is a class that "
                   "cannot be made with no arguments: TypeError"),
    ("build_raises", "backend 'build_raises' failed to build a checker for model 'puma560': RuntimeError: cannot convert "
                     "mesh link3.stl (an error in the backend)"),
])
def test_a_backend_that_fails_otherwise_is_named_with_its_entry_point(broken_backends, name, words):
    """A misspelt object, a package that raises on import, an object without build, a class that needs
    arguments, a build that raises: raw AttributeError / RuntimeError / TypeError, and on the command line
    "internal error" (4).  Each is a BackendError naming the backend (exit status 3)."""
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", name)
    assert str(e.value).startswith(words), str(e.value)
    res = CliRunner().invoke(main, ["--backend", name, "check", "puma560"])
    assert res.exit_code == ExitCode.INPUT and "internal error" not in res.output and f"backend '{name}'" in res.output, \
        res.output
