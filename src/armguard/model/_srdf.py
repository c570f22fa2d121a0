"""SRDF files (MoveIt's format): groups, disabled pairs and named states.

Only what armguard uses is read: ``<group>`` (with ``<chain base_link tip_link>`` or
``<link name>`` members), ``<disable_collisions link1 link2 reason>``, ``<group_state name
group>`` with ``<joint name value>`` and the names of ``<virtual_joint>``.  A file that does not
parse, or an element without a name armguard needs, raises a :class:`~armguard.SceneFileError`
naming the file and the element.  Where Pinocchio reads an SRDF leniently, so does armguard, with a
warning naming the element: a ``group_state`` without ``group`` (a state of the whole robot);
in the state taken as home, a value for a joint that no value moves (the SRDF's virtual joint, a
floating base's 7 values for a joint the URDF lacks, a fixed joint of the URDF: armguard's models
are fixed-base); a chain group whose links the URDF lacks, whose tip is not below its base or
whose base a joint moves (the group is then not an arm; Pinocchio reads no groups).
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from .._errors import ArmguardWarning, SceneFileError, xml_parse_error

NO_SRDF = "none"
"""An SRDF path of a model sidecar (``model.srdf``) or a scene file's URDF robot (``robots[i].srdf``) that
means no SRDF at all, not even one found beside the URDF: the URDF alone."""

__all__ = ["Srdf", "SrdfGroup", "read_srdf", "read_srdf_disabled", "HOME_STATES", "renamed_to"]

HOME_STATES = ("home", "default", "ready")
"""Names of the SRDF group state taken as an arm's home, in order of preference (else the first state)."""


@dataclass(frozen=True)
class SrdfGroup:
    """One ``<group>``: its chains ``(base_link, tip_link)`` and its listed links."""

    name: str
    chains: tuple[tuple[str, str], ...] = ()
    links: tuple[str, ...] = ()
    where: str = ""
    joints: tuple[str, ...] = ()  # <joint name> members
    subgroups: tuple[str, ...] = ()  # <group name> references


@dataclass(frozen=True)
class SrdfState:
    """One ``<group_state>``: ``values`` joint -> its value(s) (one float, or a tuple for a
    multi-value joint such as a floating base); ``where`` names the element, ``joint_where``
    each ``<joint>`` element."""

    name: str
    group: str  # "" when the element has no group attribute (a state of the whole robot)
    values: dict
    where: str
    joint_where: dict


@dataclass
class Srdf:
    """The parts of an SRDF armguard uses; ``file`` names it in error messages.

    ``found`` says how the file was chosen (``docs/models.md``, "Finding the SRDF"); ``partial``
    is True when it was found under the robot's name rather than the URDF's file name, so it may
    describe a larger robot than the URDF (links and joints it names that the URDF lacks are then
    skipped with a warning instead of refused); ``warnings`` the lenient readings."""

    file: str
    groups: dict[str, SrdfGroup] = field(default_factory=dict)
    disabled: tuple[tuple[str, str, str], ...] = ()  # (link1, link2, reason)
    states: tuple[SrdfState, ...] = ()
    found: str = "given"
    partial: bool = False
    warnings: tuple[str, ...] = ()
    virtual_joints: tuple[str, ...] = ()  # <virtual_joint name>: the robot's placement in the world, not a URDF joint
    end_effector_groups: tuple[str, ...] = ()  # the groups <end_effector group=...> names: a hand, never an arm's name

    @property
    def arm_groups(self) -> tuple[SrdfGroup, ...]:
        """The groups with a chain (in file order); ``_from_pin`` makes the outermost of them arms."""
        return tuple(g for g in self.groups.values() if g.chains)

    def home_state(self, group: str) -> SrdfState | None:
        """``group``'s home: its state named home, default or ready (in that order), else such a
        state of any group (a group that contains the arm, or a state without a group), else the
        group's first state, else the file's first state; None when the file has no state."""
        for name in HOME_STATES:
            for st in self.states:
                if st.name == name and st.group == group:
                    return st
        for name in HOME_STATES:
            for st in self.states:
                if st.name == name:
                    return st
        for st in self.states:
            if st.group == group:
                return st
        return self.states[0] if self.states else None

    def home(self, group: str) -> dict | None:
        """The joint values of :meth:`home_state` (None when the file has no state)."""
        st = self.home_state(group)
        return None if st is None else st.values

    def names(self) -> set:
        """Every link, joint and group name the SRDF's elements give (pairs, groups, states)."""
        out = {x for a, b, _ in self.disabled for x in (a, b)} | set(self.groups) | set(self.virtual_joints)
        for g in self.groups.values():
            out |= {x for c in g.chains for x in c} | set(g.links) | set(g.joints) | set(g.subgroups)
        for st in self.states:
            out |= set(st.values) | ({st.group} if st.group else set())
        return out

    def error(self, where: str, message: str) -> SceneFileError:
        return SceneFileError(self.file, where, message)

    def warn(self, message: str) -> None:
        """Record (``warnings``) and emit one lenient reading, naming the file (once per message)."""
        if message in self.warnings:
            return
        self.warnings = (*self.warnings, message)
        warnings.warn(f"{self.file}: {message}", ArmguardWarning, stacklevel=3)


