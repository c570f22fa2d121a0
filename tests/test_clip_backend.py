"""The clip backend (``plugins/armguard_clip``): Smith's verdicts over a Model's active pairs,
checked against coal's signed distances as the truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armguard
import armguard_clip
from armguard._errors import BackendError
from armguard.backends import Capability, available
from armguard.clip import ClipStatus

N_PUMA = 10_000  # the 0-wrong run below; bench/clip_backend.py runs 10^5-10^6


@pytest.fixture(scope="module")
def puma():
    model = armguard.load_model("puma560")
    return model, armguard.checker(model, "clip"), armguard.checker(model, "coal")


@pytest.fixture(scope="module")
def hermes():
    model = armguard.load_model("hermes")
    return model, armguard.checker(model, "clip"), armguard.checker(model, "coal")


def _truth(ref, Q):
    """coal's verdict per configuration and per pair: signed distance <= 0."""
    D = np.array([ref.pair_distances(q).distance for q in Q])
    return D.min(axis=1) <= 0.0, D <= 0.0


def _wrong(codes, truth):
    return ((codes == 0) & truth) | ((codes == 1) & ~truth)


def test_registered_and_built_by_name(puma, hermes):
    assert "clip" in available()
    for model, clip, _ in (puma, hermes):
        assert isinstance(clip, armguard_clip.ClipChecker)
        assert clip.capabilities == frozenset({Capability.VERDICTS})
        v = clip.verdicts(model.neutral()[None])
        assert v.shape == (1,) and isinstance(v[0], ClipStatus)
        assert len(clip.plans) == len(model.pairs)


def test_puma560_no_wrong_definite_answer_against_coal(puma):
    model, clip, ref = puma
    Q = model.random_q(N_PUMA, 7)
    batch = clip.check_pairs(Q)
    truth, pair_truth = _truth(ref, Q)
    assert 0.05 < truth.mean() < 0.95  # the sample has both answers in it
    assert not _wrong(batch.codes, truth).any()
    assert not _wrong(batch.pair_codes, pair_truth).any()
    assert not _wrong(batch.codes_8, truth).any()  # the 8 steps alone are also never wrong
    before, after = batch.maybe_share(second_level=False), batch.maybe_share()
    print(f"\npuma560, {N_PUMA} configurations: MAYBE {before:.2%} after the 8 steps, {after:.2%} with the "
          f"second level (per pair check: {batch.maybe_share(second_level=False, per='pair'):.3%} -> "
          f"{batch.maybe_share(per='pair'):.3%})")
    assert after < before < 0.1  # the second level settles some of them, and it is a minority
    # collides: INTERSECTED and MAYBE are True, so no colliding configuration is answered False
    hit = clip.collides(Q)
    assert np.array_equal(hit, batch.codes != 0)
    assert np.all(hit[truth])
    definite = batch.codes != 2
    assert np.array_equal(hit[definite], truth[definite])


def test_hermes_no_wrong_definite_answer_against_coal(hermes):
    model, clip, ref = hermes
    Q = model.random_q(2_000, 3)
    batch = clip.check_pairs(Q)
    truth, pair_truth = _truth(ref, Q)
    assert not _wrong(batch.codes, truth).any()
    assert not _wrong(batch.pair_codes, pair_truth).any()
    kinds = {k for k, _, _ in clip.plans}
    assert kinds == {"clip", "bracket"}  # capsule against capsule is bracketed
    bracket = np.array([k == "bracket" for k, _, _ in clip.plans])
    assert np.any(batch.pair_codes[:, bracket] != 2)  # and brackets do answer


def test_maybe_is_a_collision(puma):
    model, clip, _ = puma
    Q = model.random_q(3_000, 11)
    batch = clip.check_pairs(Q, subdivide=False)
    assert np.any(batch.codes == 2)
    plain = armguard.checker(model, "clip", {"subdivide": False})
    hit = plain.collides(Q)
    assert np.all(hit[batch.codes == 2])
    assert not np.any(hit[batch.codes == 0])


def test_distances_are_refused_naming_the_capability(puma):
    model, clip, _ = puma
    q = model.neutral()
    for ask in (lambda: clip.pair_distances(q), lambda: clip.nearest(q), lambda: clip.min_distance_many(q[None])):
        with pytest.raises(BackendError, match=r"'clip' does not answer distances .*verdicts"):
            ask()
    with pytest.raises(BackendError, match="margin"):
        clip.collides(q[None], margin=0.01)
    with pytest.raises(BackendError, match="unknown options"):
        armguard.checker(model, "clip", {"depth": 3})


