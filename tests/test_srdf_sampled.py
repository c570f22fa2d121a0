"""MoveIt's sampled matrix (armguard.srdfgen._sampled) against the rule as stated.

The fast path evaluates the pairs not yet witnessed, 250 configurations at a time, and drops a pair
at its first configuration within the margin; the reference computes every pair's distance at every
configuration.  On the same seeded configurations both must give every pair the same entry (reason,
witness index, configuration and distance).
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
from armguard.srdfgen._sampled import sampled, sampled_reference


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
    sampled(ev, setup, todo, fast, margin, samples, seed, lambda: None)
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


def test_the_sampled_rule_decides_two_links_fixed_to_each_other(tmp_path):
    """r2d2's and minitaur's fixed link pairs (no joint moves them) once failed ``--method sampled`` with a
    forbidden-values map's error (a Checker per pair had no pair a configuration moves); the certified method
    proves them.  Apart here, so Never; the same links placed in contact are witnessed."""
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
    model = armguard.load_model(urdf, srdf=False)
    cm = collision_matrix(model, method="sampled", samples=50)
    e = next(e for e in cm.entries if {e.link1, e.link2} == {"left", "right"})
    assert e.reason == "Never", e
    cm = collision_matrix(model, method="sampled", samples=50, margin=0.95)  # 0.9 m apart: within this margin
    e = next(e for e in cm.entries if {e.link1, e.link2} == {"left", "right"})
    assert e.reason is None and e.status == "witnessed" and e.distance == pytest.approx(0.9), e


def test_a_distance_that_is_not_finite_gives_no_verdict_and_names_its_pair(monkeypatch):
    model, setup, ev, todo = robot("puma560")
    real = PairEvaluator.all
    bad = todo[-1]

    def nan_in_one_pair(self, Q, chunk=2000, pairs=None):
        D = real(self, Q, chunk, pairs)
        ks = list(range(len(self.rows))) if pairs is None else [int(k) for k in pairs]
        if len(Q) > 1 and bad in ks:  # past the Always rule's draw: in the Never blocks
            D[len(Q) // 2, ks.index(bad)] = np.nan
        return D

    monkeypatch.setattr(PairEvaluator, "all", nan_in_one_pair)
    p = setup.pairs[bad]
    for run in (sampled, sampled_reference):
        with pytest.raises(armguard.VerificationError, match=f"{p.link1} - {p.link2} is not finite: no verdict"):
            run(ev, setup, [bad], [None] * len(setup.pairs), 0.0, 2000, 0, lambda: None)
