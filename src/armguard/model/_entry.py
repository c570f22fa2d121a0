"""What an entry point does with what it is given: :func:`scene_of` (the scene a Model answers for),
:func:`warn_edited` (said when ``model.scene`` was edited after the Model was made: the edit is not
in what is built on the Model), :func:`unknown_robots_text` (a configuration mapping that names no robot)."""

from __future__ import annotations

import sys
import warnings

__all__ = ["scene_of", "warn_edited", "unknown_robots_text"]


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside armguard and its plugins (modules ``armguard``,
    ``armguard.*``, ``armguard_*``), for a ``warnings.warn`` in the function that calls this one: the
    user's line, whichever entry point (and wrapper) led there."""
    f, level = sys._getframe(2), 2  # 1: the caller's warn; 2: its caller
    while f is not None and f.f_globals.get("__name__", "").partition(".")[0].startswith("armguard"):
        f, level = f.f_back, level + 1
    return level


def warn_edited(model, what: str) -> None:
    """Warn, when ``model.scene`` was edited after ``model`` was made (``model.scene.add_body(...)``), that
    ``what`` (a checker, a Detector, a Verifier...) answers for the Model as made, without the edit: a
    new obstacle added to ``model.scene`` is not seen by it."""
    if model.is_model_of(model.scene):
        return
    from .._errors import ArmguardWarning

    warnings.warn(f"model {model.name!r}: its scene was edited after the Model was made (a body, payload, filter or "
                  f"base changed); this {what} answers for the Model as made, without the edit. The Model of the "
                  "edited scene is armguard.model.model_of(model.scene) (or give the scene itself); a Model edits "
                  "itself with model.with_body(...) and the other with_* methods", ArmguardWarning, stacklevel=_caller_level())


def scene_of(scene_or_model, what: str = "result"):
    """The Scene of an entry point's first argument (every function and class that takes a scene
    takes a Model as well): a Scene as given; for a :class:`Model`, a scene whose Model it is
    (:meth:`Model.scene_for`): a copy of the system the Model holds, made once, so that what is built
    on a Model answers for that Model whatever ``model.scene`` does later (said, with
    :func:`warn_edited`, when ``model.scene`` was edited: ``what`` names what is built)."""
    if hasattr(scene_or_model, "pin_model") and hasattr(scene_or_model, "collision_model"):
        warn_edited(scene_or_model, what)
        return scene_or_model.scene_for()
    return scene_or_model


def unknown_robots_text(robots: dict, extra: list) -> str:
    """The error of a configuration mapping whose keys ``extra`` are not robots of ``robots`` (name -> Robot);
    joint names there (``{"panda/panda_joint1": 0.1, ...}``) are told the mapping's form."""
    joints = {j for r, rb in robots.items() for j in rb.joint_names} | {f"{r}/{j}" for r, rb in robots.items()
                                                                       for j in rb.joint_names}
    hint = (" (a mapping goes robot -> that robot's joint values; these are joint names: give a flat array in "
            "scene.joint_names order)") if set(extra) & joints else ""
    return f"q names unknown robots {extra[:4]}{' ...' if len(extra) > 4 else ''}; robots are {list(robots)}{hint}"
