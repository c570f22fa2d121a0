"""``armguard compare`` with verdicts-only backends: clip (Smith's yes / no / maybe) against coal on the
puma560 cell, the forbidden backend (a coarse forbidden-values map built here) against analytic on
Hermes, and a fake verdicts-only backend registered for the test whose unsafe answers must be caught."""

from __future__ import annotations

import json
import math
import shlex
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
import armguard.backends as backends_mod
from armguard.backends import Capability, CheckerBase, check_Q
from armguard.cli import main
from armguard.cspace import CombinedStatus, ForbiddenMap
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.harness import build_checkers, build_configs, compare_answers, evaluate, run_compare

BAND = TOL.differential_contact_band


def _coal_distances(model, Q):
    """``(M, n)`` coal's signed distances (m), computed here, apart from the harness."""
    coal = armguard.checker(model, "coal")
    return np.array([coal.pair_distances(q).distance for q in Q])


@pytest.fixture(scope="module")
def clip_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("clip")
    comp = run_compare("puma560", ("clip", "coal"), n_configs=200, seed=4, trajectories=None, out_dir=out)
    return comp, out


def test_clip_against_coal_keeps_the_contract_and_is_never_unsafe(clip_run):
    comp, out = clip_run
    data = json.loads((out / "compare.json").read_text())
    p = data["pairs"]["clip/coal"]
    assert p["reference"] == "coal" and p["verdicts_only"] == ["clip"] and p["status"] == "agree"
    assert p["max_abs_distance_error"] is None and p["distances"] == p["witness_points"] == "n/a (verdicts only)"
    assert isinstance(p["verdict_disagreements"], int) and p["unsafe_disagreements"] == 0
    assert data["backends"]["clip"]["us_per_config"] > 0 and data["backends"]["coal"]["us_per_config"] > 0
    assert data["backends"]["clip"]["answers"] == "verdicts" and data["backends"]["clip"]["distances_vs_fastest"] is None
    assert data["backends"]["clip"]["yes_no_configs_per_s"] > 0
    assert set(p["categories"]) == {"all", *comp.model.pairs.category}
    for c, r in p["categories"].items():
        assert r["clear_but_collides"] == 0 and r["collision_but_clear"] == 0, c
    assert p["pair_level"]["clear_but_collides"] == 0 and p["pair_level"]["collision_but_clear"] == 0
    # the figures, recomputed here from the backends themselves
    Q = comp.configs.Q
    batch = armguard.checker(comp.model, "clip").check_pairs(Q)
    truth = _coal_distances(comp.model, Q).min(axis=1) <= BAND
    assert p["reference_collisions"] == int(truth.sum()) and 0 < truth.sum() < len(Q)
    assert p["maybe_share"] == pytest.approx(batch.maybe_share())
    assert p["maybe_share_first_level"] == pytest.approx(batch.maybe_share(second_level=False))
    assert p["maybe_share_first_level"] >= p["maybe_share"]
    assert p["conservative_disagreements"] == int(((batch.codes != 0) & ~truth).sum())
    assert p["conservative_share"] == pytest.approx(p["conservative_disagreements"] / len(Q))
    # plots: a verdict bar chart, no distance scatter
    for name in ("verdicts_clip_coal.png", "timing.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    assert not (out / "scatter_clip_coal.png").exists() and not (out / "hist_clip_coal.png").exists()


def test_an_injected_unsafe_answer_is_caught_and_named(clip_run):
    comp, _ = clip_run
    clip, coal = comp.answers["clip"], comp.answers["coal"]
    dmin = coal.distance.min(axis=1)
    i = int(np.argmin(dmin))  # the deepest collision: say clear there
    assert dmin[i] < -BAND
    bad = replace(clip, verdict=clip.verdict.copy(), codes=clip.codes.copy())
    bad.verdict[i], bad.codes[i] = False, 0
    c = compare_answers(comp.model, comp.configs, {"clip": bad, "coal": coal}, spec="puma560")
    p = c.summary["pairs"]["clip/coal"]
    assert p["unsafe_disagreements"] == 1 and p["status"] == "differ"
    assert p["three_valued"]["second_level"]["clear_but_collides"] == 1
    w = p["worst"][0]
    assert w["why"] == "unsafe" and w["config"] == i and w["coal"]["least_distance"] == dmin[i]
    assert w["clip"]["collides"] is False and w["q"] == comp.configs.Q[i].tolist()
    argv = shlex.split(w["reproduce"])
    assert argv[:3] == ["armguard", "compare", "puma560"] and argv[-1] == "--json"
    res = CliRunner().invoke(main, argv[1:])
    assert res.exit_code == 0, res.output
    (row,) = json.loads(res.output)
    assert row["pair"] == w["pair"] and row["coal"][0] == w["coal"]["distance"]
    assert row["clip"]["collides"] is True  # the real backend does see it


class _Blind(CheckerBase):
    """A verdicts-only checker that forgets one category's pairs: coal's verdicts over the others."""

    name = "blind"
    capabilities = frozenset({Capability.VERDICTS})

    def __init__(self, model, options=None):
        super().__init__(model)
        self.forget = str((options or {}).get("forget", "arm-arm"))
        self.keep = np.asarray(model.pairs.category, dtype=object) != self.forget
        self.coal = armguard.checker(model, "coal")

    def collides(self, Q, *, margin: float = 0.0):
        Q = check_Q(self.model, Q)
        return np.array([bool(np.min(self.coal.pair_distances(q).distance[self.keep], initial=np.inf) <= margin) for q in Q])

    def pair_distances(self, q):
        self._require(Capability.DISTANCES)


@pytest.fixture
def blind_registered(monkeypatch):
    real = backends_mod._entry_points
    fake = SimpleNamespace(load=lambda: SimpleNamespace(name="blind", build=lambda model, options=None: _Blind(model, options)))
    monkeypatch.setattr(backends_mod, "_entry_points", lambda refresh=False: {**real(refresh), "blind": fake})
    return fake


def test_a_registered_verdicts_only_backend_that_is_unsafe_fails_with_reproduce_lines(blind_registered, tmp_path):
    comp = run_compare("puma560", ("blind", "coal"), n_configs=200, seed=4, trajectories=None,
                       options={"blind": {"forget": "arm-arm"}}, out_dir=tmp_path)
    p = comp.summary["pairs"]["blind/coal"]
    D = _coal_distances(comp.model, comp.configs.Q)
    arm = np.asarray(comp.model.pairs.category, dtype=object) == "arm-arm"
    expected = (D.min(axis=1) <= BAND) & ~(D[:, ~arm].min(axis=1) <= 0)
    assert expected.sum() > 0  # the sample holds configurations where only an arm-arm pair collides
    assert p["unsafe_disagreements"] == int(expected.sum()) and p["status"] == "differ"
    assert p["three_valued"] is None and p["maybe_share"] is None and p["categories"]["all"]["clear_but_collides"] == p["unsafe_disagreements"]
    unsafe = [w for w in p["worst"] if w["why"] == "unsafe"]
    assert unsafe and all(expected[w["config"]] for w in unsafe)
    assert [w["coal"]["least_distance"] for w in unsafe] == sorted(w["coal"]["least_distance"] for w in unsafe)
    w = unsafe[0]
    assert "--backend-option blind.forget=arm-arm" in w["reproduce"]
    res = CliRunner().invoke(main, shlex.split(w["reproduce"])[1:])
    assert res.exit_code == 0, res.output
    (row,) = json.loads(res.output)
    assert row["blind"] == {"collides": False, "verdict": None, "pair_verdict": None}
    assert row["coal"][0] <= BAND and comp.model.pairs.category[[tuple(n) for n in comp.model.pairs.names].index(tuple(row["pair"]))] == "arm-arm"
    # the command line: tables with "n/a (verdicts only)", the unsafe configurations listed, exit status 1
    res = CliRunner().invoke(main, ["compare", "puma560", "--backends", "blind,coal", "--configs", "200", "--seed", "4",
                                    "--trajectory", "none", "--backend-option", "blind.forget=arm-arm", "--no-plots"],
                             terminal_width=250)
    assert res.exit_code == 1, res.output
    flat = "".join(res.output.split())  # rich wraps at its console's width
    assert "n/a(verdictsonly)" in flat and "unsafe" in flat and "".join(w["reproduce"].split()) in flat


# ------------------------------------------------------------------ the forbidden backend on Hermes
@pytest.fixture(scope="module")
def hermes_map(tmp_path_factory):
    path = tmp_path_factory.mktemp("fmap") / "hermes6.agmap"  # coarse (1° in docs/backends.md), still letting most through
    ForbiddenMap.build(armguard.load_model("hermes"), out=path, resolution=math.radians(6.0), max_depth=3,
                       stopping_distance=0.0)
    return path


def test_forbidden_against_analytic_and_clip(hermes_map, tmp_path):
    opts = {"forbidden": {"map": str(hermes_map)}}
    comp = run_compare("hermes", ("forbidden", "clip", "analytic"), n_configs=300, seed=2, trajectories=None,
                       options=opts, out_dir=tmp_path)
    s = comp.summary
    p = s["pairs"]["forbidden/analytic"]
    assert p["unsafe_disagreements"] == 0 and p["status"] == "agree" and p["max_abs_distance_error"] is None
    # not vacuous: most configurations reach the geometric check, and it finds collisions there
    assert p["false_forbidden"]["reached_geometric_share"] > 0.5 and p["three_valued"]["second_level"]["collision"] > 0
    assert p["per_category"].startswith("n/a") and list(p["categories"]) == ["all"]
    assert s["pairs"]["clip/analytic"]["unsafe_disagreements"] == 0
    two = s["pairs"]["forbidden/clip"]  # two verdicts-only backends, judged by the distance backend of the run
    assert two["reference"] == "analytic" and set(two["sides"]) == {"forbidden", "clip"} and two["unsafe_disagreements"] == 0
    assert s["backends"]["forbidden"]["options"] == {"map": str(hermes_map)}
    # the false-forbidden rate, recomputed here
    Q = comp.configs.Q
    fb = armguard.checker(comp.model, "forbidden", {"map": str(hermes_map)}).verdicts(Q)
    ana = armguard.checker(comp.model, "analytic")
    clear = np.array([ana.pair_distances(q).distance.min() for q in Q]) > BAND
    ff = (fb.status == CombinedStatus.MAP_FORBIDDEN) & clear
    assert ff.sum() > 0 and p["false_forbidden"]["n"] == int(ff.sum())
    assert p["false_forbidden"]["share_of_clear"] == pytest.approx(ff.sum() / clear.sum())
    assert p["false_forbidden"]["map_forbidden_share"] == pytest.approx(np.mean(fb.status == CombinedStatus.MAP_FORBIDDEN))
    assert p["three_valued"]["second_level"]["collision_but_clear"] == 0
    assert {"verdicts_forbidden_analytic.png", "verdicts_clip_analytic.png", "verdicts_forbidden_clip.png",
            "timing.png"} <= {f.name for f in tmp_path.iterdir()}


def test_backend_options_reach_the_verdict_backends(hermes_map, tmp_path):
    model = armguard.load_model("hermes")
    ck = build_checkers(model, ("forbidden",), {"forbidden": {"map": str(hermes_map), "geometric": "coal"}})
    assert ck["forbidden"].geometric.name == "coal"
    res = CliRunner().invoke(main, ["compare", "hermes", "--backends", "forbidden,coal", "--configs", "60", "--trajectory",
                                    "none", "--backend-option", f"forbidden.map={hermes_map}", "--backend-option",
                                    "forbidden.geometric=coal", "--out", str(tmp_path), "--no-plots"], terminal_width=200)
    assert res.exit_code == 0, res.output
    data = json.loads((tmp_path / "compare.json").read_text())
    assert data["backends"]["forbidden"]["options"] == {"map": str(hermes_map), "geometric": "coal"}
    p = data["pairs"]["forbidden/coal"]
    assert p["unsafe_disagreements"] == 0 and p["max_abs_distance_error"] is None
    res = CliRunner().invoke(main, ["compare", "hermes", "--backends", "forbidden,coal", "--configs", "5",
                                    "--backend-option", "forbidden.map=/nonexistent/x.agmap"])
    assert res.exit_code != 0 and "cspace build" in res.output


def test_verdict_answers_do_not_depend_on_the_chunks():
    """Chunks are merged field by field (the Dask path ships the same per-chunk records)."""
    model = armguard.load_model("puma560")
    configs = build_configs(model, 24, seed=5, trajectories=None)
    checkers = build_checkers(model, ("clip", "coal"))
    whole = evaluate(model, configs.Q, ("clip", "coal"), chunk_size=64, checkers=checkers)
    chunked = evaluate(model, configs.Q, ("clip", "coal"), chunk_size=5, checkers=checkers)
    assert whole["clip"].verdicts_only and whole["clip"].distance is None and whole["clip"].map_forbidden is None
    for field in ("verdict", "codes", "codes_first", "pair_codes", "pair_codes_first"):
        np.testing.assert_array_equal(getattr(whole["clip"], field), getattr(chunked["clip"], field), err_msg=field)
    assert whole["clip"].pair_codes.shape == (24, len(model.pairs))
    np.testing.assert_array_equal(whole["coal"].distance, chunked["coal"].distance)


def test_two_verdicts_only_backends_with_no_distance_backend_agree_only_where_their_verdicts_do(hermes_map, tmp_path):
    """forbidden and clip alone were "agree" (exit 0) with 167 of 300 verdicts apart: nothing judged them."""
    comp = run_compare("hermes", ("forbidden", "clip"), n_configs=200, seed=2, trajectories=None,
                       options={"forbidden": {"map": str(hermes_map)}})
    p = comp.summary["pairs"]["forbidden/clip"]
    assert p["reference"] is None and "no backend of the run answers distances" in p["note"]
    n = p["verdict_disagreements"]
    assert n == int(np.sum(comp.answers["forbidden"].verdict != comp.answers["clip"].verdict)) and n > 0
    assert p["status"] == "differ"
