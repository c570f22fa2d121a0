"""SRDF files (MoveIt's format): groups, disabled pairs and named states.

Only what armguard uses is read: ``<group>`` (with ``<chain base_link tip_link>`` or
``<link name>`` members), ``<disable_collisions link1 link2 reason>`` and
``<group_state name group>`` with ``<joint name value>``.  Every problem raises a
:class:`~armguard.SceneFileError` naming the file and the element.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from .._errors import SceneFileError

__all__ = ["Srdf", "SrdfGroup", "read_srdf", "HOME_STATES"]

HOME_STATES = ("home", "default", "ready")
"""Names of the SRDF group state taken as an arm's home, in order of preference."""


@dataclass(frozen=True)
class SrdfGroup:
    """One ``<group>``: its chains ``(base_link, tip_link)`` and its listed links."""

    name: str
    chains: tuple[tuple[str, str], ...] = ()
    links: tuple[str, ...] = ()


@dataclass(frozen=True)
class Srdf:
    """The parts of an SRDF armguard uses; ``file`` names it in error messages."""

    file: str
    groups: dict[str, SrdfGroup] = field(default_factory=dict)
    disabled: tuple[tuple[str, str, str], ...] = ()  # (link1, link2, reason)
    states: dict[tuple[str, str], dict[str, float]] = field(default_factory=dict)  # (state, group) -> joint -> value

    @property
    def arm_groups(self) -> tuple[SrdfGroup, ...]:
        """The groups with a chain: each is one arm (a robot of the scene)."""
        return tuple(g for g in self.groups.values() if g.chains)

    def home(self, group: str) -> dict[str, float] | None:
        """The joint values of ``group``'s home: the state named home, default or ready (in that order) of
        that group, else of any group (a state of a group that contains the arm)."""
        for name in HOME_STATES:
            if (name, group) in self.states:
                return self.states[(name, group)]
        for name in HOME_STATES:
            for (state, _), values in self.states.items():
                if state == name:
                    return values
        return None

    def error(self, where: str, message: str) -> SceneFileError:
        return SceneFileError(self.file, where, message)


def _attr(el, key: str, srdf_file: str, where: str) -> str:
    v = el.get(key)
    if not v:
        raise SceneFileError(srdf_file, where, f"expected attribute {key!r}")
    return v


def read_srdf(path) -> Srdf:
    """Parse ``path``; a missing file or malformed XML is a :class:`SceneFileError`."""
    path = Path(path)
    f = str(path)
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise SceneFileError(f, "", "SRDF file not found") from None
    except IsADirectoryError:
        raise SceneFileError(f, "", "is a directory; expected an SRDF file") from None
    except PermissionError as exc:
        raise SceneFileError(f, "", f"cannot read the SRDF file ({exc.strerror})") from None
    except ET.ParseError as exc:
        raise SceneFileError(f, f"line {exc.position[0]}", f"not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise SceneFileError(f, root.tag, "expected a <robot> root element (an SRDF file)")
    groups: dict[str, SrdfGroup] = {}
    for k, g in enumerate(root.findall("group")):  # top level: nested <group name/> are references
        w = f"group[{k}]"
        name = _attr(g, "name", f, w)
        chains = tuple((_attr(c, "base_link", f, f"{w} ({name}).chain"), _attr(c, "tip_link", f, f"{w} ({name}).chain"))
                       for c in g.findall("chain"))
        links = tuple(_attr(ln, "name", f, f"{w} ({name}).link") for ln in g.findall("link"))
        if name in groups:
            raise SceneFileError(f, w, f"group {name!r} is defined twice")
        groups[name] = SrdfGroup(name, chains, links)
    disabled = []
    for k, el in enumerate(root.iter("disable_collisions")):
        w = f"disable_collisions[{k}]"
        disabled.append((_attr(el, "link1", f, w), _attr(el, "link2", f, w), el.get("reason", "")))
    states: dict[tuple[str, str], dict[str, float]] = {}
    for k, st in enumerate(root.iter("group_state")):
        w = f"group_state[{k}]"
        key = (_attr(st, "name", f, w), _attr(st, "group", f, w))
        values = {}
        for i, j in enumerate(st.findall("joint")):
            jn = _attr(j, "name", f, f"{w}.joint[{i}]")
            try:
                x = float(_attr(j, "value", f, f"{w}.joint[{i}]"))
            except ValueError:
                raise SceneFileError(f, f"{w}.joint[{i}] ({jn})", f"value: expected a number, got {j.get('value')!r}") from None
            if not math.isfinite(x):
                raise SceneFileError(f, f"{w}.joint[{i}] ({jn})", f"value: must be finite, got {x}")
            values[jn] = x
        states[key] = values
    return Srdf(f, groups, tuple(disabled), states)
