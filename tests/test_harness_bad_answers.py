"""The harness checks every backend answer it is given: a NaN or infinite distance or witness point, an
array of another shape or type, or no PairDistances at all is that backend's fault, a BackendError
naming the backend, the configuration number and ``q`` (and the pair of a non-finite value), so that
``armguard compare`` exits with the refused-value status (3), never an internal error (4), and writes
nothing.  The misbehaving backend is registered for the test: the analytic backend's answers, spoiled
one way per ``mode`` option."""

from __future__ import annotations

import dataclasses
import json
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
import armguard.backends as backends_mod
from armguard import ArmguardError, BackendError
from armguard.backends import Capability, CheckerBase, check_Q
from armguard.cli import ExitCode, main
from armguard.harness import build_configs, compare_at, evaluate, parse_backend_options, run_compare

MODEL = "puma560"
N_CONFIGS, SEED = 10, 0
AT, PAIR = 3, 2  # the configuration and the pair row the spoiled answer is given for


class _Spoiled(CheckerBase):
    """The analytic backend's answers, spoiled as ``mode`` says at the configuration ``at`` (comma-separated
    q; every configuration where not given) and the pair row ``pair``."""

    name = "spoiled"

    def __init__(self, model, options=None):
        super().__init__(model)
        opts = dict(options or {})
        self.mode = str(opts.get("mode", "ok"))
        at = opts.get("at")
        self.at = None if at is None else np.array([float(v) for v in str(at).split(",")])
        self.pair = int(opts.get("pair", PAIR))
        self.inner = armguard.checker(model, "analytic")

    def _here(self, q) -> bool:
        return self.at is None or np.array_equal(np.asarray(q, dtype=np.float64), self.at)

    def pair_distances(self, q):
        r = self.inner.pair_distances(q)
        if not self._here(q):
            return r
        d, pa, pb = r.distance.copy(), r.p_WA.copy(), r.p_WB.copy()
        if self.mode == "nan-distance":
            d[self.pair] = np.nan
        elif self.mode == "inf-witness":
            pb[self.pair, 1] = np.inf
        elif self.mode == "column":
            d = d[:, None]
        elif self.mode == "one-row":
            d = d[:1]  # would broadcast into every row unnoticed
        elif self.mode == "text":
            d = d.astype(str)
        elif self.mode == "none":
            return None
        return dataclasses.replace(r, distance=d, p_WA=pa, p_WB=pb)

    def collides(self, Q, *, margin: float = 0.0):
        v = self.inner.collides(Q, margin=margin)
        if self.mode == "verdict-floats":
            return v.astype(np.float64)
        if self.mode == "verdict-column":
            return v[:, None]
        return v


class _BadCodes(CheckerBase):
    """A verdicts-only backend whose per-pair codes are not CLEAR / COLLISION / UNDECIDED."""

    name = "badcodes"
    capabilities = frozenset({Capability.VERDICTS})

    def __init__(self, model, options=None):
        super().__init__(model)
        self.inner = armguard.checker(model, "analytic")

    def collides(self, Q, *, margin: float = 0.0):
        return self.inner.collides(check_Q(self.model, Q), margin=margin)

    def check_pairs(self, Q, subdivide=False):
        Q = check_Q(self.model, Q)
        return SimpleNamespace(pair_codes=np.full((len(Q), len(self.model.pairs)), 7, dtype=np.int8))

    def pair_distances(self, q):
        self._require(Capability.DISTANCES)


@pytest.fixture
def registered(monkeypatch):
    real = backends_mod._entry_points
    fakes = {name: SimpleNamespace(load=lambda cls=cls, name=name: SimpleNamespace(
        name=name, build=lambda model, options=None: cls(model, options)))
        for name, cls in (("spoiled", _Spoiled), ("badcodes", _BadCodes))}
    monkeypatch.setattr(backends_mod, "_entry_points", lambda refresh=False: {**real(refresh), **fakes})


@pytest.fixture(scope="module")
def model():
    return armguard.load_model(MODEL)


