"""Margins per pair and per category: ``collides(Q, margin=...)``, ``pair_margins`` and
``Verifier.check_edges(margin={...})`` against the obviously correct statement from the pair
distances, ``any(distance <= margin)``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard import BackendError, VerificationError
from armguard.backends import CheckerBase, check_margins, pair_margins
from armguard.verify import EdgeStatus, Verifier

BAND = 1e-9  # m: rows with a pair this close to its margin are not compared (rounding decides them)


@pytest.fixture(scope="module")
def hermes():
    return armguard.load_model("hermes")


def _reference(checker, Q, m):
    D = checker.pair_distances_many(Q).distance
    return np.any(D <= m, axis=1), ~np.any(np.abs(D - m) <= BAND, axis=1)


def test_one_margin_stays_a_float_and_mappings_become_arrays(hermes):
    cats = np.asarray(hermes.pairs.category)
    assert check_margins(hermes, 0.02) == 0.02 and type(check_margins(hermes, 1)) is float
    m = check_margins(hermes, {"arm-arm": 0.0, "*": 0.02})
    assert m.shape == (len(cats),) and not m.flags.writeable
    assert np.all(m[cats == "arm-arm"] == 0.0) and np.all(m[cats != "arm-arm"] == 0.02)
    m = check_margins(hermes, {"arm-vehicle": 0.03})  # unnamed categories: 0
    assert np.all(m[cats == "arm-vehicle"] == 0.03) and np.all(m[cats != "arm-vehicle"] == 0.0)
    assert check_margins(hermes, {"*": 0.01}) == 0.01  # every pair the same: the float
    assert check_margins(hermes, np.full(len(cats), 0.004)) == 0.004


@pytest.mark.parametrize("margin, words", [
    ({"arm-arms": 0.0}, "'arm-arms' is not a pair category; the categories: arm-arm, arm-vehicle, arm-environment, "
                        "arm-payload, payload-vehicle, payload-environment, payload-payload, workspace (this model's: "
                        "arm-arm, arm-payload, arm-vehicle, payload-vehicle), and '*' for those not named"),
    ([[0.1], [0.1, 0.2]], "margin: expected a number (m), a mapping by pair category or an array of 50 numbers"),
    ({"a": 1}.values(), "margin: expected a number (m), a mapping by pair category or an array of 50 numbers"),
    (np.r_[np.zeros(49), -0.5], "): expected a finite number >= 0 (m), got -0.5"),
    ({"arm-arm": -0.01}, "margin['arm-arm']: expected a finite number >= 0"),
    ({"*": float("nan")}, "margin['*']: expected a finite number >= 0"),
    (np.zeros(3), "an array of 50 numbers (one per Model pair, Model.pairs order), got dtype float64, shape (3,)"),
    (np.r_[np.zeros(49), np.nan], "margin[49] (pair"),
    (np.zeros(50, dtype=bool), "got dtype bool"),
    ("0.02", "margin: expected a number (m), a mapping by pair category or an array of 50 numbers (one per Model "
             "pair, Model.pairs order), got '0.02'"),
    (-0.01, "margin: expected a finite number >= 0 (m), got -0.01"),
])
def test_bad_margins_are_refused_by_name(hermes, margin, words):
    with pytest.raises(BackendError, match=None) as info:
        armguard.checker(hermes, "analytic").collides(hermes.random_q(2, 0), margin=margin)
    assert words in str(info.value)


def test_pair_margins_adds_categories_and_padding(hermes):
    pairs = hermes.pairs
    m = pair_margins(hermes, 0.01, categories={"arm-arm": 0.0}, padding={"payload": 0.05, "link6": 0.002})
    for k in range(len(pairs)):
        want = 0.0 if pairs.category[k] == "arm-arm" else 0.01
        want += sum(0.05 if o == "payload" else 0.002 if o == "hera/link6" else 0.0 for o in (pairs.owner_a[k], pairs.owner_b[k]))
        assert m[k] == pytest.approx(want, abs=1e-15), (pairs.owner_a[k], pairs.owner_b[k])
    with pytest.raises(BackendError, match="'hand' names no part of a pair; the parts: "):
        pair_margins(hermes, padding={"hand": 0.01})
    with pytest.raises(BackendError, match=r"'hera/link6' is padded twice \('link6' and 'hera/link6'\)"):
        pair_margins(hermes, padding={"link6": 0.01, "hera/link6": 0.01})
    arm = pair_margins(hermes, padding={"hera": 0.01})  # a robot's name: each of its links
    links = [sum(o.startswith("hera/") for o in (a, b)) for a, b in zip(pairs.owner_a, pairs.owner_b)]
    np.testing.assert_allclose(arm, 0.01 * np.array(links), atol=1e-15)
    m2 = pair_margins(hermes, 0.0, categories={"*": 0.02, "arm-arm": 0.0, "workspace": 0.5})  # workspace: none here
    np.testing.assert_array_equal(m2, np.where(np.asarray(pairs.category) == "arm-arm", 0.0, 0.02))
    with pytest.raises(BackendError, match=r"'link1' is a link of several robots \(camera_arm/link1, grapple_arm/link1, left_arm/link1, right_arm/link1\)"):
        pair_margins(armguard.load_model("ranger"), padding={"link1": 0.01})


@pytest.mark.parametrize("robot, backends", [("hermes", ("analytic", "coal", "fcl")), ("ranger", ("analytic", "coal")),
                                             ("ur5", ("analytic", "coal"))])
def test_collides_per_pair_is_any_distance_within_its_margin(robot, backends):
    model = armguard.load_model(robot)
    Q = model.random_q(150, 7)
    m = pair_margins(model, 0.03, categories={"arm-arm": 0.0}) if robot != "ur5" else \
        pair_margins(model, padding={"ee_link": 0.01, "wrist_1_link": 0.004})
    assert np.ptp(m) > 0
    for b in backends:
        c = armguard.checker(model, b)
        want, clear = _reference(c, Q, m)
        got = c.collides(Q, margin=m)
        assert got.dtype == bool and got.shape == (len(Q),)
        assert np.array_equal(got[clear], want[clear]), b
        # discriminating: neither one margin answers so
        assert not np.array_equal(want, c.collides(Q, margin=float(m.min()))) or not np.array_equal(
            want, c.collides(Q, margin=float(m.max()))), b


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**31 - 1), scale=st.floats(0.0, 0.3))
def test_any_margins_answer_as_the_distances_do(hermes, seed, scale):
    rng = np.random.default_rng(seed)
    c = armguard.checker(hermes, "analytic")
    Q = hermes.random_q(40, seed)
    m = scale * rng.random(len(hermes.pairs)) * (rng.random(len(hermes.pairs)) < 0.7)
    want, clear = _reference(c, Q, m)
    assert np.array_equal(c.collides(Q, margin=m)[clear], want[clear])


def test_a_verdicts_only_backend_takes_one_margin(hermes):
    c = armguard.checker(hermes, "clip")
    Q = hermes.random_q(4, 1)
    assert c.collides(Q, margin={"*": 0.0}).shape == (4,)  # every pair the same: one margin
    with pytest.raises(BackendError, match="a margin per pair needs pair distances; this backend answers verdicts only"):
        c.collides(Q, margin={"arm-arm": 0.0, "*": 0.02})


def test_a_third_party_backend_gets_margins_per_pair(hermes):
    """A CheckerBase subclass answering one margin (the float its ``collides`` is written for) answers
    margins per pair through the framework."""
    inner = armguard.checker(hermes, "coal")
    seen = []

    class OneMargin(CheckerBase):
        name = "one-margin"

        def pair_distances(self, q, *, pairs=None):
            return inner.pair_distances(q, pairs=pairs)

        def collides(self, Q, *, margin: float = 0.0):
            seen.append(type(margin))
            return inner.collides(Q, margin=margin)

    c = OneMargin(hermes)
    Q = hermes.random_q(60, 3)
    m = pair_margins(hermes, 0.04, categories={"arm-arm": 0.0})
    want, clear = _reference(inner, Q, m)
    assert np.array_equal(c.collides(Q, margin=m)[clear], want[clear])
    assert set(seen) == {float}


def _edges(model, n=60, step=0.15, seed=4):
    rob = model.scene.robots[next(iter(model.scene.robots))]
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    Q0 = lo + (hi - lo) * rng.random((n, len(lo)))
    Q1 = np.clip(Q0 + step * (hi - lo) * (rng.random((n, len(lo))) - 0.5), lo, hi)
    return Q0, Q1


def test_check_edges_by_category_against_dense_samples(hermes):
    """CLEAR edges: no sample within its pair's margin; COLLISION: the pair found within its own
    category's margin (plus the contact tolerance); the results say the margins."""
    v = Verifier(hermes)
    Q0, Q1 = _edges(hermes)
    margin = {"arm-arm": 0.0, "*": 0.03}
    res = v.check_edges(Q0, Q1, margin=margin)
    assert res.margin == {"arm-arm": 0.0, "arm-payload": 0.03, "arm-vehicle": 0.03, "payload-vehicle": 0.03}
    assert "within their category's margin (arm-arm 0 mm, arm-payload 30 mm" in res.summary()
    one = v.check_edges(Q0, Q1, margin=0.03)
    assert 0 < res.counts()["collision"] < one.counts()["collision"]  # the arm's own links no longer held 3 cm apart
    c = armguard.checker(hermes, "analytic")
    m = check_margins(hermes, margin)
    S = np.linspace(0.0, 1.0, 101)[:, None]
    contact = armguard.DEFAULT_TOLERANCES.verify_contact
    cat_of = {}
    for k in range(len(hermes.pairs)):
        cat_of[frozenset((hermes.pairs.owner_a[k], hermes.pairs.owner_b[k]))] = hermes.pairs.category[k]
    for i in range(len(Q0)):
        samples = hermes.pin_q(Q0[i] + S * (Q1[i] - Q0[i]))  # the scene's joint order to Pinocchio's
        if res.code[i] == EdgeStatus.CLEAR:
            assert not c.collides(samples, margin=m).any(), i
        elif res.code[i] == EdgeStatus.COLLISION:
            cat = cat_of[frozenset(res.pair[i])]
            assert res.distance[i] <= res.margin[cat] + contact, (i, res.pair[i], res.distance[i])


