"""URDF files into Pinocchio, checked: nothing is dropped silently.

Pinocchio parses the URDF (``buildModelFromUrdf(..., mimic=True)``) and builds the collision
``GeometryModel`` (``buildGeomFromUrdfString``).  Before and after, this module checks what
Pinocchio would let pass or refuse without saying where: malformed XML (with its line), the
problems :mod:`._urdf_check` lists (duplicate names, non-finite numbers, sizes that are not
> 0, missing limits, a mimic of no joint), a mesh that cannot be found, a collision element
that did not reach the GeometryModel (a plain ``<capsule>`` tag, an unknown geometry), a
``<collision_checking>`` entry naming no collision element.  Each is a
:class:`~armguard.SceneFileError` naming the file, the element and (where it applies) the line;
never a model with fewer pairs.

Every collision mesh is replaced by its convex hull (``coal.Convex``; distances on raw BVH
meshes are far slower, and the analytic backend sees the same hull), computed by
:func:`._hull.mesh_polytope` from the file's vertices in O(N log N) time and O(N) memory (or
read from the hull cache, :mod:`._hull_cache`); a mesh with a NaN vertex, on a line or on a
point is an error naming the link and the mesh file.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from .._errors import ArmguardError, GeometryError, SceneFileError, list_problems, unclosed_text
from ._hull import mesh_polytope
from ._hull_cache import cached_polytope
from ._shapes import convex_of_polytope
from ._urdf_check import misread_collisions, parse_with_lines, urdf_problems

__all__ = ["UrdfInfo", "load_pinocchio", "resolve_mesh"]


@dataclass(frozen=True)
class UrdfInfo:
    """What the XML says that Pinocchio's model does not keep."""

    file: str
    robot_name: str
    collisions: dict  # link name -> list of (collision name or "", geometry tag)
    mimic: dict  # joint name -> (mimicked joint, multiplier, offset)
    joint_axis: dict  # joint name -> (3,) axis as written
    joint_type: dict  # joint name -> URDF type ("revolute", "prismatic", ...)
    mesh_files: tuple  # resolved mesh paths
    meshes: dict = field(default_factory=dict)  # (link, k) -> (resolved path, (3,) scale) of collision[k] of link when a mesh
    collision_xml: bytes = b""  # the URDF with every collision <mesh> as a placeholder <box> (see load_pinocchio)
    hulls: dict = field(default_factory=dict)  # geometry object index -> MeshPolytope of its mesh (load_pinocchio)
    hull_cache: dict = field(default_factory=dict)  # "folder", "hits", "computed" (._hull_cache.cached_polytope)


_UP = 6  # folders above a URDF searched for a package:// mesh's package (a description package's own layout)


def resolve_mesh(filename: str, urdf_dir: Path, package_dirs) -> Path | None:
    """A mesh named by a URDF, or None (the caller names it: never another file of the same name).

    * ``file:///abs/x.stl`` or an absolute path: that file;
    * a relative path: from the URDF's folder, or from a folder of ``package_dirs`` (as Pinocchio
      reads one), as written;
    * ``package://pkg/rest`` or ``model://pkg/rest`` (Pinocchio reads both so; ``package:///pkg/...``,
      talos_full_v2's spelling, as Pinocchio reads it: under the package folders, not an absolute
      path): ``base/pkg/rest`` for ``base`` a folder of ``package_dirs``, the URDF's folder or one of
      the six above it; or ``base/rest`` where ``base`` is the package ``pkg`` itself: a folder of
      ``package_dirs`` (given as the package), a folder named ``pkg``, or one whose ``package.xml``
      names it (a clone or a download named otherwise: ``ur_description-main``); then, as Pinocchio
      does without package folders, under ``$ROS_PACKAGE_PATH`` (``base/pkg/rest``, or ``base`` the
      package by its name or ``package.xml``) and ``$AMENT_PREFIX_PATH`` (``prefix/share/pkg/rest``).

    A path whose leading folders are dropped until some file of that name turns up, or a relative
    path looked up in the folders above the URDF, is not a mesh the URDF names: with
    ``collision/m.obj`` missing, an ``m.obj`` two folders up was once read in its place, a different
    model without a word."""
    name, package = filename, False
    for scheme in ("file://", "package://", "model://"):
        if name.startswith(scheme):
            name = name[len(scheme):]
            if scheme != "file://":
                name, package = name.lstrip("/"), True
    p = Path(name)
    if p.is_absolute():
        return p if p.is_file() else None
    parts = p.parts
    if not parts:
        return None
    given = [Path(d) for d in package_dirs]
    if not package:
        for base in (urdf_dir, *given):
            cand = base.joinpath(*parts)
            if cand.is_file():
                return cand
        return None
    pkg, rest = parts[0], parts[1:]
    ros = [Path(d) for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if d]
    ament = [Path(d) / "share" for d in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if d]
    for base in (*given, urdf_dir, *list(urdf_dir.parents)[:_UP], *ros, *ament):
        cand = base.joinpath(*parts)  # base holds the package folder
        if cand.is_file():
            return cand
        if rest and (base in given or base.name == pkg or _package_name(base) == pkg):  # base is the package
            cand = base.joinpath(*rest)
            if cand.is_file():
                return cand
    return None


