"""A golden file cannot pass by holding nothing: NaN values, missing rows, arrays or columns, and
truncated files are refused (ReferenceFileError naming the file and the array); a live backend
answering NaN DIFFERS."""

from __future__ import annotations

import dataclasses
import json
import shutil

import numpy as np
import pytest

import armguard
from armguard._errors import ReferenceFileError
from armguard.harness import reference_dir, resolve_model
from armguard.harness._reference import DiffStatus, compare_to_reference, load_reference

NAME = "gmf_s480"  # the smallest record: 65 configurations x 15 pairs


@pytest.fixture(scope="module")
def model():
    return resolve_model(NAME)


@pytest.fixture(scope="module")
def ref():
    return load_reference(NAME)


@pytest.fixture
def copy(tmp_path):
    for ext in ("json", "npz"):
        shutil.copy(reference_dir() / "models" / f"{NAME}.{ext}", tmp_path / f"{NAME}.{ext}")
    return tmp_path


def _rewrite(d, **change):
    with np.load(d / f"{NAME}.npz") as z:
        arrays = {k: z[k] for k in z.files}
    for k, v in change.items():
        if v is None:
            arrays.pop(k)
        else:
            arrays[k] = v(arrays[k])
    np.savez_compressed(d / f"{NAME}.npz", **arrays)


def _nan_at(a, idx):
    a = a.astype(np.float64).copy()
    a[idx] = np.nan
    return a


CASES = {
    "nan distances": (dict(distance=lambda a: np.full_like(a, np.nan)), "distance", "non-finite"),
    "one nan distance": (dict(distance=lambda a: _nan_at(a, (7, 3))), "distance", r"first at \(7, 3\)"),
    "nan witness points": (dict(p_WA=lambda a: _nan_at(a, (slice(None), 2))), "p_WA", "non-finite"),
    "nan configuration": (dict(q=lambda a: _nan_at(a, (4, 0))), "q", "non-finite"),
    "one configuration": (dict(q=lambda a: a[:1], distance=lambda a: a[:1], p_WA=lambda a: a[:1], p_WB=lambda a: a[:1],
                               verdict=lambda a: a[:1]), "q", "promises"),
    "zero configurations": (dict(q=lambda a: a[:0], distance=lambda a: a[:0], p_WA=lambda a: a[:0], p_WB=lambda a: a[:0],
                                 verdict=lambda a: a[:0]), "q", "promises"),
    "rows missing from one array": (dict(verdict=lambda a: a[:-3]), "verdict", "promises"),
    "a missing column": (dict(distance=lambda a: a[:, :-1]), "distance", "promises"),
    "a missing array": (dict(p_WB=None), "p_WB", "array missing"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_hollow_golden_file_is_refused(copy, case):
    change, where, match = CASES[case]
    _rewrite(copy, **change)
    with pytest.raises(ReferenceFileError, match=match) as e:
        load_reference(NAME, copy)
    assert e.value.where == where and e.value.file == str(copy / f"{NAME}.npz")


@pytest.mark.parametrize("case", ["nan distances", "nan witness points", "one configuration", "zero configurations"])
def test_compare_to_reference_never_matches_a_hollow_record(model, ref, case):
    """The comparison itself refuses a Reference built in code the way the loader refuses a file."""
    change, where, _ = CASES[case]
    arrays = {k: getattr(ref, k) for k in ("q", "distance", "p_WA", "p_WB", "verdict")}
    for k, f in change.items():
        arrays[k] = f(arrays[k])
    hollow = dataclasses.replace(ref, **arrays)
    with pytest.raises(ReferenceFileError) as e:
        compare_to_reference(model, armguard.checker(model, "coal"), hollow)
    assert e.value.where == where


class _NanChecker:
    """A backend that answers NaN for one pair: the live side of the comparison."""

    def __init__(self, inner):
        self.inner = inner

    def pair_distances(self, q):
        r = self.inner.pair_distances(q)
        d = np.array(r.distance, dtype=np.float64)
        d[2] = np.nan
        return dataclasses.replace(r, distance=d) if dataclasses.is_dataclass(r) else r

    def collides(self, Q, margin=0.0):
        return self.inner.collides(Q)


def test_a_live_nan_differs(model, ref):
    live = _NanChecker(armguard.checker(model, "coal"))
    diff = compare_to_reference(model, live, ref, points=False)
    assert diff.status is DiffStatus.DIFFERS and diff.nonfinite == len(ref.q), diff.message
    assert compare_to_reference(model, armguard.checker(model, "coal"), ref).status is DiffStatus.MATCH


@pytest.mark.parametrize("which", ["npz half", "npz empty", "json half", "json empty", "json a list", "json no pairs"])
def test_truncated_reference_files_name_the_file(copy, which):
    kind, how = which.split(" ", 1)
    p = copy / f"{NAME}.{kind}"
    raw = p.read_bytes()
    if how == "half":
        p.write_bytes(raw[: len(raw) // 2])
    elif how == "empty":
        p.write_bytes(b"")
    elif how == "a list":
        p.write_text("[]")
    else:
        h = json.loads(raw)
        del h["pairs"]
        p.write_text(json.dumps(h))
    with pytest.raises(ReferenceFileError) as e:
        load_reference(NAME, copy)
    assert e.value.file == str(p), str(e.value)


NUMBERS = {
    "distances as text": (lambda a: a.__setitem__("distance", a["distance"].astype(str)), "distance", "expected real numbers"),
    "configurations as text": (lambda a: a.__setitem__("q", a["q"].astype(str)), "q", "expected real numbers"),
    "complex witness points": (lambda a: a.__setitem__("p_WA", a["p_WA"].astype(complex)), "p_WA", "expected real numbers"),
}
HEADER = {
    "a negative count": (lambda h: h["configurations"].__setitem__("random", -1), "random", "an integer >= 0"),
    "a fractional count": (lambda h: h.__setitem__("n_pairs", h["n_pairs"] + 0.7), "n_pairs", "an integer >= 0"),
    "pairs not a list": (lambda h: h.__setitem__("pairs", 5), "pairs", "expected a list"),
    "a pair of one link": (lambda h: h["pairs"].__setitem__(3, h["pairs"][3][:1]), "pairs[3]", "three strings"),
    "no file hashes": (lambda h: h.pop("files"), "files", "file: sha256"),
}


@pytest.mark.parametrize("case", list(NUMBERS) + list(HEADER))
def test_text_where_numbers_belong_and_malformed_headers_are_refused(copy, case):
    """Arrays of strings or complex numbers, counts that are not integers >= 0, pairs that are not
    three strings and a header without its file hashes name the file and the place (they raised
    numpy's TypeError, or loaded: 15.7 pairs read as 15, a one-link pair, complex witnesses)."""
    if case in NUMBERS:
        change, where, match = NUMBERS[case]
        with np.load(copy / f"{NAME}.npz") as z:
            arrays = {k: z[k] for k in z.files}
        change(arrays)
        np.savez_compressed(copy / f"{NAME}.npz", **arrays)
        p = copy / f"{NAME}.npz"
    else:
        change, where, match = HEADER[case]
        p = copy / f"{NAME}.json"
        h = json.loads(p.read_text())
        change(h)
        p.write_text(json.dumps(h))
    with pytest.raises(ReferenceFileError, match=match) as e:
        load_reference(NAME, copy)
    assert e.value.file == str(p) and e.value.where == where, str(e.value)
