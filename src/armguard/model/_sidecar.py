"""The sidecar YAML of an exported model: its sections, and the source file's comments carried over.

Used by :func:`armguard.model.export.export_scene`.
"""

from __future__ import annotations

import math
import re

import numpy as np

from ..kinematics import JointType

SIDECAR_SECTIONS = ("workspace", "trajectories", "canned_tests")
"""Sections of a scene file the sidecar keeps (copied as written when the source file is given)."""

__all__ = ["SIDECAR_SECTIONS", "source_notes", "generated_sections", "sidecar_text"]


def _split_comment(line: str) -> tuple[str, str]:
    """``(content, comment)`` of a YAML line (a ``#`` outside quotes, at the start or after a blank)."""
    quote = None
    for k, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or line[k - 1] in " \t"):
            return line[:k].rstrip(), line[k:].strip()  # the comment keeps its '#' (and its "# assumed")
    return line.rstrip(), ""


_TOP = re.compile(r"^([A-Za-z_]\w*):")
_KEY = re.compile(r"^\s*(?:- )?\{?\s*([A-Za-z_]\w*):")
_NAME = re.compile(r"\bname:\s*([A-Za-z0-9_.\-]+)")


def source_notes(text: str) -> tuple[str, dict, dict]:
    """``(header, notes, sections)`` of a scene file's text.

    ``header``: the leading comment block; ``notes[(section, item)]``: the comments of a listed
    body, robot or payload (``(section, "*")``: all comments of a section, ``("home", robot)`` and
    ``("self_pairs", robot)``: a robot's comments on those keys); ``sections[key]``: the text of
    a top-level section with the comment lines just above it.
    """
    lines = text.splitlines()
    k = 0
    while k < len(lines) and (lines[k].startswith("#") or not lines[k].strip()):
        k += 1
    header = "\n".join(ln[2:] if ln.startswith("# ") else ln.lstrip("#") for ln in lines[:k]).strip("\n")
    tops = [i for i, ln in enumerate(lines) if _TOP.match(ln)]
    starts = []
    for i in tops:  # a section begins with the comment lines just above its key
        start = i
        while start - 1 >= k and lines[start - 1].startswith("#"):
            start -= 1
        starts.append(start)
    sections, notes = {}, {}
    for n, i in enumerate(tops):
        key = _TOP.match(lines[i]).group(1)
        end = starts[n + 1] if n + 1 < len(tops) else len(lines)
        while end > i + 1 and not lines[end - 1].strip():
            end -= 1
        block = lines[starts[n]:end]
        sections[key] = "\n".join(block)
        comments = [c for c in (_split_comment(ln)[1] for ln in block) if c]
        notes[(key, "*")] = "\n".join(comments)
        _item_notes(key, lines[i + 1:end], notes)
    return header, notes, sections


def _item_notes(section: str, body: list[str], notes: dict) -> None:
    starts = [j for j, ln in enumerate(body) if ln.lstrip().startswith("- ")]
    if not starts:
        return
    indent = min(len(body[j]) - len(body[j].lstrip()) for j in starts)
    starts = [j for j in starts if len(body[j]) - len(body[j].lstrip()) == indent]
    prev = 0
    for n, j in enumerate(starts):
        end = starts[n + 1] if n + 1 < len(starts) else len(body)
        pre = [_split_comment(ln)[1] for ln in body[prev:j] if ln.strip().startswith("#")]
        prev = j + 1
        match = _NAME.search(body[j])
        if match is None:
            continue
        item = match.group(1)
        by_key: dict[str, list[str]] = {"name": list(pre)}
        key, pending = "name", []
        for ln in body[j:end]:
            content, comment = _split_comment(ln)
            if not content.strip():
                if comment:
                    pending.append(comment)
                continue
            km = _KEY.match(content)
            if km and len(content) - len(content.lstrip()) in (indent, indent + 2):
                key = km.group(1)
            by_key.setdefault(key, []).extend(pending)
            pending = []
            if comment:
                by_key[key].append(comment)
        by_key.setdefault(key, []).extend(pending)
        general = [c for kk, cs in by_key.items() if kk not in ("home", "self_pairs") for c in cs]
        notes[(section, item)] = "\n".join(general)
        notes[("home", item)] = "\n".join(by_key.get("home", []))
        notes[("self_pairs", item)] = "\n".join(by_key.get("self_pairs", []))


