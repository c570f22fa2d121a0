"""The scene: robots among static bodies, payloads, workspace box, pair filters, canned tests.

Load one with :func:`load_scene` (a built-in name, a ``.yaml`` scene file or a ``.urdf``),
build one in Python with :class:`Scene`, save it with :func:`save_scene`, and flatten it for
the kernels with :func:`compile_scene`.  ``docs/scene-format.md`` describes the file format.

The Scene and its parts, its YAML front end and ``compile_scene`` live in :mod:`armguard.model`
(the Model holds its Scene); this package hands them on and adds the loaders, which build a
Model (``docs/architecture.md``).
"""

from ..model._compile import PAIR_CATEGORIES, CompiledScene, compile_scene
from ..model._save import save_scene, scene_to_dict
from ..model._scene import (
    BODY_CATEGORIES,
    Body,
    CannedTest,
    CheckPair,
    PairCategory,
    Payload,
    Scene,
    SceneItem,
    WorkspaceBox,
)
from ..model._srdf import read_srdf_disabled
from ._load import load_scene, load_scene_file, scene_from_dict, scene_from_urdf

__all__ = [
    "Scene",
    "Body",
    "Payload",
    "SceneItem",
    "WorkspaceBox",
    "CheckPair",
    "PairCategory",
    "CannedTest",
    "BODY_CATEGORIES",
    "load_scene",
    "load_scene_file",
    "scene_from_dict",
    "scene_from_urdf",
    "read_srdf_disabled",
    "save_scene",
    "scene_to_dict",
    "compile_scene",
    "CompiledScene",
    "PAIR_CATEGORIES",
]
