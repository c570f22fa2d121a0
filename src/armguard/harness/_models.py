"""Named models for the harness and ``reference/``: the built-ins plus the public robots.

``resolve_model(spec)`` takes what ``armguard.load_model`` takes: a built-in, a public robot's
name (``panda``, ``ur10``, ``iiwa``..., the registry ``armguard.model._public``), a path.
``reference/models/`` records the built-ins and :data:`EXTRA_MODELS`, three public arms.  A spec
is a plain string, so it travels to Dask workers and into reproduce commands.
"""

from __future__ import annotations

from pathlib import Path

from .._errors import SceneError
from .._resources import checkout_root, data_dir, data_roots

__all__ = ["resolve_model", "seed_data", "model_sources", "reference_model_names", "repo_root", "reference_dir", "file_label",
           "robots_dir", "EXTRA_MODELS"]

EXTRA_MODELS = ("panda", "ur5", "iiwa")
"""The public robots ``reference/models/`` records (example-robot-data's Panda and UR5, pybullet_data's iiwa)."""


def repo_root() -> Path:
    """The checkout's root (the folder above ``src/``)."""
    return checkout_root()


def reference_dir() -> Path:
    """``$ARMGUARD_REFERENCE``, the installed package data or the checkout's ``reference/``."""
    return data_dir("reference")


def robots_dir() -> Path | None:
    """example-robot-data's ``robots/`` folder (it ships data only, in site-packages' cmeel prefix)."""
    from ..model._public import EXAMPLE_ROBOT_DATA, package_root

    return package_root(EXAMPLE_ROBOT_DATA)


def model_sources(spec: str) -> tuple[Path, Path | None]:
    """``(urdf, srdf or None)`` of a public robot's name; SceneError for other names."""
    from ..model._public import public_robot_files

    return public_robot_files(spec)


def resolve_model(spec):
    """The :class:`armguard.model.Model` of ``spec`` (a Model is returned as it is)."""
    from ..model import Model, load_model

    if isinstance(spec, Model):
        return spec
    return load_model(str(spec))


def reference_model_names() -> tuple[str, ...]:
    """Every model ``reference/models/`` holds: each folder of ``urdf/`` with its sidecar, then the extras."""
    from ..model import models_dir

    d = models_dir()
    own = sorted(p.name for p in d.iterdir() if (p / f"{p.name}.yaml").is_file()) if d.is_dir() else []
    return (*own, *EXTRA_MODELS)


def file_label(path) -> str:
    """A machine-independent name for a model file: relative to the checkout, example-robot-data or pybullet_data."""
    from ..model._public import EXAMPLE_ROBOT_DATA, PYBULLET_DATA, package_root

    p = Path(path).resolve()
    roots = [(f"{pkg}:", package_root(pkg)) for pkg in (EXAMPLE_ROBOT_DATA, PYBULLET_DATA)]
    # last: the virtual environment may lie inside the checkout
    roots += [("", root) for root in data_roots()]
    for prefix, root in roots:
        if root is None:
            continue
        try:
            return prefix + p.relative_to(root.resolve()).as_posix()
        except ValueError:
            continue
    return str(p)


def seed_data(name: str) -> dict:
    """``reference/seeds/<name>.yaml``: a seed paper's published numbers, each with its ``source:`` quote."""
    import yaml

    p = reference_dir() / "seeds" / f"{name}.yaml"
    if not p.is_file():
        raise SceneError(f"no seed data {name!r} in {p.parent}")
    return yaml.safe_load(p.read_text(encoding="utf-8"))
