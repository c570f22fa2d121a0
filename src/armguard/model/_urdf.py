"""URDF files into Pinocchio, checked: nothing is dropped silently.

Pinocchio parses the URDF (``buildModelFromUrdf(..., mimic=True)``) and builds the collision
``GeometryModel`` (``buildGeomFromUrdf``).  Before and after, this module checks what
Pinocchio would let pass: malformed XML (with its line), a mesh that cannot be found, a
collision element that did not reach the GeometryModel (a plain ``<capsule>`` tag, an unknown
geometry), a ``<collision_checking>`` entry naming no collision element.  Each is a
:class:`~armguard.SceneFileError` naming the file and the element; never a model with fewer
pairs.  Meshes that are not marked ``<convex>`` are replaced by their convex hull
(``coal.Convex``): distances on raw BVH meshes are far slower, and the analytic backend sees
the same hull.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import SceneFileError
from ._shapes import convex_hull

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


def resolve_mesh(filename: str, urdf_dir: Path, package_dirs) -> Path | None:
    """A mesh named by a URDF: relative to its folder, ``file://`` or ``package://pkg/...``."""
    name = filename
    for scheme in ("file://", "package://"):
        if name.startswith(scheme):
            name = name[len(scheme):]
    p = Path(name)
    if p.is_absolute():
        return p if p.is_file() else None
    parts = p.parts
    for base in (urdf_dir, *[Path(d) for d in package_dirs], *urdf_dir.parents):
        for k in range(len(parts)):  # the full relative path, then with the package name dropped
            cand = base.joinpath(*parts[k:])
            if cand.is_file():
                return cand
    return None


def _read_xml(path: Path, package_dirs) -> UrdfInfo:
    f = str(path)
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise SceneFileError(f, "", "URDF file not found") from None
    except ET.ParseError as exc:
        raise SceneFileError(f, f"line {exc.position[0]}", f"not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise SceneFileError(f, root.tag, "expected a <robot> root element (a URDF file)")
    links = root.findall("link")
    if not links:
        raise SceneFileError(f, "robot", "a URDF needs at least one <link>")
    collisions: dict = {}
    meshes = []
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
                    raise SceneFileError(f, w, f"mesh file not found: {fn!r} (relative to {path.parent} or package_dirs)")
                meshes.append(mp)
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
    return UrdfInfo(f, root.get("name", path.stem), collisions, mimic, axes, types_, tuple(meshes))


def load_pinocchio(path, package_dirs=()):
    """``(pin_model, collision_model, info)`` of a URDF file, checked (see the module docstring)."""
    import coal
    import pinocchio as pin

    path = Path(path).resolve()
    # package:// names resolve against the URDF's folder, the given folders and the folders above it
    dirs = [str(path.parent), *[str(d) for d in package_dirs], *[str(p) for p in list(path.parents)[:6]]]
    info = _read_xml(path, dirs)
    f = str(path)
    try:
        pin_model = pin.buildModelFromUrdf(f, mimic=True)
    except (RuntimeError, ValueError) as exc:
        raise SceneFileError(f, "", f"Pinocchio could not build the model: {exc}") from None
    try:
        geom = pin.buildGeomFromUrdf(pin_model, f, pin.COLLISION, package_dirs=dirs)
    except (RuntimeError, ValueError) as exc:
        raise SceneFileError(f, "", f"Pinocchio could not build the collision model: {exc}") from None
    per_link: dict = {}
    for go in geom.geometryObjects:
        per_link.setdefault(pin_model.frames[go.parentFrame].name, []).append(go)
    for ln, entries in info.collisions.items():
        got = len(per_link.get(ln, []))
        if got != len(entries):
            raise SceneFileError(f, f"link[{ln}]", f"{len(entries)} <collision> elements but {got} reached "
                                 "Pinocchio's GeometryModel (an element it cannot read was dropped)")
    for go in geom.geometryObjects:
        g = go.geometry
        if isinstance(g, (coal.BVHModelBase, coal.ConvexBase)) and go.meshPath:
            # every mesh becomes the hull of its file's vertices in double precision (Pinocchio reads
            # meshes in single precision: 0.7 m comes back as 0.69999999 m), rebuilt from scipy's
            # hull triangles (coal's own buildConvexRepresentation of the UR5's meshes gave GJK
            # answers up to 0.38 m too far)
            go.geometry = convex_hull(_mesh_vertices(go, g))
    return pin_model, geom, info


def _mesh_vertices(go, g) -> np.ndarray:
    """``(N, 3) float64, m``: the mesh file's vertices, scaled; coal's (single precision) if unreadable."""
    import coal

    try:
        import trimesh

        mesh = trimesh.load(go.meshPath, force="mesh", process=False)
        v = np.asarray(mesh.vertices, dtype=np.float64) * np.asarray(go.meshScale, dtype=np.float64)
        if len(v) >= 3 and np.all(np.isfinite(v)):
            return v
    except Exception:  # noqa: BLE001 - a format trimesh cannot read: Pinocchio's copy serves
        pass
    pts = g.vertices() if isinstance(g, coal.BVHModelBase) else g.points()
    return np.asarray(pts, dtype=np.float64)
