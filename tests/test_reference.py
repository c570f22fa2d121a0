"""Every backend against ``reference/models/`` (coal's recorded answers), and the seeds' numbers.

Live coal against its own recorded answers catches a coal or Pinocchio upgrade that changes
them; analytic and python-fcl are held to the same records with the tolerances of
``armguard.Tolerances``' ``differential_*`` fields (fcl within its band, and not on Ranger — see
``tests/test_backends.py``).  A model whose files no longer hash as recorded fails with the one
command that regenerates its reference.
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import armguard
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.harness import reference_dir, reference_model_names, repo_root, resolve_model, seed_data
from armguard.harness._reference import (
    REFERENCE_RANDOM,
    DiffStatus,
    SourceStatus,
    check_sources,
    compare_to_reference,
    load_reference,
    make_reference,
    reference_configs,
)

NAMES = list(reference_model_names())
FCL_OFF = {"ranger"}  # python-fcl is off by up to 0.32 m there (tests/test_backends.py)


@pytest.fixture(scope="module")
def loaded():
    cache = {}

    def get(name):
        if name not in cache:
            model = resolve_model(name)
            ref = load_reference(name)
            src = check_sources(model, ref)
            if src.status is not SourceStatus.CURRENT:
                pytest.fail(f"{name}: {src.message}")
            cache[name] = (model, ref)
        return cache[name]

    return get


def test_every_model_has_a_reference():
    assert {"ranger", "hermes", "puma560", "gmf_s480", "rover", "panda", "ur5", "iiwa"} <= set(NAMES)
    for name in NAMES:
        assert (reference_dir() / "models" / f"{name}.json").is_file(), name
        assert (reference_dir() / "models" / f"{name}.npz").is_file(), name


@pytest.mark.parametrize("name", NAMES)
def test_backends_match_the_reference(loaded, name):
    model, ref = loaded(name)
    head = ref.header
    assert head["configurations"]["random"] == REFERENCE_RANDOM and ref.q.shape == (1 + REFERENCE_RANDOM, model.nq)
    np.testing.assert_array_equal(ref.q, reference_configs(model))  # the documented configurations
    assert head["files"] and all(len(h) == 64 for h in head["files"].values())
    assert {"pinocchio", "coal"} <= set(head["versions"])
    for backend in ("coal", "analytic"):
        diff = compare_to_reference(model, armguard.checker(model, backend), ref)
        assert diff.status is DiffStatus.MATCH, f"{name} {backend}: {diff.message}"
    if name not in FCL_OFF:
        fcl = armguard.checker(model, "fcl")
        diff = compare_to_reference(model, fcl, ref, distance_tol=TOL.differential_fcl, points=False)
        assert diff.pairs_match and diff.distance_over == 0, f"{name} fcl: {diff.message}"
        d = np.array([fcl.pair_distances(q).distance for q in ref.q])
        far = np.abs(ref.distance) > TOL.differential_fcl
        assert np.array_equal((d > 0)[far], (ref.distance > 0)[far])


def test_a_live_sign_flip_differs_from_the_record_where_another_pair_collides(loaded):
    """A live checker saying 0.3 m apart for a pair the record has deep inside "matched": its configuration
    collides in another pair (the verdict holds) and only separated entries were compared."""
    model, ref = loaded("hermes")
    real = armguard.checker(model, "coal")
    D = ref.distance
    i = int(np.flatnonzero((D < -1e-3).sum(axis=1) >= 2)[0])
    k = int(np.flatnonzero(D[i] < -1e-3)[0])

    class Lying:
        def pair_distances(self, q):
            r = real.pair_distances(q)
            if np.array_equal(q, ref.q[i]):
                r.distance[k] = 0.3
            return r

        def collides(self, Q):
            return real.collides(Q)

    diff = compare_to_reference(model, Lying(), ref)
    assert diff.verdict_mismatches == 0 and diff.sign_disagreements == 1
    assert diff.status is DiffStatus.DIFFERS and "sign disagreements 1" in diff.message


def test_a_changed_model_file_names_the_regenerating_command(tmp_path):
    shutil.copytree(repo_root() / "urdf" / "hermes", tmp_path / "hermes")
    urdf = tmp_path / "hermes" / "hermes.urdf"
    ref = load_reference("hermes")
    assert check_sources(resolve_model(str(tmp_path / "hermes" / "hermes.yaml")), ref).status is SourceStatus.CURRENT
    urdf.write_text(urdf.read_text().replace('<cylinder radius="0.15" length="4.2"/>', '<cylinder radius="0.2" length="4.2"/>', 1))
    model = resolve_model(str(tmp_path / "hermes" / "hermes.yaml"))
    src = check_sources(model, ref)
    assert src.status is SourceStatus.STALE and src.changed == ["hermes.urdf"]
    assert "tools/make_reference.py hermes" in src.message
    # and the answers moved: coal on the edited model no longer matches the record
    assert compare_to_reference(model, armguard.checker(model, "coal"), ref).status is DiffStatus.DIFFERS


def test_make_reference_round_trips(tmp_path):
    jp, npz = make_reference("gmf_s480", tmp_path)
    mine, kept = load_reference("gmf_s480", tmp_path), load_reference("gmf_s480")
    assert mine.header["files"] == kept.header["files"] and mine.header["pairs"] == kept.header["pairs"]
    # coal's GJK on hulls answers to ~1e-10 m depending on the queries its shared Convex objects saw before
    np.testing.assert_allclose(mine.distance, kept.distance, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(mine.verdict, kept.verdict)


def test_seed_numbers_live_in_reference_seeds_with_their_source():
    ranger, hermes = seed_data("ranger"), seed_data("hermes")
    assert ranger["segment_segment"]["value"] == 16 and ranger["detection_cycle"]["value"] == 1.23
    assert "16 μsec" in ranger["segment_segment"]["source"] and "1.23 msec" in ranger["detection_cycle"]["source"]
    m = hermes["model"]
    assert (m["polyhedra"], m["faces"], m["vertices"]) == (8, 54, 76)
    assert f"{m['polyhedra']} convex polyhedra, {m['faces']} faces and {m['vertices']} vertices" in m["source"]
    for row in hermes["discretisation_error"]["table"]:
        assert f"{row['speed_mm_s']} (mm/sec) => {row['ed_mm']} (mm)" in hermes["discretisation_error"]["source"]
    # the published cycle time the docs compare against is the one recorded here
    readme = (repo_root() / "README.md").read_text()
    assert f"Ranger 1997: {ranger['detection_cycle']['value']} ms" in readme
