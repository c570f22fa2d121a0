"""Writing a collision matrix as an SRDF (MoveIt's format, read by Pinocchio's ``removeCollisionPairs``),
and reading back the one written before (``armguard srdf --update``).

Each ``<disable_collisions>`` carries its pair's certificate (``armguard_fingerprint``, see
:mod:`armguard.model._certificate`), the ``<robot>`` element the margin and method; each checked
pair is a comment ending in its fingerprint, its witness configuration written to 17 digits.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from .._errors import SceneFileError, xml_parse_error
from ..model._certificate import CERTIFICATE_FORMAT, FINGERPRINT_ATTR, FORMAT_ATTR, MARGIN_ATTR, METHOD_ATTR

__all__ = ["write_srdf", "srdf_text", "read_previous", "other_elements"]

_CHECKED = re.compile(r"^ checked: (?P<a>\S+) - (?P<b>\S+): (?P<what>.*) \[" + FINGERPRINT_ATTR + r"=(?P<fp>[0-9a-f]+)\] $")
_WITNESS = re.compile(r"^witnessed at q = \[(?P<q>[^\]]*)\] \(distance (?P<d>\S+) m\)$")


def srdf_text(matrix, keep=()) -> str:
    """The SRDF of ``matrix``: one ``<disable_collisions link1 link2 reason/>`` per disabled pair, and
    a comment per checked pair (witnessed, with its configuration, or undecided); the elements
    ``keep`` (:func:`other_elements` of the SRDF it replaces: groups, group states, end effectors,
    virtual and passive joints) first, as they were."""
    root = ET.Element("robot", name=str(matrix.model), **{MARGIN_ATTR: repr(float(matrix.margin)), METHOD_ATTR: matrix.method,
                                                          FORMAT_ATTR: CERTIFICATE_FORMAT})
    for el in keep:
        root.append(el)
    root.append(ET.Comment(f" collision matrix by armguard srdf: method {matrix.method}, margin {matrix.margin:g} m, "
                           f"{len(matrix.disabled)} of {len(matrix.entries)} link pairs disabled "))
    for e in matrix.entries:
        if e.reason is not None:
            extra = {FINGERPRINT_ATTR: e.fingerprint} if e.fingerprint else {}
            ET.SubElement(root, "disable_collisions", link1=e.link1, link2=e.link2, reason=e.reason, **extra)
    for e in matrix.entries:
        if e.reason is None:
            what = (f"witnessed at q = [{', '.join(f'{x:.17g}' for x in e.q)}] (distance {e.distance:.6g} m)"
                    if e.status == "witnessed" else e.how)
            tail = f" [{FINGERPRINT_ATTR}={e.fingerprint}]" if e.fingerprint else ""
            root.append(ET.Comment(f" checked: {e.link1} - {e.link2}: {what}{tail} "))
    ET.indent(root, "  ")
    return '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_srdf(matrix, path, keep=()) -> None:
    """Write :func:`srdf_text` to ``path`` whole (:func:`armguard._io.atomic_write`: a temporary file beside
    it, flushed, then renamed; a FIFO, a folder or a full disk is an OutputError naming the path)."""
    from .._io import atomic_write

    atomic_write(Path(path), srdf_text(matrix, keep))


def _parse(path, what: str):
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    try:
        return ET.parse(str(path), parser=parser).getroot()
    except ET.ParseError as exc:
        raise xml_parse_error(path, exc) from None
    except OSError as exc:
        raise SceneFileError(str(path), "", f"cannot read {what} ({exc.strerror or exc})") from None


def other_elements(path, searched=None) -> list:
    """The elements of the SRDF at ``path`` that a collision matrix does not make: everything but its
    ``<disable_collisions>`` and the comments :func:`srdf_text` writes (a hand-written MoveIt SRDF's
    groups, group states, end effectors, virtual and passive joints), in the file's order, for
    ``armguard srdf --update`` to keep.  ``searched``: the matrix's pairs (frozensets of two link
    names); a ``<disable_collisions>`` of any other pair (two static bodies, ``reason="Static"``; a
    link against an obstacle, a built-in's ``reason="Seed"``) is not the matrix's to decide and is
    kept too.  Comments before ``<robot>`` (a vendor's header) are kept as its first children: ElementTree
    keeps no comment outside the root.  A file that does not parse is a located error."""
    root = _parse(path, "the SRDF")
    out = [ET.Comment(c) for c in _prolog_comments(path)]
    for el in root:
        if el.tag == "disable_collisions":
            if searched is None or frozenset((el.get("link1", ""), el.get("link2", ""))) in searched:
                continue
        if el.tag is ET.Comment and (_CHECKED.match(el.text or "") or (el.text or "").startswith(" collision matrix by armguard")):
            continue
        el.tail = None
        out.append(el)
    return out


def _prolog_comments(path) -> list:
    """The text of each comment before the root element of the (parsed, so well-formed) XML file at ``path``."""
    text = Path(path).read_text(encoding="utf-8", errors="replace")
    head = re.sub(r"<!--.*?-->", lambda m: " " * len(m[0]), text, flags=re.S)
    start = re.search(r"<[A-Za-z_]", head)
    return re.findall(r"<!--(.*?)-->", text[:start.start() if start else 0], flags=re.S)


def read_previous(path) -> dict:
    """``frozenset((link1, link2)) -> MatrixEntry`` of every pair of an SRDF :func:`srdf_text` wrote that
    carries a fingerprint (disabled pairs from their elements, checked pairs from their comments); an
    SRDF made otherwise gives none.  A file that does not parse is a located error."""
    from ._matrix import MatrixEntry

    out = {}
    for el in _parse(path, "the previous SRDF"):
        if el.tag == "disable_collisions" and el.get(FINGERPRINT_ATTR):
            a, b = el.get("link1", ""), el.get("link2", "")
            out[frozenset((a, b))] = MatrixEntry(a, b, el.get("reason", ""), "disabled", how=f"kept from {path}: "
                                                 "its certificate holds", fingerprint=el.get(FINGERPRINT_ATTR))
        elif el.tag is ET.Comment and (m := _CHECKED.match(el.text or "")):
            a, b, what, fp = m["a"], m["b"], m["what"], m["fp"]
            w = _WITNESS.match(what)
            if w:
                q = tuple(float(x) for x in w["q"].split(","))
                out[frozenset((a, b))] = MatrixEntry(a, b, None, "witnessed", q, float(w["d"]), f"kept from {path}",
                                                     fingerprint=fp)
            else:
                out[frozenset((a, b))] = MatrixEntry(a, b, None, "undecided", None, float("nan"), what, fingerprint=fp)
    return out


def check_fits(path, model) -> None:
    """Refuse the SRDF at ``path`` where ``armguard srdf --update`` would keep elements that do not fit
    ``model``: a group none of whose links, joints and chain ends ``model`` has, a group state setting a
    joint it lacks (another robot's SRDF: the rewrite kept Panda's groups in ur5's file, which every command
    then refused).  Its ``<disable_collisions>`` are not judged: those of a renamed or removed link are
    dropped by the rewrite, and said.  A URDF, or a file that does not parse, is a located error
    (:func:`armguard.model._srdf.read_srdf`)."""
    import pinocchio as pin

    from ..model._srdf import read_srdf

    srdf = read_srdf(path, partial=True)
    pm = model.pin_model
    joints = {n.rsplit("/", 1)[-1] for n in list(pm.names)[1:]} | set(srdf.virtual_joints)
    links = {f.name.rsplit("/", 1)[-1] for f in pm.frames if f.type == pin.BODY}
    what = f"{model.name}'s URDF"
    for g in srdf.groups.values():  # wholly another robot's: none of its members here (a member missing
        # here and there is the loader's to warn about: z1's own SRDF names a link 'base' its URDF lacks)
        members = [("joint", x, joints) for x in g.joints] + [("link", x, links) for x in g.links]
        members += [("link", x, links) for c in g.chains for x in c]
        if members and not any(x in have for _, x, have in members):
            kind, x, _ = members[0]
            raise srdf.error(g.where or f"group {g.name}", f"none of its links and joints is in {what} (the first: "
                             f"{kind} {x!r}): not an SRDF of this robot (--update keeps its groups and states)")
    for st in srdf.states:
        for j in st.values:
            if j not in joints:
                raise srdf.error(st.joint_where.get(j, st.where), f"sets joint {j!r}, which {what} does not have: "
                                 "not an SRDF of this robot (--update keeps its groups and states)")