@pytest.fixture(scope="module")
def Q(model):
    """The configurations run_compare(MODEL, n_configs=N_CONFIGS, seed=SEED, trajectories=None) answers."""
    return build_configs(model, N_CONFIGS, SEED, None).Q


def _at(Q) -> str:
    return ",".join(repr(float(v)) for v in Q[AT])


def _pair(model) -> tuple:
    a, b = model.pairs.names[PAIR]
    return str(a), str(b)


def test_a_healthy_wrapper_passes_the_checks(registered, model, Q, tmp_path):
    """The checks refuse nothing a correct backend answers: the unspoiled wrapper agrees with analytic."""
    comp = run_compare(MODEL, ("analytic", "spoiled"), n_configs=N_CONFIGS, seed=SEED, trajectories=None,
                       out_dir=tmp_path, plots=False)
    assert comp.summary["pairs"]["analytic/spoiled"]["status"] == "agree"
    np.testing.assert_array_equal(comp.answers["spoiled"].distance, comp.answers["analytic"].distance)
    assert json.loads((tmp_path / "compare.json").read_text())["outputs"] == ["compare.json"]


def test_a_nan_distance_leaves_its_configuration_out_naming_backend_q_and_pair(registered, model, Q, tmp_path):
    """A NaN at one configuration lost every answer already computed (the whole run raised): that configuration is
    now left out of the comparison and reported, the others compared."""
    out = tmp_path / "out"
    comp = run_compare(MODEL, ("analytic", "spoiled"), n_configs=N_CONFIGS, seed=SEED, trajectories=None, out_dir=out,
                       options={"spoiled": {"mode": "nan-distance", "at": _at(Q)}})
    s = comp.summary
    assert s["configs"]["drawn"] == N_CONFIGS and s["configs"]["refused"] == 1 and s["configs"]["total"] == N_CONFIGS - 1
    assert s["refused"] == [{"config": AT, "q": Q[AT].tolist(), "message": (
        f"backend 'spoiled' answered distance NaN at configuration #{AT} (q = {Q[AT].tolist()}) for pair "
        f"{_pair(model)}, expected finite values (m)")}]
    keep = [i for i in range(N_CONFIGS) if i != AT]
    np.testing.assert_array_equal(comp.configs.Q, Q[keep])
    assert [comp.configs.number(i) for i in range(len(keep))] == keep
    np.testing.assert_array_equal(comp.answers["spoiled"].distance, comp.answers["analytic"].distance)
    assert s["pairs"]["analytic/spoiled"]["status"] == "agree"  # the others agree; the run is not whole (CLI: exit 5)
    assert s["complete"] is False
    assert json.loads((out / "compare.json").read_text())["configs"]["refused"] == 1


def test_the_configuration_number_counts_across_chunks(registered, model, Q):
    """Chunks of 2 rows: configuration #3 is row 1 of the second chunk, and is named #3."""
    opts = {"spoiled": {"mode": "inf-witness", "at": _at(Q)}}
    with pytest.raises(BackendError) as e:
        evaluate(model, Q, ("analytic", "spoiled"), opts, chunk_size=2)
    msg = str(e.value)
    assert msg.startswith(f"backend 'spoiled' answered witness point p_WB [") and "inf" in msg, msg
    assert f"at configuration #{AT} (q = {Q[AT].tolist()}) for pair {_pair(model)}" in msg


@pytest.mark.parametrize("mode, said", [
    ("column", f"answered distance of shape (N, 1) at configuration #{AT} (q = Q), expected (N,)"),
    ("one-row", f"answered distance of shape (1,) at configuration #{AT} (q = Q), expected (N,)"),
    ("text", f"answered distance of dtype <U"),
    ("none", f"answered pair_distances with NoneType at configuration #{AT} (q = Q), expected a PairDistances"),
])
def test_a_wrongly_shaped_or_typed_answer_is_the_backends_fault(registered, model, Q, mode, said):
    n = len(model.pairs)
    said = said.replace("(N, 1)", f"({n}, 1)").replace("(N,)", f"({n},)").replace("q = Q", f"q = {Q[AT].tolist()}")
    with pytest.raises(BackendError) as e:
        run_compare(MODEL, ("analytic", "spoiled"), n_configs=N_CONFIGS, seed=SEED, trajectories=None,
                    options={"spoiled": {"mode": mode, "at": _at(Q)}})
    assert str(e.value).startswith("backend 'spoiled' ") and said in str(e.value), str(e.value)


