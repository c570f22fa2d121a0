"""URDF-driven updates of a certified SRDF: certificates, ``load_model``'s warning, ``check-urdf``, ``srdf --update``.

A copy of the built-in PUMA 560's URDF gets its certified SRDF (``armguard srdf``); then one edit
grows the sphere at the end of link 3 from 6 cm to 35 cm, which makes the proven-*Never* pair
``link1``-``link3`` collide.  The certificate of that pair breaks and no other of link 1's does;
loading warns, ``check-urdf`` finds the collision (confirmed by coal at its witness), and
``armguard srdf --update`` searches only the pairs whose certificate broke.
"""

from __future__ import annotations

import shutil
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard._errors import ArmguardWarning
from armguard.cli import main
from armguard.model import models_dir
from armguard.model._certificate import FINGERPRINT_ATTR, pair_fingerprint, stale_certificates
from armguard.srdfgen import collision_matrix

MAX_EVALUATIONS = 5_000
SPHERE = '<geometry><sphere radius="0.06"/></geometry>'
NEVER = ("puma560_link1", "puma560_link3")


@pytest.fixture(scope="module")
def certified(tmp_path_factory):
    """``(folder, urdf, text of the certified SRDF)``: the PUMA 560's URDF and its certified SRDF beside it."""
    folder = tmp_path_factory.mktemp("puma")
    shutil.copytree(models_dir() / "puma560", folder / "puma560")
    urdf = folder / "puma560" / "puma560.urdf"
    cm = collision_matrix(armguard.load_model(urdf, srdf=False), max_evaluations=MAX_EVALUATIONS)
    assert any((e.link1, e.link2) == NEVER and e.reason == "Never" for e in cm.entries), cm.entries
    cm.write_srdf(urdf.with_suffix(".srdf"))
    return folder, urdf, urdf.with_suffix(".srdf").read_text()


def _fresh(certified, tmp_path, *, grow: bool) -> Path:
    folder, urdf, srdf_text = certified
    shutil.copytree(folder / "puma560", tmp_path / "puma560")
    new = tmp_path / "puma560" / "puma560.urdf"
    new.with_suffix(".srdf").write_text(srdf_text)
    if grow:
        text = new.read_text()
        assert text.count(SPHERE) == 1
        new.write_text(text.replace(SPHERE, '<geometry><sphere radius="0.35"/></geometry>'))
    return new


def test_every_written_pair_carries_a_certificate_that_the_model_reproduces(certified):
    _, urdf, text = certified
    root = ET.fromstring(text)
    pairs = root.findall("disable_collisions")
    assert pairs and all(p.get(FINGERPRINT_ATTR) for p in pairs)
    model = armguard.load_model(urdf)
    for p in pairs:
        fp = pair_fingerprint(model.pin_model, model.collision_model, p.get("link1"), p.get("link2"),
                              margin=0.0, method="certified", verdict=p.get("reason"))
        assert fp == p.get(FINGERPRINT_ATTR)
        # the same pair named the other way round has the same certificate
        assert fp == pair_fingerprint(model.pin_model, model.collision_model, p.get("link2"), p.get("link1"),
                                      margin=0.0, method="certified", verdict=p.get("reason"))
        # another margin, method or verdict is another certificate
        assert fp != pair_fingerprint(model.pin_model, model.collision_model, p.get("link1"), p.get("link2"),
                                      margin=0.01, method="certified", verdict=p.get("reason"))
        assert fp != pair_fingerprint(model.pin_model, model.collision_model, p.get("link1"), p.get("link2"),
                                      margin=0.0, method="certified", verdict=None)
    assert stale_certificates(model.pin_model, model.collision_model, urdf.with_suffix(".srdf")) == ()


def test_certificates_follow_only_what_a_verdict_depends_on(certified, tmp_path):
    """Growing link 3's sphere breaks every pair with link 3 and none without it; a joint limit below both
    links of a pair breaks that pair, one above their common ancestor does not."""
    new = _fresh(certified, tmp_path, grow=True)
    base = armguard.load_model(certified[1], srdf=False)
    grown = armguard.load_model(new, srdf=False)

    def fp(m, a, b):
        return pair_fingerprint(m.pin_model, m.collision_model, a, b, margin=0.0, method="certified", verdict="Never")

    links = ["puma560_base", "puma560_link1", "puma560_link2", "puma560_link3", "puma560_tool"]
    for i, a in enumerate(links):
        for b in links[i + 1:]:
            assert (fp(base, a, b) != fp(grown, a, b)) == ("puma560_link3" in (a, b)), (a, b)
    # joint 1 (base -> link1) drives link1-link3's common ancestor only; joint 3 (link2 -> link3) lies between them
    for joint, between in (("puma560_j1", False), ("puma560_j3", True)):
        m = armguard.load_model(certified[1], srdf=False)
        j = m.pin_model.getJointId(joint)
        m.pin_model.upperPositionLimit[m.pin_model.joints[j].idx_q] -= 0.1
        assert (fp(m, *NEVER) != fp(base, *NEVER)) is between, joint