def test_check_edges_margin_errors(hermes):
    v = Verifier(hermes)
    Q0, Q1 = _edges(hermes, n=2)
    with pytest.raises(VerificationError, match="'arm-arms' is not a pair category; the categories: arm-arm"):
        v.check_edges(Q0, Q1, margin={"arm-arms": 0.0})
    with pytest.raises(VerificationError, match=r"margin\['\*'\]: expected a finite number >= 0"):
        v.check_edges(Q0, Q1, margin={"*": -1.0})
    with pytest.raises(VerificationError, match="or 50 numbers .one per Model pair, Model.pairs order., got .3,."):
        v.check_edges(Q0, Q1, margin=np.zeros(3))
    split = np.zeros(50)
    same = [i for i, ab in enumerate(zip(hermes.pairs.owner_a, hermes.pairs.owner_b)) if ab == ("hera/link2", "cargo_bay")]
    assert len(same) == 3  # the cargo bay's three shapes against link 2
    split[same[0]] = 0.01  # one of them given another margin
    with pytest.raises(VerificationError, match="'hera/link2' - 'cargo_bay' are given 0.01 and 0 m: a pair of parts keeps one"):
        v.check_edges(Q0, Q1, margin=split)
    # a mapping given: reported by category, even where every category's is the same (armguard edges' file too)
    assert v.check_edges(Q0, Q1, margin={"*": 0.02}).margin == dict.fromkeys(
        ("arm-arm", "arm-vehicle", "arm-payload", "payload-vehicle"), 0.02)
    by_parts = v.check_edges(Q0, Q1, margin=np.full(50, 0.02)).margin  # an array given: by pair of parts
    assert set(by_parts.values()) == {0.02} and ("hera/link2", "cargo_bay") in by_parts


