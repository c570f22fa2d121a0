"""Certified collision matrices (armguard.srdfgen, ``armguard srdf`` / ``check-srdf``).

Proven-Never pairs are checked against coal on dense random samples; witnesses are re-evaluated
on a fresh checker of the whole model; the SRDF written is loaded back to exactly the pairs kept.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.srdfgen import PairVerdict, collision_matrix, matrix_scene, pair_setup, prove_pair


# --------------------------------------------------------------------------- the search on known functions
def _bump(centre, radius, depth):
    """A 1-Lipschitz "distance" (per unit of each joint, summed) that dips to ``-depth`` in a ball of ``radius``."""
    centre = np.asarray(centre, dtype=float)

    def f(Q):
        return np.abs(Q - centre).sum(axis=1) - radius + 0.0 * depth

    return f


@pytest.mark.parametrize("radius", [0.05, 0.004])
def test_prove_pair_finds_a_thin_colliding_region(radius):
    """A region far thinner than random sampling resolves (volume ~1e-7 of the box) is still found."""
    f = _bump([0.3, -1.1, 2.0], radius, 0.0)
    lo, hi = np.full(3, -3.0), np.full(3, 3.0)
    r = prove_pair(f, np.zeros(3), [0, 1, 2], lo, hi, np.ones(3), presample=0, min_width=1e-4, max_evaluations=400_000)
    assert r.verdict is PairVerdict.WITNESSED
    assert f(r.witness[None])[0] <= 0.0  # the witness really is in the region


def test_prove_pair_proves_a_clear_function_and_never_lies():
    """Clear everywhere by 0.01: proven, and the proven lower bound is below the true minimum (dense grid)."""
    f = _bump([0.3, -1.1], -0.01, 0.0)  # |q - c|_1 + 0.01 > 0
    lo, hi = np.full(2, -3.0), np.full(2, 3.0)
    r = prove_pair(f, np.zeros(2), [0, 1], lo, hi, np.ones(2), presample=0)
    assert r.verdict is PairVerdict.NEVER
    g = np.stack(np.meshgrid(np.linspace(-3, 3, 301), np.linspace(-3, 3, 301)), -1).reshape(-1, 2)
    assert r.lower_bound <= f(g).min() + 1e-12


def test_prove_pair_undecided_on_a_tangent_function_and_nan_is_not_clear():
    f = _bump([0.3, -1.1], 0.0, 0.0)  # touches 0 at one point only: neither provable nor (exactly) witnessed
    r = prove_pair(lambda Q: f(Q) + 1e-9, np.zeros(2), [0, 1], np.full(2, -3.0), np.full(2, 3.0), np.ones(2),
                   presample=0, max_evaluations=20_000)
    assert r.verdict is PairVerdict.UNDECIDED
    r = prove_pair(lambda Q: np.full(len(Q), np.nan), np.zeros(1), [0], np.full(1, -1.0), np.full(1, 1.0), np.ones(1),
                   presample=0, max_evaluations=2_000)
    assert r.verdict is PairVerdict.UNDECIDED


# --------------------------------------------------------------------------- a robot
@pytest.fixture(scope="module")
def puma():
    model = armguard.load_model("puma560", srdf=False)
    return model, collision_matrix(model, workers=2, max_evaluations=30_000)


def _coal_pair_distance(model, pair, Q_pin):
    """Coal's distance of link pair ``pair`` (a :class:`~armguard.srdfgen.LinkPair`) at ``Q_pin`` (M, nq):
    a checker of only that pair."""
    from armguard.cspace._clearance import checker_over

    scene = matrix_scene(model.scene)
    owners = {pair.owner1, pair.owner2}
    for cp in scene.allowed_pairs():
        if {cp.a, cp.b} != owners:
            scene.disable_pair(cp.a, cp.b)
    chk = checker_over(model, scene, "coal", need_distances=True)
    return chk.min_distance_many(Q_pin)


def test_matrix_classifies_every_pair_once(puma):
    model, cm = puma
    setup = pair_setup(model)
    assert len(cm.entries) == len(setup.pairs)
    assert {frozenset((e.link1, e.link2)) for e in cm.entries} == {frozenset((p.link1, p.link2)) for p in setup.pairs}
    for e, p in zip(cm.entries, setup.pairs):
        assert (e.reason == "Adjacent") == p.adjacent
    c = cm.counts()
    assert c["Never"] >= 1 and c["witnessed"] >= 1


def test_proven_never_pairs_have_no_contact_on_dense_samples_with_coal(puma):
    """10^4 random configurations, plus a dense grid over the pair's joints, find no contact (coal)."""
    model, cm = puma
    setup = pair_setup(model)
    rng = np.random.default_rng(1)
    never = [(e, p) for e, p in zip(cm.entries, setup.pairs) if e.reason == "Never"]
    assert never
    for e, p in never:
        Q = setup.lower + (setup.upper - setup.lower) * rng.random((10_000, len(setup.home)))
        grid = np.stack(np.meshgrid(*[np.linspace(setup.lower[j], setup.upper[j], 12) for j in p.joints]), -1)
        G = np.repeat(setup.home[None], grid.size // len(p.joints), axis=0)
        G[:, list(p.joints)] = grid.reshape(-1, len(p.joints))
        d = _coal_pair_distance(model, p, model.pin_q(np.concatenate([Q, G])))
        assert np.all(np.isfinite(d))
        assert d.min() > 0.0, (e.link1, e.link2, d.min())


def test_witnessed_pairs_collide_at_their_witness(puma):
    model, cm = puma
    for e, p in zip(cm.entries, pair_setup(model).pairs):
        if e.status == "witnessed":
            d = _coal_pair_distance(model, p, np.asarray([e.q]))
            assert d[0] <= 1e-6, (e.link1, e.link2, d[0])


def test_sampled_method_disables_a_superset_of_the_proven_pairs(puma):
    """MoveIt's rules: every proven-Never pair is also sampled Never (a collision there would be a bug)."""
    model, cm = puma
    sm = collision_matrix(model, method="sampled", samples=2000)
    proven = {frozenset((e.link1, e.link2)) for e in cm.entries if e.reason == "Never"}
    sampled = {frozenset((e.link1, e.link2)) for e in sm.entries if e.reason == "Never"}
    assert proven <= sampled
    for e in sm.entries:
        if e.status == "witnessed":
            assert e.distance <= 0.0


def test_bad_arguments_are_refused(puma):
    model, _ = puma
    with pytest.raises(armguard.ArmguardError, match="margin"):
        collision_matrix(model, margin=float("nan"))
    with pytest.raises(armguard.ArmguardError, match="method"):
        collision_matrix(model, method="guess")


# --------------------------------------------------------------------------- SRDF round trip and lint (a URDF)
@pytest.fixture(scope="module")
def ur5():
    from armguard.model._public import public_robot_files

    urdf, shipped = public_robot_files("ur5")
    return urdf, shipped


def test_srdf_command_writes_an_srdf_that_loads_back_to_the_pairs_kept(ur5, tmp_path):
    from armguard.cli import main

    urdf, _ = ur5
    out = tmp_path / "ur5.srdf"
    res = CliRunner().invoke(main, ["srdf", str(urdf), "--out", str(out), "--method", "sampled", "--samples", "300"])
    assert res.exit_code == 0, res.output
    root = ET.parse(out).getroot()
    dis = [(el.get("link1"), el.get("link2"), el.get("reason")) for el in root.findall("disable_collisions")]
    assert dis and all(r in ("Adjacent", "Default", "Never", "Always") for _, _, r in dis)
    full = armguard.load_model(str(urdf), srdf=False)
    loaded = armguard.load_model(str(urdf), srdf=str(out))
    setup = pair_setup(full)
    disabled = {frozenset((a, b)) for a, b, _ in dis}
    expected = {frozenset((p.owner1, p.owner2)) for p in setup.pairs if frozenset((p.link1, p.link2)) not in disabled}
    got = {frozenset((a, b)) for a, b, c in zip(loaded.pairs.owner_a, loaded.pairs.owner_b, loaded.pairs.category)
           if c == "arm_arm" or c == "arm-arm"}
    assert got == expected
    # Pinocchio reads it too
    import pinocchio as pin

    geom = full.collision_model.copy()
    geom.addAllCollisionPairs()
    n_all = len(geom.collisionPairs)
    pin.removeCollisionPairs(full.pin_model, geom, str(out))
    assert len(geom.collisionPairs) < n_all


def test_check_srdf_reports_a_disabled_pair_that_collides(tmp_path):
    """puma560's base and link2 collide (witnessed): an SRDF that disables them is flagged, with a q that collides.
    The SRDF names the URDF's links (``puma560_base``), as every SRDF does."""
    from armguard.cli import main

    BASE_LINK2 = frozenset(("puma560_base", "puma560_link2"))
    srdf = tmp_path / "bad.srdf"
    srdf.write_text('<robot name="puma560"><disable_collisions link1="puma560_base" link2="puma560_link2" reason="Never"/>'
                    '<disable_collisions link1="puma560_link1" link2="puma560_link3" reason="Never"/></robot>')
    res = CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--json", "--max-evaluations", "30000"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    pairs = {frozenset((d["link1"], d["link2"])): d for d in out["can_collide"]}
    assert set(pairs) == {BASE_LINK2}
    model = armguard.load_model("puma560", srdf=False)
    q = np.asarray([pairs[BASE_LINK2]["q"]])
    assert q.shape == (1, model.nq)
    assert pairs[BASE_LINK2]["coal_distance"] <= 1e-6
    pair = next(p for p in pair_setup(model).pairs if frozenset((p.link1, p.link2)) == BASE_LINK2)
    assert _coal_pair_distance(model, pair, q)[0] <= 1e-6
    assert {frozenset((d["link1"], d["link2"])) for d in out["proven_disabled"]} == {frozenset(("puma560_link1", "puma560_link3"))}
    strict = CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--json", "--strict", "--max-evaluations", "30000"])
    assert strict.exit_code == 1


def test_check_srdf_names_a_disabled_pair_of_a_link_the_robot_lacks(tmp_path):
    """A disabled pair naming a link puma560 lacks (a typo) was only listed under --json "skipped", exit 0 even
    with --strict, where load_model refuses the same SRDF: now printed, and --strict exits 1.  A pair of a link
    without geometry stays a quiet skip."""
    from armguard.cli import main

    srdf = tmp_path / "typo.srdf"
    srdf.write_text('<robot name="puma560"><disable_collisions link1="puma560_link1" link2="puma560_link33" reason="Never"/>'
                    '<disable_collisions link1="puma560_link1" link2="puma560_link3" reason="Never"/></robot>')
    with pytest.raises(armguard.ArmguardError, match="puma560_link33"):
        armguard.load_model("puma560", srdf=srdf)
    res = CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--max-evaluations", "3000"])
    assert res.exit_code == 0, res.output
    assert "1 disabled pair names links puma560 does not have (puma560_link33)" in res.output, res.output
    assert "disabled (Never) puma560_link1 - puma560_link33: unknown link" in res.output
    js = CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--json", "--max-evaluations", "3000"])
    assert json.loads(js.output)["skipped"] == [{"link1": "puma560_link1", "link2": "puma560_link33", "reason": "Never",
                                                 "why": "unknown link"}]
    strict = CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--strict", "--max-evaluations", "3000"])
    assert strict.exit_code == 1, strict.output
    srdf.write_text('<robot name="puma560"><disable_collisions link1="puma560_link1" link2="puma560_link3" reason="Never"/>'
                    '</robot>')
    assert CliRunner().invoke(main, ["check-srdf", "puma560", str(srdf), "--strict", "--max-evaluations", "3000"]).exit_code == 0


def test_srdf_to_a_missing_folder_is_an_output_error(puma, tmp_path):
    from armguard._errors import OutputError

    _, cm = puma
    with pytest.raises(OutputError, match="cannot write"):
        cm.write_srdf(tmp_path / "no" / "such" / "x.srdf")
    out = tmp_path / "puma.srdf"
    cm.write_srdf(out)
    root = ET.parse(out).getroot()
    assert len(root.findall("disable_collisions")) == len(cm.disabled)


def test_a_dask_cluster_gives_the_same_matrix(puma):
    """``scheduler="local"``: two worker processes load the model from its file and search the pairs; every
    verdict, witness and bound is the one a search in this process finds (same limits, same seeds; a small
    evaluation budget keeps the test short -- some pairs stay undecided, which must agree too)."""
    model, _ = puma
    cm = collision_matrix(model, max_evaluations=3_000)
    dm = collision_matrix(model, scheduler="local", workers=2, max_evaluations=3_000)
    assert [(e.link1, e.link2, e.reason, e.status, e.q, e.fingerprint) for e in dm.entries] == \
        [(e.link1, e.link2, e.reason, e.status, e.q, e.fingerprint) for e in cm.entries]
    np.testing.assert_array_equal([e.distance for e in dm.entries], [e.distance for e in cm.entries])


def _two_link(path, length: float) -> None:
    path.write_text(f"""<robot name="twolink">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.05 0.05"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="{length / 2} 0 0"/><geometry><box size="{length} 0.05 0.05"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.5"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>""", encoding="utf-8")


def test_a_long_running_cluster_searches_the_urdf_as_edited(tmp_path):
    """A cluster that stays up (``--scheduler tcp://...``) keeps each worker's model between calls: after
    the URDF is edited (l2 made long enough to reach the base), its workers search the edited model, not
    the one they loaded before (they proved base-l2 Never, and wrote it into the SRDF)."""
    from distributed import LocalCluster

    urdf = tmp_path / "twolink.urdf"
    _two_link(urdf, 0.05)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        def base_l2(model):
            cm = collision_matrix(model, scheduler=cluster.scheduler_address, max_evaluations=20_000)
            return next(e for e in cm.entries if {e.link1, e.link2} == {"base", "l2"})

        assert base_l2(armguard.load_model(urdf, srdf=False)).reason == "Never"
        _two_link(urdf, 0.6)
        edited = armguard.load_model(urdf, srdf=False)
        here = next(e for e in collision_matrix(edited, max_evaluations=20_000).entries if {e.link1, e.link2} == {"base", "l2"})
        there = base_l2(edited)
        assert here.status == "witnessed" and here.reason is None
        assert (there.status, there.reason, there.q) == (here.status, here.reason, here.q)


def test_check_srdf_without_srdf_lints_the_one_armguard_finds(tmp_path):
    """``armguard check-srdf ROBOT``: the SRDF armguard loads ROBOT with (named on the first line);
    a robot it finds none for is a usage error that says to give one."""
    import shutil

    from armguard.cli import main

    from pathlib import Path

    found = Path(armguard.load_model("puma560").srdf.file)
    res = CliRunner().invoke(main, ["check-srdf", "puma560", "--max-evaluations", "30000"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    # a built-in's SRDF is the one its sidecar names ("given (srdf=)" was printed, as if the user gave it)
    assert lines[0] == f"SRDF: {found} (named by puma560.yaml's model.srdf)"
    given = CliRunner().invoke(main, ["check-srdf", "puma560", str(found), "--max-evaluations", "30000"])
    assert given.exit_code == 0, given.output
    # the same findings as with the file given by name (the summary's elapsed time aside)
    strip = [ln.split(" (")[0] if ln.startswith(str(found)) else ln for ln in given.output.splitlines() if "linting" not in ln]
    assert [ln.split(" (")[0] if ln.startswith(str(found)) else ln for ln in lines[1:] if "linting" not in ln] == strip
    lone = tmp_path / "lone" / "puma560.urdf"  # a URDF with no SRDF beside it, in ../srdf/ or under its name
    shutil.copytree(found.parent, lone.parent, ignore=shutil.ignore_patterns("*.srdf", "*.yaml"))
    res = CliRunner().invoke(main, ["check-srdf", str(lone)])
    assert res.exit_code == 2 and "finds no SRDF" in res.output and "give SRDF" in res.output


def test_an_evaluator_that_cannot_prove_never_is_refused_by_name():
    """--evaluator fcl hung without end on hermes's adjacent cylinders (python-fcl never returned); clip was
    refused in the words of a forbidden-values map ("a map's clearances need signed distances")."""
    from click.testing import CliRunner

    from armguard.cli import main

    runner = CliRunner()
    r = runner.invoke(main, ["srdf", "hermes", "--out", "unused.srdf", "--evaluator", "fcl", "--max-evaluations", "200"])
    assert r.exit_code == 3 and "evaluator 'fcl': its distances may not return" in r.output, r.output
    r = runner.invoke(main, ["srdf", "puma560", "--out", "unused.srdf", "--evaluator", "clip"])
    assert r.exit_code == 3 and "proving pairs Never needs signed distances" in r.output, r.output


def test_srdf_json_is_strict_json(tmp_path):
    """--json printed bare NaN for the distances of Adjacent and undecided pairs (not JSON); now null."""
    from armguard.cli import main

    r = CliRunner().invoke(main, ["srdf", "puma560", "--out", str(tmp_path / "s.srdf"), "--max-evaluations", "500",
                                        "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.output, parse_constant=lambda c: pytest.fail(f"{c} in --json output"))
    assert any(p["distance"] is None for p in doc["pairs"]) and all(
        p["distance"] is None or isinstance(p["distance"], float) for p in doc["pairs"])


def test_check_srdf_witnesses_paste_into_check_q(tmp_path):
    """kinova (three continuous joints): a disabled pair's witness prints as ``check --q`` takes it, one angle
    a joint in the scene's order (it printed Pinocchio's nine values, a ``(cos, sin)`` each), and the pair is
    at the printed distance there (to the printed digits)."""
    import re

    from armguard.cli import main

    srdf = tmp_path / "mine.srdf"
    srdf.write_text('<robot name="kinova"><disable_collisions link1="j2s6s200_link_base" '
                    'link2="j2s6s200_link_finger_tip_1" reason="Never"/></robot>')
    res = CliRunner().invoke(main, ["check-srdf", "kinova", str(srdf)])
    assert res.exit_code == 0, res.output
    m = re.search(r"disabled \(Never\) j2s6s200_link_base - j2s6s200_link_finger_tip_1: distance (\S+) m.* at q = \[([^\]]*)\]",
                  res.output)
    assert m, res.output
    q = [float(x) for x in m.group(2).split(",")]
    model = armguard.load_model("kinova", srdf=False)
    assert len(q) == len(model.scene.joint_names) == 6 and model.nq == 9
    r = armguard.checker(model, "analytic").pair_distances(model.pin_q(q))
    rows = [k for k, (a, b) in enumerate(r.pairs) if {a.rsplit("_", 1)[0], b.rsplit("_", 1)[0]}
            == {"j2s6s200_link_base", "j2s6s200_link_finger_tip_1"}]
    assert abs(min(r.distance[rows]) - float(m.group(1))) < 1e-3
    check = CliRunner().invoke(main, ["check", "kinova", "--q", m.group(2).replace(" ", "")])
    assert check.exit_code in (0, 1), check.output


def test_a_sampled_matrix_from_few_samples_warns_of_its_never_pairs(tmp_path):
    """``--method sampled --samples 1`` disabled every pair of ur5 as Never without a word, and the SRDF then
    left a model with no pair to check: both are said (stderr), the file still written as asked."""
    from armguard.cli import main

    out = tmp_path / "s1.srdf"
    res = CliRunner().invoke(main, ["srdf", "ur5", "--out", str(out), "--method", "sampled", "--samples", "1"])
    assert res.exit_code == 0, res.output
    assert "disabled as Never from 1 sample:" in res.stderr and "every pair is disabled" in res.stderr
    assert out.is_file()
    ok = CliRunner().invoke(main, ["srdf", "gmf_s480", "--out", str(tmp_path / "c.srdf")])
    assert ok.exit_code == 0 and "warning" not in ok.stderr, ok.stderr


_THREE = """<robot name="r">
<link name="base"><collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
<link name="l1"><collision><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
<link name="l2"><collision><origin xyz="0 0 0.2"/><geometry><box size="0.05 0.05 0.3"/></geometry></collision></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.05"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
</robot>"""


@pytest.mark.parametrize("state,why", [('<joint name="j1" value="0"/><joint name="j9" value="1"/>', "names joint 'j9'"),
                                       ('<joint name="j1" value="0"/><joint name="j2" value="2.5"/>', "outside the limits")])
def test_check_srdf_reports_a_group_state_every_other_command_refuses(tmp_path, state, why):
    """A home naming a joint the robot lacks, or outside its limits: ``check`` and ``info`` refused the SRDF
    (exit 3), ``check-srdf --strict`` passed it (exit 0) without a word about its states."""
    import json

    from armguard.cli import main

    urdf, srdf = tmp_path / "r.urdf", tmp_path / "r.srdf"
    urdf.write_text(_THREE)
    srdf.write_text(f'<robot name="r"><group name="arm"><chain base_link="base" tip_link="l2"/></group>'
                    f'<group_state name="home" group="arm">{state}</group_state></robot>')
    args = ["check-srdf", str(urdf), str(srdf), "--max-evaluations", "2000"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0 and "load_model refuses this SRDF:" in r.output and why in r.output, r.output
    assert CliRunner().invoke(main, [*args, "--strict"]).exit_code == 1
    js = json.loads(CliRunner().invoke(main, [*args, "--json"]).output)
    assert why in js["refused"] and "group_state[0] (home)" in js["refused"]
    srdf.write_text('<robot name="r"><group name="arm"><chain base_link="base" tip_link="l2"/></group>'
                    '<group_state name="home" group="arm"><joint name="j1" value="0"/></group_state></robot>')
    assert json.loads(CliRunner().invoke(main, [*args, "--json"]).output)["refused"] is None