def test_loading_an_edited_urdf_warns_of_the_pairs_it_may_now_collide(certified, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        armguard.load_model(_fresh(certified, tmp_path / "same", grow=False))  # unedited: no warning
    with pytest.warns(ArmguardWarning, match=r"certified for another geometry.*puma560_link1-puma560_link3 \(Never\)"):
        model = armguard.load_model(_fresh(certified, tmp_path / "grown", grow=True))
    assert any("certified for another geometry" in w for w in model.srdf.warnings)


def test_check_urdf_finds_the_collision_the_edit_made_and_coal_confirms_it(certified, tmp_path):
    from armguard.harness import check_model_files

    new = _fresh(certified, tmp_path, grow=True)
    with pytest.warns(ArmguardWarning):
        report = check_model_files(new, n_configs=5)
    found = [f for f in report.findings if f.check.value == "srdf-certificate"]
    errors = [f for f in found if f.severity.value == "error"]
    assert len(errors) == 1 and "puma560_link1 - puma560_link3" in errors[0].message, found
    assert report.status.value == "errors"
    # the witness is a real collision of the edited model (coal, all pairs of the two links)
    q = np.array([float(x) for x in errors[0].message.split("q = [")[1].split("]")[0].split(",")])
    model = armguard.load_model(new, srdf=False)
    res = armguard.checker(model, "coal").pair_distances(q)

    def link(g):
        return model.pin_model.frames[model.collision_model.geometryObjects[model.geometry_index(g)].parentFrame].name

    rows = [k for k, (a, b) in enumerate(res.pairs) if {link(a), link(b)} == set(NEVER)]
    assert rows
    assert float(np.min(res.distance[rows])) < 0.0  # in contact (the message gives q to 4 decimals)


def test_srdf_update_searches_only_what_changed(certified, tmp_path):
    runner = CliRunner()
    same = _fresh(certified, tmp_path / "same", grow=False)
    srdf = same.with_suffix(".srdf")
    r = runner.invoke(main, ["srdf", str(same), "--out", str(srdf), "--update", "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0, r.output
    assert "searched again" in r.output and " 0 searched again" in r.output, r.output
    assert srdf.read_text() == certified[2]  # nothing changed: the same file

    grown = _fresh(certified, tmp_path / "grown", grow=True)
    srdf = grown.with_suffix(".srdf")
    r = runner.invoke(main, ["srdf", str(grown), "--out", str(srdf), "--update", "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0, r.output
    assert "changed puma560_link1 - puma560_link3: Never -> witnessed" in r.output, r.output
    kept = int(r.output.split("--update: ")[1].split(" pairs kept")[0])
    assert kept >= 1
    disabled = {frozenset((e.get("link1"), e.get("link2"))) for e in ET.parse(srdf).getroot().findall("disable_collisions")}
    assert frozenset(NEVER) not in disabled
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        armguard.load_model(grown)  # the updated SRDF's certificates all hold


def test_srdf_update_needs_an_existing_file(tmp_path):
    r = CliRunner().invoke(main, ["srdf", "puma560", "--out", str(tmp_path / "none.srdf"), "--update"])
    assert r.exit_code == 2 and "--update rewrites an SRDF written before" in r.output


def test_a_built_in_model_takes_the_srdf_it_is_given(certified):
    """``srdf=`` replaces a built-in model's pairs (it used to be ignored for a sidecar): the certified SRDF
    disables link1-link3, which the shipped one checks; ``srdf=False`` disables none of the file's pairs."""
    _, urdf, _ = certified
    shipped = armguard.load_model("puma560")
    given = armguard.load_model("puma560", srdf=urdf.with_suffix(".srdf"))
    assert Path(given.srdf.file) == urdf.with_suffix(".srdf")
    assert given.scene.joint_names == shipped.scene.joint_names  # the arm keeps its name and home
    own = {frozenset(p) for p in zip(shipped.pairs.owner_a, shipped.pairs.owner_b)}
    assert frozenset(("puma560/link1", "puma560/link3")) in own
    assert frozenset(("puma560/link1", "puma560/link3")) not in {frozenset(p) for p in zip(given.pairs.owner_a, given.pairs.owner_b)}
    assert armguard.load_model("puma560", srdf=False).srdf.disabled == ()


def test_a_given_srdf_that_renames_the_arm_says_so(tmp_path):
    """An SRDF given to a built-in model whose group names its arm otherwise: the sidecar's references to
    the arm fail, and the error says why (the arms are named by the SRDF's groups), naming both names."""
    from armguard import SceneFileError

    text = Path(armguard.load_model("puma560").srdf.file).read_text()
    renamed = tmp_path / "hand.srdf"
    renamed.write_text(text.replace('group name="puma560"', 'group name="manipulator"').replace('group="puma560"',
                                                                                                 'group="manipulator"'))
    with pytest.raises(SceneFileError, match=r"srdf=.*hand\.srdf names 'manipulator' where this file names 'puma560'"):
        armguard.load_model("puma560", srdf=renamed)


_HAND = """<?xml version="1.0"?>
<robot name="puma560">
  <!-- written by hand, as MoveIt's Setup Assistant would -->
  <group name="puma560"><chain base_link="puma560_base" tip_link="puma560_tool"/></group>
  <group_state name="home" group="puma560"><joint name="puma560_j1" value="0"/></group_state>
  <end_effector name="tool" parent_link="puma560_tool" group="puma560"/>
  <disable_collisions link1="puma560_link1" link2="puma560_link2" reason="Adjacent"/>
</robot>
"""


def test_srdf_never_drops_a_hand_written_srdfs_groups(tmp_path):
    """A MoveIt SRDF's groups, states and end effector are not a collision matrix's to drop: writing over
    such a file is refused (the file untouched), ``--update`` keeps them, in order, and replaces the
    ``disable_collisions`` (no certificates in the file: every pair searched)."""
    srdf = tmp_path / "hand.srdf"
    srdf.write_text(_HAND)
    runner = CliRunner()
    r = runner.invoke(main, ["srdf", "puma560", "--out", str(srdf), "--max-evaluations", "300"])
    assert r.exit_code == 2 and "--update keeps them" in r.output and "group_state" in r.output, r.output
    assert srdf.read_text() == _HAND

    r = runner.invoke(main, ["srdf", "puma560", "--out", str(srdf), "--update", "--max-evaluations", "300"])
    assert r.exit_code == 0, r.output
    assert "carried no armguard certificates" in r.output and "kept 1 group, 1 group_state, 1 end_effector" in r.output, r.output
    root = ET.parse(srdf).getroot()
    assert [el.tag for el in root if el.tag != "disable_collisions"] == ["group", "group_state", "end_effector"]
    assert root.find("group/chain").get("tip_link") == "puma560_tool"
    assert root.find("group_state/joint").get("name") == "puma560_j1"
    disabled = root.findall("disable_collisions")
    assert disabled and all(el.get(FINGERPRINT_ATTR) for el in disabled)  # armguard's entries, with certificates
    model = armguard.load_model("puma560", srdf=srdf)
    assert model.srdf.file == srdf or Path(model.srdf.file) == srdf


def test_srdf_update_keeps_the_disabled_pairs_it_does_not_search(tmp_path):
    """hermes.srdf disables pairs the collision matrix never searches: static bodies against each other
    (``Static``) and links against obstacles by the paper's rules (``Seed``).  ``--update`` dropped them
    unannounced (the model then checked 8 more pairs); now they are kept as written and counted."""
    import shutil

    src = Path(armguard.load_model("hermes").srdf.file)
    srdf = tmp_path / "hermes.srdf"
    shutil.copy(src, srdf)
    outside = {(el.get("link1"), el.get("link2"), el.get("reason")) for el in ET.parse(src).getroot().findall("disable_collisions")
               if el.get("reason") in ("Static", "Seed") and not (el.get("link1") + el.get("link2")).count("hera_link") == 2}
    assert outside
    r = CliRunner().invoke(main, ["srdf", "hermes", "--out", str(srdf), "--update", "--max-evaluations", "300"])
    assert r.exit_code == 0, r.output
    n_static = sum(1 for o in outside if o[2] == "Static")
    assert f"{n_static} disable_collisions (Static, not searched)" in r.output, r.output
    after = {(el.get("link1"), el.get("link2"), el.get("reason")) for el in ET.parse(srdf).getroot().findall("disable_collisions")}
    assert outside <= after
    before_pairs = armguard.load_model("hermes").pairs
    after_pairs = armguard.load_model("hermes", srdf=srdf).pairs

    def robot_vs_rest(p):  # every pair but HERA's link-link pairs (the matrix's)
        return {(a, b) for a, b in zip(p.owner_a, p.owner_b) if not (a.startswith("hera/") and b.startswith("hera/"))}
    assert robot_vs_rest(after_pairs) == robot_vs_rest(before_pairs)  # the pairs the matrix does not search: as they were


_THREE = """<robot name="three">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0.55 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l3"><collision><origin xyz="0.2 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
</robot>"""


def test_srdf_update_after_a_joint_became_a_mimic_searches_the_witnessed_pairs_again(tmp_path):
    """A witness is a configuration of the model it was found on: with ``j3`` made a mimic of ``j2`` the
    configuration has 2 values; base - l2 (whose certificate holds: j1 and j2 unchanged) kept its witness of 3,
    and the summary failed after writing the file (and every later update the same)."""
    urdf, srdf = tmp_path / "three.urdf", tmp_path / "three.srdf"
    urdf.write_text(_THREE)
    r = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(srdf), "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0 and "checked base - l2: distance" in r.output, r.output
    urdf.write_text(_THREE.replace('<child link="l3"/>', '<child link="l3"/><mimic joint="j2" multiplier="-1" offset="0.1"/>'))
    for _ in range(2):  # and again on the file it wrote
        r = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(srdf), "--update", "--max-evaluations", str(MAX_EVALUATIONS)])
        assert r.exit_code == 0, r.output
    assert armguard.load_model(urdf).pin_model.nq == 2
    witnesses = [ln for ln in r.output.splitlines() if " at q = " in ln]
    assert witnesses and all(len(ln.split(" at q = ")[1].split(",")) == 2 for ln in witnesses), r.output


def test_no_stale_warning_for_a_pair_whose_link_lost_its_geometry(certified, tmp_path):
    """A link without geometry collides with nothing: its disabled pairs (Adjacent or Never) are not
    "may now collide"."""
    new = _fresh(certified, tmp_path, grow=False)
    root = ET.parse(new).getroot()
    link = next(ln for ln in root.findall("link") if ln.get("name") == "puma560_link3")
    for c in link.findall("collision") + link.findall("collision_checking"):
        link.remove(c)
    new.write_text(ET.tostring(root, encoding="unicode"))
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        model = armguard.load_model(new)
    assert not [w for w in rec if "may now collide" in str(w.message)], [str(w.message) for w in rec]
    assert not stale_certificates(model.pin_model, model.collision_model, new.with_suffix(".srdf"))


def test_a_group_state_value_of_a_mimic_joint_is_said_not_read(tmp_path):
    urdf = tmp_path / "three.urdf"
    urdf.write_text(_THREE.replace('<child link="l3"/>', '<child link="l3"/><mimic joint="j2" multiplier="-1" offset="0.1"/>'))
    (tmp_path / "three.srdf").write_text('<robot name="three"><group name="arm"><chain base_link="base" tip_link="l3"/></group>'
                                         '<group_state name="home" group="arm"><joint name="j1" value="0.2"/>'
                                         '<joint name="j2" value="1.0"/><joint name="j3" value="0.5"/></group_state></robot>')
    with pytest.warns(ArmguardWarning, match=r"\(j3\): value not read, a mimic joint of the URDF .*three.urdf: its value follows "
                                             r"joint 'j2' \(0.1 \+ -1 x its value\)"):
        model = armguard.load_model(urdf)
    np.testing.assert_allclose(model.neutral(), [0.2, 1.0])


def test_a_renamed_link_is_suggested(certified, tmp_path):
    """A link renamed in the URDF alone: the SRDF's pairs naming the old name suggest the link the SRDF never names."""
    new = _fresh(certified, tmp_path, grow=False)
    new.write_text(new.read_text().replace('"puma560_link3"', '"puma560_elbow"'))
    with pytest.raises(armguard.SceneFileError, match=r"names link 'puma560_link3', which the URDF .* does not have \(a link "
                                                      r"renamed 'puma560_elbow'\? then update the SRDF\)"):
        armguard.load_model(new)
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(new), "--json"])
    import json

    hints = {f["suggestion"] for f in json.loads(r.output)["findings"] if f["check"] == "srdf-name"}
    assert hints == {"a link renamed 'puma560_elbow'? then update the SRDF"}, r.output


def test_a_pair_an_edit_puts_in_contact_at_home_is_warned_of(tmp_path):
    """Disabled as Default (MoveIt's rule) after an edit grew a shape into another at home: it was only listed
    among the changes, as if the edit were meant."""
    urdf, srdf = tmp_path / "three.urdf", tmp_path / "three.srdf"
    urdf.write_text(_THREE)
    r = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(srdf), "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0, r.output
    grown = _THREE.replace('<link name="l3"><collision><origin xyz="0.2 0 0"/><geometry><box size="0.1 0.1 0.1"/>',
                           '<link name="l3"><collision><origin xyz="0.2 0 0"/><geometry><box size="2.5 0.1 0.1"/>')
    assert grown != _THREE
    urdf.write_text(grown)
    r = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(srdf), "--update", "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0, r.output
    assert "changed l1 - l3:" in r.output and "-> Default" in r.output, r.output
    assert "warning: l1 - l3 are in contact at home now (" in r.output and "did a shape grow or a joint move" in r.output


def test_check_urdf_says_when_a_checked_pair_is_no_longer_checked(tmp_path):
    """l2 stripped of its geometry joins l1 and l3 through a link without geometry (MoveIt's Adjacent): the pair
    the SRDF records as checked was dropped without a word."""
    import json

    urdf, srdf = tmp_path / "three.urdf", tmp_path / "three.srdf"
    urdf.write_text(_THREE)
    r = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(srdf), "--max-evaluations", str(MAX_EVALUATIONS)])
    assert r.exit_code == 0 and "checked l1 - l3: distance" in r.output, r.output
    urdf.write_text(_THREE.replace('<link name="l2"><collision><origin xyz="0.55 0 0"/><geometry><box size="0.1 0.1 0.1"/>'
                                   '</geometry></collision></link>', '<link name="l2"/>'))
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(urdf), "--json"])
    found = [(f["where"].split(": ", 1)[1], f["severity"], f["message"]) for f in json.loads(r.output)["findings"]
             if f["check"] == "srdf-certificate"]
    assert [(w, sev) for w, sev, _ in found] == [("l1 - l3", "warning")], found
    assert "recorded as checked (witnessed within the margin" in found[0][2] and "no longer checked" in found[0][2]