def frozen_joint_text(lim) -> str:
    """What a revolute or prismatic ``<limit>`` without ``lower`` or ``upper`` means, and what to write instead."""
    lo, hi = lim.get("lower") or "0 (unset)", lim.get("upper") or "0 (unset)"
    return (f"no lower or upper: read as [{lo}, {hi}] (urdfdom's default of 0), a joint that can move "
            f"{'nowhere' if not (lim.get('lower') or lim.get('upper')) else 'only to one side of 0'}; give both, or "
            "type=\"continuous\" for one that turns without end")


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of ``folder/package.xml`` (a ROS package's own name), or None."""
    f = folder / "package.xml"
    if not f.is_file():
        return None
    try:
        el = ET.parse(f).getroot().find("name")
    except (ET.ParseError, OSError):
        return None
    return el.text.strip() if el is not None and el.text else None


_MAX_DEPTH = 64  # levels of elements below <robot> (a URDF has 4: link, collision, geometry, box)


def _non_utf8_names(data: bytes, root, lines: dict, f: str) -> None:
    """A file in another encoding (``ISO-8859-1``) whose names or values hold non-ASCII characters is refused:
    urdfdom and Pinocchio read its bytes as UTF-8 (a name no Python string can hold).  Its comments may."""
    try:
        data.decode("utf-8")
        return
    except UnicodeDecodeError:
        pass
    for el in root.iter():
        for a, v in el.attrib.items():
            if a in ("name", "link", "joint", "filename") and not v.isascii():  # what Pinocchio hands back, or opens
                raise SceneFileError(f, f"<{el.tag}> {a}={v!r}", "a non-ASCII value in a file that is not UTF-8: "
                                     "Pinocchio reads the bytes as UTF-8; save the file as UTF-8", line=lines.get(id(el)))


def _nested_too_deep(root):
    """The first element more than ``_MAX_DEPTH`` levels below ``root``, or None (walked without recursion)."""
    stack = [(root, 0)]
    while stack:
        el, depth = stack.pop()
        if depth > _MAX_DEPTH:
            return el
        stack.extend((c, depth + 1) for c in el)
    return None


def _read_xml(path: Path, package_dirs) -> UrdfInfo:
    f = str(path)
    try:
        data = path.read_bytes()
        root, lines = parse_with_lines(data)
    except FileNotFoundError:
        raise SceneFileError(f, "", "URDF file not found") from None
    except expat.ExpatError as exc:
        raise SceneFileError(f, f"line {exc.lineno}, column {exc.offset + 1}",
                             f"not well-formed XML: {expat.ErrorString(exc.code)}{unclosed_text(data, exc.code)}",
                             line=exc.lineno) from None
    if root.tag != "robot":
        raise SceneFileError(f, root.tag, "expected a <robot> root element (a URDF file)")
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):  # expat reads it, urdfdom does not
        raise SceneFileError(f, "", "UTF-16 text: urdfdom reads URDF files as UTF-8; save the file as UTF-8")
    _non_utf8_names(data, root, lines, f)
    deep = _nested_too_deep(root)
    if deep is not None:  # the XML tools downstream recurse per level (a RecursionError, no place named)
        raise SceneFileError(f, f"<{deep.tag}>", f"elements nested more than {_MAX_DEPTH} deep: a URDF nests a few "
                             "levels", line=lines.get(id(deep)))
    links = root.findall("link")
    if not links:
        raise SceneFileError(f, "robot", "a URDF needs at least one <link>")
    if root.get("name") is None:  # urdfdom refuses it, naming no place (an empty name it takes)
        raise SceneFileError(f, "robot", "a <robot> needs a name attribute", line=lines.get(id(root)))
    problems = urdf_problems(root, lines)
    if problems:
        # each problem with its line (the first one's goes in the error's own place)
        where, message = list_problems([(w if k == 0 or ln is None else f"{w} (line {ln})", m)
                                        for k, (w, m, ln) in enumerate(problems)])
        raise SceneFileError(f, where, message, line=problems[0][2])
    misread = misread_collisions(root, lines)
    if misread:  # a misspelling that changes what is checked: never a smaller model (a link without its shapes)
        where, message = list_problems([(w if k == 0 or ln is None else f"{w} (line {ln})", m)
                                        for k, (w, m, ln) in enumerate(misread)])
        raise SceneFileError(f, where, message, line=misread[0][2])
    collisions: dict = {}
    meshes = []
    mesh_at: dict = {}
    for link in links:
        ln = link.get("name")
        if not ln:
            raise SceneFileError(f, "link", "a <link> needs a name")
        entries = []
        for k, c in enumerate(link.findall("collision")):
            w = f"link[{ln}].collision[{k}]"
            g = c.find("geometry")
            kids = list(g) if g is not None else []
            if len(kids) != 1:
                raise SceneFileError(f, w, "expected one shape inside <geometry>")
            tag = kids[0].tag
            if tag not in ("box", "sphere", "cylinder", "mesh"):
                raise SceneFileError(f, w, f"<{tag}> is not a geometry Pinocchio reads (it would be dropped); "
                                     "use box, sphere, cylinder (with <collision_checking><capsule name=.../> for a "
                                     "capsule) or mesh")
            if tag == "mesh":
                fn = kids[0].get("filename", "")
                mp = resolve_mesh(fn, path.parent, package_dirs)
                if mp is None:
                    line = lines.get(id(kids[0]))
                    raise SceneFileError(f, w, f"mesh file not found: {fn!r} (relative to {path.parent} or package_dirs"
                                         + (", $ROS_PACKAGE_PATH or $AMENT_PREFIX_PATH: set ROS_PACKAGE_PATH to a folder that "
                                            "holds the package, for the command line too)" if "://" in fn else ")"),
                                         line=line)
                meshes.append(mp)
                mesh_at[(ln, k)] = (mp, tuple(float(x) for x in kids[0].get("scale", "1 1 1").split()))
                kids[0].tag, kids[0].attrib = "box", {"size": "1 1 1"}  # only in collision_xml: read below, not by Pinocchio
            entries.append((c.get("name", ""), tag))
        names = {n for n, _ in entries if n}
        for cc in link.findall("collision_checking"):
            for el in cc:
                if el.get("name") not in names:
                    raise SceneFileError(f, f"link[{ln}].collision_checking.{el.tag}[{el.get('name')}]",
                                         f"names no <collision> of this link; its collision names are {sorted(names)}")
        collisions[ln] = entries
    mimic, axes, types_ = {}, {}, {}
    for j in root.findall("joint"):
        jn = j.get("name", "")
        types_[jn] = j.get("type", "")
        ax = j.find("axis")
        if ax is not None:
            axes[jn] = tuple(float(x) for x in ax.get("xyz", "1 0 0").split())
        m = j.find("mimic")
        if m is not None:
            mimic[jn] = (m.get("joint", ""), float(m.get("multiplier", "1")), float(m.get("offset", "0")))
        lim = j.find("limit")
        if types_[jn] in ("revolute", "prismatic") and m is None and lim is not None and not (lim.get("lower") and lim.get("upper")):
            import warnings

            from .._errors import ArmguardWarning

            line = lines.get(id(lim))
            warnings.warn(f"{f}: joint[{jn}].limit{f' (line {line})' if line else ''}: {frozen_joint_text(lim)}",
                          ArmguardWarning, stacklevel=4)
    return UrdfInfo(f, root.get("name", path.stem), collisions, mimic, axes, types_, tuple(meshes), mesh_at,
                    ET.tostring(root))


