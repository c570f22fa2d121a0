"""Proven-Never pairs, tried a million times with coal as the truth (issue: a certified collision matrix).

For three robots -- the built-in PUMA 560, example-robot-data's UR5 and Panda -- every pair that
``collision_matrix`` proves *Never* is checked by Pinocchio + coal, not by the analytic kernels
the proof used:

* at 10^6 random configurations within the joint limits, and
* at configurations sampled densely over the joints between the two links (a grid over those
  joints, the rest at random): 20,000 per pair.

No contact may be found: one would contradict a proof.  The same harness is shown able to find
contacts: every pair the search *witnessed* colliding collides, per coal, at its witness.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import armguard
from armguard.srdfgen import collision_matrix, pair_setup

pin = pytest.importorskip("pinocchio")

ROBOTS = ["puma560", "ur5", "panda"]
N_RANDOM = 1_000_000
N_DENSE_PER_PAIR = 20_000
BLOCK = 50_000
THREADS = 2


def _pair_geometry(model, pairs) -> "pin.GeometryModel":
    """A copy of the Model's GeometryModel that checks exactly the GeometryObject pairs between
    the links of each ``(link1, link2)`` in ``pairs`` (URDF link names)."""
    gm = model.collision_model.copy()
    gm.removeAllCollisionPairs()
    frames = model.pin_model.frames
    by_link: dict = {}
    for i, go in enumerate(gm.geometryObjects):
        by_link.setdefault(frames[go.parentFrame].name, []).append(i)
    n = 0
    for a, b in pairs:
        assert a in by_link and b in by_link, f"no GeometryObject on {a!r} or {b!r}"
        for i in by_link[a]:
            for j in by_link[b]:
                gm.addCollisionPair(pin.CollisionPair(min(i, j), max(i, j)))
                n += 1
    assert n > 0
    return gm


def _collides(model, gm, Q_pin: np.ndarray) -> np.ndarray:
    """``(M,) bool``: any of ``gm``'s pairs in contact at each row of ``Q_pin`` (coal, through Pinocchio)."""
    pool = pin.GeometryPool(model.pin_model, gm, THREADS)
    out = np.empty(len(Q_pin), bool)
    for s in range(0, len(Q_pin), BLOCK):
        q = np.asfortranarray(Q_pin[s:s + BLOCK].T)
        out[s:s + BLOCK] = pin.computeCollisionsInParallel(THREADS, pool, q, False, False)
    return out


def _grid(setup, joints, n: int, rng) -> np.ndarray:
    """``(n, nq_flat)`` scene configurations: ``joints`` on a regular grid spanning their limits
    (limits included), every other joint uniform at random."""
    lo, hi = setup.lower, setup.upper
    k = max(2, int(math.floor(n ** (1.0 / len(joints)))))
    axes = [np.linspace(lo[j], hi[j], k) for j in joints]
    G = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(joints))
    Q = lo + (hi - lo) * rng.random((len(G), len(lo)))
    Q[:, list(joints)] = G
    return Q


@pytest.fixture(scope="module", params=ROBOTS)
def proven(request):
    model = armguard.load_model(request.param, srdf=False)
    cm = collision_matrix(model, workers=2)
    setup = pair_setup(model)
    assert [(p.link1, p.link2) for p in setup.pairs] == [(e.link1, e.link2) for e in cm.entries]
    return model, cm, setup


def test_every_proven_never_pair_is_free_of_contact_at_a_million_configurations(proven):
    model, cm, setup = proven
    never = [(p, e) for p, e in zip(setup.pairs, cm.entries) if e.reason == "Never"]
    assert never, f"{model.name}: no pair proven Never: nothing to test"
    gm = _pair_geometry(model, [(e.link1, e.link2) for _, e in never])
    rng = np.random.default_rng(20261202)
    lo, hi = setup.lower, setup.upper
    assert np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
    hits = 0
    for s in range(0, N_RANDOM, 200_000):
        Q = lo + (hi - lo) * rng.random((min(200_000, N_RANDOM - s), len(lo)))
        bad = _collides(model, gm, model.pin_q(Q))
        hits += int(bad.sum())
        assert not bad.any(), f"{model.name}: a proven-Never pair collides at scene q = {Q[np.argmax(bad)].tolist()}"
    assert hits == 0


def test_every_proven_never_pair_is_free_of_contact_over_its_own_joints(proven):
    model, cm, setup = proven
    rng = np.random.default_rng(7)
    checked = 0
    for p, e in zip(setup.pairs, cm.entries):
        if e.reason != "Never" or not p.joints:
            continue
        gm = _pair_geometry(model, [(e.link1, e.link2)])
        Q = _grid(setup, p.joints, N_DENSE_PER_PAIR, rng)
        bad = _collides(model, gm, model.pin_q(Q))
        assert not bad.any(), f"{model.name}: {e.link1}-{e.link2} (proven Never) collides at scene q = {Q[np.argmax(bad)].tolist()}"
        checked += len(Q)
    assert checked > 0


def test_the_coal_harness_finds_the_witnessed_contacts(proven):
    """The harness above can fail: every pair witnessed in contact (by more than 1 mm) collides per coal there."""
    model, cm, setup = proven
    witnessed = [e for e in cm.entries if e.status == "witnessed" and e.distance < -1e-3]
    assert witnessed, f"{model.name}: no witnessed contact to show the harness on"
    for e in witnessed:
        gm = _pair_geometry(model, [(e.link1, e.link2)])
        q = np.asarray(e.q, dtype=np.float64)[None]
        assert _collides(model, gm, q)[0], f"{model.name}: {e.link1}-{e.link2} at its witness ({e.distance:.4f} m) not in contact per coal"
