"""Models of record: URDF (+ SRDF) files loaded by Pinocchio, with armguard's scene extras.

``load_model(name_or_path)`` -> :class:`Model` (``pin_model``, ``collision_model``, the active
pairs with their categories, the scene the analytic backend compiles).  The file convention
of ``urdf/<system>/`` is ``docs/models.md``; the public robots loadable by name (example-robot-data,
pybullet_data) are ``known_models()``.

The front ends that build a Model live here too: URDF/SRDF through Pinocchio (``_urdf``,
``_srdf``, ``_from_pin``), YAML scene files (``_scenefile``, ``_schema``, ``_yaml``) and the
Scene the Model holds (``_scene``, ``_items``, ``_compile``, ``_save``; :mod:`armguard.scene`
hands these on, one layer up, with its loaders).  See ``docs/architecture.md``.
"""

from ._load import builtin_model_names, kinematics_of, load_model, model_from_scene, model_of, models_dir
from ._model import WORKSPACE, GeometryPairs, Model, scene_of
from ._public import known_models, public_robot_files, public_robot_names

__all__ = ["load_model", "model_of", "kinematics_of", "scene_of", "model_from_scene", "Model", "GeometryPairs", "WORKSPACE", "models_dir", "builtin_model_names",
           "known_models", "public_robot_names", "public_robot_files"]