def test_check_edges_takes_collides_array_of_margins(hermes):
    """``pair_margins``' array (category and padding) in check_edges: CLEAR edges have no dense sample within a
    pair's margin by ``collides`` with the same array; the results give the margin of each pair of parts."""
    v = Verifier(hermes)
    Q0, Q1 = _edges(hermes, seed=9)
    m = pair_margins(hermes, 0.01, categories={"arm-arm": 0.0}, padding={"payload": 0.04})
    res = v.check_edges(Q0, Q1, margin=m)
    assert res.margin[("payload", "cargo_bay")] == pytest.approx(0.05) or res.margin[("cargo_bay", "payload")] == pytest.approx(0.05)
    assert "within their pair's margin (0 to 50 mm)" in res.summary()
    c = armguard.checker(hermes, "analytic")
    S = np.linspace(0.0, 1.0, 101)[:, None]
    for i in np.flatnonzero(res.code == EdgeStatus.CLEAR):
        assert not c.collides(hermes.pin_q(Q0[i] + S * (Q1[i] - Q0[i])), margin=m).any(), i
    assert res.counts()["clear"] > 0 and res.counts()["collision"] > 0


def test_a_boolean_among_numbers_is_refused_never_read_as_one():
    """numpy reads ``[True, -1.5, ...]`` as ``[1.0, -1.5, ...]``: a boolean in a list of joint values or margins
    was 1 rad (a CLEAR edge) or a 1 m margin, where a boolean alone is refused."""
    m = armguard.load_model("ur5")
    c = armguard.checker(m)
    row = [True, -1.5, 1.5, 0.0, 0.0, 0.0]
    for call in (lambda: c.collides([row]), lambda: c.pair_distances(row), lambda: c.collides((tuple(row),)),
                 lambda: c.collides([[np.True_, -1.5, 1.5, 0.0, 0.0, 0.0]])):
        with pytest.raises(BackendError, match="expected real joint values, got a boolean in"):
            call()
    with pytest.raises(VerificationError, match="Q0: expected real joint values, got a boolean in"):
        Verifier(m).check_edges(row, [0.0, -1.5, 1.5, 0.0, 0.0, 0.0])
    with pytest.raises(BackendError, match="got a boolean in the list"):
        c.collides(m.random_q(3, 0), margin=[True] + [0.0] * (len(m.pairs) - 1))
    q = [0.0, -1.5, 1.5, 0.0, 0.0, 0.0]
    with pytest.raises(VerificationError, match="or 17 numbers"):
        Verifier(m).check_edges(q, q, margin=[True] + [0.0] * 16)
    with pytest.raises(VerificationError, match="or 17 numbers"):  # text, which collides refuses too
        Verifier(m).check_edges(q, q, margin=["0.0"] * 17)


