"""Verification and the guard on several threads, and while the scene is edited: every report is of
one state of the scene, never a mix, and each verification counts its own evaluations.

The failures these guard against, as they were (``Verifier`` and ``Guard`` before their state was
published whole): one Verifier on 3 threads, 30 verifications each, gave 89 of 90 reports another
verification's ``samples_evaluated`` (one counter on the shared ClearanceModel, reset by each
verification; the certified budget read it too); with another thread adding and removing a body,
29 of 90 verifications raised ``ValueError: shape mismatch`` (the Detector had rebuilt for the new
pairs, the ClearanceModel still mapped the old ones); a ClearanceModel on the reference source kept
answering after ``add_body``, without the new body.
"""

from __future__ import annotations

import functools
import math
import threading

import numpy as np
import pytest

import armguard
from armguard.geometry import Sphere
from armguard.testing import run_in_threads
from armguard.verify import ClearanceModel, Guard, GuardVerdict, Verifier, VerificationStatus


@pytest.fixture
def ranger():
    return armguard.load_model("ranger")  # a fresh Model per test: the tests edit its scene


def _post(scene, trajectory) -> Sphere:
    """A sphere on the moving robot's last link at the middle of ``trajectory``: there, it collides."""
    _, Q = trajectory.sample(frequency=10)
    q = scene.default_q()
    q[trajectory.robot_name] = Q[len(Q) // 2]
    last = [it for it in scene.shapes_at(scene.flat_q(q)) if it.owner.startswith(trajectory.robot_name + "/")][-1]
    return Sphere(last.shape.support(np.array([0.0, 0.0, 1.0])), 0.08)


def _key(rep) -> tuple:
    c = rep.first_collision
    return (rep.status, rep.min_clearance, rep.min_clearance_lower_bound, rep.details.samples_evaluated,
            None if c is None else (c.a, c.b, c.time))


def _toggle_while(scene, name, shape, readers, n_toggles: int) -> None:
    """Add and remove body ``name`` ``n_toggles`` times on a thread of its own while ``readers`` (each a
    function of ``done`` and ``stop``) run on theirs; after each edit the editor waits until every
    reader has finished one call since (``done()``), so that edits land inside the other readers'
    calls while each reader still gets calls through.  A reader that returns counts as done from then
    on.  The GIL changes hands every 10 µs (:func:`armguard.testing.run_in_threads`)."""
    cond = threading.Condition()
    since = [0] * len(readers)
    stop = threading.Event()

    def done(k, n=1):
        with cond:
            since[k] += n
            cond.notify_all()

    def editor():
        try:
            for t in range(n_toggles):
                with cond:
                    assert cond.wait_for(lambda: min(since) >= 1, timeout=120), "a reader made no progress"
                    since[:] = [s if s == math.inf else 0 for s in since]
                if t % 2 == 0:
                    scene.add_body(name, shape)
                else:
                    scene.remove_body(name)
        finally:
            stop.set()

    def run(k, r):
        try:
            r(lambda: done(k), stop)
        finally:
            done(k, math.inf)

    run_in_threads([editor] + [functools.partial(run, k, r) for k, r in enumerate(readers)])


@pytest.mark.parametrize("source", ["detector", "reference"])
def test_a_clearance_model_refuses_to_answer_for_an_edited_scene(ranger, source):
    sc = ranger.scene
    cm = ClearanceModel(sc, source=source)
    q = sc.flat_q(sc.default_q())
    d0, _, _ = cm.distances(q)
    assert len(d0) == len(cm.owner_a) and not cm.is_stale()
    sc.add_body("post", Sphere([0.5, 0.0, 0.5], 0.3))
    assert cm.is_stale()
    with pytest.raises(armguard.StaleModelError, match=r"changed \(revision \d+ -> \d+\) since this ClearanceModel"):
        cm.distances(q)
    with pytest.raises(armguard.StaleModelError):
        cm.reference_distances(q)
    fresh = ClearanceModel(sc, source=source)  # what the message says to do
    d1, _, _ = fresh.distances(q)
    assert len(d1) > len(d0) and any("post" in (a, b) for a, b in zip(fresh.owner_a, fresh.owner_b))


def test_one_verifier_on_three_threads_gives_each_its_own_report(ranger):
    sc = ranger.scene
    tr = sc.trajectories["left_arm_sweep"]
    v = Verifier(sc)
    ref = _key(v.verify(tr))
    assert ref[0] is VerificationStatus.SAFE and ref[3] > 10
    out, errors = [], []

    def worker():
        try:
            for _ in range(15):
                out.append(_key(v.verify(tr)))
        except Exception as exc:  # noqa: BLE001 - reported by the assertion below
            errors.append(repr(exc))

    run_in_threads([worker] * 3)
    assert not errors
    assert len(out) == 45 and all(k == ref for k in out)


def test_verifications_while_another_thread_edits_the_scene_are_of_one_state(ranger):
    sc = ranger.scene
    tr = sc.trajectories["left_arm_sweep"]
    post = _post(sc, tr)
    without = _key(Verifier(sc).verify(tr))
    sc.add_body("post", post)
    with_post = _key(Verifier(sc).verify(tr))
    sc.remove_body("post")
    assert without[0] is VerificationStatus.SAFE and with_post[0] is VerificationStatus.COLLISION
    assert with_post[4][1] == "post"
    v = Verifier(sc)
    seen, errors = [], []

    def reader(done, stop):
        try:
            while not stop.is_set():
                seen.append(_key(v.verify(tr)))
                done()
        except Exception as exc:  # noqa: BLE001 - reported by the assertion below
            errors.append(repr(exc))

    _toggle_while(sc, "post", post, [reader, reader], n_toggles=8)
    assert not errors
    assert set(seen) <= {without, with_post}
    assert {without, with_post} <= set(seen)  # each reader verified on both scenes


def test_guard_steps_while_another_thread_edits_the_scene_are_of_one_state(ranger):
    sc = ranger.scene
    tr = sc.trajectories["left_arm_sweep"]
    post = _post(sc, tr)
    _, Q = tr.sample(frequency=10)
    q = Q[len(Q) // 2]
    qdot = np.full(len(q), 0.05)

    def key(dec):
        return dec.verdict, dec.pair, dec.clearance, dec.predicted_clearance, dec.evaluations

    g = Guard(sc, robot=tr.robot_name, stopping_distance=0.02)
    clear = key(g.step(q, qdot=qdot))
    sc.add_body("post", post)
    blocked = key(g.step(q, qdot=qdot))  # the same Guard: it follows the edit
    sc.remove_body("post")
    assert clear[0] is GuardVerdict.OK and blocked[0] is GuardVerdict.STOP and "post" in blocked[1]
    assert key(g.step(q, qdot=qdot)) == clear
    seen, errors = [], []

    def reader(done, stop):
        try:
            while not stop.is_set():
                seen.append(key(g.step(q, qdot=qdot)))
                done()
        except Exception as exc:  # noqa: BLE001 - reported by the assertion below
            errors.append(repr(exc))

    _toggle_while(sc, "post", post, [reader, reader, reader], n_toggles=10)
    assert not errors
    assert set(seen) <= {clear, blocked}
    assert {clear, blocked} <= set(seen)


def test_a_scene_that_never_holds_still_gets_no_verdict(ranger, monkeypatch):
    """Where every attempt finds the scene changed, verify raises and the guard answers STOP: never
    SAFE or OK from a check that did not finish on one scene."""
    sc = ranger.scene
    tr = sc.trajectories["left_arm_sweep"]
    v = Verifier(sc)
    g = Guard(sc, robot=tr.robot_name)
    q = sc.default_q()[tr.robot_name]
    assert g.step(q, qdot=np.zeros(len(q))).ok and v.verify(tr).safe
    monkeypatch.setattr(ClearanceModel, "is_stale", lambda self: True)
    with pytest.raises(armguard.StaleModelError, match="changed during each of 5 attempts to verify"):
        v.verify(tr)
    dec = g.step(q, qdot=np.zeros(len(q)))
    assert dec.verdict is GuardVerdict.STOP and "changed during each of 3 attempts" in dec.reason
