"""Networks of uncertain relations that series/parallel steps cannot reduce (Smith & Cheeseman,
Section 4.1, the Wheatstone bridge): the paper's link deletion and the full joint least-squares
estimate, against the resistor analogy's exact answers (a weighted graph Laplacian), a textbook
weighted least squares, a brute-force search over deletion sets and a Monte Carlo."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import UncertaintyError
from armguard.uncertainty import (
    ReductionStatus,
    UncertainPose2,
    joint_estimate,
    reduce_network,
    reduce_network_report,
    se2,
)

EPS_THETA = 1e-8  # rad² per m²: the angle pinned, so relations at θ = 0 are translations (linear)
FRAMES = {"s": (0.0, 0.0), "a": (1.0, 1.0), "b": (1.0, -1.0), "t": (2.0, 0.0)}
# bridge: s-a R1, s-b R2, a-b R5 (the bridge link), a-t R3, b-t R4
BRIDGE = [("s", "a"), ("s", "b"), ("a", "b"), ("a", "t"), ("b", "t")]


def linear_bridge(r, offsets=None):
    """Translation relations p_j - p_i (+ an inconsistency), covariance diag(R, R, ε R): the three
    coordinates are one resistor network scaled, so det C ranks deletions as R does."""
    offsets = np.zeros((5, 2)) if offsets is None else offsets
    net = []
    for (i, j), rk, off in zip(BRIDGE, r, offsets):
        d = np.subtract(FRAMES[j], FRAMES[i]) + off
        net.append((i, j, UncertainPose2([d[0], d[1], 0.0], np.diag([rk, rk, EPS_THETA * rk]))))
    return net


def effective_resistance(edges, r, s="s", t="t"):
    """Resistance between s and t: (e_s - e_t)^T L^+ (e_s - e_t), L the weighted Laplacian."""
    nodes = sorted({n for e in edges for n in e})
    ix = {n: k for k, n in enumerate(nodes)}
    lap = np.zeros((len(nodes), len(nodes)))
    for (i, j), rk in zip(edges, r):
        v = np.zeros(len(nodes))
        v[ix[i]], v[ix[j]] = 1.0, -1.0
        lap += np.outer(v, v) / rk
    u = np.zeros(len(nodes))
    u[ix[s]], u[ix[t]] = 1.0, -1.0
    return float(u @ np.linalg.pinv(lap) @ u)


def wheatstone(r1, r2, r5, r3, r4):
    """The bridge's resistance by Kennelly's delta-star transform of the triangle s-a-b."""
    tot = r1 + r2 + r5
    r_s, r_a, r_b = r1 * r2 / tot, r1 * r5 / tot, r2 * r5 / tot
    return r_s + 1.0 / (1.0 / (r_a + r3) + 1.0 / (r_b + r4))


def weighted_least_squares(edges, r, z, s="s", t="t"):
    """p_t (2,) from measurements z_e = p_j - p_i, weights 1/R_e, p_s = 0: lstsq of the whitened system."""
    nodes = [n for n in sorted({n for e in edges for n in e}) if n != s]
    ix = {n: k for k, n in enumerate(nodes)}
    a = np.zeros((len(edges), len(nodes)))
    for k, (i, j) in enumerate(edges):
        if i != s:
            a[k, ix[i]] -= 1.0
        if j != s:
            a[k, ix[j]] += 1.0
    w = 1.0 / np.sqrt(np.asarray(r))
    sol = np.linalg.lstsq(a * w[:, None], z * w[:, None], rcond=None)[0]
    return sol[ix[t]]


R_UNBALANCED = [1e-4, 2e-4, 5e-4, 3e-4, 4e-4]  # R1, R2, R5, R3, R4 in BRIDGE order
R_BALANCED = [1e-4, 2e-4, 5e-4, 3e-4, 6e-4]  # R1 / R3 = R2 / R4: no current in the bridge


def test_bridge_joint_estimate_equals_the_exact_linear_gaussian_answer():
    offsets = np.random.default_rng(4).normal(scale=0.02, size=(5, 2))  # inconsistent measurements
    net = linear_bridge(R_UNBALANCED, offsets)
    got = joint_estimate(net, "s", "t")
    r_eq = effective_resistance(BRIDGE, R_UNBALANCED)
    assert r_eq == pytest.approx(wheatstone(*R_UNBALANCED), rel=1e-12)
    np.testing.assert_allclose(np.diag(got.cov)[:2], [r_eq, r_eq], rtol=1e-6)
    assert abs(got.cov[0, 1]) < 1e-6 * r_eq
    z = np.array([n[2].mean[:2] for n in net])
    np.testing.assert_allclose(got.mean[:2], weighted_least_squares(BRIDGE, R_UNBALANCED, z), atol=1e-9)
    assert abs(got.mean[2]) < 1e-9
    assert reduce_network(net, "s", "t", irreducible="joint").mean == pytest.approx(got.mean)


R_STRONG_BRIDGE = [1e-4, 4e-4, 0.5e-4, 4e-4, 1e-4]  # a cheap path s-a-b-t through the bridge link


# docs/uncertainty.md's table: the deletion's variance over the joint (exact) one, per bridge
@pytest.mark.parametrize("r, ratio", [(R_UNBALANCED, 1.00235), (R_BALANCED, 1.0), (R_STRONG_BRIDGE, 1.19481)])
def test_bridge_deletion_is_the_best_single_deletion_and_overestimates_the_joint(r, ratio):
    offsets = np.random.default_rng(5).normal(scale=0.02, size=(5, 2))
    net = linear_bridge(r, offsets)
    rep = reduce_network_report(net, "s", "t")
    assert rep.status is ReductionStatus.DELETED and rep.alternatives == 5
    # each single deletion leaves a series-parallel network; its resistance by the Laplacian
    per_deletion = [effective_resistance(BRIDGE[:k] + BRIDGE[k + 1:], r[:k] + r[k + 1:]) for k in range(5)]
    best = min(per_deletion)
    assert per_deletion[rep.deleted[0]] == pytest.approx(best, rel=1e-12) and len(rep.deleted) == 1
    np.testing.assert_allclose(np.diag(rep.pose.cov)[:2], [best] * 2, rtol=1e-6)
    z = np.array([n[2].mean[:2] for n in net])
    keep = [j for j in range(5) if j != rep.deleted[0]]
    want = weighted_least_squares([BRIDGE[j] for j in keep], [r[j] for j in keep], z[keep])
    np.testing.assert_allclose(rep.pose.mean[:2], want, atol=1e-9)
    # the paper's "overestimates because they do not utilize all the available information"
    r_eq = effective_resistance(BRIDGE, r)
    assert best / r_eq == pytest.approx(ratio, abs=1e-5)
    joint = joint_estimate(net, "s", "t")
    assert rep.pose.cov[0, 0] / joint.cov[0, 0] == pytest.approx(ratio, abs=1e-5)


def test_balanced_bridge_deletion_is_exact():
    net = linear_bridge(R_BALANCED)
    rep = reduce_network_report(net, "s", "t")
    assert rep.deleted == (2,)  # the bridge link itself
    joint = joint_estimate(net, "s", "t")
    np.testing.assert_allclose(rep.pose.cov[:2, :2], joint.cov[:2, :2], rtol=1e-6)
    assert rep.pose.cov[0, 0] == pytest.approx(effective_resistance(BRIDGE, R_BALANCED), rel=1e-6)


def test_joint_estimate_equals_series_parallel_on_reducible_networks():
    rng = np.random.default_rng(7)

    def rel(seed):
        a = np.random.default_rng(seed).normal(size=(3, 3)) * 0.02
        return UncertainPose2(rng.normal(size=3), a @ a.T + np.eye(3) * 1e-5)

    chain = [("w", "l1", rel(1)), ("l1", "l2", rel(2)), ("l2", "l3", rel(3))]
    got, want = joint_estimate(chain, "w", "l3"), reduce_network(chain, "w", "l3")
    np.testing.assert_allclose(got.mean, want.mean, atol=1e-12)  # a chain: the same to round-off
    np.testing.assert_allclose(got.cov, want.cov, rtol=1e-9, atol=1e-15)
    # a loop closed by a consistent sensor: equal means, covariances equal to first order
    g = reduce_network(chain, "w", "l3")
    sensor = UncertainPose2(g.reverse().mean, np.diag([1e-4, 1e-4, 1e-4]))
    net = chain + [("l3", "w", sensor)]
    got, want = joint_estimate(net, "w", "l3"), reduce_network(net, "w", "l3")
    np.testing.assert_allclose(got.mean, want.mean, atol=1e-10)
    np.testing.assert_allclose(got.cov, want.cov, rtol=1e-6, atol=1e-12)


def test_deletion_search_equals_brute_force_over_every_deletion_set():
    rng = np.random.default_rng(11)
    frames = {"s": (0, 0, 0), "a": (1, 0.8, 0.6), "b": (1.2, -0.7, -0.4), "c": (2.0, 1.0, 0.1),
              "d": (2.2, -0.5, 0.9), "t": (3.1, 0.2, -0.3)}
    pairs = [("s", "a"), ("s", "b"), ("a", "b"), ("a", "c"), ("b", "d"), ("c", "d"), ("c", "t"), ("d", "t"), ("a", "d")]
    net = []
    for i, j in pairs:
        m = rng.normal(size=(3, 3)) * 0.03
        z = se2.compound_mean(se2.reverse_mean(np.array(frames[i])), np.array(frames[j]))
        net.append((i, j, UncertainPose2(z + rng.normal(scale=0.01, size=3), m @ m.T + np.eye(3) * 1e-5)))
    with pytest.raises(UncertaintyError, match="Wheatstone"):
        reduce_network(net, "s", "t", irreducible="raise")
    rep = reduce_network_report(net, "s", "t")
    best = None
    for n_del in range(1, len(net)):
        for dropped in itertools.combinations(range(len(net)), n_del):
            rest = [e for k, e in enumerate(net) if k not in dropped]
            try:
                p = reduce_network(rest, "s", "t", irreducible="raise")
            except UncertaintyError:
                continue
            key = np.linalg.slogdet(p.cov)[1]
            if best is None or key < best[0]:
                best = (key, p, dropped)
    assert rep.status is ReductionStatus.DELETED
    assert np.linalg.slogdet(rep.pose.cov)[1] == pytest.approx(best[0], abs=1e-9)
    np.testing.assert_allclose(rep.pose.mean, best[1].mean, atol=1e-12)
    assert set(rep.deleted) == set(best[2])


def test_bridge_monte_carlo_each_estimate_is_as_uncertain_as_it_says():
    """Nonlinear relations: sample the measurements, re-estimate, and compare the scatter with the
    covariance each estimate states (m² ~ χ²(3): mean 3)."""
    truth = {"s": np.zeros(3), "a": np.array([1.0, 0.8, 0.6]), "b": np.array([1.2, -0.7, -0.4]),
             "t": np.array([2.3, 0.1, 0.3])}
    base = np.diag([4e-4, 4e-4, 3e-4])
    scale = [1.0, 2.0, 5.0, 3.0, 4.0]
    z_true = [se2.compound_mean(se2.reverse_mean(truth[i]), truth[j]) for i, j in BRIDGE]
    rng = np.random.default_rng(2026)
    n = 1000
    m2 = {"joint": [], "deleted": []}
    err = {"joint": [], "deleted": []}
    for _ in range(n):
        net = [(i, j, UncertainPose2(z + rng.multivariate_normal(np.zeros(3), base * sc), base * sc))
               for (i, j), z, sc in zip(BRIDGE, z_true, scale)]
        for name, est in (("joint", joint_estimate(net, "s", "t")), ("deleted", reduce_network(net, "s", "t"))):
            e = est.mean - truth["t"]
            e[2] = se2.wrap_angle(e[2])
            err[name].append(e)
            m2[name].append(e @ np.linalg.solve(est.cov, e))
    se_mean = math.sqrt(6.0 / n)  # χ²(3) has variance 6
    for name in m2:
        assert abs(np.mean(m2[name]) - 3.0) < 5 * se_mean, (name, np.mean(m2[name]))
    det = {k: np.linalg.det(np.cov(np.array(v).T)) for k, v in err.items()}
    assert det["joint"] < det["deleted"]


def test_reduce_network_arguments_and_disconnected_networks():
    e = UncertainPose2([1, 0, 0], np.eye(3) * 1e-3)
    with pytest.raises(UncertaintyError, match="irreducible must be one of"):
        reduce_network([("s", "t", e)], "s", "t", irreducible="ignore")
    with pytest.raises(UncertaintyError, match="no chain"):
        reduce_network([("s", "a", e), ("t", "b", e)], "s", "t")
    with pytest.raises(UncertaintyError, match="no chain"):
        joint_estimate([("s", "a", e), ("t", "b", e)], "s", "t")
    single = reduce_network_report([("s", "t", e)], "s", "t")
    assert single.status is ReductionStatus.SERIES_PARALLEL and single.deleted == () and single.alternatives == 0
    singular = UncertainPose2([1, 0, 0], np.diag([1e-3, 1e-3, 0.0]))
    with pytest.raises(UncertaintyError, match=r"network\[0\].*singular"):
        joint_estimate([("s", "t", singular), ("s", "t", e)], "s", "t")


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.2, 20.0), min_size=5, max_size=5))
def test_property_deletion_never_claims_less_than_the_joint_on_linear_bridges(scale):
    """Any bridge of linear relations: the joint variance is the effective resistance, and the
    paper's deletion is the best single deletion, never below it (it discards information)."""
    r = [1e-4 * k for k in scale]
    net = linear_bridge(r)
    joint = joint_estimate(net, "s", "t")
    rep = reduce_network_report(net, "s", "t")
    r_eq = effective_resistance(BRIDGE, r)
    best = min(effective_resistance(BRIDGE[:k] + BRIDGE[k + 1:], r[:k] + r[k + 1:]) for k in range(5))
    assert joint.cov[0, 0] == pytest.approx(r_eq, rel=1e-6)
    assert rep.pose.cov[0, 0] == pytest.approx(best, rel=1e-6)
    assert rep.pose.cov[0, 0] >= joint.cov[0, 0] * (1 - 1e-6)
    assert np.all(np.linalg.eigvalsh(rep.pose.cov[:2, :2] - joint.cov[:2, :2]) >= -1e-6 * r_eq)


