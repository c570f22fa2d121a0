"""A Pinocchio model and GeometryModel as armguard's Scene: arms, static bodies, payloads.

The URDF link tree is read off Pinocchio's frames (each BODY frame is a URDF link; the frame
before it is its joint).  Arms are the SRDF's chain groups (``docs/models.md``): an arm ``R``
is the subtree below its chain's base link, with the ``R_`` prefix stripped from its link
and joint names.  Links fixed to the world outside every arm are static bodies; links in the
SRDF group ``payload`` are payloads held by the arm link they are fixed to.  Each
GeometryObject becomes one shape of its owner; ``geometry_names[(owner, i)]`` records which.
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import ArmguardError, SceneFileError
from .._tolerance import DEFAULT_TOLERANCES
from ._shapes import shape_from_coal, shape_of_polytope

__all__ = ["scene_parts_from_pin", "ScenePart"]

_SLACK = DEFAULT_TOLERANCES.joint_limit  # a home value this close outside its limits is read as on them

_REVOLUTE = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}
_CIRCULAR = {"JointModelRUBX": (1.0, 0.0, 0.0), "JointModelRUBY": (0.0, 1.0, 0.0), "JointModelRUBZ": (0.0, 0.0, 1.0)}
_PRISMATIC = {"JointModelPX": (1.0, 0.0, 0.0), "JointModelPY": (0.0, 1.0, 0.0), "JointModelPZ": (0.0, 0.0, 1.0)}


class ScenePart:
    """What the converter found: robots (with pin q indices), bodies, payloads, geometry names, notes."""

    def __init__(self) -> None:
        self.robots: list = []  # (Robot, home (n,) or None, q_index (n,) int into pin q)
        self.bodies: list = []  # (name, shapes in W, category)
        self.payloads: list = []  # (name, robot, link, shapes in P, X_LP)
        self.geometry_names: dict = {}  # (owner, i) -> GeometryObject name
        self.notes: dict = {}  # GeometryObject name -> representation note
        self.link_owner: dict = {}  # URDF link name -> owner name ("R/link", body or payload)
        self.circular: list = []  # per robot: its joints (indices into joint_names) that are continuous


def _se3(M) -> np.ndarray:
    return np.asarray(M.homogeneous, dtype=np.float64)


def _inv(X: np.ndarray) -> np.ndarray:
    Y = np.eye(4)
    Y[:3, :3] = X[:3, :3].T
    Y[:3, 3] = -X[:3, :3].T @ X[:3, 3]
    return Y


def _identity(X: np.ndarray) -> bool:
    return bool(np.allclose(X, np.eye(4), atol=1e-15, rtol=0.0))


def _strip(name: str, prefix: str) -> str:
    return name[len(prefix):] if prefix and name.startswith(prefix) else name


def scene_parts_from_pin(pin_model, geom_model, info, srdf, *, accelerations=None) -> ScenePart:
    """Convert (see the module docstring). ``accelerations``: joint -> rad/s² (or m/s²), the joint named as
    the scene names it (``"arm/joint"``) or by its URDF name."""
    import pinocchio as pin

    from ..kinematics import Coupling, JointSpec, JointType, Robot

    f = info.file
    frames = pin_model.frames
    FT = pin.FrameType
    body_ids = {fr.name: i for i, fr in enumerate(frames) if fr.type == FT.BODY}
    if "universe" in body_ids:  # pinocchio's own root is never a URDF link we own
        del body_ids["universe"]

    def parent_body(i: int):
        """The BODY frame above BODY frame ``i`` and the joint frame between them (None at the root)."""
        jf = frames[i].parentFrame
        if jf == 0 or jf == i:  # frame 0 is pinocchio's universe: i is the URDF's root link
            return None, None
        return frames[jf].parentFrame, jf

    children: dict[int, list[int]] = {}
    for name, i in body_ids.items():
        p, _ = parent_body(i)
        if p is not None:
            children.setdefault(p, []).append(i)

    def subtree(i: int, stop: set) -> list[int]:
        out, stack = [], [i]
        while stack:
            k = stack.pop()
            if k in stop and k != i:
                continue
            out.append(k)
            stack.extend(sorted(children.get(k, []), reverse=True))
        return out

    payload_links = set(srdf.groups["payload"].links) if srdf is not None and "payload" in srdf.groups else set()
    vehicle_links = set(srdf.groups["vehicle"].links) if srdf is not None and "vehicle" in srdf.groups else set()
    for ln in payload_links | vehicle_links:
        if ln not in body_ids:
            raise SceneFileError(srdf.file, "group payload/vehicle", f"names link {ln!r}, which the URDF {f} does not have")
    stop = {body_ids[ln] for ln in payload_links}

    # the arms: SRDF chain groups, or the whole movable tree as one robot named after the URDF
    arms = []
    if srdf is not None and srdf.arm_groups:
        arms = _arms_of_groups(srdf, body_ids, parent_body, f, lambda b: frames[b].parentJoint != 0, info.robot_name)
    if not arms and pin_model.njoints > 1:
        first = pin_model.frames[pin_model.getFrameId(pin_model.names[1], FT.JOINT)]
        root = first.parentFrame
        while True:  # climb to the topmost link fixed to the world on joint 1's branch
            p, _ = parent_body(root)
            if p is None or frames[p].name == "world":
                break
            root = p
        arms.append((info.robot_name, root, ""))
    movable = {pin_model.names[j] for j in range(1, pin_model.njoints)} | set(info.mimic)
    fixed = frozenset(j for j, t in info.joint_type.items() if t == "fixed")

    part = ScenePart()
    in_arm: set[int] = set()
    accelerations = accelerations or {}
    # arms keep the SRDF's group order (the scene's flat q order); Model.q_index maps to pinocchio's
    for rname, root, prefix in arms:
        links = subtree(root, stop)
        if frames[root].parentJoint != 0:  # (an SRDF chain's base a joint moves is not an arm: _arms_of_groups)
            raise SceneFileError(f, f"link[{frames[root].name}]", f"arm {rname!r}: its base link must be fixed to the world")
        in_arm.update(links)
        specs, jnames, q_index, circular = [], [], [], []
        for i in links[1:]:
            p, jf = parent_body(i)
            child, parent = _strip(frames[i].name, prefix), _strip(frames[p].name, prefix)
            J = frames[jf]
            Xp = _se3(frames[p].placement)
            jname = J.name
            if J.type == FT.JOINT:
                jid = J.parentJoint
                jm = pin_model.joints[jid]
                short = jm.shortname()
                X_pre = _inv(Xp) @ _se3(pin_model.jointPlacements[jid])
                X_post = _se3(frames[i].placement)
                coupling = None
                if short == "JointModelMimic":
                    if jname not in info.mimic:
                        raise SceneFileError(f, f"joint[{jname}]", "Pinocchio made it a mimic joint but the URDF has no <mimic>")
                    master, mult, off = info.mimic[jname]
                    coupling = Coupling(_strip(jname, prefix), {_strip(master, prefix): mult}, off)
                    axis = np.asarray(info.joint_axis.get(jname, (1.0, 0.0, 0.0)))
                    jt = JointType.PRISMATIC if info.joint_type.get(jname) == "prismatic" else JointType.REVOLUTE
                    lo = hi = None
                elif short in _REVOLUTE or short == "JointModelRevoluteUnaligned":
                    jt, axis = JointType.REVOLUTE, np.asarray(_REVOLUTE.get(short) or info.joint_axis[jname])
                elif short in _PRISMATIC or short == "JointModelPrismaticUnaligned":
                    jt, axis = JointType.PRISMATIC, np.asarray(_PRISMATIC.get(short) or info.joint_axis[jname])
                elif short in _CIRCULAR or short == "JointModelRevoluteUnboundedUnaligned":
                    # continuous: pinocchio's q holds (cos, sin); Model.scene_q turns it into an angle
                    jt, axis = JointType.REVOLUTE, np.asarray(_CIRCULAR.get(short) or info.joint_axis[jname])
                else:
                    raise SceneFileError(f, f"joint[{jname}]", f"joint type {short} is not supported (revolute, prismatic, "
                                         "continuous, fixed and mimic joints are)")
                axis = axis / np.linalg.norm(axis)
                if coupling is None:
                    iq, iv = jm.idx_q, jm.idx_v
                    lo, hi = float(pin_model.lowerPositionLimit[iq]), float(pin_model.upperPositionLimit[iq])
                    if jm.nq == 2:
                        lo, hi = -math.inf, math.inf
                        circular.append(len(jnames))
                    elif not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
                        raise SceneFileError(f, f"joint[{jname}]", f"limits [{lo}, {hi}]: expected finite lower <= upper")
                    vmax = float(pin_model.velocityLimit[iv])
                    jnames.append(_strip(jname, prefix))
                    q_index.append(iq)
                specs.append(JointSpec(
                    name=_strip(jname, prefix), joint_type=jt, parent=parent, child=child, X_pre=X_pre, axis=axis,
                    X_post=None if _identity(X_post) else X_post,
                    lower=-math.inf if lo is None else lo, upper=math.inf if hi is None else hi,
                    max_velocity=(vmax if coupling is None and vmax > 0 else math.inf),
                    max_acceleration=float(accelerations.get(f"{rname}/{_strip(jname, prefix)}", accelerations.get(jname, math.inf))),
                    coupling=coupling))
            else:
                X_pre = _inv(Xp) @ _se3(J.placement)
                X_post = _inv(_se3(J.placement)) @ _se3(frames[i].placement)
                specs.append(JointSpec(name=_strip(jname, prefix), joint_type=JointType.FIXED, parent=parent, child=child,
                                       X_pre=X_pre @ X_post))
        X_WB = _se3(frames[root].placement)
        try:
            robot = Robot(rname, _strip(frames[root].name, prefix), specs, joint_names=jnames, X_WB=X_WB)
        except Exception as exc:  # noqa: BLE001 - reported against the file
            raise SceneFileError(f, f"arm {rname!r}", str(exc)) from None
        home = None
        st = srdf.home_state(rname) if srdf is not None else None
        if st is not None:
            home = _home(srdf, st, robot, prefix, movable, f, fixed, info.mimic)
        part.robots.append((robot, home, np.asarray(q_index, dtype=np.int64)))
        part.circular.append(np.asarray(circular, dtype=np.int64))
        for k in links:
            part.link_owner[frames[k].name] = f"{rname}/{_strip(frames[k].name, prefix)}"
    # payloads and static bodies
    for ln in sorted(payload_links, key=lambda n: body_ids[n]):
        i = body_ids[ln]
        p, _ = parent_body(i)
        if p is None or p not in in_arm:
            raise SceneFileError(srdf.file, "group payload", f"payload link {ln!r} is not fixed to an arm link")
        owner = part.link_owner[frames[p].name]
        rname, link = owner.split("/", 1)
        if frames[p].parentJoint != frames[i].parentJoint:
            raise SceneFileError(f, f"link[{ln}]", "a payload link must be fixed (no joint between it and its arm link)")
        X_LP = _inv(_se3(frames[p].placement)) @ _se3(frames[i].placement)
        part.payloads.append([ln, rname, link, [], X_LP])
        part.link_owner[ln] = ln
    for ln, i in body_ids.items():
        if i in in_arm or ln in payload_links:
            continue
        if frames[i].parentJoint != 0:
            if any(prefix for _, _, prefix in arms):  # the SRDF's chain groups left it out: its element is at fault
                named = [srdf.groups[r] for r, _, p in arms if p]
                raise srdf.error(", ".join(f"{g.where}.chain" for g in named),
                                 f"link {ln!r} is moved by joint {pin_model.names[frames[i].parentJoint]!r} of the URDF "
                                 f"{f} but lies in no arm: the chain groups {[g.name for g in named]} do not reach it; "
                                 "add a chain group from a link fixed to the world above it")
            raise SceneFileError(f, f"link[{ln}]", "a link outside every arm (SRDF chain group) must be fixed to the world")
        part.link_owner[ln] = ln
    # shapes, in the owner's frame (W for bodies, the link frame for links, P for payloads)
    body_shapes: dict[str, list] = {}
    link_shapes: dict[str, dict[str, list]] = {r.name: {} for r, _, _ in part.robots}
    pay = {p[0]: p for p in part.payloads}
    hulls = getattr(info, "hulls", {})

    def shape_of(go_index, go, X):
        mp = hulls.get(go_index)  # a mesh's hull, merged once by load_pinocchio: moved, not rebuilt
        return (shape_of_polytope(mp, X), "") if mp is not None else shape_from_coal(go.geometry, X)

    for gi, go in enumerate(geom_model.geometryObjects):
        fr = frames[go.parentFrame]
        X_FG = _inv(_se3(fr.placement)) @ _se3(go.placement)
        owner = part.link_owner.get(fr.name)
        if owner is None:
            raise SceneFileError(f, f"link[{fr.name}]", "collision geometry on a link armguard could not place")
        k_local = sum(1 for g2 in geom_model.geometryObjects[:geom_model.getGeometryId(go.name)]
                      if g2.parentFrame == go.parentFrame)
        try:
            if fr.name in pay:
                shape, note = shape_of(gi, go, X_FG)
                lst = pay[fr.name][3]
            elif "/" in owner:
                shape, note = shape_of(gi, go, X_FG)
                r, ln = owner.split("/", 1)
                lst = link_shapes[r].setdefault(ln, [])
            else:
                shape, note = shape_of(gi, go, _se3(fr.placement) @ X_FG)
                lst = body_shapes.setdefault(owner, [])
        except ArmguardError as exc:
            raise SceneFileError(f, f"link[{fr.name}].collision[{k_local}]", str(exc)) from None
        part.geometry_names[(owner, len(lst))] = go.name
        if note:
            part.notes[go.name] = note
        lst.append(shape)
    part.robots = [(r.with_link_shapes({k: tuple(v) for k, v in link_shapes[r.name].items()}), h, qi)
                   for r, h, qi in part.robots]
    for name, shapes in body_shapes.items():
        part.bodies.append((name, shapes, "vehicle" if name in vehicle_links else "environment"))
    part.payloads = [tuple(p) for p in part.payloads if p[3]]
    return part


def _descends(i: int, ancestor: int, parent_body) -> bool:
    """Whether BODY frame ``i`` is ``ancestor`` or below it."""
    while i is not None:
        if i == ancestor:
            return True
        i, _ = parent_body(i)
    return False


def _arms_of_groups(srdf, body_ids: dict, parent_body, f: str, moved, robot_name: str) -> list:
    """``(name, base frame, prefix)`` of the arms of the SRDF's chain groups.

    Groups describe the robot; they never split it.  An arm is the whole subtree below its chain's
    base link, so a group whose base is another group's base or lies below it (MoveIt's
    ``panda_arm`` link0->link8 beside ``panda_arm_hand`` link0->hand, or a ``hand`` group) is part of
    that arm, not a second robot: the first group in file order of each outermost base names the arm,
    unless two groups from that base end on different branches (a1's four legs from its trunk,
    talos's legs from its pelvis), or that group is an ``<end_effector>``'s (kinova.srdf's one group, a
    chain from the base to the hand, is named ``end_effector``): then the arm is the robot, named as
    the URDF names it.
    A chain naming a link the URDF lacks is skipped with a warning naming the SRDF's element, as
    Pinocchio ignores it (z1.srdf's chain starts at a link ``base`` z1.urdf does not have), and so
    is a chain whose tip is not below its base (icub.srdf's legs from the chest) or whose base a
    joint moves (``moved(body)``: icub's arms from its chest; an arm is a tree fixed to the world):
    the shapes still move with their joints, as the remaining arms or the whole tree."""
    cand = []
    for g in srdf.arm_groups:
        base, tip = g.chains[0]
        missing = [ln for ln in (base, tip) if ln not in body_ids]
        if missing:
            srdf.warn(f"{g.where}.chain: names link {missing[0]!r}, which the URDF {f} does not have; "
                      "the group is not an arm")
            continue
        if not _descends(body_ids[tip], body_ids[base], parent_body):  # icub.srdf's l_leg: chest -> l_sole
            srdf.warn(f"{g.where}.chain: tip link {tip!r} is not below base link {base!r} in the URDF {f}; "
                      "the group is not an arm")
            continue
        if moved(body_ids[base]):
            srdf.warn(f"{g.where}.chain: base link {base!r} is moved by a joint in the URDF {f}; the group is not an "
                      "arm (an arm's base is fixed to the world)")
            continue
        cand.append((g, body_ids[base]))
    arms, bases = [], set()
    for g, b in cand:
        if b in bases or any(b2 != b and _descends(b, b2, parent_body) for _, b2 in cand):
            continue  # inside an arm another group already names
        bases.add(b)
        tips = [body_ids[g2.chains[0][1]] for g2, b2 in cand if b2 == b]
        if any(not _descends(t1, t2, parent_body) and not _descends(t2, t1, parent_body) for t1 in tips for t2 in tips):
            arms.append((robot_name, b, ""))  # limbs from one base (a1's legs from the trunk): the robot, not one limb
        elif g.name in srdf.end_effector_groups:  # kinova.srdf's one group, the <end_effector>'s: the arm was named
            # 'end_effector' (a trajectory's 'robot: kinova' was refused); its links keep the group's prefix rule
            arms.append((robot_name, b, f"{g.name}_"))
        else:
            arms.append((g.name, b, f"{g.name}_"))
    return arms


def _home(srdf, st, robot, prefix: str, movable: set, f: str, fixed: frozenset, mimic=None) -> np.ndarray:
    """The home of ``robot`` from SRDF state ``st``; a joint the URDF lacks (unless the SRDF is
    ``partial``), a multi-value for a one-value joint, or a value outside the joint's limits is an
    error naming the state's ``<joint>`` element in the SRDF.  A revolute joint's value that lies
    in the limits after a whole turn (kinova.srdf: -1.5707 for a joint limited to [0.33, 5.95])
    is that angle, the same pose, with a warning.  A value no joint of the model takes is skipped
    with a warning naming the element: the SRDF's virtual joint or a floating base's pose (7 values)
    for a joint the URDF lacks (Pinocchio's free-flyer ``root_joint``: the legged robots' SRDFs;
    armguard's models are fixed-base), a joint of ``fixed`` (the URDF's fixed joints: finger_edu,
    the flying arms), or a joint of ``mimic`` (its value follows its leader's)."""
    from ..kinematics import JointType

    def skipped(jn, v) -> str:  # why the value of ``jn`` is not read ("": it is)
        if jn in (mimic or {}):
            lead, mult, off = mimic[jn]
            return (f"a mimic joint of the URDF {f}: its value follows joint {lead!r} ({off:g} + {mult:g} x its value), "
                    "whatever the state says")
        if jn in movable:
            return ""
        if jn in srdf.virtual_joints or (jn not in fixed and isinstance(v, tuple) and len(v) == 7):
            return "the robot's placement in the world (a floating base): armguard's models are fixed-base"
        return f"a fixed joint of the URDF {f}: no value moves it" if jn in fixed else ""

    skip = {jn: why for jn, v in st.values.items() if (why := skipped(jn, v))}
    for jn, why in skip.items():
        srdf.warn(f"{st.joint_where[jn]}: value not read, {why}")
    unknown = [jn for jn in st.values if jn not in movable and jn not in skip]
    if unknown and not srdf.partial:
        jn = unknown[0]
        raise srdf.error(st.joint_where[jn], f"names joint {jn!r}, which is not a movable joint of the URDF {f} "
                         f"(its movable joints are {sorted(movable)})")
    if unknown:  # an SRDF of a larger robot (Srdf.warn says it once)
        srdf.warn(f"{st.where}: {len(unknown)} joints the URDF {f} does not have were skipped (first: {unknown[0]!r})")
    out = []
    for j, jt, lo, hi in zip(robot.joint_names, robot.joint_types, robot.lower, robot.upper):
        key = prefix + j if prefix + j in st.values else j
        if key not in st.values:
            out.append(min(max(0.0, lo), hi))
            continue
        v, where = st.values[key], st.joint_where[key]
        if isinstance(v, tuple):
            raise srdf.error(where, f"expected one value for joint {key!r}, got {len(v)}")
        if not (lo - _SLACK <= v <= hi + _SLACK) and jt is JointType.REVOLUTE:
            turned = v + 2.0 * math.pi * math.ceil((lo - _SLACK - v) / (2.0 * math.pi))  # the first turn >= lo
            if lo - _SLACK <= turned <= hi + _SLACK:
                srdf.warn(f"{where}: value {v:.10g} is outside the limits [{lo:.10g}, {hi:.10g}] of joint {key!r}; "
                          f"read as {turned:.6g} (the same angle {_turns(turned - v)} away)")
                v = turned
        if not (lo - _SLACK <= v <= hi + _SLACK):
            raise srdf.error(where, f"value {v:.10g} is outside the limits [{lo:.10g}, {hi:.10g}] of joint {key!r} in the URDF {f}")
        out.append(min(max(v, lo), hi))
    return np.asarray(out, dtype=np.float64)


def _turns(d: float) -> str:
    """``d`` rad (a whole number of turns) in words: "a whole turn", "15 whole turns"."""
    n = int(round(abs(d) / (2.0 * math.pi)))
    return "a whole turn" if n == 1 else f"{n} whole turns"