def load_pinocchio(path, package_dirs=()):
    """``(pin_model, collision_model, info)`` of a URDF file, checked (see the module docstring)."""
    import pinocchio as pin

    path = Path(path).resolve()
    # package:// names resolve against the given folders, the URDF's folder and the folders above it
    # (resolve_mesh searches those itself); relative names against the URDF's folder and the given ones
    dirs = [str(path.parent), *[str(d) for d in package_dirs], *[str(p) for p in list(path.parents)[:_UP]]]
    info = _read_xml(path, [str(d) for d in package_dirs])
    f = str(path)
    try:
        pin_model = pin.buildModelFromUrdf(f, mimic=True)
    except (RuntimeError, ValueError) as exc:
        pin_model = _mimics_after_their_joints(path, info) if "mimic" in str(exc) and info.mimic else None
        if pin_model is None:
            raise SceneFileError(f, "", f"Pinocchio could not build the model: {exc}") from None
    try:
        # the collision meshes are read here (trimesh, in double precision), not by Pinocchio: its
        # loader builds a BVH of every mesh (seconds for so101's 1.2 M vertices) only for it to be
        # replaced by the hull; Pinocchio places a unit box where each mesh is, then the box's
        # geometry becomes the mesh's hull and meshPath / meshScale are the mesh's
        geom = pin.buildGeomFromUrdfString(pin_model, info.collision_xml.decode(), pin.COLLISION, package_dirs=dirs)
    except (RuntimeError, ValueError) as exc:
        raise SceneFileError(f, "", f"Pinocchio could not build the collision model: {exc}") from None
    per_link: dict = {}
    for i, go in enumerate(geom.geometryObjects):
        per_link.setdefault(pin_model.frames[go.parentFrame].name, []).append((i, go))
    for ln, entries in info.collisions.items():
        got = len(per_link.get(ln, []))
        if got != len(entries):
            raise SceneFileError(f, f"link[{ln}]", f"{len(entries)} <collision> elements but {got} reached "
                                 "Pinocchio's GeometryModel (an element it cannot read was dropped)")
    hulls: dict = {}  # (mesh file, scale) -> its hull: a file a URDF uses twice is read and hulled once
    for (ln, k), (mesh_path, scale) in info.meshes.items():
        i, go = per_link[ln][k]
        go.meshPath, go.meshScale = str(mesh_path), np.asarray(scale, dtype=np.float64)
        # every mesh becomes the hull of its file's vertices in double precision (Pinocchio reads
        # meshes in single precision: 0.7 m comes back as 0.69999999 m), rebuilt from scipy's
        # hull triangles (coal's own buildConvexRepresentation of the UR5's meshes gave GJK
        # answers up to 0.38 m too far); armguard's shape is the same hull, its faces merged once
        key = (str(mesh_path), tuple(float(x) for x in np.asarray(scale, dtype=np.float64).reshape(-1)))
        try:
            if key not in hulls:
                hulls[key] = cached_polytope(mesh_path, scale, lambda: mesh_polytope(_mesh_vertices(mesh_path, scale)),
                                             info.hull_cache)
            go.geometry = convex_of_polytope(hulls[key])
        except ArmguardError as exc:
            raise SceneFileError(f, f"link[{ln}].collision[{k}]", f"mesh {mesh_path}: {exc}") from None
        info.hulls[i] = hulls[key]
    return pin_model, geom, info


