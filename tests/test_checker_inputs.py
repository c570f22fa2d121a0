"""Inputs a Checker must refuse or protect, on a public robot with continuous joints (kinova).

* A continuous joint's ``(cos, sin)`` off the unit circle: coal checked a scaled, sheared link and
  the analytic backend read the angle, so the two gave different verdicts (``(0, 0)``: analytic
  clear by 29 mm, coal in contact by 16 mm); now every entry point of both refuses it.
* The names in ``PairDistances.pairs`` are one array shared by every result: a write into one
  result's names renamed the pair in later results (and in ``nearest``); now read-only.
* coal's options: ``threads="x"`` was an internal ValueError, ``gjk_tolerance=1.0`` accepted.
"""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard._errors import BackendError

from armguard.backends._interface import UNIT_CIRCLE


@pytest.fixture(scope="module")
def kinova():
    return armguard.load_model("kinova")


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_a_cos_sin_off_the_unit_circle_is_refused(kinova, backend):
    c = armguard.checker(kinova, backend)
    q = kinova.random_q(1, 7)[0]
    k = int(kinova.continuous_q[1])
    good = c.pair_distances(q).distance
    near = q.copy()
    near[k:k + 2] *= 1.0 + 0.25 * UNIT_CIRCLE  # rounding of a stored (cos, sin): accepted
    assert np.allclose(c.pair_distances(near).distance, good, atol=1e-6)
    for bad_pair in ((0.0, 0.0), (3 * q[k], 3 * q[k + 1]), (q[k] * (1 + 4 * UNIT_CIRCLE), q[k + 1] * (1 + 4 * UNIT_CIRCLE))):
        bad = q.copy()
        bad[k:k + 2] = bad_pair
        for call in (lambda: c.pair_distances(bad), lambda: c.pair_distances(bad, pairs=np.arange(3)),
                     lambda: c.collides(bad[None]), lambda: c.pair_distances_many(np.stack([q, bad]))):
            with pytest.raises(BackendError, match="not on the unit circle") as e:
                call()
            assert "continuous joint" in str(e.value)
    with pytest.raises(BackendError, match="row 1"):
        c.collides(np.stack([q, np.where(np.arange(len(q)) == k, 0.0, q)]))


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_result_names_cannot_rename_a_pair(kinova, backend):
    c = armguard.checker(kinova, backend)
    q = kinova.random_q(1, 3)[0]
    for r in (c.pair_distances(q), c.pair_distances(q, pairs=np.array([2, 0])), c.pair_distances_many(q[None]),
              c.pair_distances_many(q[None], pairs=np.array([2, 0]))):
        try:
            r.pairs[0] = ["X", "Y"]  # read-only where shared; a fresh array of its own otherwise
        except ValueError:
            pass
    assert tuple(c.pair_distances(q).pairs[0]) == (kinova.pairs.a[0], kinova.pairs.b[0])
    assert tuple(c.pair_distances(q, pairs=np.array([2, 0])).pairs[0]) == (kinova.pairs.a[2], kinova.pairs.b[2])
    assert tuple(c.pair_distances_many(q[None]).pairs[0]) == (kinova.pairs.a[0], kinova.pairs.b[0])
    assert all(n.a != "X" for n in c.nearest(q).values())
    with pytest.raises(ValueError):
        c.pair_distances(q).pairs[0] = ["X", "Y"]
    assert not kinova.pairs.names.flags.writeable


@pytest.mark.parametrize("options,said", [({"threads": "x"}, "threads = 'x'"), ({"threads": 0}, "threads = 0"),
                                          ({"threads": 1.5}, "threads = 1.5"), ({"gjk_tolerance": float("nan")}, "gjk_tolerance"),
                                          ({"gjk_tolerance": 0.0}, "gjk_tolerance"), ({"gjk_tolerance": "a"}, "gjk_tolerance")])
def test_coal_options_are_checked(options, said):
    with pytest.raises(BackendError, match="expected") as e:
        armguard.checker("puma560", "coal", options)
    assert said in str(e.value)


def test_coal_option_from_a_config_file_names_the_file(tmp_path, monkeypatch):
    cfg = tmp_path / "armguard.toml"
    cfg.write_text('[backend]\nname = "coal"\nthreads = "x"\n')
    with pytest.raises(BackendError) as e:
        armguard.checker("puma560", config=cfg)
    assert str(cfg) in str(e.value) and "threads = 'x'" in str(e.value)


