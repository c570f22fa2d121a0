"""armguard's own pass over a URDF's XML, before Pinocchio reads it.

Pinocchio (through urdfdom) refuses some files with "the file does not contain a valid URDF
model", naming nothing, and loads others into a wrong shape (a capsule with a negative length
became a capsule with its ends swapped).  :func:`urdf_problems` lists what it would refuse or
misread, each as ``(where, message)`` naming the element and the attribute:

* a second ``<link>`` or ``<joint>`` of one name;
* a number that is not a finite number: ``origin`` ``xyz``/``rpy``, ``axis``, ``limit``,
  ``mimic``, ``dynamics``, ``calibration``, ``safety_controller``, and the collision shapes'
  sizes; a ``<limit>`` without ``effort`` or ``velocity`` (urdfdom requires both);
* a collision shape without size: a box edge, a sphere or cylinder radius, a cylinder length
  that is not > 0; a capsule (a cylinder named by ``<collision_checking><capsule>``) of negative
  length (length 0 is a sphere); a mesh scale factor of 0 (a negative factor is allowed: a
  mirrored mesh is a valid shape, and armguard's hull of the scaled vertices is its exact hull);
* a revolute or prismatic joint without ``<limit>`` or with ``lower > upper``; a joint axis of
  length 0; a joint type URDF does not have;
* a joint whose parent or child link does not exist, a ``<mimic>`` naming a joint that does
  not exist (or the joint itself).

Line numbers come from expat as the file is read (:func:`parse_with_lines`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from xml.parsers import expat

from .._tolerance import DEFAULT_TOLERANCES

__all__ = ["parse_with_lines", "urdf_problems", "misread_collisions"]

_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def parse_with_lines(data: bytes) -> tuple[ET.Element, dict]:
    """``(root, lines)``: the XML document ``data`` and each element's 1-based start line
    (``lines[id(element)]``).  Raises ``expat.ExpatError`` (``.lineno``) when not well-formed."""
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()
    lines: dict[int, int] = {}

    def start(tag, attrs):
        el = builder.start(tag, attrs)
        lines[id(el)] = parser.CurrentLineNumber

    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    parser.Parse(data, True)
    return builder.close(), lines


def _numbers(el: ET.Element, attr: str, count: int, default: str | None = None):
    """``(values or None, problem or None)`` for the attribute ``attr`` of ``el``: ``count``
    finite numbers (``default`` when absent; no default: the attribute is required)."""
    raw = el.get(attr, default)
    if raw is None:
        return None, f"expected attribute {attr!r} ({count} number{'s' if count > 1 else ''})"
    parts = raw.split()
    try:
        vals = [float(x) for x in parts]
    except ValueError:
        return None, f"{attr}={raw!r}: expected {count} number{'s' if count > 1 else ''}"
    if len(vals) != count:
        return None, f"{attr}={raw!r}: expected {count} number{'s' if count > 1 else ''}, got {len(vals)}"
    if not all(math.isfinite(v) for v in vals):
        return None, f"{attr}={raw!r}: every number must be finite (no NaN or inf)"
    return vals, None


def urdf_problems(root: ET.Element, lines: dict) -> list[tuple[str, str, int | None]]:
    """Every problem of the URDF ``root`` (see the module docstring) as ``(where, message, line)``."""
    out: list[tuple[str, str, int | None]] = []

    def add(where: str, message: str, el: ET.Element | None) -> None:
        out.append((where, message, lines.get(id(el)) if el is not None else None))

    def check(where: str, el: ET.Element, attr: str, count: int, default: str | None = None):
        vals, problem = _numbers(el, attr, count, default)
        if problem:
            add(where, problem, el)
        elif el.tag != "limit" and any(abs(v) > DEFAULT_TOLERANCES.max_magnitude for v in vals):  # as scene files
            add(where, f"{attr}={el.get(attr)!r}: beyond {DEFAULT_TOLERANCES.max_magnitude:g} (Tolerances.max_magnitude): "
                "the poses computed from it overflow", el)  # (a limit's own bound is checked below)
            return None
        return vals

    def origin(where: str, parent: ET.Element) -> None:
        o = parent.find("origin")
        if o is not None:
            check(f"{where}.origin", o, "xyz", 3, "0 0 0")
            check(f"{where}.origin", o, "rpy", 3, "0 0 0")

    links: dict[str, ET.Element] = {}
    for link in root.findall("link"):
        ln = link.get("name", "")
        if ln in links:
            add(f"link[{ln}]", f"a second <link> named {ln!r} (link names must be unique; the first is at line "
                f"{lines.get(id(links[ln]), '?')})", link)
            continue
        links[ln] = link
        for tag in ("inertial", "visual"):
            for k, el in enumerate(link.findall(tag)):
                origin(f"link[{ln}].{tag}[{k}]", el)
        capsules = {el.get("name") for cc in link.findall("collision_checking") for el in cc if el.tag == "capsule"}
        for k, c in enumerate(link.findall("collision")):
            w = f"link[{ln}].collision[{k}]"
            origin(w, c)
            g = c.find("geometry")
            shape = list(g)[0] if g is not None and len(g) == 1 else None
            if shape is None:
                continue  # _urdf._read_xml names an empty or crowded <geometry>
            if shape.tag == "box":
                v = check(w, shape, "size", 3)
                if v is not None and min(v) <= 0.0:
                    add(w, f"<box size={shape.get('size')!r}>: each edge must be > 0 (a box with volume)", shape)
            elif shape.tag == "sphere":
                v = check(w, shape, "radius", 1)
                if v is not None and v[0] <= 0.0:
                    add(w, f"<sphere radius={shape.get('radius')!r}>: the radius must be > 0", shape)
            elif shape.tag == "cylinder":
                capsule = c.get("name") in capsules
                r = check(w, shape, "radius", 1)
                if r is not None and r[0] <= 0.0:
                    add(w, f"<cylinder radius={shape.get('radius')!r}>: the radius must be > 0", shape)
                length = check(w, shape, "length", 1)
                if length is not None and (length[0] < 0.0 if capsule else length[0] <= 0.0):
                    add(w, f"<cylinder length={shape.get('length')!r}>: " + (
                        "a capsule's length must be >= 0 (0 is a sphere; a negative length is no capsule)" if capsule
                        else "the length must be > 0 (a cylinder with volume)"), shape)
            elif shape.tag == "mesh":
                v = check(w, shape, "scale", 3, "1 1 1")
                if v is not None and min(abs(x) for x in v) == 0.0:
                    add(w, f"<mesh scale={shape.get('scale')!r}>: a zero scale flattens the mesh (each factor "
                        "must be non-zero)", shape)
    joints: dict[str, ET.Element] = {}
    for j in root.findall("joint"):
        jn = j.get("name", "")
        w = f"joint[{jn}]"
        if not jn:
            add("joint", "a <joint> needs a name", j)
            continue
        if jn in joints:
            add(w, f"a second <joint> named {jn!r} (joint names must be unique; the first is at line "
                f"{lines.get(id(joints[jn]), '?')})", j)
            continue
        joints[jn] = j
        jt = j.get("type", "")
        if jt not in _JOINT_TYPES:
            add(w, f"type={jt!r}: expected one of {list(_JOINT_TYPES)}", j)
        for end in ("parent", "child"):
            e = j.find(end)
            if e is None or not e.get("link"):
                add(w, f"expected <{end} link=...>", j)
            elif e.get("link") not in links:
                add(f"{w}.{end}", f"link={e.get('link')!r}: no <link> of that name", e)
        origin(w, j)
        ax = j.find("axis")
        if ax is not None:
            v = check(f"{w}.axis", ax, "xyz", 3, "1 0 0")
            if v is not None and jt in ("revolute", "continuous", "prismatic") and not any(v):
                add(f"{w}.axis", f"xyz={ax.get('xyz')!r}: a joint axis of length 0", ax)
        lim = j.find("limit")
        if lim is None:
            if jt in ("revolute", "prismatic"):
                add(w, f"a {jt} joint needs <limit lower=... upper=... velocity=... effort=...>", j)
        else:
            # urdfdom defaults lower and upper to 0 and requires effort and velocity
            got = {a: check(f"{w}.limit", lim, a, 1, None if a in ("velocity", "effort") else "0")
                   for a in ("lower", "upper", "velocity", "effort")}
            lo, hi = got["lower"], got["upper"]
            for a, v in (("lower", lo), ("upper", hi)):  # 1e308: upper - lower overflows, every sample NaN
                if jt in ("revolute", "prismatic") and v is not None and abs(v[0]) > DEFAULT_TOLERANCES.max_magnitude:
                    add(f"{w}.limit", f"{a}={lim.get(a)!r}: beyond {DEFAULT_TOLERANCES.max_magnitude:g} (Tolerances."
                        "max_magnitude); a revolute joint that turns without end is type=\"continuous\"", lim)
            if jt in ("revolute", "prismatic") and lo is not None and hi is not None and lo[0] > hi[0]:
                add(f"{w}.limit", f"lower={lim.get('lower')!r} > upper={lim.get('upper')!r}", lim)
            for a in ("velocity", "effort"):  # Pinocchio: "min_velocity greater than max_velocity", no joint named
                if got[a] is not None and got[a][0] < 0.0:
                    add(f"{w}.limit", f"{a}={lim.get(a)!r}: must be >= 0 (a bound on its magnitude)", lim)
        for tag, attrs in (("dynamics", ("damping", "friction")), ("calibration", ("rising", "falling")),
                           ("safety_controller", ("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"))):
            el = j.find(tag)
            if el is not None:
                for a in attrs:
                    if el.get(a) is not None:
                        check(f"{w}.{tag}", el, a, 1)
    _tree_problems(links, joints, add, lines)
    for jn, j in joints.items():
        m = j.find("mimic")
        if m is None:
            continue
        target = m.get("joint", "")
        if target not in joints or target == jn:
            known = sorted(k for k in joints if k != jn)
            add(f"joint[{jn}].mimic", f"joint={target!r}: " + ("a joint cannot mimic itself" if target == jn else
                f"no joint of that name (joints: {known[:12]}{' ...' if len(known) > 12 else ''})"), m)
        for a, d in (("multiplier", "1"), ("offset", "0")):
            check(f"joint[{jn}].mimic", m, a, 1, d)
    return out


def _tree_problems(links: dict, joints: dict, add, lines: dict) -> None:
    """The links and joints must form one tree (urdfdom said only "Failed to find root link: Two root links
    found" or "Failed to build tree", and Pinocchio "does not contain a valid URDF model", naming nothing):
    a link that is the child of two joints, a loop of joints, or more than one root link."""
    parent_of: dict = {}  # child link -> (joint name, joint element)
    for jn, j in joints.items():
        p, c = j.find("parent"), j.find("child")
        if p is None or c is None or p.get("link") not in links or c.get("link") not in links:
            continue  # named above
        child = c.get("link")
        if child in parent_of:
            first = parent_of[child][1]
            add(f"joint[{jn}].child", f"link={child!r} is already the child of joint {parent_of[child][0]!r} (line "
                f"{lines.get(id(first), '?')}): a URDF is a tree, each link the child of one joint at most", c)
            continue
        parent_of[child] = (jn, j, p.get("link"))
    for child, (jn, j, _) in parent_of.items():  # a loop: walking up from a child comes back to it
        seen, up = {child}, parent_of[child][2]
        while up in parent_of and up not in seen:
            seen.add(up)
            up = parent_of[up][2]
        if up == child:
            add(f"joint[{jn}]", f"the joints make a loop through link {child!r} ({' -> '.join(sorted(seen))}): a URDF "
                "is a tree", j)
            return
    roots = [ln for ln in links if ln not in parent_of]
    if len(roots) > 1:
        add(f"link[{roots[1]}]", f"{len(roots)} root links ({', '.join(map(repr, roots[:6]))}"
            f"{' ...' if len(roots) > 6 else ''}): no joint joins link {roots[1]!r} to the tree of {roots[0]!r} "
            "(a URDF has one root link)", links[roots[1]])


_LINK_READ = ("visual", "collision", "inertial", "collision_checking")
_COLLISION_READ = ("origin", "geometry")
READ = {"link": _LINK_READ, "collision": _COLLISION_READ, "visual": ("origin", "geometry", "material"),
        "joint": ("origin", "parent", "child", "axis", "limit", "mimic", "dynamics", "calibration", "safety_controller")}
"""The child elements urdfdom reads, by parent: another name close to one of them is a misspelling."""
CHANGES_CHECKS = frozenset({("link", "collision"), ("collision", "origin"), ("collision", "geometry")})
"""(parent, element) whose misspelling changes what is checked: load_model refuses the file, check-urdf errs."""


def misread_collisions(root: ET.Element, lines: dict) -> list[tuple[str, str, int | None]]:
    """Elements that nothing reads yet that look like one that sets what is checked, as ``(where, message,
    line)``: a link's ``<colision>`` (the link has no geometry from it: its pairs are never checked) and a
    collision's ``<orgin>`` (the shape sits at the link's origin).  Other unread elements (a simulator's
    ``<contact>``) are ``check-urdf``'s ``unread-element`` warnings."""
    import difflib

    out = []
    for link in root.findall("link"):
        ln = link.get("name", "")
        kinds = [(link, "link", f"link[{ln}]")]
        kinds += [(c, "collision", f"link[{ln}].collision[{k}]") for k, c in enumerate(link.findall("collision"))]
        for el, kind, where in kinds:
            for c in el:
                if not isinstance(c.tag, str) or c.tag in READ[kind]:
                    continue
                near = difflib.get_close_matches(c.tag, READ[kind], n=1, cutoff=0.75)
                if near and (kind, near[0]) in CHANGES_CHECKS:
                    what = ("the link has no geometry from it: its pairs are not checked" if near[0] == "collision"
                            else "the shape sits at the link's origin" if near[0] == "origin" else "no shape is read from it")
                    out.append((f"{where}.{c.tag}", f"<{c.tag}> is read by nothing: did you mean <{near[0]}>? ({what})",
                                lines.get(id(c))))
    return out + _misread_attributes(root, lines)


