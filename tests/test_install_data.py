"""Installed package data (``armguard._resources``) and the numba cache of a read-only install
(``armguard._numba_cache``).  The wheel itself is built, installed and run by ``make smoke-wheel``
(``tools/smoke_wheel.sh``, part of ``make test``); here: the lookup order, and that the build
script copies exactly the checkout's data folders.
"""

from __future__ import annotations

import importlib
import os
import sys
import tempfile
from pathlib import Path

import pytest

import armguard
from armguard import _numba_cache, _resources
from armguard.harness import reference_dir
from armguard.harness._models import file_label
from armguard.model import load_model, models_dir

ROOT = Path(__file__).resolve().parents[1]


def test_checkout_folders_are_used_in_a_checkout(monkeypatch):
    monkeypatch.delenv("ARMGUARD_MODELS", raising=False)
    monkeypatch.delenv("ARMGUARD_REFERENCE", raising=False)
    monkeypatch.setattr(_resources, "_installed", lambda name: None)
    assert models_dir() == ROOT / "urdf"
    assert reference_dir() == ROOT / "reference"


def test_precedence_environment_then_package_data_then_checkout(tmp_path, monkeypatch):
    installed = tmp_path / "site" / "armguard" / "_data"
    (installed / "urdf").mkdir(parents=True)
    (installed / "reference").mkdir()
    monkeypatch.setattr(_resources, "_installed", lambda name: installed / name if (installed / name).is_dir() else None)
    monkeypatch.delenv("ARMGUARD_MODELS", raising=False)
    monkeypatch.delenv("ARMGUARD_REFERENCE", raising=False)
    assert models_dir() == installed / "urdf" and reference_dir() == installed / "reference"
    monkeypatch.setenv("ARMGUARD_MODELS", str(tmp_path / "mine"))
    monkeypatch.setenv("ARMGUARD_REFERENCE", str(tmp_path / "ref"))
    assert models_dir() == tmp_path / "mine" and reference_dir() == tmp_path / "ref"
    with pytest.raises(ValueError, match="'urdf', 'reference'"):
        _resources.data_dir("docs")


def test_builtin_models_load_from_a_copy_of_the_package_data(tmp_path, monkeypatch):
    """What a wheel holds (armguard/_data/urdf, a copy) loads, and its files are labelled as in the checkout."""
    import shutil

    data = tmp_path / "armguard" / "_data"
    shutil.copytree(ROOT / "urdf" / "hermes", data / "urdf" / "hermes")
    monkeypatch.setattr(_resources, "_installed", lambda name: data / name if (data / name).is_dir() else None)
    monkeypatch.setattr(_resources, "data_roots", lambda: [data, ROOT])
    monkeypatch.delenv("ARMGUARD_MODELS", raising=False)
    m = load_model("hermes")
    assert Path(m.files[0]) == data / "urdf" / "hermes" / "hermes.yaml"
    import armguard.harness._models as hm

    monkeypatch.setattr(hm, "data_roots", lambda: [data, ROOT])
    assert file_label(m.files[0]) == "urdf/hermes/hermes.yaml" == file_label(ROOT / "urdf" / "hermes" / "hermes.yaml")


def test_build_copies_the_data_folders(tmp_path, monkeypatch):
    """setup.py's build_py puts urdf/ and reference/ under armguard/_data/, file for file (no caches)."""
    import runpy

    import setuptools
    from setuptools.dist import Distribution

    seen = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kw: seen.update(kw))
    runpy.run_path(str(ROOT / "setup.py"))
    cmd_cls = seen["cmdclass"]["build_py"]
    dist = Distribution({"name": "armguard", "packages": [], "package_dir": {}})
    cmd = cmd_cls(dist)
    cmd.initialize_options()
    cmd.build_lib = str(tmp_path / "lib")
    cmd.finalize_options()
    (tmp_path / "lib" / "armguard" / "_data" / "urdf").mkdir(parents=True)
    (tmp_path / "lib" / "armguard" / "_data" / "urdf" / "stale.txt").write_text("from an earlier build")
    cmd.run()
    for name in ("urdf", "reference"):
        want = {p.relative_to(ROOT / name) for p in (ROOT / name).rglob("*")
                if p.is_file() and "__pycache__" not in p.parts and not p.name.startswith(".")}
        got_root = tmp_path / "lib" / "armguard" / "_data" / name
        got = {p.relative_to(got_root) for p in got_root.rglob("*") if p.is_file()}
        assert want and got == want, (name, sorted(got ^ want)[:5])