def renamed_to(missing: str, pool, named) -> str | None:
    """The name ``missing`` (an SRDF name the URDF lacks) was likely renamed to: the closest of ``pool``
    (the URDF's names of that kind; for a pair's link, its links with shapes) that the SRDF never names
    (``named``), or None.  ``load_model``'s error and ``check-urdf``'s srdf-name finding both ask this."""
    import difflib

    near = difflib.get_close_matches(str(missing), [str(x) for x in pool if x and x not in named], n=1, cutoff=0.6)
    return near[0] if near else None


def _attr(el, key: str, srdf_file: str, where: str) -> str:
    v = el.get(key)
    if not v:
        raise SceneFileError(srdf_file, where, f"expected attribute {key!r}")
    return v


def _value(text: str, f: str, where: str):
    """One float, or a tuple of floats for a multi-value joint (``"0 0 1 0 0 0 1"``)."""
    try:
        xs = tuple(float(t) for t in text.split())
    except ValueError:
        raise SceneFileError(f, where, f"value: expected a number, got {text!r}") from None
    if not xs:
        raise SceneFileError(f, where, "value: expected a number, got nothing")
    bad = [x for x in xs if not math.isfinite(x)]
    if bad:
        raise SceneFileError(f, where, f"value: must be finite, got {bad[0]}")
    return xs[0] if len(xs) == 1 else xs


_SRDF_READ = {"robot": ("group", "group_state", "end_effector", "virtual_joint", "passive_joint", "disable_collisions",
                         "enable_collisions", "disable_default_collisions", "link_sphere_approximations", "joint_property"),
              "group": ("link", "joint", "chain", "group"), "group_state": ("joint",)}


def _misspelt(root, f: str) -> None:
    """An element that nothing reads but that looks like one that is (``<group_sate>``: the home pose then all
    zeros; ``<disable_colisions>``: the pair checked after all) is refused, as a URDF's ``<colision>`` is: the
    file would give another model than the one written.  Unrelated elements (a tool's own) are left alone."""
    import difflib

    def scan(el, kind: str, where: str) -> None:
        for k, c in enumerate(x for x in el if isinstance(x.tag, str)):
            if c.tag not in _SRDF_READ[kind]:
                near = difflib.get_close_matches(c.tag, _SRDF_READ[kind], n=1, cutoff=0.75)
                if near:
                    raise SceneFileError(f, f"{where}<{c.tag}> (child {k + 1})", f"<{c.tag}> is read by nothing: did you "
                                         f"mean <{near[0]}>? (it would give another model than the one written)")
            elif c.tag in _SRDF_READ and kind == "robot":
                scan(c, c.tag, f"{c.tag}[{c.get('name', '')}].")

    scan(root, "robot", "")


