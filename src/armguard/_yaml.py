"""Reading a scene, trajectory or program file's YAML: a stricter safe loader (duplicate keys, aliases,
YAML 1.2 floats)."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from ._errors import SceneFileError

__all__ = ["read_scene_yaml"]


def read_scene_yaml(path):
    """The parsed YAML of a scene file; a missing file or bad YAML is a :class:`SceneFileError`."""
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        hint = ""
        if path.parts[:1] == ("examples",):  # the docs' examples/workmate/...: the source checkout's, not a wheel's
            hint = " (examples/ comes with the source checkout, not with a wheel: run from the checkout's root)"
        raise SceneFileError(file, "", "file not found" + hint) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneFileError(file, "", f"cannot read the file: {exc}") from None
    try:
        data = yaml.load(text, Loader=_SceneLoader)
    except _DuplicateKey as exc:
        raise SceneFileError(file, f"line {exc.line}", f"duplicate key {exc.key!r} (first given at line {exc.first}); "
                             "a key may appear once per mapping") from None
    except _Alias as exc:
        raise SceneFileError(file, f"line {exc.line}", "a YAML anchor defined here is reused by an alias; anchors and aliases are not allowed in scene files "
                             "(an alias can make a small file expand without bound)") from None
    except _BadNumber as exc:
        raise SceneFileError(file, f"line {exc.line}, column {exc.column}", exc.reason) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise SceneFileError(file, where, f"YAML syntax error: {problem}") from None
    return data


class _DuplicateKey(yaml.YAMLError):
    def __init__(self, key, line: int, first: int) -> None:
        super().__init__(f"duplicate key {key!r} at line {line} (first at line {first})")
        self.key, self.line, self.first = key, line, first


class _Alias(yaml.YAMLError):
    def __init__(self, line: int) -> None:
        super().__init__(f"alias at line {line}")
        self.line = line


class _BadNumber(yaml.YAMLError):
    def __init__(self, text: str, mark, reason: str) -> None:
        super().__init__(reason)
        self.line, self.column, self.reason = mark.line + 1, mark.column + 1, f"{text!r}: {reason}"


_INT = re.compile(r"[-+]?(?:0|[1-9][0-9]*)")  # YAML 1.2's core-schema decimal integer


class _SceneLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """YAML's safe loader, stricter for scene files: a key repeated in one mapping is an error
    (PyYAML keeps the last silently), anchors and aliases are refused, and floats are read as in
    YAML 1.2 (``1e3``, ``1.5e-3`` are numbers, not strings, so strict number fields accept them)."""

    def construct_document(self, node):
        seen, stack = set(), [node]
        while stack:  # an alias is a node reached twice
            n = stack.pop()
            if id(n) in seen:
                raise _Alias(n.start_mark.line + 1)
            seen.add(id(n))
            if isinstance(n, yaml.MappingNode):
                stack.extend(x for kv in n.value for x in kv)
            elif isinstance(n, yaml.SequenceNode):
                stack.extend(n.value)
        return super().construct_document(node)

    def construct_yaml_int(self, node):
        """YAML 1.1 reads ``010`` as 8, ``0x10`` as 16 and ``0b11`` as 3, where YAML 1.2, which the scene
        files follow, reads ``010`` as 10 and ``0b11`` as text: such a number is refused where it stands
        (never one reading or the other).  ``1:30`` (1.1: 90) and ``1_0`` (1.1: 10) are text in YAML 1.2
        and are read so (a number field then refuses them by name; a name keeps them)."""
        text = self.construct_scalar(node)
        if _INT.fullmatch(text):
            return int(text)
        if ":" in text or "_" in text:
            return text
        if re.fullmatch(r"[-+]?0[0-9]+", text):
            why = "a number with a leading zero (YAML 1.1 reads 010 as the octal 8, YAML 1.2 as 10)"
        else:
            why = "a hexadecimal, octal or binary number (YAML 1.1 and 1.2 read them differently)"
        raise _BadNumber(text, node.start_mark, why + "; write it in decimal, or quote it if it is a name")

    def construct_yaml_float(self, node):
        """YAML 1.1's floats also read ``1:30.5`` (base 60) and ``1_0.5`` (underscores dropped): text in YAML
        1.2, and read so; ``.inf`` and ``.nan`` are read (the fields that take a number refuse them by name)."""
        text = self.construct_scalar(node)
        if ":" in text or "_" in text:
            return text
        return super().construct_yaml_float(node)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            first: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                line = key_node.start_mark.line + 1
                try:
                    if key in first:
                        raise _DuplicateKey(key, line, first[key])
                    first[key] = line
                except TypeError:  # an unhashable key: the base constructor reports it
                    continue
        return super().construct_mapping(node, deep=deep)


_SceneLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)
_SceneLoader.add_constructor("tag:yaml.org,2002:int", _SceneLoader.construct_yaml_int)
_SceneLoader.add_constructor("tag:yaml.org,2002:float", _SceneLoader.construct_yaml_float)