def test_pair_margins_refuses_a_sum_past_the_largest_float():
    with pytest.raises(BackendError, match="is not a finite number"):
        pair_margins(armguard.load_model("ranger"), 0.01, padding={"camera_arm/camera": 1e308, "camera_arm/link1": 1e308})


@pytest.mark.parametrize("backend", ["analytic", "coal", "fcl"])
def test_collides_on_a_subset_of_the_pairs(hermes, backend):
    """``collides(Q, pairs=rows)``: a planner's allowed-collision change (the payload may touch the cargo bay while
    it is stowed) without a new Model; exactly ``any(distance[rows] <= margin[rows])``."""
    c = armguard.checker(hermes, backend)
    Q = hermes.random_q(120, 11)
    D = c.pair_distances_many(Q).distance
    cats = np.asarray(hermes.pairs.category)
    rows = np.flatnonzero(cats != "payload-vehicle")  # the payload's pairs with the orbiter allowed
    for margin in (0.0, 0.02, {"arm-arm": 0.0, "*": 0.02}):
        m = check_margins(hermes, margin)
        mk = np.full(len(cats), m) if type(m) is float else m
        want = np.any(D[:, rows] <= mk[rows], axis=1)
        got = c.collides(Q, margin=margin, pairs=rows)
        clear = ~np.any(np.abs(D[:, rows] - mk[rows]) <= BAND, axis=1)
        assert np.array_equal(got[clear], want[clear])
    every = c.collides(Q)
    assert (every & ~c.collides(Q, pairs=rows)).any()  # some rows collide only through the pairs left out
    assert not c.collides(Q, pairs=[]).any()
    with pytest.raises(BackendError, match="pairs: row 50 is not a Model pair row"):
        c.collides(Q, pairs=[50])


