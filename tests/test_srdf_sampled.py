"""MoveIt's sampled matrix on verdicts (armguard.srdfgen._sampled) against the rule as stated.

The fast path asks each undecided pair a yes/no (``Checker.collides`` of that pair alone), stops a
pair at its first confirmed hit and drops it from the batches; the reference computes every pair's
distance at every configuration.  On the same seeded configurations both must give every pair the
same entry (reason, witness index, configuration and distance).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armguard
from armguard.srdfgen import pair_setup
from armguard.srdfgen._matrix import PairEvaluator
from armguard.srdfgen._sampled import PairVerdicts, random_configurations, sampled, sampled_reference


def _robot(name):
    try:
        model = armguard.load_model(name, srdf=False)
    except armguard.SceneError as exc:  # a public robot whose package is not installed
        pytest.skip(str(exc))
    setup = pair_setup(model)
    ev = PairEvaluator(model, setup)
    d_home = ev.all(setup.home[None, :])[0]
    todo = [k for k, p in enumerate(setup.pairs) if not p.adjacent and d_home[k] > 0.0]
    return model, setup, ev, todo


_ROBOTS: dict = {}


def robot(name):
    if name not in _ROBOTS:
        _ROBOTS[name] = _robot(name)
    return _ROBOTS[name]


def _key(e):
    """An entry as a comparable tuple (NaN distances equal)."""
    d = e.distance
    return dataclasses.astuple(dataclasses.replace(e, distance=0.0)) + ("nan" if np.isnan(d) else d,)


def _both(name, samples, seed, margin):
    model, setup, ev, todo = robot(name)
    fast, ref = [None] * len(setup.pairs), [None] * len(setup.pairs)
    sampled(ev, PairVerdicts(model, setup, margin=margin), setup, todo, fast, margin, samples, seed, lambda: None)
    sampled_reference(ev, setup, todo, ref, margin, samples, seed, lambda: None)
    return [fast[k] for k in todo], [ref[k] for k in todo]


@pytest.mark.parametrize("name,samples,margin", [("puma560", 6000, 0.0), ("puma560", 3000, 0.05),
                                                 ("ur5", 3000, 0.0), ("panda_collision", 2500, 0.02)])
def test_verdict_path_gives_the_reference_entries(name, samples, margin):
    fast, ref = _both(name, samples, 0, margin)
    assert [_key(e) for e in fast] == [_key(e) for e in ref]
    kinds = {e.reason or e.status for e in ref}
    assert "witnessed" in kinds and "Never" in kinds  # both outcomes are exercised
    assert any(e.evaluations > 1 for e in ref if e.status == "witnessed")  # a witness past the first sample


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), margin=st.sampled_from([0.0, 0.01, 0.1]))
def test_verdict_path_matches_the_reference_on_any_seed(seed, margin):
    fast, ref = _both("puma560", 2200, seed, margin)  # two draws (2000 + 200): a pair decided across chunks
    assert [_key(e) for e in fast] == [_key(e) for e in ref]


@pytest.mark.parametrize("name,margin", [("puma560", 0.0), ("puma560", 0.1), ("ur5", 0.0), ("ur5", 0.03)])
def test_pair_verdicts_never_say_clear_within_the_margin(name, margin):
    """No false "clear": wherever a pair's exact distance is within the margin, its verdict says so
    (a True elsewhere only costs a confirmation)."""
    model, setup, ev, todo = robot(name)
    pv = PairVerdicts(model, setup, margin=margin)
    Q = random_configurations(setup, 1500, np.random.default_rng(11))
    D = ev.all(Q, pairs=todo)
    within = 0
    for i, k in enumerate(todo):
        v = pv(k, Q)
        assert v.shape == (len(Q),) and v.dtype == bool
        assert np.all(v[D[:, i] <= margin]), (setup.pairs[k].link1, setup.pairs[k].link2)
        assert np.all(~v[D[:, i] > margin + 1e-9])  # and no hit far outside it
        within += int(np.sum(D[:, i] <= margin))
    assert within > 0


def test_the_sampled_rule_decides_two_links_fixed_to_each_other(tmp_path):
    """r2d2's and minitaur's fixed link pairs (no joint moves them) failed ``--method sampled`` with a forbidden-
    values map's error (the per-pair Checker had no pair a configuration moves); the certified method proves them.
    One distance decides such a pair: apart here, so Never."""
    import armguard
    from armguard.srdfgen import collision_matrix

    urdf = tmp_path / "fx.urdf"
    urdf.write_text("""<robot name="fx">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="left"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="right"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.3 0 0"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="fl" type="fixed"><parent link="base"/><child link="left"/><origin xyz="0 0.5 0"/></joint>
  <joint name="fr" type="fixed"><parent link="base"/><child link="right"/><origin xyz="0 -0.5 0"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>""")
    cm = collision_matrix(armguard.load_model(urdf, srdf=False), method="sampled", samples=50)
    e = next(e for e in cm.entries if {e.link1, e.link2} == {"left", "right"})
    assert e.reason == "Never", e