@pytest.mark.parametrize("irreducible", ["joint", "delete"])
def test_a_network_given_as_a_generator_reduces_as_the_list(irreducible):
    """The Iterable the signature allows: irreducible="joint" read it a second time (empty: "source frame
    's' is not in the network")."""
    net = linear_bridge(R_UNBALANCED)
    from_list = reduce_network(net, "s", "t", irreducible=irreducible)
    from_gen = reduce_network((e for e in net), "s", "t", irreducible=irreducible)
    np.testing.assert_array_equal(from_gen.mean, from_list.mean)
    np.testing.assert_array_equal(from_gen.cov, from_list.cov)


@pytest.mark.parametrize("k", [4, 6])
def test_relations_off_every_chain_from_source_to_target_are_left_out(k):
    """A complete graph of k frames hanging off the source (a cut vertex) carries no information about
    source→target: the answer is the one relation s-t.  It could not be reduced: with k = 4 a relation
    of it was "deleted", with k = 6 the deletion search gave up after seconds."""
    rng = np.random.default_rng(k)
    direct = UncertainPose2([0.5, 0.1, 0.2], np.diag([1e-4, 2e-4, 1e-5]))
    net = [("s", "t", direct)]
    frames = ["s"] + [f"h{i}" for i in range(k - 1)]
    for a, b in itertools.combinations(frames, 2):
        net.append((a, b, UncertainPose2(rng.normal(size=3) * 0.3, np.diag(rng.uniform(1e-5, 1e-3, 3)))))
    rep = reduce_network_report(net, "s", "t", irreducible="raise")
    assert rep.status is ReductionStatus.SERIES_PARALLEL and rep.deleted == ()
    np.testing.assert_array_equal(rep.pose.mean, direct.mean)
    np.testing.assert_array_equal(rep.pose.cov, direct.cov)
    np.testing.assert_allclose(joint_estimate(net, "s", "t").cov, direct.cov, rtol=1e-6)


