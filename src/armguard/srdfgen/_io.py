"""Writing a collision matrix as an SRDF (MoveIt's format, read by Pinocchio's ``removeCollisionPairs``)."""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

from .._errors import OutputError

__all__ = ["write_srdf", "srdf_text"]


def srdf_text(matrix) -> str:
    """The SRDF of ``matrix``: one ``<disable_collisions link1 link2 reason/>`` per disabled pair, and
    a comment per checked pair (witnessed, with its configuration, or undecided)."""
    root = ET.Element("robot", name=str(matrix.model))
    root.append(ET.Comment(f" collision matrix by armguard srdf: method {matrix.method}, margin {matrix.margin:g} m, "
                           f"{len(matrix.disabled)} of {len(matrix.entries)} link pairs disabled "))
    for e in matrix.entries:
        if e.reason is not None:
            ET.SubElement(root, "disable_collisions", link1=e.link1, link2=e.link2, reason=e.reason)
    for e in matrix.entries:
        if e.reason is None:
            what = (f"witnessed at q = [{', '.join(f'{x:.6g}' for x in e.q)}] (distance {e.distance:.3g} m)"
                    if e.status == "witnessed" else e.how)
            root.append(ET.Comment(f" checked: {e.link1} - {e.link2}: {what} "))
    ET.indent(root, "  ")
    return '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_srdf(matrix, path) -> None:
    """Write :func:`srdf_text` to ``path`` whole (a temporary file beside it, then a rename)."""
    path = Path(path)
    text = srdf_text(matrix)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent if str(path.parent) else ".")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        raise OutputError(f"{path}: cannot write the SRDF ({exc.strerror or exc})") from None
