"""Named models for the harness and ``reference/``: the built-ins plus three public arms.

``resolve_model(spec)`` takes what ``armguard.load_model`` takes, plus ``panda`` and ``ur5``
(example-robot-data, with their SRDFs) and ``iiwa`` (pybullet_data's KUKA iiwa, no SRDF).
A spec is a plain string, so it travels to Dask workers and into reproduce commands.
"""

from __future__ import annotations

import os
import sysconfig
from pathlib import Path

from .._errors import SceneError

__all__ = ["resolve_model", "seed_data", "model_sources", "reference_model_names", "repo_root", "reference_dir", "file_label",
           "robots_dir", "EXTRA_MODELS"]

EXTRA_MODELS = ("panda", "ur5", "iiwa")


def repo_root() -> Path:
    return Path(__file__).resolve().parents[3]


def reference_dir() -> Path:
    """``$ARMGUARD_REFERENCE`` or the checkout's ``reference/``."""
    env = os.environ.get("ARMGUARD_REFERENCE")
    return Path(env) if env else repo_root() / "reference"


def robots_dir() -> Path:
    """example-robot-data's ``robots/`` folder (it ships data only, in site-packages' cmeel prefix)."""
    return Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"


def _pybullet_data() -> Path:
    import pybullet_data

    return Path(pybullet_data.getDataPath())


def model_sources(spec: str) -> tuple[Path, Path | None]:
    """``(urdf_or_yaml, srdf or None)`` of an extra model name; SceneError for other names."""
    if spec == "panda":
        r = robots_dir() / "panda_description"
        return r / "urdf/panda.urdf", r / "srdf/panda.srdf"
    if spec == "ur5":
        r = robots_dir() / "ur_description"
        return r / "urdf/ur5_robot.urdf", r / "srdf/ur5.srdf"
    if spec == "iiwa":
        return _pybullet_data() / "kuka_iiwa/model.urdf", None
    raise SceneError(f"{spec!r} is not one of the extra models {list(EXTRA_MODELS)}")


def resolve_model(spec):
    """The :class:`armguard.model.Model` of ``spec`` (a Model is returned as it is)."""
    from ..model import Model, load_model

    if isinstance(spec, Model):
        return spec
    s = str(spec)
    if s in EXTRA_MODELS:
        urdf, srdf = model_sources(s)
        return load_model(urdf, srdf=srdf)
    return load_model(s)


def reference_model_names() -> tuple[str, ...]:
    """Every model ``reference/models/`` holds: each folder of ``urdf/`` with its sidecar, then the extras."""
    from ..model import models_dir

    d = models_dir()
    own = sorted(p.name for p in d.iterdir() if (p / f"{p.name}.yaml").is_file()) if d.is_dir() else []
    return (*own, *EXTRA_MODELS)


def file_label(path) -> str:
    """A machine-independent name for a model file: relative to the checkout, example-robot-data or pybullet_data."""
    p = Path(path).resolve()
    roots = [("example-robot-data:", robots_dir())]
    try:
        roots.append(("pybullet_data:", _pybullet_data().resolve()))
    except ImportError:  # pragma: no cover - a test extra
        pass
    roots.append(("", repo_root()))  # last: the virtual environment may lie inside the checkout
    for prefix, root in roots:
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