def _loop_network(rng, n=6, sd_xy=1e-6, sd_theta=1.0):
    """Six frames 50 m apart, three loops; positions to 1 µm, angles to 1 rad (far from linear)."""
    truth = {i: np.r_[rng.normal(size=2) * 50, rng.uniform(-3, 3)] for i in range(n)}
    truth[0] = np.zeros(3)
    c = np.diag([sd_xy**2, sd_xy**2, sd_theta**2])
    net = []
    for a, b in [(i, i + 1) for i in range(n - 1)] + [(0, 3), (2, 5), (1, 4)]:
        z = se2.compound_mean(se2.reverse_mean(truth[a]), truth[b])
        net.append((a, b, UncertainPose2(rng.multivariate_normal(z, c), c)))
    return net


def test_joint_estimate_converges_where_full_gauss_newton_steps_overshoot():
    """Networks whose full Gauss-Newton steps did not lower the residuals: without the backtracking these
    two never converged (steps stuck at 1e-10 m, 2000 iterations).  (nets[5] still takes more than 100
    iterations, its steps 3e4 m: an error, never an estimate.)"""
    rng = np.random.default_rng(9)
    nets = [_loop_network(rng) for _ in range(16)]
    for k in (2, 15):
        est = joint_estimate(nets[k], 0, 5)
        assert np.all(np.isfinite(est.cov)) and np.linalg.eigvalsh(est.cov)[0] > 0.0
