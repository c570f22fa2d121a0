"""Line numbers for the places an error names in a YAML file (``bodies[0].shapes[1].size``).

The loaders name a place by its path of keys and indices; :func:`with_lines` adds the line each
place starts on (the line of the mapping that lacks a missing key), composing the file's YAML
nodes once, only when there is an error to report.
"""

from __future__ import annotations

import re

import yaml

from ._errors import SceneFileError

__all__ = ["line_map", "line_of", "with_lines", "lines_for"]

_STEP = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def line_map(text: str) -> dict[tuple, int]:
    """``{path: line}`` (1-based) of every node of the YAML document ``text``; ``()`` is the root.

    A mapping entry's line is its key's line.  Empty when the text does not compose."""
    try:
        root = yaml.compose(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError:
        return {}
    out: dict[tuple, int] = {}
    if root is None:
        return out
    stack = [((), root, root.start_mark.line + 1)]
    while stack:
        path, node, line = stack.pop()
        out[path] = line
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode):
                    stack.append((path + (k.value,), v, k.start_mark.line + 1))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                stack.append((path + (i,), v, v.start_mark.line + 1))
    return out


def _steps(where: str) -> tuple:
    steps = []
    for m in _STEP.finditer(where):
        steps.append(m.group(1).strip() if m.group(1) is not None else int(m.group(2)))
    return tuple(steps)


def line_of(where: str, lines: dict[tuple, int]) -> int | None:
    """The line of place ``where`` (``a.b[2].c``), else of its deepest existing parent; None when
    the place is not a path in the file."""
    steps = _steps(where)
    if not steps:
        return None
    for n in range(len(steps), 0, -1):
        line = lines.get(steps[:n])
        if line is not None:
            return line
    return None


def _locate(where: str, lines) -> str:
    line = line_of(where, lines) if where and not where.startswith("line ") else None
    return f"{where} (line {line})" if line is not None else where


def with_lines(exc: SceneFileError, text: str) -> SceneFileError:
    """``exc`` with the line of its place, and of each further ``\\n  place: message`` problem listed
    in its message, added; ``exc`` itself when the text names no such place."""
    lines = line_map(text)
    if not lines:
        return exc
    line = line_of(exc.where, lines) if exc.where and exc.line is None else exc.line
    msg_lines = exc.message.split("\n")
    for i, ln in enumerate(msg_lines):
        m = re.match(r"^(  )([A-Za-z_][\w.\[\]]*)(: .*)$", ln)
        if m:
            msg_lines[i] = m.group(1) + _locate(m.group(2), lines) + m.group(3)
    if line == exc.line and msg_lines == exc.message.split("\n"):
        return exc
    return SceneFileError(exc.file, exc.where, "\n".join(msg_lines), line=line)


class lines_for:
    """``with lines_for(path): ...``: a :class:`SceneFileError` about ``path`` raised inside gets
    :func:`with_lines`; errors about other files (a URDF, a mesh) pass unchanged."""

    def __init__(self, path) -> None:
        self.path = str(path)

    def __enter__(self) -> "lines_for":
        return self

    def __exit__(self, kind, exc, tb) -> bool:
        if isinstance(exc, SceneFileError) and exc.file == self.path and exc.where and not exc.where.startswith("line ") \
                and exc.line is None:
            try:
                with open(self.path, encoding="utf-8") as fh:
                    text = fh.read()
            except (OSError, UnicodeDecodeError):
                return False
            new = with_lines(exc, text)
            if new is not exc:
                raise new from None
        return False