def test_manifest_carries_the_data_folders_into_the_sdist():
    text = (ROOT / "MANIFEST.in").read_text()
    assert "graft urdf" in text and "graft reference" in text


def test_numba_cache_left_to_numba_when_it_has_a_place(monkeypatch, tmp_path):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert _numba_cache.ensure_numba_cache(tmp_path) is None  # the package folder is writable
    assert "NUMBA_CACHE_DIR" not in os.environ
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "given"))
    monkeypatch.setattr(_numba_cache, "writable", lambda folder: False)
    assert _numba_cache.ensure_numba_cache(tmp_path) is None  # the user's choice stands
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "given")


def test_read_only_install_caches_kernels_in_a_temp_folder(monkeypatch, tmp_path):
    """Neither the package nor the user cache writable: kernels are cached under the temp dir (a real
    kernel is compiled and its cache files are found there), instead of numba refusing to define it."""
    from numba.core import config

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(_numba_cache, "writable", lambda folder: False)
    folder = _numba_cache.ensure_numba_cache(tmp_path / "pkg")
    assert folder is not None and folder.parent == tmp_path / "tmp" and folder.name.startswith("armguard-numba-")
    assert os.environ["NUMBA_CACHE_DIR"] == str(folder) == config.CACHE_DIR
    mod_dir = tmp_path / "kernels"
    mod_dir.mkdir()
    (mod_dir / "ag_cache_probe.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    monkeypatch.syspath_prepend(str(mod_dir))
    probe = importlib.import_module("ag_cache_probe")
    assert probe.twice(21) == 42
    assert list(folder.rglob("ag_cache_probe.twice-*.nbi")), sorted(folder.rglob("*"))
    assert not list(mod_dir.rglob("*.nbi"))


def test_writable_walks_up_to_an_existing_folder(tmp_path):
    assert _numba_cache.writable(tmp_path / "a" / "b")
    f = tmp_path / "file"
    f.write_text("")
    assert not _numba_cache.writable(f / "below")


def test_import_armguard_does_not_import_numba():
    import subprocess

    code = "import sys, armguard; print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"
    assert armguard.__version__


@pytest.mark.parametrize("planted", ["open to others", "a link", "a file"])
def test_the_temp_cache_folder_is_never_one_another_user_could_write(monkeypatch, tmp_path, planted):
    """numba reads its index files with pickle: the temp folder's usual name taken by a folder others may
    write, a link or a file (another user could have made it first and put code in it) is passed over
    for a fresh private folder; the usual folder, when made here, is 0700."""
    import stat

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    from numba.core import config

    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(_numba_cache, "writable", lambda folder: False)
    usual = tmp_path / "tmp" / f"armguard-numba-{_numba_cache._user()}"
    made = _numba_cache.ensure_numba_cache(tmp_path / "pkg")
    assert made == usual and stat.S_IMODE(usual.stat().st_mode) == 0o700
    usual.rmdir()
    if planted == "open to others":
        usual.mkdir()
        usual.chmod(0o777)
    elif planted == "a link":
        (tmp_path / "elsewhere").mkdir(mode=0o700)
        usual.symlink_to(tmp_path / "elsewhere")
    else:
        usual.write_text("not a folder")
    monkeypatch.delenv("NUMBA_CACHE_DIR")  # set by the first call
    folder = _numba_cache.ensure_numba_cache(tmp_path / "pkg")
    assert folder != usual and folder.is_dir() and not folder.is_symlink()
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700 and os.environ["NUMBA_CACHE_DIR"] == str(folder)


def test_the_checkout_is_a_data_root_only_when_armguard_runs_from_one(monkeypatch, tmp_path):
    """From a wheel the folder above ``armguard`` is the venv's ``lib/pythonX.Y``: it was listed as a checkout,
    so a file label read ``site-packages/trimesh/...``.  A root is a checkout when it holds pyproject.toml and
    src/armguard."""
    from armguard import _resources

    assert _resources.in_checkout() and _resources.checkout_root() in _resources.data_roots()  # this checkout
    monkeypatch.setattr(_resources, "checkout_root", lambda: tmp_path)  # as from a venv's lib/python3.11
    assert not _resources.in_checkout() and tmp_path not in _resources.data_roots()