def read_srdf(path, *, found: str = "given", partial: bool = False) -> Srdf:
    """Parse ``path``; a missing file or malformed XML is a :class:`SceneFileError`."""
    path = Path(path)
    f = str(path)
    if path.is_dir():
        raise SceneFileError(f, "", "expected an SRDF file, got a directory")
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise SceneFileError(f, "", "SRDF file not found") from None
    except IsADirectoryError:
        raise SceneFileError(f, "", "is a directory; expected an SRDF file") from None
    except PermissionError as exc:
        raise SceneFileError(f, "", f"cannot read the SRDF file ({exc.strerror})") from None
    except ET.ParseError as exc:
        raise xml_parse_error(f, exc) from None
    if root.tag != "robot":
        raise SceneFileError(f, root.tag, "expected a <robot> root element (an SRDF file)")
    urdf = [t for t in ("link", "joint", "transmission", "gazebo") if root.find(t) is not None]
    if urdf:  # a URDF given as the SRDF: it would read as an SRDF that disables nothing
        raise SceneFileError(f, f"{urdf[0]}[0]", f"a URDF element <{urdf[0]}> at the top level: this is a URDF, not an "
                             "SRDF (an SRDF holds group, group_state, end_effector, virtual_joint, passive_joint, "
                             "disable_collisions)")
    _misspelt(root, f)
    out = Srdf(f, found=found, partial=partial)
    groups: dict[str, SrdfGroup] = {}
    for k, g in enumerate(root.findall("group")):  # top level: nested <group name/> are references
        w = f"group[{k}]"
        name = _attr(g, "name", f, w)
        chains = tuple((_attr(c, "base_link", f, f"{w} ({name}).chain"), _attr(c, "tip_link", f, f"{w} ({name}).chain"))
                       for c in g.findall("chain"))
        links = tuple(_attr(ln, "name", f, f"{w} ({name}).link") for ln in g.findall("link"))
        joints = tuple(_attr(j, "name", f, f"{w} ({name}).joint") for j in g.findall("joint"))
        subs = tuple(_attr(sg, "name", f, f"{w} ({name}).group") for sg in g.findall("group"))
        if name in groups:
            raise SceneFileError(f, w, f"group {name!r} is defined twice")
        groups[name] = SrdfGroup(name, chains, links, f"{w} ({name})", joints, subs)
    disabled = []
    for k, el in enumerate(root.iter("disable_collisions")):
        w = f"disable_collisions[{k}]"
        disabled.append((_attr(el, "link1", f, w), _attr(el, "link2", f, w), el.get("reason", "")))
    states: list[SrdfState] = []
    for k, st in enumerate(root.iter("group_state")):
        name = _attr(st, "name", f, f"group_state[{k}]")
        w = f"group_state[{k}] ({name})"
        group = st.get("group") or ""
        if not group:
            out.warn(f"{w}: no attribute 'group'; read as a state of the whole robot (as Pinocchio does)")
        values, jw = {}, {}
        for i, j in enumerate(st.findall("joint")):
            jn = _attr(j, "name", f, f"{w}.joint[{i}]")
            where = f"{w}.joint[{i}] ({jn})"
            if jn in values:
                raise SceneFileError(f, where, f"joint {jn!r} is given twice in this state")
            values[jn] = _value(_attr(j, "value", f, f"{w}.joint[{i}]"), f, where)
            jw[jn] = where
        if any(s.name == name and s.group == group for s in states):
            raise SceneFileError(f, w, f"state {name!r} of group {group!r} is defined twice")
        states.append(SrdfState(name, group, values, w, jw))
    out.groups, out.disabled, out.states = groups, tuple(disabled), tuple(states)
    out.virtual_joints = tuple(_attr(vj, "name", f, f"virtual_joint[{k}]") for k, vj in enumerate(root.findall("virtual_joint")))
    out.end_effector_groups = tuple(ee.get("group") for ee in root.findall("end_effector") if ee.get("group"))
    return out


def _renamed(s, names: dict, found: str, *, disabled: bool = True):
    """``s`` with its joints and links renamed by ``names`` (a name with no counterpart kept)."""
    import dataclasses

    n = lambda x: names.get(x, x)  # noqa: E731
    groups = {g: dataclasses.replace(grp, chains=tuple((n(a), n(b)) for a, b in grp.chains),
                                     links=tuple(n(x) for x in grp.links), joints=tuple(n(x) for x in grp.joints))
              for g, grp in s.groups.items()}
    states = tuple(dataclasses.replace(st, values={n(j): v for j, v in st.values.items()},
                                       joint_where={n(j): w for j, w in st.joint_where.items()}) for st in s.states)
    pairs = tuple((n(a), n(b), r) for a, b, r in s.disabled) if disabled else ()
    return dataclasses.replace(s, groups=groups, states=states, disabled=pairs, found=found)


def _pin_to_scene(m) -> dict:
    """Model ``m``'s Pinocchio joint and link names -> its scene's (``"robot/joint"``, ``"robot/link"``)."""
    pm = m.pin_model
    by_iq = {pm.joints[j].idx_q: pm.names[j] for j in range(1, pm.njoints) if pm.joints[j].nq > 0}
    names = {by_iq[int(m.q_index[k])]: sn for k, sn in enumerate(m.scene.joint_names)}
    names.update({pm.frames[f].name: owner for owner, f in m.link_frames.items()})
    return names