ATTRIBUTES = {"origin": ("xyz", "rpy"), "axis": ("xyz",), "limit": ("lower", "upper", "effort", "velocity"),
              "mimic": ("joint", "multiplier", "offset"), "box": ("size",), "cylinder": ("radius", "length"),
              "sphere": ("radius",), "mesh": ("filename", "scale"), "parent": ("link",), "child": ("link",)}
"""The attributes urdfdom reads on the elements that place and shape what is checked."""


def _misread_attributes(root: ET.Element, lines: dict) -> list[tuple[str, str, int | None]]:
    """Attributes of a joint's or a collision's elements that nothing reads yet that look like one that is
    (``<origin ryp="...">``: read as no rotation; ``xzy``, ``lenght``): a misspelling, never a value dropped."""
    import difflib

    out = []
    places = [(j, f"joint[{j.get('name', '')}]") for j in root.findall("joint")]
    for link in root.findall("link"):
        places += [(c, f"link[{link.get('name', '')}].collision[{k}]") for k, c in enumerate(link.findall("collision"))]
    for el, where in places:
        for c in el.iter():
            known = ATTRIBUTES.get(c.tag) if isinstance(c.tag, str) else None
            for a in (() if known is None else c.attrib):
                if a in known or any(k in a for k in known):  # an extension (ANYmal's gear_velocity), no misspelling
                    continue
                near = difflib.get_close_matches(a, known, n=1, cutoff=0.6) or [k for k in known if sorted(k) == sorted(a)]
                if near:
                    out.append((f"{where}.{c.tag}", f'{a}="{c.get(a)}" is read by nothing: did you mean {near[0]}=? '
                                f"(<{c.tag}> takes {', '.join(known)}; unread, it would give another model)", lines.get(id(c))))
    return out
