"""``armguard check-urdf`` / ``tools/check_urdf.py``: the built-ins are clean; broken copies are named, never a crash."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main
from armguard.harness import Check, LintStatus, Severity, check_model_files, mesh_convexity, repo_root

BUILTINS = ["ranger", "hermes", "puma560", "gmf_s480", "rover"]

# an L-shaped prism (not convex): the polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), z in [0, 1]
_L = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]


def _l_prism_obj(offset=(0.0, 0.0, 0.0)) -> str:
    ox, oy, oz = offset
    v = [f"v {x + ox} {y + oy} {z + oz}" for z in (0, 1) for x, y in _L]
    n = len(_L)
    f = [f"f 1 {k + 2} {k + 1}" for k in range(1, n - 1)]  # bottom, facing -z (a fan from (0,0): the L is star-shaped)
    f += [f"f {n + 1} {n + k + 1} {n + k + 2}" for k in range(1, n - 1)]  # top
    for k in range(n):
        a, b = k + 1, (k + 1) % n + 1
        f += [f"f {a} {b} {b + n}", f"f {a} {b + n} {a + n}"]
    return "\n".join(v + f) + "\n"


@pytest.fixture
def hermes_copy(tmp_path):
    shutil.copytree(repo_root() / "urdf" / "hermes", tmp_path / "hermes")
    return tmp_path / "hermes"


def _edit(path: Path, old: str, new: str) -> None:
    s = path.read_text()
    assert old in s, old
    path.write_text(s.replace(old, new, 1))


@pytest.mark.parametrize("name", BUILTINS)
def test_the_builtin_models_are_clean(name):
    report = check_model_files(name, n_configs=40)
    assert report.status is LintStatus.CLEAN, [f.message for f in report.findings]


def test_a_plain_capsule_tag_is_a_finding_not_a_crash(hermes_copy):
    _edit(hermes_copy / "hermes.urdf", '<cylinder radius="0.15" length="4.2"/>', '<capsule radius="0.15" length="4.2"/>')
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=10)
    assert report.status is LintStatus.ERRORS
    (load,) = report.by_check(Check.LOAD)
    assert "link[hera_link3].collision[0]" in load.message
    (dropped,) = report.by_check(Check.UNPARSED)
    assert dropped.where.endswith("link[hera_link3].collision[0]") and "<capsule>" in dropped.message
    assert "collision_checking" in dropped.suggestion


def test_a_nonconvex_mesh_marked_convex(hermes_copy, tmp_path):
    (hermes_copy / "meshes" / "tail_0.obj").write_text(_l_prism_obj((-7.0, -1.0, 1.0)))
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=10)
    (f,) = report.by_check(Check.NON_CONVEX)
    assert f.severity is Severity.ERROR and "link[tail].collision[0]" in f.where and "volume 0.8571 of its hull" in f.message  # 3 of 3.5 m^3
    # the measure itself: a cube is convex, a flat L is not, a flat square is
    ok, _ = mesh_convexity(repo_root() / "urdf" / "hermes" / "meshes" / "tail_0.obj")
    assert ok
    flat = tmp_path / "flat.obj"
    flat.write_text("\n".join(f"v {x} {y} 0" for x, y in _L) + "\nf 1 2 3 4 5 6\n")
    assert not mesh_convexity(flat)[0]
    flat.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    assert mesh_convexity(flat)[0]


def test_a_zero_length_capsule(hermes_copy):
    _edit(hermes_copy / "hermes.urdf", '<cylinder radius="0.15" length="4.2"/>', '<cylinder radius="0.15" length="0"/>')
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=10)
    (f,) = report.by_check(Check.ZERO_LENGTH_CAPSULE)
    assert "hera_link3" in f.where and f.suggestion == '<sphere radius="0.15"/>'


def test_srdf_names_that_match_nothing(hermes_copy):
    _edit(hermes_copy / "hermes.srdf", "</robot>",
          '<group name="tools"><link name="gripper"/></group>\n'
          '<group_state name="ready" group="hera"><joint name="hera_knee" value="0"/></group_state>\n</robot>')
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=10)
    found = {(f.where.split(": ")[1], f.message) for f in report.by_check(Check.SRDF_NAME)}
    text = (hermes_copy / "hermes.srdf").read_text()
    line = text[:text.index('<link name="gripper"/>')].count("\n") + 1  # each place with the line of its element
    assert (f"group[tools].link (line {line})", "link 'gripper' matches nothing in the URDF") in found
    assert (f"group_state[ready].joint (line {line + 1})", "joint 'hera_knee' matches nothing in the URDF") in found


def test_a_group_state_without_group_is_a_warning_as_the_loader_reads_it(hermes_copy):
    # the loader reads such a state as the whole robot's (as Pinocchio does) and warns; the lint says
    # the same, not "group None matches nothing"
    _edit(hermes_copy / "hermes.srdf", "</robot>",
          '<group_state name="stowed"><joint name="hera_elbow" value="0"/></group_state>\n</robot>')
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=10)
    found = [f for f in report.by_check(Check.SRDF_NAME) if "stowed" in f.where]
    assert [(f.severity, f.where.split(": ")[1]) for f in found] == [(Severity.WARNING, "group_state[stowed]")]
    assert "whole robot" in found[0].message and "None" not in found[0].message


def test_the_findings_table_prints_brackets_as_they_are(hermes_copy):
    # rich read "[tools]" in a finding's place as markup and dropped it: "group.link" instead of "group[tools].link"
    _edit(hermes_copy / "hermes.srdf", "</robot>", '<group name="tools"><link name="gripper"/></group>\n</robot>')
    res = CliRunner().invoke(main, ["check-urdf", str(hermes_copy / "hermes.yaml"), "--configs", "5"])
    assert res.exit_code == 1, res.output
    assert "group[tools].link" in res.output and "link 'gripper' matches nothing in the URDF" in res.output


def test_a_pair_in_permanent_collision_gets_a_disable_line(hermes_copy):
    # link 2 grown to a 3 m radius round the shoulder, which stands on the bay floor: it never clears the floor
    _edit(hermes_copy / "hermes.urdf", '<geometry><cylinder radius="0.18" length="4.2"/>',
          '<geometry><cylinder radius="3.0" length="4.2"/>')
    report = check_model_files(hermes_copy / "hermes.yaml", n_configs=60)
    perm = [f for f in report.by_check(Check.PERMANENT_COLLISION) if f.severity is Severity.ERROR]
    assert perm, [f.message for f in report.findings]
    assert all(f.suggestion.startswith("<disable_collisions link1=") for f in perm)
    # "Always", MoveIt's reason for a pair in collision at >= 95 % of samples ("Never" said the opposite)
    assert '<disable_collisions link1="hera_link2" link2="cargo_bay" reason="Always"/>' in {f.suggestion for f in perm}


def test_a_pair_in_collision_at_home_only_is_not_called_permanent():
    """franka_panda's fingers touch at home (-0.2 mm) and almost never elsewhere: a home-collision warning,
    not a "permanent-collision" that is "in collision at 0% of 200 random configurations"."""
    report = check_model_files("franka_panda", n_configs=40)
    home = report.by_check(Check.HOME_COLLISION)
    assert any("panda_leftfinger_0, panda_rightfinger_0" in f.where for f in home), [f.where for f in report.findings]
    assert all(f.severity is Severity.WARNING and f.suggestion is None for f in home)
    for f in report.by_check(Check.PERMANENT_COLLISION):
        share = float(f.message.split("in collision at ")[-1].split("%")[0])
        assert share > 95.0, f.message


def test_cli_and_tool(hermes_copy):
    res = CliRunner().invoke(main, ["check-urdf", "gmf_s480", "--configs", "10"])
    assert res.exit_code == 0 and "clean" in res.output
    _edit(hermes_copy / "hermes.urdf", '<cylinder radius="0.15" length="4.2"/>', '<capsule radius="0.15" length="4.2"/>')
    res = CliRunner().invoke(main, ["check-urdf", str(hermes_copy / "hermes.urdf"), "--json"])
    assert res.exit_code == 1
    assert json.loads(res.output)["status"] == "errors"
    tool = subprocess.run([sys.executable, str(repo_root() / "tools" / "check_urdf.py"), str(hermes_copy / "hermes.urdf"),
                           "--configs", "5"], capture_output=True, text=True, timeout=120)
    assert tool.returncode == 1 and "unparsed" in tool.stdout


def test_a_file_that_is_not_xml_is_one_finding_and_an_srdf_says_its_place_once(tmp_path):
    """Not XML: the load finding alone (it was there twice, column 1 in one and 0 in the other); a truncated
    SRDF's error says ``line L, column C`` once (it said the line twice)."""
    bad = tmp_path / "garbage.urdf"
    bad.write_text("garbage here\n")
    report = check_model_files(bad, n_configs=5)
    assert [f.check for f in report.findings] == [Check.LOAD]
    assert "line 1, column 1: not well-formed XML: syntax error" in report.findings[0].message
    srdf = tmp_path / "cut.srdf"
    srdf.write_text('<robot name="ur5"><disable_collisions link1="a"')
    with pytest.raises(armguard.SceneFileError) as exc:
        armguard.load_model("ur5", srdf=srdf)
    assert exc.value.where == "line 1, column 19" and exc.value.message == "not well-formed XML: unclosed token"
    assert str(exc.value).count("line 1") == 1