def test_collides_on_a_subset_needs_distances(hermes):
    with pytest.raises(BackendError, match=r"collides\(pairs=...\) needs pair distances"):
        armguard.checker(hermes, "clip").collides(hermes.random_q(2, 0), pairs=[0])


def _inner_backend(hermes, **body):
    inner = armguard.checker(hermes, "coal")

    def pair_distances(self, q, *, pairs=None):
        return inner.pair_distances(q, pairs=pairs)

    return inner, type("B", (CheckerBase,), {"pair_distances": pair_distances, **body})(hermes)


def test_the_framework_seam_as_a_backend_author_meets_it(hermes):
    """From a backend author's review: a backend's collides taking pairs= got a mapping margin unconverted; a
    read-only answer made the per-pair path fail; the shown signature lacked pairs=."""
    import inspect

    from armguard.backends import check_margin

    Q = hermes.random_q(60, 3)
    m = {"arm-arm": 0.0, "*": 0.03}
    ref = armguard.checker(hermes, "coal")

    def read_only(self, Q, *, margin=0.0):
        v = ref.collides(Q, margin=check_margin(margin))
        v.flags.writeable = False
        return v

    def own_pairs(self, Q, *, margin=0.0, pairs=None):
        return ref.collides(Q, margin=check_margin(margin), pairs=pairs)

    _, ro = _inner_backend(hermes, collides=read_only)
    assert np.array_equal(ro.collides(Q, margin=m), ref.collides(Q, margin=m))
    _, np_ = _inner_backend(hermes, collides=own_pairs)
    rows = np.arange(0, 50, 2)
    assert np.array_equal(np_.collides(Q, margin=m, pairs=rows), ref.collides(Q, margin=m, pairs=rows))
    assert np.array_equal(np_.collides(Q, margin=0.03, pairs=rows), ref.collides(Q, margin=0.03, pairs=rows))
    assert str(inspect.signature(type(ro).collides)) == "(self, Q, *, margin: 'float' = 0.0, pairs=None) -> 'np.ndarray'"


def test_a_margin_not_given_is_the_backends_own_default(hermes):
    """The wrapper passed its own 0.0 over a backend's default: a default other than the contract's 0 went unseen
    (the conformance suite's collides_matches_distances now catches it)."""
    from armguard.backends import check_margin

    ref = armguard.checker(hermes, "coal")
    Q = hermes.random_q(60, 3)

    def wide(self, Q, *, margin=0.3):
        return ref.collides(Q, margin=check_margin(margin))

    _, b = _inner_backend(hermes, collides=wide)
    assert np.array_equal(b.collides(Q), ref.collides(Q, margin=0.3))
    assert np.array_equal(b.collides(Q, margin=0.0), ref.collides(Q))
