"""The forbidden backend (Fig. 14 as a Checker) and map clearances through the backend interface.

One coarse map (6°, joint-3 quantum 6°, depth 3, the paper's worst stopping distance 0.1 m) is
built per module for ``armguard.load_model("hermes")``; every claim below is about that map, and
none depends on its resolution.
"""

from __future__ import annotations

import math
import re
import shutil

import numpy as np
import pytest

import armguard
from armguard import BackendError, ForbiddenMapError
from armguard.backends import Capability, available
from armguard.cspace import CheckerClearance, CombinedChecker, CombinedStatus, ForbiddenMap, map_links
from armguard.cspace._certify import certify_substructure
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.harness import build_configs
from armguard.model import models_dir

RES = math.radians(6.0)
DEPTH = 3
SD = 0.1
KW = dict(resolution=RES, stopping_distance=SD, max_depth=DEPTH)


@pytest.fixture(scope="module")
def model():
    return armguard.load_model("hermes")


@pytest.fixture(scope="module")
def fmap(model, tmp_path_factory):
    return ForbiddenMap.build(model, out=tmp_path_factory.mktemp("fb") / "hermes6.agmap", **KW)


@pytest.fixture(scope="module")
def forbidden(model, fmap):
    return armguard.checker(model, "forbidden", {"map": str(fmap.path)})


@pytest.fixture(scope="module")
def analytic(model):
    return armguard.checker(model, "analytic")


def test_registered_verdicts_only(forbidden, fmap, model):
    assert "forbidden" in available()
    assert forbidden.capabilities == frozenset({Capability.VERDICTS})
    assert forbidden.geometric.name == "analytic" and forbidden.max_margin == pytest.approx(SD + 1e-6)
    # the map's header names the Model's own files (sidecar, URDF, SRDF) and the clearance backend
    assert sorted(r["sha256"] for r in fmap.header["model_files"]) == sorted(model.sha256.values())
    assert fmap.header["backend"] == "analytic"
    for call in (lambda: forbidden.pair_distances(model.neutral()), lambda: forbidden.nearest(model.neutral()),
                 lambda: forbidden.min_distance_many(model.neutral()[None])):
        with pytest.raises(BackendError, match="does not answer distances"):
            call()


def test_never_free_where_the_exact_check_collides(forbidden, analytic, model):
    Q = model.random_q(10_000, 11)
    for margin in (SD, 0.0):
        batch = forbidden.verdicts(Q, margin=margin)
        exact = analytic.collides(Q, margin=margin)
        assert not np.any(exact & ~batch.collision), margin
        assert np.array_equal(forbidden.collides(Q, margin=margin), batch.collision)
        for s in CombinedStatus:  # a useful answer: every verdict occurs
            assert np.any(batch.status == s), (margin, s)
        print(f"\nmargin {margin} m: exact collides {exact.mean():.3f}, forbidden says collision "
              f"{batch.collision.mean():.3f} (false-forbidden {np.mean(batch.collision & ~exact):.3f})")
    coal = armguard.checker(model, "coal")  # the reference backend's full check agrees on a smaller sample
    assert not np.any(coal.collides(Q[:2000], margin=SD) & ~forbidden.collides(Q[:2000], margin=SD))


def test_no_category_is_skipped(forbidden, model):
    """The conformance suite's per-category check cannot run here (the map refuses a Model made in process),
    so: at every configuration where the pairs of one category alone collide (coal; every other category
    clear), the forbidden backend says collision -- a backend that skipped a category (the payload's) would
    call those rows clear, however the other categories decide the rest."""
    Q = model.random_q(3000, 14)
    D = armguard.checker(model, "coal").pair_distances_many(Q)
    D = getattr(D, "distance", D)
    cat = np.asarray(model.pairs.category)
    least = {c: D[:, cat == c].min(axis=1) for c in sorted(set(cat))}
    said = forbidden.collides(Q, margin=0.0)
    for c in least:
        alone = (least[c] <= 0.0) & np.all([least[o] > 0.0 for o in least if o != c], axis=0)
        assert alone.sum() >= 5, (c, int(alone.sum()))  # hermes: 319 arm-arm, 7 arm-payload, 214, 88 rows
        assert said[alone].all(), (c, np.flatnonzero(alone & ~said)[:5])


def test_agrees_with_the_combined_checker(forbidden, fmap, model):
    Q = model.random_q(5000, 12)
    verdict = forbidden.verdicts(Q, margin=SD)
    Qs = model.scene_q(Q)
    for scene in (model.scene, armguard.load_scene("hermes")):  # the Model's scene, and a scene loaded alone
        comb = CombinedChecker(fmap, scene).prepare()
        batch = comb.check_many(Qs)
        assert np.array_equal(batch.status, verdict.status)
    with pytest.raises(ForbiddenMapError, match="margin"):
        comb.check_many(Qs[:2], margin=0.5)


