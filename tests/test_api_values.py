"""One reading of an option's value for every entry point (``armguard._values``), and the API calls that
answered text, ``True`` or NaN with a raw TypeError / ValueError / ZeroDivisionError, or took them as numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

import armguard
from armguard import ArmguardError, BackendError, DetectionError, VerificationError
from armguard._values import number, whole_number


class _Refused(Exception):
    pass


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(-10, 10), st.floats(0, 10), st.booleans(), st.booleans())
def test_number_takes_exactly_the_finite_values_in_range(x, low, width, low_open, high_open):
    high = low + width
    inside = math.isfinite(x) and (x > low if low_open else x >= low) and (x < high if high_open else x <= high)
    try:
        got = number(x, "v", _Refused, low=low, high=high, low_open=low_open, high_open=high_open)
    except _Refused as exc:
        assert not inside
        assert str(exc).startswith("v: expected a finite number in ") and repr(x) in str(exc)
    else:
        assert inside and got == x


@pytest.mark.parametrize("value", [True, False, np.bool_(True), None, "0.5", b"1", [0.5], complex(0.5, 0)])
def test_number_refuses_what_is_not_a_real_number(value):
    with pytest.raises(_Refused, match="v: expected a finite number"):
        number(value, "v", _Refused)


def test_number_reads_text_only_when_asked():
    assert number("0.25", "v", _Refused, text=True) == 0.25
    assert number(np.float32(0.5), "v", _Refused) == 0.5 and number(np.int64(3), "v", _Refused) == 3.0
    with pytest.raises(_Refused, match="got 'abc'"):
        number("abc", "v", _Refused, text=True)
    with pytest.raises(_Refused, match="got 'nan'"):
        number("nan", "v", _Refused, text=True)


@given(st.one_of(st.integers(-5, 5), st.floats(-5, 5), st.sampled_from([math.nan, math.inf]), st.booleans(), st.text(max_size=2)))
def test_whole_number_takes_the_integers_from_low(v):
    ok = not isinstance(v, (bool, str)) and math.isfinite(v) and v == int(v) and v >= 1
    try:
        got = whole_number(v, "n", _Refused, low=1)
    except _Refused as exc:
        assert not ok and str(exc) == f"n: expected an integer >= 1, got {v!r}"
    else:
        assert ok and got == int(v) and isinstance(got, int)


@pytest.fixture(scope="module")
def puma():
    return armguard.load_model("puma560")


@pytest.mark.parametrize("backend", ["analytic", "coal"])
@pytest.mark.parametrize("threshold", ["0.1", True])
def test_a_detector_threshold_is_a_number(puma, backend, threshold):
    """``threshold="0.1"`` was read as 0.1 m and ``True`` as 1 m."""
    with pytest.raises(DetectionError, match=r"threshold: expected a finite number in \[0, 1e\+09\] \(m\)"):
        armguard.Detector(puma, threshold=threshold, backend=backend)


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_the_obstacle_list_of_an_unknown_link_is_refused(puma, backend):
    """``obstacle_list("nosuch")`` answered (): read as "nothing near that link"."""
    det = armguard.Detector(puma, backend=backend)
    assert det.obstacle_list("puma560/link3")  # a real link has a list
    with pytest.raises(DetectionError, match=r"link: expected a robot link .*got 'nosuch'.*puma560/link3"):
        det.obstacle_list("nosuch")


def test_harness_configurations_refuse_what_they_cannot_use(puma):
    from armguard.harness import build_configs, compare_at

    assert build_configs(puma, 1).Q.shape[1] == puma.nq
    assert build_configs(puma, 2, trajectories=None, frequency=0).Q.shape == (2, puma.nq)  # no trajectory to sample
    for kwargs, said in ((dict(n_random=1, frequency=0), "frequency: expected a finite number > 0"),  # ZeroDivisionError
                         (dict(n_random=1, frequency=float("nan")), "frequency: expected a finite number > 0"),
                         (dict(n_random=-1), "n_random: expected an integer >= 0"),
                         (dict(n_random="x"), "n_random: expected an integer >= 0"),
                         (dict(n_random=2, seed=1.5), "seed: expected an integer >= 0")):
        with pytest.raises(ArmguardError, match=said):
            build_configs(puma, **kwargs)
    with pytest.raises(BackendError, match="q: expected 6 numbers, got 'abc'"):  # a raw ValueError
        compare_at(puma, ["analytic", "coal"], "abc", model=puma)
    rows = compare_at(puma, ["analytic", "coal"], puma.random_q(1, 0)[0], model=puma)
    assert len(rows) == len(puma.pairs.names)


@pytest.mark.parametrize("kwargs, said", [(dict(margin="0.1"), "margin: expected a finite number >= 0"),
                                          (dict(margin=float("nan")), "margin: expected a finite number >= 0"),
                                          (dict(max_evaluations=float("nan")), "max_evaluations: expected an integer >= 1"),
                                          (dict(workers=0), "workers: expected an integer >= 1"),
                                          (dict(min_width=0.0), "min_width: expected a finite number > 0")])
def test_collision_matrix_and_lint_options_are_checked_before_any_search(puma, tmp_path, kwargs, said):
    from armguard.srdfgen import check_srdf, collision_matrix

    with pytest.raises(VerificationError, match=said):
        collision_matrix(puma, **kwargs)
    srdf = tmp_path / "p.srdf"
    srdf.write_text('<robot name="puma560"/>')
    with pytest.raises(VerificationError, match=said):
        check_srdf(puma, srdf, **kwargs)


@pytest.mark.parametrize("bad", [None, 3, ["ur5"]])
def test_load_model_of_what_is_not_a_name_or_path_is_a_type_error(bad):
    """``load_model(None)`` looked up a model named 'None' (a SceneError listing the known names)."""
    with pytest.raises(TypeError, match="expected a model name or a path"):
        armguard.load_model(bad)


@pytest.mark.parametrize("path", ["arm.xacro", "arm.urdf.xacro"])
def test_a_xacro_file_is_told_to_be_expanded_first(path, tmp_path):
    """A xacro macro file is not a URDF: the error says how to make one (it listed the model names)."""
    for load in (armguard.load_model, armguard.load_scene):
        with pytest.raises(armguard.SceneError, match=r"xacro macro file.*`xacro [\w.]+ > arm\.urdf`"):
            load(tmp_path / path)
