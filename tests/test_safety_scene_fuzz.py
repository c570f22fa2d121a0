"""A bounded, seeded fuzz test of the YAML scene loader.

Each input is a valid scene file with one mutation (a value replaced by a boolean, a numeric
string, a huge or non-finite number, a wrong type, a key dropped, an unknown key added, a key
repeated).  Every input must either load into a scene that the detector and the verifier accept,
or raise an ArmguardError naming the file and the place; no other exception, no hang, and no
value silently coerced into a number.
"""

from __future__ import annotations

import copy
import signal
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard import ArmguardError, DetectionError, SceneFileError
from armguard.scene import load_scene_file

BASE = {
    "armguard_scene": 1,
    "name": "fuzz",
    "units": {"angle": "deg", "length": "m"},
    "frames": [{"name": "site", "xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]}],
    "bodies": [
        {"name": "table", "frame": "site", "xyz": [0.0, 0.0, -0.05],
         "shapes": [{"type": "box", "size": [2.0, 2.0, 0.1]}]},
        {"name": "post", "xyz": [0.8, 0.0, 0.0], "shapes": [
            {"type": "capsule", "p0": [0.0, 0.0, 0.0], "p1": [0.0, 0.0, 0.5], "radius": 0.05},
            {"type": "sphere", "xyz": [0.0, 0.0, 0.6], "radius": 0.08}]},
        {"name": "bin", "xyz": [-0.7, 0.3, 0.2], "shapes": [
            {"type": "prism", "n_sides": 6, "apothem": 0.1, "length": 0.2},
            {"type": "polyhedron", "xyz": [0.0, 0.4, 0.0],
             "vertices": [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]},
            {"type": "polygon", "xyz": [0.0, -0.4, 0.0], "vertices": [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]}]},
    ],
    "robots": [{
        "name": "arm",
        "joints": [
            {"a": 0.3, "alpha": 0.0, "d": 0.2, "limits": [-170.0, 170.0], "max_velocity": 90.0,
             "max_acceleration": 180.0},
            {"a": 0.25, "limits": [-120.0, 120.0], "max_velocity": 90.0, "max_acceleration": 180.0},
        ],
        "link_shapes": {"link1": [{"type": "link_capsule", "radius": 0.03}],
                        "link2": [{"type": "capsule", "p0": [-0.25, 0, 0], "p1": [0, 0, 0], "radius": 0.03}]},
        "home": [10.0, 20.0],
    }],
    "workspace": {"lo": [-2.0, -2.0, -1.0], "hi": [2.0, 2.0, 2.0]},
    "trajectories": [{"name": "swing", "robot": "arm", "waypoints": [[10.0, 20.0], [60.0, -30.0]],
                      "profile": "trapezoidal"}],
}

REPLACEMENTS = [True, False, "1e3", "0.5", "abc", "", None, 0, 1, -1, 0.0, -0.5, 1e300, -1e300, 1e12, 3.5, 500.0, 1e8,
                2 ** 70, [], {}, [1.0, 2.0], [[1.0]], {"x": 1.0}, "inf", ".nan"]
NON_FINITE_TEXT = [".nan", ".inf", "-.inf"]
TIMEOUT_S = 20  # per input: loading plus the detector and the verifier on a tiny scene


class _Dumper(yaml.SafeDumper):
    """Writes a string that reads as a number quoted (YAML 1.2 reads an unquoted 1e3 as a number)."""


def _str(dumper, s):
    try:
        float(s)
        style = '"'
    except ValueError:
        style = None
    return dumper.represent_scalar("tag:yaml.org,2002:str", s, style=style)


_Dumper.add_representer(str, _str)


def _dump(doc) -> str:
    return yaml.dump(doc, Dumper=_Dumper, sort_keys=False)


def _paths(node, prefix=()):
    """Every (path, value) below ``node`` (mapping keys and list indices)."""
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out.append((prefix + (k,), v))
            out.extend(_paths(v, prefix + (k,)))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out.append((prefix + (i,), v))
            out.extend(_paths(v, prefix + (i,)))
    return out


PATHS = _paths(BASE)


def _parent(doc, path):
    node = doc
    for p in path[:-1]:
        node = node[p]
    return node


@st.composite
def mutated(draw):
    """(YAML text, description, whether a number was replaced by a non-number)."""
    doc = copy.deepcopy(BASE)
    path, old = draw(st.sampled_from(PATHS))
    kind = draw(st.sampled_from(["replace", "replace", "replace", "drop", "unknown_key", "duplicate", "nonfinite"]))
    parent = _parent(doc, path)
    key = path[-1]
    coerced = False
    if kind == "replace":
        new = draw(st.sampled_from(REPLACEMENTS))
        parent[key] = new
        numeric = isinstance(old, (int, float)) and not isinstance(old, bool)
        coerced = numeric and (isinstance(new, (bool, str)))
        return _dump(doc), f"{path} = {new!r}", coerced
    if kind == "drop":
        if isinstance(parent, dict):
            del parent[key]
        else:
            parent.pop(key)
        return _dump(doc), f"drop {path}", False
    if kind == "unknown_key":
        target = parent[key] if isinstance(parent[key], dict) else parent
        if isinstance(target, dict):
            target["colour"] = "red"
        return _dump(doc), f"unknown key at {path}", False
    text = _dump(doc)
    lines = text.splitlines()
    k = draw(st.integers(0, len(lines) - 1))
    line = lines[k]
    if kind == "nonfinite":
        nums = [i for i, ln in enumerate(lines) if ln.rstrip().split(" ")[-1].replace(".", "", 1).replace("-", "", 1).isdigit()]
        if nums:
            k = nums[k % len(nums)]
            head = lines[k].rstrip().rsplit(" ", 1)[0]
            lines[k] = f"{head} {draw(st.sampled_from(NON_FINITE_TEXT))}"
            return "\n".join(lines) + "\n", f"non-finite at line {k + 1}", False
        return text, "unchanged", False
    # duplicate: repeat a "key: value" line right after itself (same indentation, same mapping)
    if ":" in line and not line.lstrip().startswith("- "):
        lines.insert(k + 1, line)
        return "\n".join(lines) + "\n", f"duplicate line {k + 1}: {line.strip()}", False
    return text, "unchanged", False


class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang(f"no answer within {TIMEOUT_S} s")


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """Load the base scene once and run every entry point on it (compiles the kernels before any timing)."""
    path = tmp_path_factory.mktemp("fuzz") / "base.yaml"
    path.write_text(_dump(BASE), encoding="utf-8")
    _entry_points(load_scene_file(path))
    return path.parent


def _entry_points(scene):
    """Every entry point on a loaded scene: the detector (exact, budget, batch) and the verifier."""
    det = armguard.Detector(scene, threshold=0.05)
    q = scene.flat_q(scene.default_q())
    det.check(q)
    det.check(q, budget_us=0.0)
    det.collides_many(np.tile(q, (4, 1)))
    det.pair_distances(q)
    if scene.trajectories:
        armguard.verify(scene, next(iter(scene.trajectories.values())), stopping_distance=0.01)


@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(case=mutated())
def test_the_loader_loads_or_names_the_file_and_place(warm, case):
    text, what, coerced = case
    path = Path(warm) / "case.yaml"
    path.write_text(text, encoding="utf-8")
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIMEOUT_S)
    try:
        try:
            scene = load_scene_file(path)
        except SceneFileError as exc:
            assert str(path) in str(exc), (what, str(exc))
            assert exc.where, f"{what}: the error names no place: {exc}"
            return
        except ArmguardError as exc:  # pragma: no cover - every loader error is a SceneFileError
            pytest.fail(f"{what}: {type(exc).__name__} instead of SceneFileError: {exc}")
        assert not coerced, f"{what}: a non-number was accepted as a number"
        try:
            _entry_points(scene)
        except DetectionError as exc:  # a scene with nothing to check (a robot whose shapes were dropped): named, no verdict
            assert "has no pair to check" in str(exc), (what, str(exc))
    except _Hang:
        pytest.fail(f"{what}: hang")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_the_fuzzer_reaches_both_outcomes(warm):
    """An honest fuzz test: its mutations produce loadable files and refused ones."""
    loaded = refused = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        doc = copy.deepcopy(BASE)
        path, old = PATHS[rng.integers(len(PATHS))]
        if isinstance(old, (int, float)) and not isinstance(old, bool):
            _parent(doc, path)[path[-1]] = "1e3" if seed % 2 else float(old)
        p = Path(warm) / "probe.yaml"
        p.write_text(_dump(doc), encoding="utf-8")
        try:
            load_scene_file(p)
            loaded += 1
        except SceneFileError:
            refused += 1
    assert loaded > 0 and refused > 0
