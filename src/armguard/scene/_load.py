"""The scene loaders: a built-in name, a YAML scene file or a URDF into a Scene.

A built-in, a URDF and a model sidecar are loaded as a :class:`~armguard.model.Model` (through
Pinocchio) and its scene returned; a plain scene file (robots from DH tables, bodies as shapes)
is read by the YAML front end (:mod:`armguard.model._scenefile`).  These sit above
:mod:`armguard.model` (the layers: ``docs/architecture.md``).
"""

from __future__ import annotations

from pathlib import Path

from .._lines import lines_for
from ..model import load_model
from ..model._load import model_from_scenefile
from ..model._scene import Scene
from ..model._scenefile import read_scene_yaml, scene_from_dict_validated, validate_scene_dict

__all__ = ["load_scene", "load_scene_file", "scene_from_dict", "scene_from_urdf"]


def scene_from_dict(data, file: str = "<dict>", base: Path | None = None) -> Scene:
    """Validate ``data`` (a parsed scene file) and build the Scene; errors name ``file``.

    A model sidecar (``model: {urdf: ...}``) is loaded through Pinocchio (:func:`armguard.load_model`).
    """
    sf = validate_scene_dict(data, file)
    if sf.model is not None:
        return model_from_scenefile(sf, file, base or Path.cwd()).scene
    return scene_from_dict_validated(sf, file, base)


def load_scene_file(path) -> Scene:
    """Load a YAML scene file (``armguard_scene: 1``)."""
    path = Path(path)
    with lines_for(path):
        return scene_from_dict(read_scene_yaml(path), str(path), path.parent)


def scene_from_urdf(path, *, srdf=None) -> Scene:
    """The scene of a URDF file (and the SRDF beside it, or ``srdf``), loaded through Pinocchio."""
    return load_model(path, srdf=srdf).scene


def load_scene(name_or_path) -> Scene:
    """A Scene from a built-in name (``"hermes"``), a public robot's name (``"ur10"``, see
    :func:`armguard.model.load_model`), a ``.yaml`` / ``.yml`` scene file or a ``.urdf`` file."""
    s = str(name_or_path)
    p = Path(s)
    if p.suffix.lower() in (".yaml", ".yml"):
        return load_scene_file(p)
    if p.suffix.lower() == ".urdf":
        return scene_from_urdf(p)
    # a built-in (urdf/<name>/: the URDF, SRDF and sidecar) or a public robot, through Pinocchio; anything
    # else: load_model's error (the known names; a xacro file's way out)
    return load_model(name_or_path).scene