def test_a_joint_allowed_more_than_a_turn_is_searched_over_one(tmp_path):
    """Every pose a revolute joint takes within its limits it takes within one turn about its home: limits of
    +-31 rad (degrees written as radians, or UR's +-2 pi) searched over 62 rad left pairs undecided that one
    turn proves.  Not for a joint a mimic follows at another rate (its follower does not repeat)."""
    from armguard.srdfgen._pairs import pair_setup

    wide = tmp_path / "wide.urdf"
    wide.write_text(_THREE.replace('lower="-3.1" upper="3.1"', 'lower="-31" upper="31"'))
    narrow = tmp_path / "narrow.urdf"
    narrow.write_text(_THREE.replace('lower="-3.1" upper="3.1"', 'lower="-3.14159" upper="3.14159"'))
    st = pair_setup(armguard.load_model(wide, srdf=False))
    np.testing.assert_allclose(st.upper - st.lower, 2 * np.pi)
    assert np.all((st.lower <= st.home) & (st.home <= st.upper))
    verdicts = [{(e.link1, e.link2): (e.reason, e.status) for e in collision_matrix(
        armguard.load_model(p, srdf=False), max_evaluations=MAX_EVALUATIONS).entries} for p in (wide, narrow)]
    assert verdicts[0] == verdicts[1]
    coupled = tmp_path / "coupled.urdf"
    coupled.write_text(_THREE.replace('lower="-3.1" upper="3.1"', 'lower="-31" upper="31"').replace(
        '<child link="l3"/>', '<child link="l3"/><mimic joint="j2" multiplier="0.5" offset="0"/>'))
    st = pair_setup(armguard.load_model(coupled, srdf=False))
    assert st.upper[1] - st.lower[1] == pytest.approx(62.0)  # j2, followed by j3 at half its rate: not folded


