"""Edits on a Model: ``Model.edited`` and the ``with_*`` methods return a new Model and leave the
one they were called on, its scene and its Checkers as they were.

Held to the scene path they stand for (the same edit on the scene, then ``model_of``): the same
pairs and coal's distances row for row; the analytic backend's verdicts equal coal's.
"""

from __future__ import annotations

import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import armguard
from armguard import SceneError
from armguard.geometry import Box, Sphere
from armguard.model import load_model, model_of


def _load(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_model(name)


def _crate(x=0.5):
    return [Box([x, 0.2, 0.3], [0.05, 0.05, 0.05], np.eye(3))]


def _same_answers(a, b, n=8, seed=3):
    """``a`` and ``b`` list the same pairs and coal gives the same distances (1e-9 m); the analytic
    backend's verdicts on ``a`` are coal's."""
    assert list(a.pairs.a) == list(b.pairs.a) and list(a.pairs.b) == list(b.pairs.b)
    assert list(a.pairs.category) == list(b.pairs.category)
    ca, cb, an = armguard.checker(a, "coal"), armguard.checker(b, "coal"), armguard.checker(a, "analytic")
    for q in a.random_q(n, seed):
        da, db = ca.pair_distances(q).distance, cb.pair_distances(q).distance
        np.testing.assert_allclose(da, db, rtol=0, atol=1e-9)
        x = an.pair_distances(q).distance
        clear = (np.abs(x) > 1e-6) & (np.abs(da) > 1e-6)
        np.testing.assert_array_equal((x <= 0)[clear], (da <= 0)[clear])


@pytest.mark.parametrize("name", ["panda", "ranger"])
def test_each_edit_equals_the_scene_path_and_leaves_the_model_alone(name):
    model = _load(name)
    robot = next(iter(model.robots))
    link = model.robots[robot].link_names[-1]
    before = list(model.pairs.a), dict(model.bodies), dict(model.payloads)
    coal = armguard.checker(model, "coal")
    q0 = model.random_q(1, 1)[0]
    d0 = coal.pair_distances(q0).distance
    X = np.eye(4)
    X[:3, 3] = [0.1, 0.0, 0.0]
    edits = {
        "with_body": (lambda m: m.with_body("crate", _crate()), lambda s: s.add_body("crate", _crate())),
        "with_payload": (lambda m: m.with_payload("held", robot, link, [Sphere([0, 0, 0.05], 0.03)]),
                         lambda s: s.attach_payload("held", robot, link, [Sphere([0, 0, 0.05], 0.03)])),
        "with_robot_base": (lambda m: m.with_robot_base(robot, X @ m.robots[robot].X_WB),
                            lambda s: s.set_robot_base(robot, X @ s.robots[robot].X_WB)),
        "with_workspace": (lambda m: m.with_workspace([-2, -2, -1], [2, 2, 2]), lambda s: s.set_workspace([-2, -2, -1], [2, 2, 2])),
    }
    for what, (on_model, on_scene) in edits.items():
        new = on_model(model)
        assert new is not model and new.scene is not model.scene, what
        reference = _load(name)
        on_scene(reference.scene)
        _same_answers(new, model_of(reference.scene))
    assert (list(model.pairs.a), dict(model.bodies), dict(model.payloads)) == before
    assert model.scene.workspace is None or name == "ranger"
    np.testing.assert_allclose(coal.pair_distances(q0).distance, d0, rtol=0, atol=1e-9)


def test_edits_chain_and_a_robot_can_be_added():
    model = _load("panda")
    puma = next(iter(_load("puma560").robots.values())).with_name("puma_2")
    X = np.eye(4)
    X[:3, 3] = [1.0, 0.0, 0.0]
    new = (model.with_body("crate", _crate())
                .with_robot(puma.with_base(X))
                .with_payload("tool", "puma_2", puma.link_names[-1], [Sphere([0, 0, 0.05], 0.03)])
                .without_body("crate"))
    assert list(new.robots) == ["panda", "puma_2"] and "crate" not in new.bodies and "tool" in new.payloads
    assert new.nq == model.nq + len(puma.joint_names) and new.srdf is model.srdf
    reference = _load("panda").scene
    reference.add_robot(puma.with_base(X))
    reference.attach_payload("tool", "puma_2", puma.link_names[-1], [Sphere([0, 0, 0.05], 0.03)])
    _same_answers(new, model_of(reference))


def test_grasp_then_release_puts_the_body_back_where_it_was():
    model = _load("panda").with_body("crate", _crate(0.4))
    robot = "panda"
    link = model.robots[robot].link_names[-1]
    q_grasp = model.neutral()
    held = model.with_grasp("crate", robot, link, q_grasp)
    assert "crate" in held.payloads and "crate" not in held.bodies
    put_back = held.with_payload_released("crate", q_grasp)
    assert "crate" in put_back.bodies
    (b0,), (b1,) = model.bodies["crate"].shapes, put_back.bodies["crate"].shapes
    np.testing.assert_allclose(b1.center, b0.center, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b1.rotation, b0.rotation, rtol=0, atol=1e-12)


def test_an_edit_of_a_model_the_scene_moved_on_from_starts_from_that_model():
    """The scene was edited after this Model was made (a body ``x`` added: another Model derived);
    an edit of this Model starts from its own bodies, not the scene's."""
    model = _load("panda")
    model.scene.add_body("x", _crate(0.6))
    moved_on = model_of(model.scene)
    assert "x" in moved_on.bodies and "x" not in model.bodies
    new = model.with_body("y", _crate(-0.6))
    assert "y" in new.bodies and "x" not in new.bodies
    assert "x" not in new.pairs.owner_b and "y" in new.pairs.owner_b


def test_a_refused_edit_raises_and_changes_nothing():
    model = _load("panda").with_body("crate", _crate())
    pairs = list(model.pairs.a)
    with pytest.raises(SceneError, match="already used"):
        model.with_body("crate", _crate(0.7))
    with pytest.raises(SceneError, match="unknown body"):
        model.without_body("nope")
    assert list(model.pairs.a) == pairs and list(model.bodies) == ["crate"]


def test_threads_editing_one_model_each_get_their_own():
    model = _load("panda")
    coal = armguard.checker(model, "coal")
    q = model.random_q(1, 5)[0]
    d = coal.pair_distances(q).distance

    def edit(i):
        return model.with_body(f"b{i}", _crate(0.3 + 0.05 * i))

    with ThreadPoolExecutor(4) as ex:
        got = list(ex.map(edit, range(8)))
    for i, m in enumerate(got):
        assert list(m.bodies) == [f"b{i}"]
    assert not model.bodies
    np.testing.assert_allclose(coal.pair_distances(q).distance, d, rtol=0, atol=1e-9)


def test_a_models_pairs_are_fixed_when_it_is_made():
    """Pair filters and the workspace box set on the scene afterwards leave the Model's pairs, and
    every Checker built on it, as they were (before, the analytic Checker followed the scene to 56
    rows on puma560 while coal's stayed at 62); the scene's Model is another one, sharing the
    Pinocchio models, and a Detector on the scene follows the scene."""
    from armguard.model import model_of

    model = _load("puma560")
    scene = model.scene
    ana, coal = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    q = model.neutral()
    before = [tuple(map(tuple, model.pairs.names))]
    body = next(iter(scene.bodies))
    scene.disable_pair("puma560", body)
    scene.set_workspace([-2.0, -2.0, -1.0], [2.0, 2.0, 2.0])
    assert [tuple(map(tuple, model.pairs.names))] == before and model.workspace is None
    a, c = ana.pair_distances(q), coal.pair_distances(q)
    assert [tuple(map(tuple, a.pairs))] == before and [tuple(map(tuple, c.pairs))] == before
    now = model_of(scene)
    assert now is not model and now.is_model_of(scene) and not model.is_model_of(scene)
    assert now.collision_model is model.collision_model and now.pin_model is model.pin_model
    assert body not in now.pairs.owner_b and "workspace" in now.pairs.category and now.workspace is scene.workspace
    assert not now.files and model.files  # its pairs are not the files': no map or reference for them accepts it
    det = armguard.Detector(scene, threshold=0.05)
    rows = det.pair_distances(scene.flat_q(scene.default_q()))
    assert len(rows.distance) == len(now.pairs)
    n_ana, n_coal = armguard.checker(now, "analytic").pair_distances(q), armguard.checker(now, "coal").pair_distances(q)
    np.testing.assert_array_equal(n_ana.pairs, n_coal.pairs)
    np.testing.assert_allclose(n_ana.distance, n_coal.distance, rtol=0, atol=1e-6)


def test_a_model_whose_scene_gained_a_robot_answers_as_before():
    """The scene gained a robot (``add_robot``: more joints): the Model it was made as keeps its
    joints, its neutral pose and its Checkers, without recompiling (the analytic Checker's plan is
    the one it made)."""
    model = _load("panda")
    ana, coal = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    q = model.neutral()
    d_ana, d_coal = ana.pair_distances(q).distance, coal.pair_distances(q).distance
    plan = ana._plan()
    puma = next(iter(_load("puma560").robots.values())).with_name("puma_2")
    X = np.eye(4)
    X[:3, 3] = [1.0, 0.0, 0.0]
    model.scene.add_robot(puma.with_base(X))
    model.scene.disable_pair("panda", "puma_2")
    assert model.neutral().shape == (model.nq,) == q.shape and len(model.scene.joint_names) > model.nq
    np.testing.assert_array_equal(ana.pair_distances(q).distance, d_ana)
    np.testing.assert_allclose(coal.pair_distances(q).distance, d_coal, rtol=0, atol=1e-9)
    assert ana._plan() is plan
    assert model_of(model.scene).nq == model.nq + len(puma.joint_names)


def test_what_is_built_on_a_model_answers_for_that_model():
    """The scene moved on (a body added) after the Model was made: a Detector and a Verifier
    built on the Model answer for the Model (no such body), as its Checkers do; built on the scene
    they see the body.  Built on the Model *before* the edit, too: they work on a copy of the system
    the Model holds, never on ``model.scene`` (a Verifier built first once followed the edit while a
    Checker of the same Model did not)."""
    from armguard.model import scene_of
    from armguard.verify import Verifier

    model = _load("puma560")
    bound = scene_of(model)
    assert bound is not model.scene and model_of(bound) is model and scene_of(model) is bound
    q = model.neutral()
    early_det, early_ver = armguard.Detector(model, threshold=0.05), Verifier(model)
    model.scene.add_body("wall", [Box([0.0, 0.0, 0.0], [2.0, 2.0, 2.0], np.eye(3))])  # encloses the arm
    assert "wall" not in bound.bodies and scene_of(model) is bound
    qs0 = model.scene_q(q)
    assert early_det.check(qs0).status.value != "collision"
    assert early_ver.verify(_still(model, q)).status.value != "collision"
    on_model = armguard.Detector(model, threshold=0.05)
    on_scene = armguard.Detector(model.scene, threshold=0.05)
    qs = model.scene_q(q)
    assert on_model.check(qs).status.value != "collision" and on_scene.check(qs).status.value == "collision"
    on_model_coal = armguard.Detector(model, threshold=0.05, backend="coal")  # Ranger's algorithm over coal
    assert on_model_coal.check(qs).status.value == on_model.check(qs).status.value
    checker = armguard.checker(model, "analytic").pair_distances(q)
    rows = on_model.pair_distances(qs)
    np.testing.assert_allclose(np.sort(rows.distance), np.sort(checker.distance), rtol=0, atol=1e-9)
    robot = next(iter(model.robots))
    traj = next(iter(model.trajectories.values()))
    assert Verifier(model).verify(traj).safe == armguard.verify(model, traj).safe
    assert not Verifier(model.scene).verify(traj).safe
    assert robot in model.robots


def test_a_checker_of_a_model_whose_scene_was_edited_says_so():
    """``model.scene.add_body(...)``: a Verifier or Detector on that scene follows the edit, a Checker of the
    Model does not (the Model is fixed when made): said with a warning naming the way to the edited one."""
    import warnings

    import armguard
    from armguard import ArmguardWarning
    from armguard.geometry import Box
    from armguard.model import model_of

    m = armguard.load_model("ur5")
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        armguard.checker(m)  # nothing edited: no warning
    m.scene.add_body("crate", [Box(center=[0.4, 0.0, 0.3], half_extents=[0.05, 0.05, 0.05])])
    with pytest.warns(ArmguardWarning, match=r"model_of\(model.scene\)"):
        old = armguard.checker(m)
    assert len(old.pair_distances(m.random_q(1, 0)[0]).distance) == len(m.pairs)  # the Model as made
    edited = model_of(m.scene)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        new = armguard.checker(edited)
    assert len(edited.pairs) > len(m.pairs) and len(new.pair_distances(edited.random_q(1, 0)[0]).distance) == len(edited.pairs)


def test_a_detector_verifier_or_verification_of_a_model_whose_scene_was_edited_says_so():
    """A sphere added to ``model.scene`` around the tool: ``verify(model, ...)`` said SAFE, a Verifier's edge
    CLEAR and a Detector's check missed it, without a word (a checker warned).  Each answers for the Model
    as made, as documented, and now says so; on the scene they see the sphere."""
    from armguard import ArmguardWarning
    from armguard.verify import Verifier

    m = armguard.load_model("ur5")
    qs = m.scene_q(m.neutral())
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        armguard.Detector(m), Verifier(m)  # nothing edited: no warning
    tip = m.link_poses(qs)["ur5"][-1][:3, 3]
    m.scene.add_body("blob", [Sphere(tip, 0.1)])
    still = _still(m, m.neutral())
    with pytest.warns(ArmguardWarning, match=r"this verification answers for the Model as made") as w1:
        assert armguard.verify(m, still).safe
    with pytest.warns(ArmguardWarning, match=r"this Verifier answers for the Model as made") as w2:
        assert Verifier(m).check_edges(qs, qs).code[0] == 0
    with pytest.warns(ArmguardWarning, match=r"this Detector answers for the Model as made") as w3:
        assert armguard.Detector(m).check(qs).status.value != "collision"
    with pytest.warns(ArmguardWarning, match=r"this checker answers for the Model as made") as w4:
        armguard.checker(m)
    for w in (w1, w2, w3, w4):  # each points at the caller's line (it pointed into armguard, or above the caller)
        assert [x.filename for x in w if issubclass(x.category, ArmguardWarning)] == [__file__], [x.filename for x in w]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        assert not armguard.verify(m.scene, still).safe
        assert armguard.Detector(m.scene).check(qs).status.value == "collision"


def _still(model, q):
    """A two-knot trajectory of the model's robot standing at ``q`` (Pinocchio's order)."""
    from armguard.kinematics import Trajectory

    r = next(iter(model.robots))
    qs = model.scene_q(q)
    return Trajectory(r, model.robots[r].joint_names, [0.0, 1.0], [qs, qs])


def test_a_bare_link_name_is_answered_with_its_owner_name():
    """``with_pair_disabled('panda_link0', ...)``: the owners are 'robot/link'; the message names the one meant.
    ``Trajectory.joint_interpolated('panda', ...)``: a Robot is needed (its limits), said so."""
    from armguard import TrajectoryError
    from armguard.kinematics import Trajectory

    m = load_model("panda")
    with pytest.raises(SceneError, match=r"did you mean 'panda/panda_link0'\?"):
        m.with_pair_disabled("panda_link0", "panda/panda_hand")
    with pytest.raises(TrajectoryError, match=r"expected a Robot \(e.g. model.robots\['panda'\]\)"):
        Trajectory.joint_interpolated("panda", [[0.0] * 8, [0.1] * 8])


def test_an_edit_of_the_models_own_copy_is_not_the_model():
    """``scene_of(model)`` (a Verifier's ``.scene``) edited: what was built on it follows the edit; what is
    built on the Model afterwards answers for the Model as made again (a fresh copy), as its Checkers do."""
    from armguard.model import scene_of
    from armguard.verify import Verifier

    model = _load("puma560")
    v = Verifier(model)
    v.scene.add_body("wall", [Box([0.0, 0.0, 0.0], [2.0, 2.0, 2.0], np.eye(3))])  # encloses the arm
    traj = _still(model, model.neutral())
    assert v.verify(traj).status.value == "collision"
    fresh = scene_of(model)
    assert fresh is not v.scene and "wall" not in fresh.bodies
    assert armguard.verify(model, traj).status.value != "collision"
    for backend in (None, "coal"):
        det = armguard.Detector(model, threshold=0.05, backend=backend)
        assert det.check(model.scene_q(model.neutral())).status.value != "collision"


def test_maps_matrices_and_uncertain_checks_on_a_model_ignore_a_later_edit_of_its_scene():
    """The cspace clearance hook, the SRDF matrix's pair list and the uncertain checks built on a Model read the
    Model's own copy of its system, not ``model.scene``: an edit there once raised KeyError ('wall', 0) in the
    map's clearance hook."""
    from armguard.cspace._clearance import CheckerClearance, map_links

    model = _load("puma560")
    before = CheckerClearance(model, map_links(model, None))
    Q3 = np.array([[0.0, 0.0, 0.0], [0.3, -0.5, 0.2]])
    want = before(Q3)
    model.scene.add_body("wall", [Box([0.0, 0.0, 0.0], [2.0, 2.0, 2.0], np.eye(3))])
    np.testing.assert_array_equal(CheckerClearance(model, map_links(model, None))(Q3), want)


def test_every_backend_measures_the_models_own_workspace_after_its_scene_was_edited():
    """``model.scene.set_workspace(...)`` after the Model was made: coal, fcl (and the example backend) measured
    the edited box, analytic the Model's (0.23 m against 0.43 m on ranger) -- under a warning that each
    answers for the Model as made.  Every backend now reads ``model.workspace``."""
    from armguard import ArmguardWarning

    m = armguard.load_model("ranger")
    q = m.neutral()
    want = {}
    for name in ("analytic", "coal", "fcl"):
        r = armguard.checker(m, name).pair_distances(q)
        want[name] = r.distance[np.asarray(r.category) == "workspace"].min()
    ws = m.scene.workspace
    m.scene.set_workspace(np.asarray(ws.lo) + 0.2, np.asarray(ws.hi) - 0.2)
    for name in ("analytic", "coal", "fcl"):
        with pytest.warns(ArmguardWarning, match="answers for the Model as made"):
            c = armguard.checker(m, name)
        r = c.pair_distances(q)
        got = r.distance[np.asarray(r.category) == "workspace"].min()
        assert abs(got - want["analytic"]) < 1e-6 and abs(want[name] - want["analytic"]) < 1e-6, (name, got, want)