def test_subpackages_are_attributes_after_a_plain_import():
    """``import armguard; armguard.backends.available()`` raised AttributeError in a fresh process."""
    import subprocess
    import sys

    code = "import armguard; print(sorted(armguard.backends.available())); print(armguard.geometry.Box.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "'analytic'" in out.stdout and "'coal'" in out.stdout and "Box" in out.stdout


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_complex_and_boolean_joint_values_are_refused(backend):
    """numpy read a complex q as its real part (a ComplexWarning only) and True as 1 rad: a verdict from
    values no caller meant."""
    c = armguard.checker("puma560", backend)
    q = c.model.neutral()
    for bad in (q.astype(complex), np.ones(len(q), bool), [True] * len(q)):
        with pytest.raises(BackendError, match="expected real joint values"):
            c.pair_distances(bad)
    with pytest.raises(BackendError, match="expected real joint values"):
        c.collides(np.ones((2, len(q)), bool))


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_detectors_and_trajectories_refuse_complex_and_boolean_values(backend):
    """The same refusal outside the Checkers: the Detector (both backends: check, check_many,
    collides_many, pair_distances) and Trajectory read q + 0.5j as q and True as 1 rad."""
    from armguard import DetectionError, Trajectory, TrajectoryError

    m = armguard.load_model("ur5")
    q = np.array([np.pi, -1.57, 0.0, -1.57, 0.0, 0.0])
    det = armguard.Detector(m, threshold=0.05, backend=backend)
    for call in (lambda: det.check(q + 0.5j), lambda: det.check(np.array([True, False] * 3)),
                 lambda: det.check_many((q + 0.5j)[None]), lambda: det.collides_many(np.ones((2, 6), bool)),
                 lambda: det.pair_distances(q + 0.5j)):
        with pytest.raises(DetectionError, match="expected real joint values"):
            call()
    with pytest.raises(TrajectoryError, match="expected real joint values"):
        Trajectory("ur5", list(m.scene.robots["ur5"].joint_names), [0.0, 1.0], [q, q + 1j])


def test_compiled_scene_rows_equal_the_models_scene_q(kinova):
    """``collides``' compiled conversion of Pinocchio's rows (``scene_rows``) against its reference,
    ``Model.scene_q`` (numpy): the same angles, in the same order, on rows whose ``(cos, sin)`` lie
    on the unit circle up to the rounding it accepts; the first row off it is the one returned."""
    from armguard_analytic._engine._pair_rows import scene_rows

    Q = kinova.random_q(200, 23)
    cq = kinova.continuous_q
    Q[::3, cq] *= 1.0 + 0.5 * UNIT_CIRCLE  # accepted rounding of a stored (cos, sin)
    qidx = np.ascontiguousarray(kinova.q_index, dtype=np.int64)
    circ = np.ascontiguousarray(kinova._circular, dtype=np.int64)
    out = np.empty((len(Q), len(qidx)))
    assert scene_rows(Q, qidx, circ, out) == -1
    # the angles to an ulp (the kernel's atan2 is LLVM's, numpy's its own: they differ in the last bit
    # on 2 % of these angles; pair_distances' kernel reads them as scene_rows does), the rest exactly
    ref = kinova.scene_q(Q)
    np.testing.assert_allclose(out, ref, rtol=0, atol=2 * np.finfo(float).eps * np.pi)
    other = np.setdiff1d(np.arange(len(qidx)), circ)
    np.testing.assert_array_equal(out[:, other], ref[:, other])
    Q[57, cq[1]] *= 1.0 + 4 * UNIT_CIRCLE
    Q[120, cq[0] + 1] = 0.0
    assert scene_rows(Q, qidx, circ, out) == 57


def test_a_batch_of_the_wrong_width_is_told_the_layout_as_a_single_q_is():
    """``collides(Q)`` with kinova's 6 angles a row said only ``expected shape (M, 9)``; ``pair_distances(q)``
    names each position and points to ``Model.pin_q``: the batch now says the same of each row."""
    import numpy as np

    import armguard

    m = armguard.load_model("kinova")
    c = armguard.checker(m)
    with pytest.raises(armguard.BackendError) as info:
        c.collides(np.zeros((2, 6)))
    msg = str(info.value)
    assert "expected shape (M, 9), each row" in msg and "j2s6s200_joint_1 (cos, sin)" in msg and "Model.pin_q" in msg