def test_a_stale_certificate_is_located_by_its_line(certified, tmp_path):
    new = _fresh(certified, tmp_path, grow=True)
    model = armguard.load_model(new, srdf=False)
    stale = stale_certificates(model.pin_model, model.collision_model, new.with_suffix(".srdf"))
    text = new.with_suffix(".srdf").read_text()
    s = next(s for s in stale if {s.link1, s.link2} == set(NEVER))
    el = next(ln for ln in text.splitlines() if "disable_collisions" in ln and NEVER[0] in ln and f'"{NEVER[1]}"' in ln)
    line = text.splitlines().index(el) + 1
    assert s.where.startswith("disable_collisions[") and s.where.endswith(f"(line {line})"), s.where


def test_a_checked_pairs_certificate_moved_onto_a_never_does_not_hold(certified, tmp_path):
    """The certificate covers the verdict: a checked pair's comment (witnessed in collision) turned by
    hand into ``<disable_collisions reason="Never">`` with the same fingerprint is stale -- ``load_model``
    warns and checks the pair, ``srdf --update`` searches it again and writes it checked."""
    import re

    from armguard.srdfgen._io import _CHECKED

    model = _fresh(certified, tmp_path, grow=False)
    srdf = model.with_suffix(".srdf")
    text = srdf.read_text()
    comment = next(m for m in re.finditer(r"<!--(.*?)-->", text, flags=re.S) if _CHECKED.match(m[1])
                   and "witnessed" in m[1])
    c = _CHECKED.match(comment[1])
    for reason in ("", ' reason=""', ' reason="checked"'):  # no reason, an empty one, the checked namespace's name
        forged = f'<disable_collisions link1="{c["a"]}" link2="{c["b"]}"{reason} {FINGERPRINT_ATTR}="{c["fp"]}"/>'
        srdf.write_text(text.replace(comment[0], forged))
        m = armguard.load_model(model, srdf=False)
        assert [{x.link1, x.link2} for x in stale_certificates(m.pin_model, m.collision_model, srdf)] == \
            [{c["a"], c["b"]}], reason
    forged = (f'<disable_collisions link1="{c["a"]}" link2="{c["b"]}" reason="Never" '
              f'{FINGERPRINT_ATTR}="{c["fp"]}"/>')
    srdf.write_text(text.replace(comment[0], forged))
    with pytest.warns(ArmguardWarning, match=f"{c['a']}.*{c['b']}|{c['b']}.*{c['a']}"):
        m = armguard.load_model(model)
    stale = stale_certificates(m.pin_model, m.collision_model, srdf)
    assert [{s.link1, s.link2} for s in stale] == [{c["a"], c["b"]}]
    r = CliRunner().invoke(main, ["srdf", str(model), "--out", str(srdf), "--update", "--max-evaluations",
                                  str(MAX_EVALUATIONS)])
    assert r.exit_code == 0, r.output
    assert " 1 searched again" in r.output and "Never -> witnessed" in r.output, r.output
    disabled = {frozenset((e.get("link1"), e.get("link2"))) for e in ET.parse(srdf).getroot().findall("disable_collisions")}
    assert frozenset((c["a"], c["b"])) not in disabled


def test_certificates_of_an_older_armguard_are_said_to_be_so(certified, tmp_path):
    """An SRDF certified before the verdict was hashed (no ``armguard_certificates="2"`` on ``<robot>``): every
    certificate reads as stale; load_model says they are an older armguard's, not that the URDF changed, and
    srdf --update writes the current format."""
    from armguard.model._certificate import FORMAT_ATTR

    model = _fresh(certified, tmp_path, grow=False)
    srdf = model.with_suffix(".srdf")
    text = srdf.read_text()
    assert f'{FORMAT_ATTR}="2"' in text
    import re

    old = re.sub(f'{FINGERPRINT_ATTR}="[0-9a-f]+"', f'{FINGERPRINT_ATTR}="0123456789abcdef"', text)  # other prints
    srdf.write_text(old.replace(f' {FORMAT_ATTR}="2"', ""))  # ... and no format: an older armguard's file
    with pytest.warns(ArmguardWarning, match="written by an older armguard") as got:
        armguard.load_model(model)
    assert not any("another geometry" in str(w.message) for w in got)
    srdf.write_text(old)  # the current format with prints that do not match: the URDF is blamed
    with pytest.warns(ArmguardWarning, match="certified for another geometry"):
        armguard.load_model(model)
