"""A Scene as ``urdf/<system>/`` files: URDF, SRDF, a YAML sidecar and OBJ meshes (docs/models.md).

:func:`export_scene` is the logic of ``tools/dh_to_urdf.py``.  What it writes:

* ``<name>.urdf``: root link ``world``; each static body a link fixed to ``world`` (its shapes
  in W); each robot ``R`` a subtree whose base link ``R_<root>`` is fixed to ``world`` at the
  mount pose by joint ``R_mount``, links and joints named ``R_<link>`` / ``R_<joint>``.  A
  JointSpec ``X_pre @ M(q) @ X_post`` becomes a URDF joint whose origin is the parent's
  ``X_post`` times this joint's ``X_pre`` (for DH rows: the previous row's ``a, alpha`` and this
  row's ``theta, d``), so a URDF link frame U is the joint frame and a link's shapes are
  re-expressed in it (``X_UL = X_post``).  The tool link's ``X_post`` is a fixed link ``R_tool``
  (joint ``R_tool_joint``) unless the tool link is already fixed to its parent.
* a coupled joint (value = sum of ``c_k q_k``) as a chain of joints about one axis, each a
  ``<mimic>`` of one commanded joint: ``R_<joint>_<source>`` into a zero-length link
  ``R_<link>_<source>`` for every term but the last, ``R_<joint>`` into ``R_<link>`` for the
  last (a drive coupling keeps its own command as the last, plain joint); an offset is folded
  into the first origin.  Pinocchio loads the chain with ``mimic=True``.
* payloads as links fixed to their holding link at ``X_LP``.
* shapes: Sphere -> ``<sphere>``, Box -> ``<box>``, Capsule -> ``<cylinder>`` marked
  ``<capsule>`` in ``<collision_checking>``, Prism and ConvexPolyhedron -> an OBJ hull marked
  ``<convex>``, Polygon -> a flat two-sided OBJ marked ``<convex>`` (coal keeps it as a planar
  ``Convex``).  Collision ``i`` of link ``N`` is named ``N_i``, as Pinocchio names its object.
* ``<name>.srdf``: one chain group per robot, groups ``vehicle`` and ``payload``, the robots'
  homes, and a ``<disable_collisions>`` for every pair of links with geometry that
  :meth:`Scene.allowed_pairs` does not check.
* ``<name>.yaml``: the sidecar (workspace, accelerations, trajectories, canned tests).

Given the scene's ``source`` file, its comments (the ``# assumed`` notes, where numbers come
from) are carried into the URDF and SRDF as XML comments, and the sidecar's sections are the
file's own text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._errors import OutputError, SceneError
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ..kinematics import JointType, pose_from_xyz_rpy, xyz_rpy_from_pose
from ._sidecar import SIDECAR_SECTIONS, generated_sections, sidecar_text, source_notes

__all__ = ["export_scene", "owner_link_name", "SIDECAR_SECTIONS"]


@dataclass
class _Link:
    name: str
    shapes: list  # armguard shapes in this URDF link's frame
    comment: str = ""


@dataclass
class _Joint:
    name: str
    type: str  # fixed, revolute, continuous, prismatic
    parent: str
    child: str
    X: np.ndarray  # origin: the parent link frame -> the joint frame
    axis: np.ndarray | None = None
    lower: float = -math.inf
    upper: float = math.inf
    velocity: float = math.inf
    mimic: tuple | None = None  # (joint, multiplier)
    comment: str = ""


@dataclass
class _Model:
    links: list = field(default_factory=list)
    joints: list = field(default_factory=list)
    tips: dict = field(default_factory=dict)  # robot -> (base link, tip link)
    homes: dict = field(default_factory=dict)  # robot -> [(urdf joint, value)]


def owner_link_name(scene, owner: str) -> str:
    """The URDF link of a scene owner: a body or payload by its name, ``R/link`` as ``R_link``."""
    if owner in scene.bodies or owner in scene.payloads:
        return owner
    robot, _, link = owner.partition("/")
    if robot not in scene.robots or link not in scene.robots[robot].link_names:
        raise SceneError(f"unknown owner {owner!r}")
    return f"{robot}_{link}"


def _motion(jtype: JointType, axis: np.ndarray, value: float) -> np.ndarray:
    X = np.eye(4)
    if jtype is JointType.PRISMATIC:
        X[:3, 3] = value * axis
        return X
    a = axis / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    X[:3, :3] = np.eye(3) + math.sin(value) * K + (1 - math.cos(value)) * K @ K
    return X


def _build(scene, notes: dict) -> _Model:
    m = _Model(links=[_Link("world", [])])
    for body in scene.bodies.values():
        m.links.append(_Link(body.name, list(body.shapes), notes.get(("bodies", body.name), "")))
        m.joints.append(_Joint(f"world_to_{body.name}", "fixed", "world", body.name, np.eye(4)))
    for rname, robot in scene.robots.items():
        _robot_parts(m, rname, robot, notes.get(("robots", rname), ""))
        m.homes[rname] = [(f"{rname}_{j}", float(v)) for j, v in zip(robot.joint_names, scene.home(rname))]
    for p in scene.payloads.values():
        robot = scene.robots[p.robot]
        X_post = _x_post(robot, p.link)
        m.links.append(_Link(p.name, list(p.shapes), notes.get(("payloads", p.name), "")))
        m.joints.append(_Joint(f"{p.robot}_{p.link}_to_{p.name}", "fixed", f"{p.robot}_{p.link}", p.name,
                               X_post @ np.asarray(p.X_LP)))
    names = [ln.name for ln in m.links]
    jnames = [j.name for j in m.joints]
    for what, lst in (("link", names), ("joint", jnames)):
        dup = sorted({n for n in lst if lst.count(n) > 1})
        if dup:
            raise SceneError(f"scene {scene.name!r}: URDF {what} names {dup} would be used twice")
    return m


def _x_post(robot, link: str) -> np.ndarray:
    spec = robot.joint_of_link(link)
    return np.eye(4) if spec is None or spec.X_post is None else np.asarray(spec.X_post, dtype=np.float64)


def _robot_parts(m: _Model, rname: str, robot, comment: str) -> None:
    P = f"{rname}_"
    root = robot.root_link
    tree = robot.flat_tree
    m.links.append(_Link(P + root, list(robot.link_shapes.get(root, ())), comment))
    m.joints.append(_Joint(P + "mount", "fixed", "world", P + root, robot.X_WB))
    lo = dict(zip(robot.joint_names, robot.lower))
    hi = dict(zip(robot.joint_names, robot.upper))
    vmax = dict(zip(robot.joint_names, robot.max_velocity))
    for i, ln in enumerate(robot.link_names[1:], start=1):
        s = robot.joint_of_link(ln)
        X = _x_post(robot, s.parent) @ np.asarray(s.X_pre, dtype=np.float64)
        shapes = [sh.transformed(_x_post(robot, ln)) for sh in robot.link_shapes.get(ln, ())]
        if s.joint_type is JointType.FIXED:
            m.joints.append(_Joint(P + s.name, "fixed", P + s.parent, P + ln, X))
            m.links.append(_Link(P + ln, shapes))
            continue
        axis = np.asarray(tree.axis[i], dtype=np.float64)
        a, b = int(tree.term_start[i]), int(tree.term_start[i + 1])
        terms = [(robot.joint_names[int(k)], float(c)) for k, c in zip(tree.term_joint[a:b], tree.term_coeff[a:b])
                 if float(c) != 0.0]
        if float(tree.offset[i]) != 0.0:
            X = X @ _motion(s.joint_type, axis, float(tree.offset[i]))
        if s.name in robot.joint_names:  # commanded (a drive coupling adds mimic terms before it)
            own = dict(terms).get(s.name, 0.0)
            if own != 1.0:
                raise SceneError(f"robot {rname!r} joint {s.name!r}: a commanded joint whose value is {own} times "
                                 "its command has no URDF form")
            chain = [(j, c) for j, c in terms if j != s.name] + [(None, 1.0)]
        else:
            chain = terms
        if not chain:  # a dependent joint with a constant value: its offset is in X
            m.joints.append(_Joint(P + s.name, "fixed", P + s.parent, P + ln, X))
            m.links.append(_Link(P + ln, shapes))
            continue
        if len(chain) > 1 or chain[0][0] is not None:
            expr = " ".join(f"{'+' if c >= 0 else '-'} {'' if abs(c) == 1 else f'{abs(c):.12g} '}{j or s.name}"
                            for j, c in chain)
            expr = expr[2:] if expr.startswith("+") else "-" + expr[2:]
            note = f"{s.name} = {expr}" + (f" + {float(tree.offset[i]):.12g}" if tree.offset[i] else "")
            note += ": one joint per term about the same axis, each a mimic of a commanded joint"
        else:
            note = ""
        parent = P + s.parent
        for k, (src, c) in enumerate(chain):
            last = k == len(chain) - 1
            jn = P + s.name if last else f"{P}{s.name}_{src}"
            child = P + ln if last else f"{P}{ln}_{src}"
            if src is None:
                lower, upper, vel = s.lower, s.upper, s.max_velocity
            else:
                ends = sorted((c * lo[src], c * hi[src]))
                lower, upper, vel = ends[0], ends[1], abs(c) * vmax[src]
            jtype = "prismatic" if s.joint_type is JointType.PRISMATIC else (
                "continuous" if math.isinf(lower) and math.isinf(upper) else "revolute")
            if jtype != "continuous" and not (math.isfinite(lower) and math.isfinite(upper)):
                # a URDF <limit> needs both (the model made from it was refused, naming a deleted temporary file)
                raise SceneError(f"robot {rname!r}, joint {s.name!r} ({jtype}): limits [{lower}, {upper}]: "
                                 + ("a prismatic joint needs both limits finite" if jtype == "prismatic" else
                                    "give both limits finite, or none (a revolute joint without limits turns freely)"))
            m.joints.append(_Joint(jn, jtype, parent, child, X if k == 0 else np.eye(4), axis, lower, upper, vel,
                                   None if src is None else (P + src, c), note if k == 0 else ""))
            if not last:
                m.links.append(_Link(child, []))
            parent = child
        m.links.append(_Link(P + ln, shapes))
    tool = robot.tool_link
    spec = robot.joint_of_link(tool)
    X_post = _x_post(robot, tool)
    if spec is not None and spec.joint_type is JointType.FIXED and np.array_equal(X_post, np.eye(4)):
        m.tips[rname] = (P + root, P + tool)
        return
    if "tool" in robot.link_names:
        raise SceneError(f"robot {rname!r}: a link is already named 'tool'; the tool frame needs that name")
    m.joints.append(_Joint(P + "tool_joint", "fixed", P + tool, P + "tool", X_post,
                           comment=f"the tool frame: the {tool} frame of the scene (its DH a, alpha)"))
    m.links.append(_Link(P + "tool", []))
    m.tips[rname] = (P + root, P + "tool")


# ------------------------------------------------------------------ writing
def _num(x: float) -> str:
    x = float(x)
    r = round(x, 12)
    if abs(x - r) < 1e-14:
        x = r
    if x == 0.0:
        return "0"
    s = repr(x)
    return s[:-2] if s.endswith(".0") else s


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _origin(X: np.ndarray) -> str:
    xyz, rpy = xyz_rpy_from_pose(X)
    err = np.abs(pose_from_xyz_rpy(xyz, rpy)[:3, :3] - X[:3, :3]).max()
    if err > 1e-12:  # pragma: no cover - xyz_rpy_from_pose is exact to rounding
        raise SceneError(f"a pose has no accurate roll-pitch-yaw form (error {err:.3g})")
    return f'<origin xyz="{_vec(xyz)}" rpy="{_vec(rpy)}"/>'


def _pose(center, R) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = center
    return X


def _comment(text: str, indent: str) -> list[str]:
    if not text.strip():
        return []
    text = text.replace("--", "- -")
    body = text.strip("\n").split("\n")
    if len(body) == 1:
        return [f"{indent}<!-- {body[0]} -->"]
    return [f"{indent}<!--"] + [f"{indent}  {ln}".rstrip() for ln in body] + [f"{indent}-->"]


def _frame_of_segment(p0, p1) -> tuple[np.ndarray, float]:
    axis = np.asarray(p1) - np.asarray(p0)
    L = float(np.linalg.norm(axis))
    z = axis / L
    a = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return _pose(0.5 * (np.asarray(p0) + np.asarray(p1)), np.column_stack([x, np.cross(z, x), z])), L


def _obj(vertices, triangles, note: str) -> str:
    out = [f"# {note}"]
    out += [f"v {_vec(v)}" for v in vertices]
    out += ["f " + " ".join(str(int(k) + 1) for k in t) for t in triangles]
    return "\n".join(out) + "\n"


def _hull_triangles(poly: ConvexPolyhedron) -> list:
    """Each face as a fan of counter-clockwise triangles, faces in a fixed order (qhull's varies)."""
    faces = []
    for f in poly.faces:
        f = [int(v) for v in f]
        k = f.index(min(f))
        faces.append(f[k:] + f[:k])
    return [(f[0], f[k], f[k + 1]) for f in sorted(faces) for k in range(1, len(f) - 1)]


def _collision(shape, cname: str, meshes: dict) -> tuple[list[str], str | None]:
    """XML lines of one ``<collision>`` and its collision_checking tag (capsule, convex or None)."""
    mesh_note = None
    if isinstance(shape, Sphere):
        X, geom, mark = _pose(shape.center, np.eye(3)), f'<sphere radius="{_num(shape.radius)}"/>', None
    elif isinstance(shape, Capsule) and shape.length == 0.0:
        X, geom, mark = _pose(shape.p0, np.eye(3)), f'<sphere radius="{_num(shape.radius)}"/>', None
    elif isinstance(shape, Capsule):
        X, L = _frame_of_segment(shape.p0, shape.p1)
        geom, mark = f'<cylinder radius="{_num(shape.radius)}" length="{_num(L)}"/>', "capsule"
    elif isinstance(shape, Box):
        X, geom, mark = _pose(shape.center, shape.rotation), f'<box size="{_vec(2.0 * shape.half_extents)}"/>', None
    elif isinstance(shape, Cylinder):  # an exact cylinder (unmarked: Pinocchio gives coal.Cylinder)
        X = _pose(shape.center, shape.rotation)
        geom = f'<cylinder radius="{_num(shape.radius)}" length="{_num(2.0 * shape.half_length)}"/>'
        mark = None
    elif isinstance(shape, Prism):
        local = Prism(np.zeros(3), np.eye(3), shape.apothem, shape.half_length, shape.n_sides).as_polyhedron()
        X, mark = _pose(shape.center, shape.rotation), "convex"
        mesh_note = (f"{cname}: a right prism over a regular {shape.n_sides}-gon, apothem {shape.apothem:.12g} m, "
                     f"length {2 * shape.half_length:.12g} m, axis z, first face normal x (the <origin> places it)")
        meshes[cname] = _obj(local.vertices, _hull_triangles(local), mesh_note)
    elif isinstance(shape, ConvexPolyhedron):
        X, mark = np.eye(4), "convex"
        mesh_note = f"{cname}: a convex polyhedron, {len(shape.faces)} faces, {len(shape.vertices)} vertices"
        meshes[cname] = _obj(shape.vertices, _hull_triangles(shape), mesh_note)
    elif isinstance(shape, Polygon):
        X, mark = np.eye(4), "convex"
        n = len(shape.vertices)
        front = [(0, k, k + 1) for k in range(1, n - 1)]
        mesh_note = f"{cname}: a planar convex polygon of {n} vertices, both sides (front faces along its normal)"
        meshes[cname] = _obj(shape.vertices, front + [(a, c, b) for a, b, c in front], mesh_note)
    else:
        raise SceneError(f"{cname}: a {type(shape).__name__} has no URDF form")
    if mesh_note is not None:
        geom = f'<mesh filename="meshes/{cname}.obj"/>'
    return [f'    <collision name="{cname}">', f"      {_origin(X)}", f"      <geometry>{geom}</geometry>",
            "    </collision>"], mark


def _urdf_text(name: str, m: _Model, header: str, meshes: dict) -> str:
    out = ['<?xml version="1.0"?>'] + _comment(header, "") + [f'<robot name="{name}">']
    joint_into = {j.child: j for j in m.joints}
    for link in m.links:
        j = joint_into.get(link.name)
        out.append("")
        out += _comment(link.comment, "  ")
        if j is not None:
            out += _comment(j.comment, "  ")
            out += [f'  <joint name="{j.name}" type="{j.type}">', f'    <parent link="{j.parent}"/>',
                    f'    <child link="{j.child}"/>', f"    {_origin(j.X)}"]
            if j.type != "fixed":
                out.append(f'    <axis xyz="{_vec(j.axis)}"/>')
                lim = f'effort="0" velocity="{_num(j.velocity)}"' if math.isfinite(j.velocity) else 'effort="0" velocity="0"'
                if j.type != "continuous":
                    lim = f'lower="{repr(float(j.lower))}" upper="{repr(float(j.upper))}" ' + lim
                out.append(f"    <limit {lim}/>")
                if j.mimic is not None:
                    out.append(f'    <mimic joint="{j.mimic[0]}" multiplier="{_num(j.mimic[1])}" offset="0"/>')
            out.append("  </joint>")
        if not link.shapes:
            out.append(f'  <link name="{link.name}"/>')
            continue
        out.append(f'  <link name="{link.name}">')
        marks = []
        for i, shape in enumerate(link.shapes):
            lines, mark = _collision(shape, f"{link.name}_{i}", meshes)
            out += lines
            if mark:
                marks.append(f'      <{mark} name="{link.name}_{i}"/>')
        if marks:
            out += ["    <collision_checking>", *marks, "    </collision_checking>"]
        out.append("  </link>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def _adjacent(robot, a: str, b: str) -> bool:
    """As the Scene decides: joined by one joint, or through links without geometry."""
    if tuple(sorted((a, b))) in robot.adjacent_pairs:
        return True

    def shaped_ancestor(ln):
        p = robot.parent_link(ln)
        while p is not None and not robot.link_shapes.get(p):
            p = robot.parent_link(p)
        return p

    return shaped_ancestor(a) == b or shaped_ancestor(b) == a


def _disabled(scene) -> list[tuple[str, str, str]]:
    """``(link1, link2, reason)`` for every pair of owners with geometry the scene does not check."""
    owners = scene.owners()
    allowed = {frozenset((p.a, p.b)) for p in scene.allowed_pairs()}
    kind = {o: ("body" if o in scene.bodies else "payload" if o in scene.payloads else "link") for o in owners}
    explicit = set(scene.disabled_pairs)
    out = []
    for i, a in enumerate(owners):
        for b in owners[i + 1:]:
            if frozenset((a, b)) in allowed:
                continue
            ra = a.partition("/")[0] if kind[a] == "link" else None
            rb = b.partition("/")[0] if kind[b] == "link" else None
            if kind[a] == kind[b] == "body":
                reason = "Static"
            elif any(frozenset((x, y)) in explicit for x in (a, ra) for y in (b, rb) if x and y):
                reason = "Seed"
            elif ra is not None and ra == rb and _adjacent(scene.robots[ra], a.partition("/")[2], b.partition("/")[2]):
                reason = "Adjacent"
            elif {kind[a], kind[b]} == {"link", "payload"}:
                p = scene.payloads[a if kind[a] == "payload" else b]
                reason = "Adjacent" if p.owner_link in (a, b) else "Never"
            else:
                reason = "Seed" if ra is not None and ra == rb and ra in scene.self_pairs else "Never"
            out.append((owner_link_name(scene, a), owner_link_name(scene, b), reason))
    return out


_REASON_NOTES = {
    "Adjacent": "joined by one joint, or through links without geometry: never checked",
    "Static": "two static bodies: never checked against each other",
    "Never": "not checked in the scene",
}


def _srdf_text(name: str, scene, m: _Model, notes: dict) -> str:
    out = ['<?xml version="1.0"?>', f"<!-- {name}: arms, vehicle and payload groups, homes and the pairs never checked "
           "(docs/models.md) -->", f'<robot name="{name}">']
    for r, (base, tip) in m.tips.items():
        out += [f'  <group name="{r}">', f'    <chain base_link="{base}" tip_link="{tip}"/>', "  </group>"]
    vehicle = [b.name for b in scene.bodies.values() if b.category == "vehicle"]
    for group, members, note in (("vehicle", vehicle, "the bodies of the arm-vehicle category"),
                                 ("payload", list(scene.payloads), notes.get(("payloads", "*"), ""))):
        if members:
            out += _comment(note, "  ") + [f'  <group name="{group}">']
            out += [f'    <link name="{ln}"/>' for ln in members] + ["  </group>"]
    for r, values in m.homes.items():
        out += _comment(notes.get(("home", r), ""), "  ") + [f'  <group_state name="home" group="{r}">']
        out += [f'    <joint name="{j}" value="{repr(v)}"/>' for j, v in values] + ["  </group_state>"]
    pairs = _disabled(scene)
    for reason in ("Adjacent", "Static", "Seed", "Never"):
        chosen = [p for p in pairs if p[2] == reason]
        if not chosen:
            continue
        note = notes.get(("pairs", "*"), "") if reason == "Seed" else _REASON_NOTES[reason]
        if reason == "Seed":
            note = "\n".join(x for x in [note] + [notes.get(("self_pairs", r), "") for r in scene.self_pairs] if x)
            if scene.self_pairs:
                note += ("\nOnly the listed link pairs of " + ", ".join(scene.self_pairs) +
                         " are checked: every other pair of their links is disabled (here, or above as Adjacent).")
        out += [""] + _comment(note, "  ")
        out += [f'  <disable_collisions link1="{a}" link2="{b}" reason="{reason}"/>' for a, b, _ in chosen]
    out.append("</robot>")
    return "\n".join(out) + "\n"


def plain_name(name: str) -> bool:
    """Whether ``name`` can be the stem of the exported files (no folder part, not ``.`` or ``..``)."""
    return bool(name) and "/" not in name and "\\" not in name and name not in (".", "..")


# ------------------------------------------------------------------ the source file's comments
def export_scene(scene, out_dir, *, name: str | None = None, source=None, sidecar: bool = True) -> dict:
    """Write ``scene`` as ``<name>.urdf``, ``<name>.srdf``, ``<name>.yaml`` and ``meshes/*.obj`` in ``out_dir``.

    ``name`` defaults to ``scene.name``; ``source`` is the scene file the scene was loaded from
    (optional): its comments are carried over and the sidecar keeps its workspace, trajectories
    and canned tests as written.  Returns ``{"urdf": Path, "srdf": Path, "yaml": Path,
    "meshes": [Path, ...]}``.  ``sidecar=False``: no ``<name>.yaml`` (no ``"yaml"`` key): what
    :func:`armguard.model.model_from_scene` needs, for any scene (the sidecar saves each robot's DH
    table or URDF file, which a robot built from JointSpecs in code has not).
    """
    import yaml

    name = name or scene.name
    out = Path(out_dir)
    if not plain_name(name):  # its files at out/<name>.urdf, its meshes at meshes/ beside the URDF
        raise OutputError(f"cannot write {out / name}.urdf: the name {name!r} is not a plain file name (no folder part: "
                          "the URDF finds its meshes in meshes/ beside it)")
    header, notes, sections, units = "", {}, {}, {"angle": "deg", "length": "m"}
    if source is not None:
        text = Path(source).read_text(encoding="utf-8")
        header, notes, sections = source_notes(text)
        units = {"angle": "rad", "length": "m", **(yaml.safe_load(text).get("units") or {})}
        sections = {k: v for k, v in sections.items() if k in SIDECAR_SECTIONS}
    elif sidecar:
        sections = generated_sections(scene)
    model = _build(scene, notes)
    meshes: dict[str, str] = {}
    frames = notes.get(("frames", "*"), "")
    frames = f"\n\nThe scene file's frames (flattened into W here):\n{frames}" if frames else ""
    urdf_header = header + frames + ("\n\n" if header or frames else "") + (
        f"The model of {name} (docs/models.md), written by tools/dh_to_urdf from the scene file "
        f"{Path(source).name if source else name}; edit this file from now on.  Link frames are DH joint frames.")
    urdf = _urdf_text(name, model, urdf_header, meshes)
    srdf = _srdf_text(name, scene, model, notes)
    sidecar = sidecar_text(name, scene, header, sections, units) if sidecar else None
    from .._io import atomic_write, check_target, make_folder, output_set

    make_folder(out / "meshes")  # an OutputError naming the folder (a raw FileExistsError / NotADirectoryError)
    paths = {"urdf": out / f"{name}.urdf", "srdf": out / f"{name}.srdf", "yaml": out / f"{name}.yaml", "meshes": []}

    if sidecar is None:
        del paths["yaml"]
    mesh_paths = {cname: out / "meshes" / f"{cname}.obj" for cname in meshes}
    for p in [paths[k] for k in ("urdf", "srdf", "yaml") if k in paths] + list(mesh_paths.values()):
        check_target(p)  # a folder or FIFO at any name: refused before one file is written (not half a model)
    # one set: every file staged first (a full disk there replaces nothing: an old URDF never names a new
    # mesh), then moved into place, the meshes before the URDF that names them
    with output_set(out) as stage:
        make_folder(stage / "meshes")
        for cname, obj in meshes.items():
            atomic_write(stage / "meshes" / f"{cname}.obj", obj)
        for key, text in (("yaml", sidecar), ("srdf", srdf), ("urdf", urdf)):
            if text is not None:
                atomic_write(stage / paths[key].name, text)
    paths["meshes"] = list(mesh_paths.values())
    return paths