# ------------------------------------------------------------------ the sidecar
def generated_sections(scene) -> dict:
    """The sidecar sections from the scene itself (no source file): angles in degrees."""
    import yaml

    from ._save import scene_to_dict

    d = scene_to_dict(scene)

    def q(robot, values):  # rad -> deg for revolute joints
        f = [1.0 if jt is JointType.PRISMATIC else 180.0 / math.pi for jt in scene.robots[robot].joint_types]
        return [float(f"{x:.12g}") for x in np.asarray(values) * f]

    for t in d.get("trajectories", []):
        t["waypoints"] = [q(t["robot"], w) for w in t["waypoints"]]
    for c in d.get("canned_tests", []):
        c["setup"] = {r: q(r, v) for r, v in c["setup"].items()}
        mo = c["motion"]
        if "goal" in mo:
            mo["goal"] = q(c["robot"], mo["goal"])
        elif "end_effector" in mo:
            scale = np.array([1.0, 1.0, 1.0] + [180.0 / math.pi] * 3)  # m stay m; rad -> deg
            mo["end_effector"] = [float(f"{x:.12g}") for x in np.asarray(mo["end_effector"]) * scale]
        else:
            mo["arm_angle"] = float(f"{mo['arm_angle'] * 180.0 / math.pi:.12g}")
    out = {}
    for key in SIDECAR_SECTIONS:
        if d.get(key):
            out[key] = yaml.safe_dump({key: d[key]}, sort_keys=False, default_flow_style=None, width=120).rstrip()
    return out


def sidecar_text(name: str, scene, header: str, sections: dict, units: dict) -> str:
    import yaml

    deg = units.get("angle", "rad") == "deg"
    mm = units.get("length", "m") == "mm"
    out = [f"# {ln}".rstrip() for ln in header.split("\n")] if header else []
    if out:
        out.append("#")
    out += ["# The sidecar of the model: what URDF cannot say (docs/models.md).  Geometry, kinematics,",
            f"# limits and speeds are in {name}.urdf; groups, disabled pairs and homes in {name}.srdf.",
            "armguard_scene: 1", f"name: {name}"]
    if scene.description:
        out.append(yaml.safe_dump({"description": scene.description}, width=10**6).rstrip())
    out += [f"units: {{angle: {'deg' if deg else 'rad'}, length: {'mm' if mm else 'm'}}}",
            f"model: {{urdf: {name}.urdf, srdf: {name}.srdf}}"]
    ik = {r: robot.ik for r, robot in scene.robots.items() if getattr(robot, "ik", None)}
    if ik:  # each arm's inverse kinematics (without it a numeric arm warns on its first use)
        flow = "ik: {" + ", ".join(f"{r}: {routine}" for r, routine in ik.items()) + "}"
        if all(routine == "numeric" for routine in ik.values()):
            out.append(flow + "  # inverse kinematics: damped least squares (no closed form for this arm)")
        else:
            out += ["# Each robot's inverse kinematics: a routine registered by name (armguard.kinematics.register_ik),",
                    '# "module:function", or "numeric" (the default solver).', flow]
    if "workspace" in sections:
        out += ["", sections["workspace"]]
    acc = []
    for rname, robot in scene.robots.items():
        for j, jt, a in zip(robot.joint_names, robot.joint_types, robot.max_acceleration):
            if math.isfinite(a):
                f = (1e3 if mm else 1.0) if jt is JointType.PRISMATIC else (180.0 / math.pi if deg else 1.0)
                acc.append(f"  {rname}/{j}: {{max_acceleration: {float(a) * f:.12g}}}")
    if acc:
        unit = "deg/s^2" if deg else "rad/s^2"
        out += ["", f"# Joint accelerations for trapezoidal profiles ({unit}; prismatic joints "
                f"{'mm' if mm else 'm'}/s^2): URDF has no place for them.", "joints:", *acc]
    for key in SIDECAR_SECTIONS[1:]:
        if key in sections:
            out += ["", sections[key]]
    return "\n".join(out) + "\n"