def _mesh_vertices(mesh_path, scale) -> np.ndarray:
    """``(N, 3) float64, m``: the mesh file's vertices, scaled (trimesh; coal's loader, in single
    precision, for a format trimesh cannot read)."""
    import coal

    scale = np.asarray(scale, dtype=np.float64)
    try:
        import trimesh

        mesh = trimesh.load(str(mesh_path), force="mesh", process=False)
        v = np.asarray(mesh.vertices, dtype=np.float64) * scale
        if len(v):
            return v  # checked by mesh_hull: a NaN vertex is an error, not a reason to read it again
    except Exception:  # noqa: BLE001 - a format trimesh cannot read: coal's loader serves
        pass
    try:
        bvh = coal.MeshLoader().load(str(mesh_path), scale)
    except (RuntimeError, ValueError) as exc:
        # coal's message: its C++ source place, then assimp's reason, then a hint about mesh folders that
        # does not apply to a file found and opened: the reason is kept
        said = [ln.strip() for ln in str(exc).splitlines() if ln.strip() and not ln.strip().startswith(
            ("From file:", "in function:", "at line:", "message:", "Hint:"))]
        try:
            empty = Path(mesh_path).stat().st_size == 0
        except OSError:
            empty = False
        reason = "the file is empty (0 bytes)" if empty else said[-1] if said else str(exc).strip()
        raise GeometryError(f"neither trimesh nor coal's loader could read it: {reason}") from None
    return np.asarray(bvh.vertices(), dtype=np.float64)