def test_any_geometric_backend(fmap, forbidden, model):
    Q = model.random_q(2000, 13)
    fc = armguard.checker(model, "forbidden", {"map": str(fmap.path), "geometric": "coal", "geometric.threads": 1})
    assert fc.geometric.name == "coal" and fc.geometric.threads == 1
    a = forbidden.verdicts(Q, margin=SD)
    c = fc.verdicts(Q, margin=SD)
    assert np.array_equal(a.status == CombinedStatus.MAP_FORBIDDEN, c.status == CombinedStatus.MAP_FORBIDDEN)
    # the other pairs' verdicts differ only within the backends' distance tolerance of the margin
    differ = a.collision != c.collision
    if np.any(differ):
        d = forbidden.geometric.min_distance_many(Q[differ])
        assert np.all(np.abs(d - SD) <= TOL.differential_hull)
    full = armguard.checker(model, "coal").collides(Q, margin=SD)
    assert not np.any(full & ~c.collision)


def test_model_files_must_match(fmap, model, tmp_path):
    with pytest.raises(BackendError, match="built for other model files") as err:
        armguard.checker(armguard.load_model("ranger"), "forbidden", {"map": str(fmap.path)})
    msg = str(err.value)
    assert re.search(r"in the map only: [^;]*hermes\.urdf", msg) and re.search(r"new: [^;]*ranger\.urdf", msg)
    assert "armguard cspace build ranger" in msg
    # a map built for a copy of the model refuses once a model file changes
    src = tmp_path / "hermes"
    shutil.copytree(models_dir() / "hermes", src)
    copy = armguard.load_model(src / "hermes.yaml")
    small = ForbiddenMap.build(copy, out=tmp_path / "small.agmap", resolution=math.radians(30), stopping_distance=SD,
                               max_depth=0)
    armguard.checker(copy, "forbidden", {"map": str(small.path)})
    old = copy.sha256[str((src / "hermes.urdf").resolve())][:12]
    urdf = src / "hermes.urdf"
    urdf.write_text(urdf.read_text() + "\n<!-- edited -->\n")
    edited = armguard.load_model(src / "hermes.yaml")
    new = edited.sha256[str(urdf.resolve())][:12]
    with pytest.raises(BackendError, match="built for other model files") as err:
        armguard.checker(edited, "forbidden", {"map": str(small.path)})
    assert f"changed: hermes.urdf (sha256 {old} in the map, {new} now)" in str(err.value)


def test_bad_options(fmap, forbidden, model, tmp_path):
    with pytest.raises(BackendError, match="option 'map' is required.*armguard cspace build hermes"):
        armguard.checker(model, "forbidden")
    missing = tmp_path / "none.agmap"
    with pytest.raises(BackendError, match=f"{missing} not found; build it with `armguard cspace build hermes .*--out {missing}`"):
        armguard.checker(model, "forbidden", {"map": str(missing)})
    with pytest.raises(BackendError, match=f"map {tmp_path} is a folder, not a .agmap file"):  # it said "not found"
        armguard.checker(model, "forbidden", {"map": str(tmp_path)})
    with pytest.raises(BackendError, match="unknown options"):
        armguard.checker(model, "forbidden", {"map": str(fmap.path), "bogus": 1})
    with pytest.raises(BackendError, match="not forbidden itself"):
        armguard.checker(model, "forbidden", {"map": str(fmap.path), "geometric": "forbidden"})
    with pytest.raises(BackendError, match="unknown backend"):
        armguard.checker(model, "forbidden", {"map": str(fmap.path), "geometric": "nope"})
    Q = model.random_q(3, 0)
    with pytest.raises(BackendError, match="exceeds the map's stopping distance 0.1 m.*--stopping-distance 0.2"):
        forbidden.collides(Q, margin=0.2)
    with pytest.raises(BackendError, match="margin"):
        forbidden.collides(Q, margin=-1.0)
    with pytest.raises(BackendError, match="shape"):
        forbidden.collides(Q[:, :3])


def test_detector_over_the_forbidden_backend(fmap, forbidden, model):
    det = armguard.Detector(model.scene, threshold=0.0, stopping_distance=SD, backend="forbidden",
                            backend_options={"map": str(fmap.path)})
    assert det.backend == "forbidden"
    Q = model.random_q(2000, 14)
    assert np.array_equal(det.collides_many(model.scene_q(Q)), forbidden.collides(Q, margin=SD))
    with pytest.raises(BackendError, match="'forbidden' answers verdicts only"):
        det.check(model.scene.default_q())
    # a scene loaded alone is its model's (the same files); a copy made in code has no files to check the map against
    alone = armguard.Detector(armguard.load_scene("hermes"), threshold=0.0, stopping_distance=SD, backend="forbidden",
                              backend_options={"map": str(fmap.path)})
    assert np.array_equal(alone.collides_many(model.scene_q(Q)), forbidden.collides(Q, margin=SD))
    with pytest.raises(BackendError, match="no source files"):
        armguard.Detector(armguard.load_scene("hermes").copy(), backend="forbidden",
                          backend_options={"map": str(fmap.path)})


