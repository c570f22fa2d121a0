"""The backend harness (``armguard compare``): its numbers, outputs, Dask path, and models that follow their URDF."""

from __future__ import annotations

import json
import shlex
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard import DEFAULT_TOLERANCES as TOL
from armguard import BackendError
from armguard.cli import main
from armguard.harness import (
    build_checkers,
    build_configs,
    compare_answers,
    evaluate,
    parse_backend_options,
    repo_root,
    resolve_model,
    run_compare,
)


@pytest.fixture(scope="module")
def hermes_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    comp = run_compare("hermes", ("analytic", "coal"), n_configs=200, seed=3, trajectories="unstow", frequency=0.5,
                       out_dir=out)
    return comp, out


def test_small_run_writes_the_contract_and_the_plots(hermes_run):
    comp, out = hermes_run
    data = json.loads((out / "compare.json").read_text())
    pair = data["pairs"]["analytic/coal"]
    assert pair["verdict_disagreements"] == 0 and pair["status"] == "agree"
    assert 0.0 <= pair["max_abs_distance_error"] <= TOL.differential_hull
    assert data["backends"]["analytic"]["us_per_config"] > 0 and data["backends"]["coal"]["us_per_config"] > 0
    assert data["configs"]["total"] == 200 + data["configs"]["trajectories"]["unstow"] == len(comp.configs)
    assert set(pair["categories"]) == {"all", *comp.model.pairs.category}
    assert pair["categories"]["all"]["unique_points"]["n"] > 0  # capsule-capsule pairs were compared point to point
    for name in ("scatter_analytic_coal.png", "hist_analytic_coal.png", "timing.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name


def test_the_worst_configuration_reproduces_in_one_line(hermes_run):
    comp, _ = hermes_run
    worst = comp.summary["pairs"]["analytic/coal"]["worst"][0]
    argv = shlex.split(worst["reproduce"])
    assert argv[:3] == ["armguard", "compare", "hermes"]
    res = CliRunner().invoke(main, argv[1:] + ["--json"])
    assert res.exit_code == 0, res.output
    (row,) = json.loads(res.output)
    assert row["pair"] == worst["pair"]
    assert row["analytic"][0] == worst["analytic"]["distance"] and row["coal"][0] == worst["coal"]["distance"]


def test_the_comparison_sees_a_wrong_answer(hermes_run):
    comp, _ = hermes_run
    model, answers = comp.model, comp.answers
    bad = replace(answers["analytic"], distance=answers["analytic"].distance.copy(), verdict=answers["analytic"].verdict.copy())
    dmin = answers["coal"].distance.min(axis=1)
    i = int(np.argmax(dmin))  # the clearest configuration: flip its verdict, and push one pair 1 mm
    bad.verdict[i] = not bad.verdict[i]
    bad.distance[5, 0] += 1e-3
    c = compare_answers(model, comp.configs, {"analytic": bad, "coal": answers["coal"]}, spec="hermes")
    p = c.summary["pairs"]["analytic/coal"]
    assert p["verdict_disagreements"] == 1 and p["worst"][0]["why"] == "verdict" and p["worst"][0]["config"] == i
    assert p["max_abs_distance_error"] == pytest.approx(1e-3, rel=1e-9)
    assert p["status"] == "differ"


def test_the_slow_reference_says_which_side_is_off(hermes_run):
    """A worst distance entry beyond the pair's tolerance carries the slow support-function reference's
    distance and each side's error against it: the doctored side is the one off; entries within
    tolerance carry none."""
    comp, _ = hermes_run
    model, answers = comp.model, comp.answers
    bad = replace(answers["analytic"], distance=answers["analytic"].distance.copy())
    bad.distance[5, 0] += 1e-3
    c = compare_answers(model, comp.configs, {"analytic": bad, "coal": answers["coal"]}, spec="hermes")
    worst = [w for w in c.summary["pairs"]["analytic/coal"]["worst"] if w["why"] == "distance"]
    first, rest = worst[0], worst[1:]
    assert (first["config"], first["pair"]) == (5, list(model.pairs.names[0]))
    ref = first["slow_reference"]
    assert ref["error"]["analytic"] == pytest.approx(1e-3, abs=1e-8) and ref["error"]["coal"] < 1e-8
    assert ref["distance"] == pytest.approx(answers["coal"].distance[5, 0], abs=1e-8)
    assert rest and all("slow_reference" not in w for w in rest)  # the others agree within tolerance: nothing to decide


def test_one_pair_at_one_configuration_has_the_references_word():
    """``compare --q --pair`` on z1's two cylinders at a configuration where coal's EPA depth is 33 mm too
    deep (``armguard compare z1``'s worst entry): the reference sides with armguard's closed-form depth."""
    q = [1.6353843202705982, 1.9816677582893327, -0.11976014315454409, 1.2928410620261392, 0.667244076847598,
         2.0145367082212755, -1.1825066149760657]
    res = CliRunner().invoke(main, ["compare", "z1", "--backends", "analytic,coal", "--q", ",".join(map(repr, q)),
                                    "--pair", "link02_1,link04_0", "--json"])
    assert res.exit_code == 0, res.output
    (row,) = json.loads(res.stdout)  # the SRDF warnings go to stderr
    ref = row["slow_reference"]
    assert ref["distance"] < 0 and ref["error"]["analytic"] < 1e-9 and ref["error"]["coal"] > 1e-2
    assert abs(row["analytic"][0] - ref["distance"]) == ref["error"]["analytic"]


def test_compare_q_takes_angles_where_joints_are_continuous():
    """kinova's three continuous joints: ``compare --q`` takes Pinocchio's 9 values (a ``(cos, sin)`` each)
    or the 6 joint angles ``check --q`` takes (turned into Pinocchio's by ``Model.pin_q``): the same rows."""
    model = armguard.load_model("kinova")
    angles = [1.57, 2.6, 4.7, 3.14, 2.6, 0.0]
    pin = model.pin_q(angles)
    out = []
    for q in (angles, pin.tolist()):
        res = CliRunner().invoke(main, ["compare", "kinova", "--backends", "analytic", "--q", ",".join(map(repr, q)),
                                        "--json"])
        assert res.exit_code == 0, res.output
        out.append(json.loads(res.stdout))
    assert out[0] == out[1] and len(out[0]) == len(model.pairs)
    res = CliRunner().invoke(main, ["compare", "kinova", "--q", "1,2,3"])
    assert res.exit_code == 2 and "j2s6s200_joint_1 (cos, sin)" in res.output


def test_a_workspace_pair_is_judged_against_the_walls():
    """A workspace pair (a link against the workspace box's walls, not a GeometryObject pair) that the
    two backends answer 1 mm apart: the comparison says "differ" and the reference (the link's support
    along the six walls' normals) sides with the undoctored side; its reproduce line answers (exit 0)."""
    model = armguard.load_model("ranger")
    configs = build_configs(model, n_random=8, seed=2, trajectories=None)
    answers = evaluate(model, configs.Q, ("analytic", "coal"))
    k = int(np.flatnonzero(model.pairs.names[:, 1] == "workspace")[0])
    bad = replace(answers["analytic"], distance=answers["analytic"].distance.copy())
    bad.distance[3, k] += 1e-3
    c = compare_answers(model, configs, {"analytic": bad, "coal": answers["coal"]}, spec="ranger")
    p = c.summary["pairs"]["analytic/coal"]
    (w,) = [w for w in p["worst"] if "slow_reference" in w]
    assert p["status"] == "differ" and (w["config"], w["pair"][1]) == (3, "workspace")
    assert w["slow_reference"]["error"]["coal"] < 1e-12 and w["slow_reference"]["error"]["analytic"] == pytest.approx(1e-3, abs=1e-12)
    res = CliRunner().invoke(main, shlex.split(w["reproduce"])[1:])
    assert res.exit_code == 0, res.output
    assert "reference  d = " in res.stdout and "analytic off" in res.stdout


def test_the_wall_reference_is_the_least_vertex_room():
    """``reference_wall_distance`` (six support values) on a hull against the least, over its vertices and
    the six walls, of the room left (a polytope's extreme points are vertices)."""
    from armguard.geometry import ConvexPolyhedron
    from armguard.geometry._support_reference import reference_wall_distance

    rng = np.random.default_rng(4)
    lo, hi = np.array([-1.0, -2.0, -0.5]), np.array([1.5, 2.0, 3.0])
    for _ in range(20):
        v = rng.normal(size=(12, 3)) * rng.uniform(0.1, 1.0) + rng.uniform(lo - 0.5, hi + 0.5)
        room = np.minimum(hi - v, v - lo).min()
        assert reference_wall_distance(ConvexPolyhedron(v), lo, hi) == pytest.approx(room, abs=1e-12)


def test_backend_options_pass_through():
    assert parse_backend_options(["analytic.fidelity=paper", "coal.threads=1", "coal.gjk_tolerance=1e-9"]) == {
        "analytic": {"fidelity": "paper"}, "coal": {"threads": 1, "gjk_tolerance": 1e-9}}
    with pytest.raises(armguard.ArmguardError, match="BACKEND.KEY=VALUE"):
        parse_backend_options(["fidelity=paper"])
    model = resolve_model("hermes")
    cks = build_checkers(model, ("analytic", "coal"), {"coal": {"threads": 1}})
    assert cks["coal"].threads == 1
    with pytest.raises(BackendError, match="unknown options"):
        build_checkers(model, ("coal",), {"coal": {"nonesuch": 1}})


def test_dask_answers_equal_the_serial_ones():
    model = resolve_model("hermes")
    configs = build_configs(model, 24, seed=5, trajectories=None)
    serial = evaluate(model, configs.Q, ("analytic", "coal"), {"coal": {"threads": 1}})
    dask = evaluate(model, configs.Q, ("analytic", "coal"), {"coal": {"threads": 1}}, spec="hermes", workers=2,
                    chunk_size=5)
    for b in ("analytic", "coal"):
        for field in ("distance", "p_WA", "p_WB", "verdict"):
            if b == "coal" and field != "verdict":  # coal's answers depend on the process's earlier calls to its
                # gjk_tolerance (1e-9 m, plugins/armguard_coal's docstring): this process's hermes coal Checker was
                # seen 1.8e-10 m off a fresh worker's after other tests ran in it first
                np.testing.assert_allclose(getattr(serial[b], field), getattr(dask[b], field), rtol=0, atol=1e-9,
                                           err_msg=f"{b}.{field}")
            else:  # armguard's own answers: bit for bit
                np.testing.assert_array_equal(getattr(serial[b], field), getattr(dask[b], field), err_msg=f"{b}.{field}")


def test_cli_compare_writes_compare_json(tmp_path):
    res = CliRunner().invoke(main, ["compare", "gmf_s480", "--backends", "analytic,coal", "--configs", "40",
                                    "--trajectory", "none", "--out", str(tmp_path), "--no-plots"])
    assert res.exit_code == 0, res.output
    data = json.loads((tmp_path / "compare.json").read_text())
    assert data["pairs"]["analytic/coal"]["verdict_disagreements"] == 0 and data["configs"]["total"] == 40
    assert "timings" in res.output
    # not a terminal: the tables keep whole headers (rich's 80 columns cut all 13 to "…")
    header = next(ln for ln in res.output.splitlines() if "category" in ln)
    assert "…" not in header and "contract ✗ analytic" in header and "sep |Δd| max" in header, header
    res = CliRunner().invoke(main, ["compare", "gmf_s480", "--backends", "coal"])
    assert res.exit_code == 2 and "at least two backends" in res.output, res.output  # ExitCode.USAGE (was 3)


@pytest.mark.parametrize("args, said", [
    (["--backends", "coal,coal"], "each once"),
    (["--backend-option", "analytic"], "expected BACKEND.KEY=VALUE"),
    (["--workers", "2", "--scheduler", "tcp://localhost:1"], "not both"),
    (["--q", "0,0,0,0,0,0", "--out", "somewhere"], "drop --out, or --q"),
    (["--trajectory", "all", "--trajectory", "reach_over_fixture"], "'all' stands alone"),
])
def test_cli_compare_usage_errors_exit_2(args, said, tmp_path):
    """A bad option is click's usage error (2): these exited 3 (a refused file), and --q with --out wrote
    nothing without saying so."""
    res = CliRunner().invoke(main, ["compare", "gmf_s480", "--configs", "4", *args])
    assert res.exit_code == 2 and said in res.output, res.output
    assert not (tmp_path / "somewhere").exists()


def test_a_trajectory_named_twice_is_sampled_once():
    from armguard.harness import build_configs

    model = armguard.load_model("gmf_s480")
    name = next(iter(model.scene.trajectories))
    once = build_configs(model, 0, trajectories=[name])
    twice = build_configs(model, 0, trajectories=[name, name])
    assert twice.Q.shape == once.Q.shape and twice.trajectories == once.trajectories and len(once) > 0


# ------------------------------------------------------------------ URDF-driven updates
THICKER = 0.2  # hera_link3's capsule radius 0.15 -> 0.35 m
RAISE = 0.5  # the cargo bay moved up by this (m)


def _edited_hermes(folder: Path) -> Path:
    shutil.copytree(repo_root() / "urdf" / "hermes", folder / "hermes")
    urdf = folder / "hermes" / "hermes.urdf"
    s = urdf.read_text()
    bay = '<child link="cargo_bay"/>\n    <origin xyz="0 0 0" rpy="0 0 0"/>'
    assert bay in s
    s = s.replace(bay, f'<child link="cargo_bay"/>\n    <origin xyz="0 0 {RAISE}" rpy="0 0 0"/>')
    i = s.index('<collision name="hera_link3_0">')
    j = s.index('radius="0.15"', i)
    s = s[:j] + f'radius="{0.15 + THICKER}"' + s[j + len('radius="0.15"'):]
    urdf.write_text(s)
    return folder / "hermes" / "hermes.yaml"


def test_detector_verifier_and_harness_follow_an_edited_urdf(tmp_path):
    path = _edited_hermes(tmp_path)
    old, new = armguard.load_model("hermes"), armguard.load_model(path)
    # the detector: link 3 is 0.2 m thicker, the bay 0.5 m higher
    r0 = armguard.Detector(old.scene, threshold=0.05).check(old.scene.default_q())
    r1 = armguard.Detector(new.scene, threshold=0.05).check(new.scene.default_q())
    assert r0.by_category["arm"].link == r1.by_category["arm"].link == "hera/link3"
    assert r1.by_category["arm"].distance == pytest.approx(r0.by_category["arm"].distance - THICKER, abs=1e-9)
    assert r1.by_category["environment"].distance < r0.by_category["environment"].distance - THICKER
    assert r0.status.value == "clear" and r1.status.value != "clear"
    # the verifier: unstow was safe and now meets the raised bay; the misaligned stow hits the tail earlier
    assert armguard.verify(old.scene, old.scene.trajectories["unstow"]).safe
    hit = armguard.verify(new.scene, new.scene.trajectories["unstow"]).first_collision
    assert hit is not None and hit.obstacle == "cargo_bay"
    t0 = armguard.verify(old.scene, old.scene.trajectories["stow_misaligned"]).first_collision.time
    t1 = armguard.verify(new.scene, new.scene.trajectories["stow_misaligned"]).first_collision.time
    assert t1 < t0
    # the harness: the same configurations, coal's link-3 capsule pairs exactly 0.2 m closer, analytic still agreeing
    c0 = run_compare("hermes", ("analytic", "coal"), n_configs=40, seed=9, trajectories=None, plots=False)
    c1 = run_compare(str(path), ("analytic", "coal"), n_configs=40, seed=9, trajectories=None, plots=False)
    np.testing.assert_array_equal(c0.configs.Q, c1.configs.Q)
    assert c1.summary["pairs"]["analytic/coal"]["status"] == "agree"
    names = new.pairs.names
    kinds = [type(new.collision_model.geometryObjects[new.geometry_index(n)].geometry).__name__ for n in names[:, 1]]
    d0, d1 = c0.answers["coal"].distance, c1.answers["coal"].distance
    link3_caps = np.array([(a == "hera_link3_0" or b == "hera_link3_0") and k == "Capsule" and
                           type(new.collision_model.geometryObjects[new.geometry_index(a)].geometry).__name__ == "Capsule"
                           for (a, b), k in zip(names, kinds)])
    assert link3_caps.any()
    np.testing.assert_allclose(d1[:, link3_caps], d0[:, link3_caps] - THICKER, atol=1e-9)
    bay = np.array([b.startswith("cargo_bay") and a != "hera_link3_0" for a, b in names])
    assert np.abs(d1[:, bay] - d0[:, bay]).max() > 0.1  # the bay moved
    untouched = ~bay & ~np.array(["hera_link3_0" in p or p[1].startswith("cargo_bay") for p in map(tuple, names)])
    np.testing.assert_array_equal(d1[:, untouched], d0[:, untouched])


def test_run_compare_gives_no_verdict_from_no_configuration():
    """n_configs=0 without trajectories reported 'agree' over 0 configurations (and wrote compare.json);
    -3 was numpy's negative-dimensions error, 2.7 ran as 2; a backends string was split into letters."""
    from armguard import ArmguardError
    from armguard.harness import run_compare

    with pytest.raises(ArmguardError, match="no configuration to compare"):
        run_compare("hermes", n_configs=0, trajectories=None)
    for bad in (-3, 2.7, True):
        with pytest.raises(ArmguardError, match="n_configs: expected an integer >= 0"):
            run_compare("hermes", n_configs=bad, trajectories=None)
    assert list(run_compare("hermes", "analytic,coal", n_configs=3, trajectories=None).summary["pairs"]) == ["analytic/coal"]


@pytest.fixture(scope="module")
def hermes_coal():
    from armguard.harness import build_configs, evaluate

    m = armguard.load_model("hermes")
    cfg = build_configs(m, 40, 0, None, 1.0)
    return m, cfg, evaluate(m, cfg.Q, ("coal",))["coal"]


def _judged(m, cfg, C, X):
    from armguard.harness import compare_answers

    return compare_answers(m, cfg, {"coal": C, "x": X}, spec="hermes").summary["pairs"]["coal/x"]


def test_a_sign_flip_where_another_pair_collides_is_a_difference(hermes_coal):
    """One pair 12 cm deep said 25 cm apart, in a configuration another pair collides in both: "agree" before
    (only verdicts and separated distances were judged)."""
    import copy

    m, cfg, C = hermes_coal
    D = C.distance
    i = int(np.flatnonzero((D < -1e-3).sum(axis=1) >= 2)[0])
    k = int(np.flatnonzero(D[i] < -1e-3)[0])
    X = copy.deepcopy(C)
    assert _judged(m, cfg, C, X)["status"] == "agree"
    X.distance = D.copy()
    X.distance[i, k] = 0.25
    p = _judged(m, cfg, C, X)
    assert p["verdict_disagreements"] == 0 and p["categories"]["all"]["sign_disagreements"] == 1
    assert p["status"] == "differ"


def test_moved_witness_points_are_a_difference(hermes_coal):
    import copy

    m, cfg, C = hermes_coal
    X = copy.deepcopy(C)
    X.p_WA = C.p_WA + np.array([0.3, 0.0, 0.0])  # every witness on A moved 30 cm
    X.p_WB = C.p_WB + np.array([0.3, 0.0, 0.0])
    p = _judged(m, cfg, C, X)
    al = p["categories"]["all"]
    assert al["unique_points"]["over_tolerance"] > 0 and p["status"] == "differ"


def test_the_contact_band_excuses_a_disagreement_only_when_both_are_in_it(hermes_coal):
    """The reference touching (d = 0) excused the other saying 0.5 m apart with the opposite verdict."""
    import copy

    m, cfg, C0 = hermes_coal
    C, X = copy.deepcopy(C0), copy.deepcopy(C0)
    i = int(np.flatnonzero(C.distance.min(axis=1) > 0.01)[0])
    k = int(np.argmin(C.distance[i]))
    C.distance[i, k], C.verdict[i] = 0.0, True
    X.distance[i, k], X.verdict[i] = 0.5, False
    p = _judged(m, cfg, C, X)
    assert p["verdict_disagreements"] == 1 and p["status"] == "differ"
    X.distance[i, k] = 1e-7  # both in the band (witness points made to fit both distances): excused
    C.p_WB[i, k] = C.p_WA[i, k]
    X.p_WA[i, k], X.p_WB[i, k] = C.p_WA[i, k], C.p_WA[i, k] + [1e-7, 0.0, 0.0]
    p = _judged(m, cfg, C, X)
    assert p["verdict_disagreements"] == 0 and p["verdict_disagreements_in_band"] == 1 and p["status"] == "agree"


def test_two_answers_both_apart_across_the_band_edge_are_no_sign_disagreement(hermes_coal):
    """1.1 µm against 0.9 µm (both apart; the band is 1 µm) counted as a sign disagreement and made "differ"."""
    import copy

    m, cfg, C0 = hermes_coal
    C, X = copy.deepcopy(C0), copy.deepcopy(C0)
    i = int(np.flatnonzero(C.distance.min(axis=1) > 0.01)[0])
    k = int(np.argsort(C.distance[i])[1])  # not the nearest pair
    for A, dist in ((C, 1.1e-6), (X, 0.9e-6)):
        A.distance[i, k] = dist
        A.p_WB[i, k] = A.p_WA[i, k] + [dist, 0.0, 0.0]
    p = _judged(m, cfg, C, X)
    assert p["categories"]["all"]["sign_disagreements"] == 0 and p["status"] == "agree", p["categories"]["all"]