@pytest.mark.parametrize("mode, said", [("verdict-floats", "answered collides of dtype float64"),
                                        ("verdict-column", f"answered collides of shape ({N_CONFIGS}, 1)")])
def test_a_bad_collides_answer_is_the_backends_fault(registered, mode, said):
    with pytest.raises(BackendError) as e:
        run_compare(MODEL, ("analytic", "spoiled"), n_configs=N_CONFIGS, seed=SEED, trajectories=None,
                    options={"spoiled": {"mode": mode}})
    assert str(e.value).startswith(f"backend 'spoiled' {said} at configurations #0..#{N_CONFIGS - 1}"), str(e.value)


def test_verdict_codes_out_of_range_are_the_backends_fault(registered):
    with pytest.raises(BackendError) as e:
        run_compare(MODEL, ("badcodes", "analytic"), n_configs=N_CONFIGS, seed=SEED, trajectories=None)
    assert str(e.value) == ("backend 'badcodes' answered pair_codes codes [7] at the 65 warm-up configurations (the "
                            "neutral q, then model.random_q(64, seed=0)), expected 0 (clear), 1 (collision) or 2 "
                            "(undecided)")


def test_compare_at_refuses_a_nan_instead_of_printing_it(registered, model, Q):
    with pytest.raises(BackendError) as e:
        compare_at(MODEL, ("analytic", "spoiled"), Q[AT], options={"spoiled": {"mode": "nan-distance", "at": _at(Q)}},
                   model=model)
    assert str(e.value) == (f"backend 'spoiled' answered distance NaN at the configuration given (q = {Q[AT].tolist()}) "
                            f"for pair {_pair(model)}, expected finite values (m)")


def _cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args], terminal_width=250)


def test_cli_compare_with_a_refused_configuration_exits_5_and_says_which(registered, model, Q, tmp_path):
    out = tmp_path / "out"
    res = _cli("compare", MODEL, "--backends", "analytic,spoiled", "--configs", N_CONFIGS, "--seed", SEED,
               "--trajectory", "none", "--no-plots", "--out", out, "--backend-option", "spoiled.mode=nan-distance",
               "--backend-option", f"spoiled.at={_at(Q)}")
    assert res.exit_code == ExitCode.INCOMPLETE, res.output
    assert f"1 of {N_CONFIGS} configurations refused by a backend, left out of the comparison" in res.output
    assert (f"#{AT}: backend 'spoiled' answered distance NaN at configuration #{AT} (q = {Q[AT].tolist()}) "
            f"for pair {_pair(model)}, expected finite values (m)") in res.output.replace("\n", "")
    assert json.loads((out / "compare.json").read_text())["configs"]["refused"] == 1


def test_cli_compare_refuses_an_unwritable_out_before_the_work(tmp_path):
    """A file where --out's folder goes was found after every answer was computed, and the comparison was lost."""
    (tmp_path / "afile").write_text("")
    res = _cli("compare", MODEL, "--backends", "analytic,coal", "--configs", 5, "--trajectory", "none", "--no-plots",
               "--out", tmp_path / "afile" / "sub")
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "afile exists and is not a folder" in res.output and "answers" not in res.output


def test_cli_compare_shape_error_exits_3(registered, model):
    res = _cli("compare", MODEL, "--backends", "analytic,spoiled", "--configs", 4, "--trajectory", "none", "--no-plots",
               "--backend-option", "spoiled.mode=column")
    assert res.exit_code == ExitCode.INPUT, res.output
    n = len(model.pairs)
    assert res.output.strip().startswith(f"error: backend 'spoiled' answered distance of shape ({n}, 1) at configuration #0 ")
    assert "internal error" not in res.output and "broadcast" not in res.output