def test_verdicts_on_the_harness_configurations(forbidden, analytic, model):
    """``armguard compare``'s configurations (seeded random + every canned trajectory's samples), verdicts at its
    margin 0: the forbidden backend never says free where the analytic backend says collision."""
    configs = build_configs(model, 2000, 0, "all", 1.0)
    v = forbidden.collides(configs.Q)
    exact = analytic.collides(configs.Q)
    assert len(configs.Q) > 2000
    assert not np.any(exact & ~v)
    print(f"\nharness configurations: {len(v)}; analytic collides {exact.mean():.3f}; forbidden {v.mean():.3f}")


def test_coal_clearances_give_the_analytic_map(fmap, model, tmp_path):
    """Maps built with coal's clearances equal the analytic ones up to the documented tolerance.

    Certification is monotone in the clearance (a smaller clearance never frees a box: it can only
    mark more), so wherever two backends' clearances differ by at most ``TOL.differential_hull`` (the
    hulls' distance tolerance), the coal map lies between the analytic maps built with clearances
    lowered and raised by that much: ``mask(analytic - δ) ⊇ mask(coal) ⊇ mask(analytic + δ)``.
    """
    delta = TOL.differential_hull
    ml = map_links(model.scene, fmap.robot)
    ha = CheckerClearance(model, ml, "analytic")
    hc = CheckerClearance(model, ml, "coal")
    g = fmap.grid
    Q3 = np.random.default_rng(15).uniform(g.lower, g.upper, size=(2000, 3))
    assert np.max(np.abs(ha(Q3) - hc(Q3))) <= delta
    masks = [fmap.substructure_mask(s) for s in range(g.n_substructures)]
    mixed = [s for s, m in enumerate(masks) if m.any() and not m.all()]
    pick = mixed[:: max(1, len(mixed) // 4)][:4]
    contact = armguard.DEFAULT_TOLERANCES.cspace_contact
    n_diff = 0
    for s in pick:
        i1a, i1b, i2a, i2b = g.sub_cells(s)
        shape = (i1b - i1a, i2b - i2a, int(g.counts[2]))

        def mask_of(hook):
            from armguard.cspace._certify import decode_intervals

            r = certify_substructure(g, s, hook, ml.lever, SD, contact, DEPTH)
            return decode_intervals(r.pointers, r.intervals, shape)

        mc = mask_of(hc)
        ma = mask_of(ha)
        assert np.array_equal(ma, masks[s])  # the map's own substructure
        lo, hi = mask_of(lambda Q: ha(Q) - delta), mask_of(lambda Q: ha(Q) + delta)
        assert np.all(mc <= lo) and np.all(hi <= mc)
        n_diff += int(np.sum(mc != ma))
    print(f"\ncoal vs analytic on {len(pick)} mixed substructures: {n_diff} bins differ")
    # the whole build with backend="coal", very coarse so that coal's one-at-a-time distances stay quick (every bin
    # is forbidden at 30°: this checks that the build takes and records the backend; the substructures above, the content)
    kw = dict(resolution=math.radians(30), stopping_distance=SD, max_depth=1)
    a = ForbiddenMap.build(model, out=tmp_path / "a.agmap", **kw)
    c = ForbiddenMap.build(model, out=tmp_path / "c.agmap", backend="coal", **kw)
    assert c.header["backend"] == "coal" and np.array_equal(a.mask(), c.mask())
    with pytest.raises(ForbiddenMapError, match="verdicts only"):
        ForbiddenMap.build(model, out=tmp_path / "x.agmap", backend="clip", **kw)
    with pytest.raises(ForbiddenMapError, match="not both"):
        ForbiddenMap.build(model, out=tmp_path / "x.agmap", backend="coal", clearance=ha, **kw)


def test_the_documented_example_runs():
    """docs/cspace.md's example of the forbidden backend, executed as written."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parent.parent / "docs" / "cspace.md").read_text(encoding="utf-8")
    blocks = [b for b in re.findall(r"```python\n(.*?)```", text, re.S) if '"forbidden"' in b]
    assert len(blocks) == 1
    exec(compile(blocks[0], "docs/cspace.md", "exec"), {"__name__": "docs_cspace"})