def test_guard_choice(puma, hermes):
    model, clip, _ = puma
    plans = dict(((g, o), k) for k, g, o in clip.plans)
    shapes = {}
    for rn, robot in model.scene.robots.items():
        for ln, shs in robot.link_shapes.items():
            for i, s in enumerate(shs):
                shapes[model.geometry_name(f"{rn}/{ln}", i)] = s
    for (g, o), kind in plans.items():
        if o in shapes and g in shapes:  # a moving-moving pair: the curved side guards
            if type(shapes[o]).__name__ in ("Capsule", "Sphere"):
                assert kind == "bracket" and type(shapes[g]).__name__ in ("Capsule", "Sphere")
        if g not in shapes:  # a static body guards only when it is curved and the link is not
            pytest.fail(f"static {g} guards {o}")
    # side A guards when both sides are curved (hermes: capsule links)
    a_of = {(a, b): True for a, b in zip(hermes[0].pairs.a, hermes[0].pairs.b)}
    for kind, g, o in hermes[1].plans:
        if kind == "bracket":
            assert (g, o) in a_of


def test_guards_are_reposed_not_rebuilt(puma, monkeypatch):
    model, clip, _ = puma

    def refuse(*args, **kwargs):
        raise AssertionError("a guard was rebuilt at check time")

    monkeypatch.setattr(armguard_clip.Guard, "from_shape", refuse)
    assert clip.verdicts(model.random_q(50, 2)).shape == (50,)


def test_workspace_walls_are_definite_and_agree_with_coal(tmp_path):
    # Ranger with its box's x faces at +-1.5 m (the scene's own are at +-2.5 m, beyond every arm's
    # random reach): random configurations then both touch and clear the walls
    import shutil

    src = Path(armguard.__file__).resolve().parents[2] / "urdf" / "ranger"
    shutil.copytree(src, tmp_path / "ranger")
    sidecar = tmp_path / "ranger" / "ranger.yaml"
    text = sidecar.read_text()
    box = "workspace: {lo: [-2.5, -3.0, -2.5], hi: [2.5, 3.0, 2.5]}"
    assert box in text
    sidecar.write_text(text.replace(box, "workspace: {lo: [-1.5, -3.0, -2.5], hi: [1.5, 3.0, 2.5]}"))
    model = armguard.load_model(sidecar)
    clip, ref = armguard.checker(model, "clip"), armguard.checker(model, "coal")
    ws = np.array([k == "workspace" for k, _, _ in clip.plans])
    assert ws.sum() == 16
    Q = model.random_q(300, 5)
    batch = clip.check_pairs(Q)
    truth, pair_truth = _truth(ref, Q)
    assert not _wrong(batch.codes, truth).any()
    assert not _wrong(batch.pair_codes, pair_truth).any()
    assert np.all(batch.pair_codes[:, ws] != 2)
    assert np.any(pair_truth[:, ws]) and not np.all(pair_truth[:, ws])


@pytest.mark.parametrize("opts, said", [
    ({"subdivide": "no"}, "subdivide: expected true or false"), ({"rings": 8}, "rings: expected"),
    ({"rings": "8"}, "rings: expected"), ({"rings": [2, 1]}, "rings: expected"),
    ({"inner_scale": "abc"}, "inner_scale: expected a finite number in (0, 1)"), ({"inner_scale": 1.5}, "inner_scale"),
    ({"max_depth": 1.5}, "max_depth: expected an integer >= 0"), ({"bracket_rings": None}, "bracket_rings"),
])
def test_bad_options_are_refused_naming_the_option(puma, opts, said):
    """rings=8 and inner_scale=abc were internal errors (TypeError, ValueError; exit 4 from the CLI);
    subdivide="no" was read as True."""
    model = puma[0]
    with pytest.raises(BackendError, match=said.replace("(", r"\(").replace(")", r"\)")):
        armguard.checker(model, "clip", opts)
    assert armguard.checker(model, "clip", {"rings": "12,3", "subdivide": False})._guard_opts["rings"] == (12, 3)


@pytest.mark.parametrize("gap_mm, hit", [(-1.0, True), (0.5, False), (1.0, False), (1.5, False), (3.0, False)])
def test_a_cylinder_link_beside_a_workspace_wall_is_judged_by_the_cylinder_itself(tmp_path, gap_mm, hit):
    """A cylinder turned 11.25 deg about its axis: its 16-sided circumscribed prism reaches 2 % of the radius
    beyond it, and 1-1.5 mm from the wall read INTERSECTED (coal: clear)."""
    urdf = tmp_path / "cyl.urdf"
    urdf.write_text("""<robot name="cyl">
  <link name="base"/>
  <link name="arm"><collision><origin xyz="0.5 0 0" rpy="0 0 0.19635"/>
    <geometry><cylinder radius="0.1" length="0.2"/></geometry></collision></link>
  <joint name="j" type="prismatic"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>
</robot>""")
    model = armguard.load_model(urdf).with_workspace([-2, -2, -2], [0.6 + gap_mm * 1e-3, 2, 2])
    clip, ref = armguard.checker(model, "clip"), armguard.checker(model, "coal")
    Q = np.array([[0.0], [0.05]])
    assert np.array_equal(ref.collides(Q), [hit, hit])
    assert np.array_equal(clip.collides(Q), [hit, hit])