def carry_srdf(old, new):
    """The SRDF of Model ``old`` in the names of Model ``new``, built from the same scene after
    ``set_robot_base`` or ``add_robot`` (its URDF is the scene written out, so joints and links are
    renamed): joints are matched through the scene's joint names, links through ``link_frames``;
    a name with no counterpart is kept as it was.  ``found`` says where the groups came from."""
    def by_iq(m):
        pm = m.pin_model
        return {pm.joints[j].idx_q: pm.names[j] for j in range(1, pm.njoints) if pm.joints[j].nq > 0}

    old_iq, new_iq = by_iq(old), by_iq(new)
    old_scene = [f"{n}/{j}" for n, r in old._robots for j in r.joint_names]  # the Model's own robots (the scene may have more)
    new_pos = {sn: k for k, sn in enumerate(new.scene.joint_names)}
    names = {}
    for k, sn in enumerate(old_scene):
        if sn in new_pos:
            names[old_iq[int(old.q_index[k])]] = new_iq[int(new.q_index[new_pos[sn]])]
    for owner, f_old in old.link_frames.items():
        f_new = new.link_frames.get(owner)
        if f_new is not None:
            names[old.pin_model.frames[f_old].name] = new.pin_model.frames[f_new].name
    return _renamed(old.srdf, names, f"carried over from the model before the scene's robots changed ({old.srdf.found})")


def scene_srdf(model, name: str):
    """The groups and states of the SRDF of ``model`` (a Model of one arm's URDF) in scene names, its
    arm called ``name`` (``"name/joint"``, ``"name/link"``), for a scene file's robot: None without
    groups.  Its disabled pairs are left out (the scene file applies them itself)."""
    if model.srdf is None or not model.srdf.groups:
        return None
    old = next(iter(model.scene.robots))
    names = {pin: f"{name}/{sn.split('/', 1)[1]}" if sn.startswith(f"{old}/") else sn
             for pin, sn in _pin_to_scene(model).items()}
    return _renamed(model.srdf, names, model.srdf.found, disabled=False)


def srdf_of_scene(srdfs: dict, model):
    """One Srdf of the scene-named ``srdfs`` (robot -> :func:`scene_srdf`'s) in the names of ``model``
    (the Model of the scene written out): each robot's groups under their own names, or as
    ``"robot/group"`` where two robots' SRDFs name a group alike; None when there is none."""
    import dataclasses

    if not srdfs:
        return None
    back = {v: k for k, v in _pin_to_scene(model).items()}
    count: dict = {}
    for s in srdfs.values():
        for g in s.groups:
            count[g] = count.get(g, 0) + 1
    groups, states = {}, []
    for robot, s in srdfs.items():
        r = _renamed(s, back, s.found, disabled=False)
        named = {g: (g if count[g] == 1 else f"{robot}/{g}") for g in r.groups}
        for g, grp in r.groups.items():
            groups[named[g]] = dataclasses.replace(grp, name=named[g], subgroups=tuple(named.get(x, x) for x in grp.subgroups))
        states += [dataclasses.replace(st, group=named.get(st.group, st.group)) for st in r.states]
    first = next(iter(srdfs.values()))
    files = sorted({s.file for s in srdfs.values()})
    return dataclasses.replace(first, file=files[0] if len(files) == 1 else ", ".join(files), groups=groups,
                               states=tuple(states), disabled=(), partial=False,
                               found=f"the SRDF{'s' if len(files) > 1 else ''} of the scene file's URDF robots")


def read_srdf_disabled(path) -> list[tuple[str, str]]:
    """The ``<disable_collisions link1=... link2=...>`` pairs of an SRDF file (MoveIt's format)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise SceneFileError(str(path), "", "SRDF file not found") from None
    except IsADirectoryError:
        raise SceneFileError(str(path), "", "is a directory; expected an SRDF file") from None
    except ET.ParseError as exc:
        raise xml_parse_error(path, exc) from None
    out = []
    for k, el in enumerate(root.iter("disable_collisions")):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise SceneFileError(str(path), f"disable_collisions[{k}]", "expected attributes link1 and link2")
        out.append((a, b))
    return out


def reshaped_pairs(robot, pairs, reshaped: set, where: str) -> list:
    """``pairs`` (an SRDF's disabled ``(link, link)``) less those of a link in ``reshaped`` (given other shapes
    than the URDF's: a scene file's ``link_shapes``) but for a link and its parent (MoveIt's Adjacent, disabled
    whatever the shapes): a Never was proved, or sampled, for the URDF's shapes (a 0.3 m sphere given to a link
    certified apart from another stayed unchecked, 0.14 m deep in it).  The pairs dropped are warned of at ``where``."""
    keep, dropped = [], []
    for a, b in pairs:
        adjacent = robot.parent_link(a) == b or robot.parent_link(b) == a
        (keep if adjacent or not ({a, b} & reshaped) else dropped).append((a, b))
    if dropped:
        warnings.warn(f"{where}: the robot's SRDF disables {len(dropped)} pair(s) of a link given other shapes here, "
                      f"judged for the URDF's shapes: checked after all: {', '.join(f'{a}-{b}' for a, b in dropped)}",
                      ArmguardWarning, stacklevel=3)
    return keep
