"""The scene: robots among static bodies, payloads, workspace box, pair filters, canned tests.

Load one with :func:`load_scene` (a built-in name, a ``.yaml`` scene file or a ``.urdf``),
build one in Python with :class:`Scene`, save it with :func:`save_scene`, and flatten it for
the kernels with :func:`compile_scene`.  ``docs/scene-format.md`` describes the file format.
"""

from ._compile import PAIR_CATEGORIES, CompiledScene, compile_scene
from ._load import load_scene, load_scene_file, read_srdf_disabled, scene_from_dict, scene_from_urdf
from ._save import save_scene, scene_to_dict
from ._scene import (
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
