"""Functions a lower layer calls and a higher one provides: the package root fills them in.

The layers import only downwards (``pyproject.toml``, ``docs/architecture.md``).  Where a lower
package offers an entry point whose work is done above it, it calls the function held here, and
``armguard/__init__`` (the composition root, in no layer) sets it to one that imports the upper
module when first called (so ``import armguard`` stays fast):

* ``read_robot_urdf(path, *, name, X_WB, load_collision, mesh_dir)``: ``Robot.from_urdf``
  (:mod:`armguard.kinematics`) reads a URDF through Pinocchio with :mod:`armguard.model`
  (:func:`armguard.model._robot_urdf.robot_from_urdf`).
"""

from __future__ import annotations

from ._errors import ArmguardError

__all__ = ["read_robot_urdf"]


def read_robot_urdf(*args, **kwargs):  # pragma: no cover - replaced by armguard/__init__
    raise ArmguardError("Robot.from_urdf: no URDF reader is set (armguard/__init__ sets it)")
