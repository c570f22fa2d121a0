"""Where the data folders are: the built-in models (``urdf/``) and the recorded reference data (``reference/``).

In a checkout they are the top-level ``urdf/`` and ``reference/`` folders, where they are
edited (an editable install reads them there).  A wheel, or ``pip install .``, carries a copy
of both as package data, ``armguard/_data/urdf`` and ``armguard/_data/reference`` (written by
``setup.py``'s ``build_py`` at build time), found through :mod:`importlib.resources`.  One
precedence, here only: an environment variable (``$ARMGUARD_MODELS``, ``$ARMGUARD_REFERENCE``),
then the installed package data, then the checkout's folder.
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

__all__ = ["DATA_FOLDERS", "data_dir", "data_roots", "checkout_root", "in_checkout"]

DATA_FOLDERS = {"urdf": "ARMGUARD_MODELS", "reference": "ARMGUARD_REFERENCE"}
"""Each data folder, with the environment variable that overrides it."""


def checkout_root() -> Path:
    """The folder above ``src/`` (the checkout, when armguard runs from one: :func:`in_checkout`)."""
    return Path(__file__).resolve().parents[2]


def in_checkout() -> bool:
    """Whether armguard runs from a source checkout (an editable install): :func:`checkout_root` holds
    ``pyproject.toml`` and ``src/armguard``.  From a wheel it is ``<venv>/lib/pythonX.Y``."""
    root = checkout_root()
    return (root / "pyproject.toml").is_file() and (root / "src" / "armguard").is_dir()


def _installed(name: str) -> Path | None:
    p = files("armguard") / "_data" / name
    return Path(str(p)) if p.is_dir() else None


def data_dir(name: str) -> Path:
    """The folder of data set ``name`` (``"urdf"`` or ``"reference"``): its environment variable, the
    installed package data, else the checkout's top-level folder (returned even when missing: the
    caller says what it looked for)."""
    if name not in DATA_FOLDERS:
        raise ValueError(f"unknown data folder {name!r}; data folders are {list(DATA_FOLDERS)}")
    env = os.environ.get(DATA_FOLDERS[name])
    if env:
        return Path(env)
    return _installed(name) or checkout_root() / name


def data_roots() -> list[Path]:
    """The folders that hold ``urdf/`` and ``reference/`` (the installed ``_data``, the checkout): the roots
    that name a model file machine-independently (``urdf/hermes/hermes.urdf``)."""
    out = []
    installed = files("armguard") / "_data"
    if installed.is_dir():
        out.append(Path(str(installed)))
    if in_checkout():  # from a wheel the folder above is the venv's lib/pythonX.Y, no root of models
        out.append(checkout_root())
    return out