def _mimics_after_their_joints(path: Path, info: UrdfInfo):
    """Pinocchio's model of a URDF whose mimic joint Pinocchio reaches before the joint it mimics,
    or None where no order of the links' children can help.

    Pinocchio walks the tree depth first, each link's child joints in the order of their names
    (urdfdom keeps joints in a name-sorted map), and refuses a mimic joint met before the joint it
    mimics (talos_full_v2's ``gripper_left_inner_double_joint`` sorts before ``gripper_left_joint``,
    its sibling).  Here the XML Pinocchio reads has each joint renamed ``<rank>~<name>``: at every
    link, the child whose subtree holds a mimicked joint ranks before the sibling whose subtree
    holds the mimic, the others keep their name order; then every joint and frame gets its URDF name
    back.  The model is the URDF's (same joints, placements, limits, couplings); only the order of
    its joints in ``q`` differs from the name-sorted one."""
    import pinocchio as pin

    root = ET.fromstring(path.read_bytes())
    children: dict = {}  # parent link -> [joint element]
    up: dict = {}  # joint name -> the joint above it (None: on the root link)
    by_child = {}  # child link -> its joint
    for j in root.findall("joint"):
        p, c = j.find("parent"), j.find("child")
        if p is None or c is None:
            return None
        children.setdefault(p.get("link"), []).append(j)
        by_child[c.get("link")] = j
    for j in root.findall("joint"):
        pj = by_child.get(j.find("parent").get("link"))
        up[j.get("name")] = pj.get("name") if pj is not None else None

    def chain(jn):  # the joints from the root down to jn
        out = []
        while jn is not None:
            out.append(jn)
            jn = up.get(jn)
        return out[::-1]

    before: dict = {}  # joint -> its siblings that must come after it
    for jn, (primary, _m, _o) in info.mimic.items():
        a, b = chain(primary), chain(jn)
        k = 0
        while k < min(len(a), len(b)) and a[k] == b[k]:
            k += 1
        if k == len(a) or k == len(b):  # one above the other: no order of siblings changes which comes first
            continue
        before.setdefault(a[k], set()).add(b[k])
    rename = {}
    for kids in children.values():
        names = sorted(j.get("name") for j in kids)
        order = []
        while names:  # Kahn's order, the smallest name first among those free to go
            free = [n for n in names if not any(n in before.get(m, ()) for m in names if m != n)]
            if not free:
                return None  # a cycle: no order puts every mimicked joint first
            order.append(free[0])
            names.remove(free[0])
        rename.update({n: f"{r:04d}~{n}" for r, n in enumerate(order)})
    for j in root.findall("joint"):
        j.set("name", rename[j.get("name")])
        m = j.find("mimic")
        if m is not None and m.get("joint") in rename:
            m.set("joint", rename[m.get("joint")])
    try:
        model = pin.buildModelFromXML(ET.tostring(root, encoding="unicode"), mimic=True)
    except (RuntimeError, ValueError):
        return None
    back = {v: k for k, v in rename.items()}
    for j in range(model.njoints):
        model.names[j] = back.get(model.names[j], model.names[j])
    for fr in model.frames:
        fr.name = back.get(fr.name, fr.name)
    return model