def test_cli_compare_q_exits_3_instead_of_printing_nan(registered, model, Q):
    res = _cli("compare", MODEL, "--backends", "analytic,spoiled", "--q", _at(Q), "--backend-option",
               "spoiled.mode=nan-distance", "--backend-option", f"spoiled.at={_at(Q)}")
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "d = nan" not in res.output and "answered distance NaN at the configuration given" in res.output
    # the same configuration unspoiled is answered (exit 0), so the 3 above is the NaN's
    res = _cli("compare", MODEL, "--backends", "analytic,spoiled", "--q", _at(Q), "--json")
    assert res.exit_code == ExitCode.OK, res.output
    rows = json.loads(res.output)
    assert len(rows) == len(model.pairs) and rows[PAIR]["spoiled"][0] == rows[PAIR]["analytic"][0]


def test_a_non_finite_option_value_stays_text():
    """``--backend-option b.k=nan`` reached compare.json as a NaN float (no JSON): it stays the text."""
    assert parse_backend_options(["b.x=nan", "b.y=-inf", "b.z=1e-3", "b.n=7"]) == {
        "b": {"x": "nan", "y": "-inf", "z": 1e-3, "n": 7}}


def test_the_pytest_plugin_reads_options_as_compare_does():
    """``--backend-option`` of the conformance suite's pytest plugin and of ``armguard compare`` are read by one
    function: ``inf`` stays text in both (the plugin had made it a float)."""
    from types import SimpleNamespace

    from armguard.testing._plugin import options_from_config

    given = ["threads=1", "tol=1e-9", "flag=true", "limit=inf", "mode=exact"]
    config = SimpleNamespace(getoption=lambda name: {"armguard_backend": "coal", "armguard_backend_options": given}.get(name))
    opts = options_from_config(config)["options"]
    want = parse_backend_options([f"coal.{g}" for g in given])["coal"]
    assert want["limit"] == "inf" and want["threads"] == 1 and want["flag"] is True
    assert {k: opts[k] for k in want} == want


def test_a_non_finite_value_in_the_summary_is_refused_before_writing(registered, tmp_path):
    out = tmp_path / "out"
    with pytest.raises(ArmguardError) as e:
        run_compare(MODEL, ("analytic", "spoiled"), n_configs=N_CONFIGS, seed=SEED, trajectories=None, out_dir=out,
                    plots=False, options={"spoiled": {"scale": float("nan")}})
    msg = str(e.value)
    assert msg.startswith(str(out / "compare.json")) and "['spoiled']['options']['scale'] = nan" in msg, msg
    assert "not a finite number" in msg and not out.exists()


@pytest.mark.parametrize("status, said", [
    (np.array(["CLEAR", "BOGUS"], dtype=object), "answered a verdict that is none at 2 configurations: three-valued "
                                                 "verdict 'BOGUS'"),
    (SimpleNamespace(status=np.array([0, 7]), collision=np.zeros(2, bool)), "7 is not a valid CombinedStatus"),
    (np.array(["CLEAR"], dtype=object), "answered verdicts of shape (1,) at 2 configurations, expected (2,)"),
])
def test_a_verdicts_answer_that_is_no_verdict_is_the_backends_fault(model, Q, status, said):
    """The ``verdicts()`` path (the forbidden backend's): an unknown status name was an ArmguardError naming no
    backend, a bad CombinedStatus code a raw ValueError (exit 4)."""
    from armguard.harness._evaluate import verdict_detail

    checker = SimpleNamespace(name="maps", model=model, verdicts=lambda Q: status)
    with pytest.raises(armguard.BackendError, match="backend 'maps'") as info:
        verdict_detail(checker, Q[:2])
    assert said in str(info.value)
