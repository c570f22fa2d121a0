"""The built-in seed systems, as scene files in ``models/data/`` (loadable by name).

=============  ===================================================================  ======
name           what                                                                 seed
=============  ===================================================================  ======
``ranger``     Ranger vehicle modules, two 7-DOF dexterous arms, camera and         000
               grapple arms, workspace box, the ten canned tests
``hermes``     Hermes as 8 convex polyhedra (54 faces, 76 vertices), the 6-DOF      001
               HERA arm, a cylindrical payload, the listed link pairs
``puma560``    PUMA 560 (standard DH) in a WORKMATE-like cell: table, blocks,       004
               the two cylinders of the pick-and-place demonstration
``gmf_s480``   GMF S-480 with its parallelogram linkage (a coupled joint)           004
``rover``      a rover body with wheels and mast and a 5-DOF instrument arm         002
=============  ===================================================================  ======

``armguard.load_scene(name)`` loads one; :func:`builtin_path` gives its file.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["builtin_names", "builtin_path", "DATA_DIR"]

DATA_DIR = Path(__file__).resolve().parent / "data"
_NAMES = ("ranger", "hermes", "puma560", "gmf_s480", "rover")


def builtin_names() -> tuple[str, ...]:
    """The names of the built-in scenes."""
    return _NAMES


def builtin_path(name: str) -> Path | None:
    """The scene file of built-in ``name``, or None when there is no such built-in scene."""
    if name not in _NAMES:
        return None
    return DATA_DIR / f"{name}.yaml"
