"""``reference/models/``: coal's answers at a fixed set of configurations, with where they came from.

Per model two files: ``<name>.json`` (the header: source files and meshes with their sha256,
the pin/coal versions, the configuration set, the pairs) and ``<name>.npz`` (the arrays:
``q (K, nq)``, ``distance (K, n)``, ``p_WA``/``p_WB (K, n, 3)`` in m, ``verdict (K,)`` from
``collides``).  The configurations: the neutral pose (each arm's home) then
``model.random_q(REFERENCE_RANDOM, REFERENCE_SEED)``.  ``tools/make_reference.py NAME...``
writes them; :func:`check_sources` says whether a model's files still hash as recorded and
:func:`compare_to_reference` holds a live backend to the recorded answers.
"""

from __future__ import annotations

import enum
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._errors import ArmguardError, ReferenceFileError
from ._models import file_label, reference_dir, resolve_model
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._tolerances import pair_distance_tolerance

__all__ = ["REFERENCE_SEED", "REFERENCE_RANDOM", "FORMAT", "Reference", "SourceStatus", "SourceCheck", "DiffStatus",
           "ReferenceDiff", "reference_configs", "make_reference", "load_reference", "check_sources",
           "compare_to_reference", "regenerate_command", "source_hashes", "check_reference"]

REFERENCE_SEED = 20240612
REFERENCE_RANDOM = 64
FORMAT = 1


def regenerate_command(name: str) -> str:
    return f".venv/bin/python tools/make_reference.py {name}"


def reference_configs(model) -> np.ndarray:
    """``(1 + REFERENCE_RANDOM, nq)``: the neutral pose, then the seeded random in-limit configurations."""
    return np.concatenate([model.neutral()[None], model.random_q(REFERENCE_RANDOM, REFERENCE_SEED)])


def _model_files(model) -> tuple[Path, list, list]:
    meshes = sorted({Path(go.meshPath).resolve() for go in model.collision_model.geometryObjects
                     if go.meshPath and Path(go.meshPath).is_file()})
    files = [Path(p).resolve() for p in model.sha256 if Path(p).resolve() not in set(meshes)]  # Model.files lists meshes too
    root = Path(os.path.commonpath([str(p.parent) for p in files + meshes]))
    return root, files, meshes


def source_hashes(model) -> tuple[dict, dict]:
    """``({file: sha256}, {mesh: sha256})`` of a model's files (Model.sha256) and its mesh files, each named
    relative to the folder holding them all (so a copy of the folder hashes the same)."""
    from ..model._model import file_sha256

    root, files, meshes = _model_files(model)
    return ({p.relative_to(root).as_posix(): model.sha256[str(p)] for p in files},
            {p.relative_to(root).as_posix(): file_sha256(p) for p in meshes})


def _versions() -> dict:
    import coal
    import pinocchio as pin
    from importlib.metadata import version

    return {"pinocchio": pin.__version__, "coal": coal.__version__, "numpy": np.__version__, "armguard": version("armguard")}


@dataclass
class Reference:
    """One model's recorded answers (see the module docstring); ``header`` is the JSON header as read."""

    name: str
    header: dict
    q: np.ndarray
    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    verdict: np.ndarray

    @property
    def pairs(self) -> np.ndarray:
        return np.asarray([p[:2] for p in self.header["pairs"]], dtype=object).reshape(-1, 2)


def make_reference(spec: str, out_dir=None, *, name: str | None = None) -> tuple[Path, Path]:
    """Write ``<name>.json`` and ``<name>.npz`` for model ``spec`` (coal's answers); returns the two paths."""
    from ..backends import checker

    name = name or str(spec)
    out = Path(out_dir) if out_dir is not None else reference_dir() / "models"
    out.mkdir(parents=True, exist_ok=True)
    model = resolve_model(spec)
    c = checker(model, "coal")
    Q = reference_configs(model)
    n = len(model.pairs)
    d = np.empty((len(Q), n))
    pa = np.empty((len(Q), n, 3))
    pb = np.empty((len(Q), n, 3))
    for i, q in enumerate(Q):
        r = c.pair_distances(q)
        d[i], pa[i], pb[i] = r.distance, r.p_WA, r.p_WB
    verdict = np.asarray(c.collides(Q), dtype=bool)
    files, meshes = source_hashes(model)
    header = {
        "format": FORMAT, "model": name, "spec": str(spec), "backend": "coal",
        "backend_options": {"gjk_tolerance": c.gjk_tolerance},
        "configurations": {"neutral": 1, "random": REFERENCE_RANDOM, "seed": REFERENCE_SEED,
                           "rule": "row 0 model.neutral(), rows 1.. model.random_q(random, seed) (pin order)"},
        "root": file_label(_model_files(model)[0]), "files": files, "meshes": meshes, "versions": _versions(), "nq": model.nq, "n_pairs": n,
        "regenerate": regenerate_command(name),
        "pairs": [[a, b, cat] for (a, b), cat in zip(model.pairs.names.tolist(), model.pairs.category)],
        "arrays": {"q": "(K, nq) rad/m", "distance": "(K, n) m", "p_WA": "(K, n, 3) m", "p_WB": "(K, n, 3) m",
                   "verdict": "(K,) bool, collides(Q)"},
    }
    from .._io import atomic_write, output_set

    with output_set(out) as staging:  # the header and its arrays replace the old pair together, or neither does
        atomic_write(staging / f"{name}.npz",
                     lambda f: np.savez_compressed(f, q=Q, distance=d, p_WA=pa, p_WB=pb, verdict=verdict))
        atomic_write(staging / f"{name}.json", json.dumps(header, indent=1) + "\n")
    return out / f"{name}.json", out / f"{name}.npz"


_ARRAYS = ("q", "distance", "p_WA", "p_WB", "verdict")


def load_reference(name: str, ref_dir=None) -> Reference:
    """The recorded answers ``<name>.json`` + ``<name>.npz``; a file that is truncated, lacks an array, a key or
    rows its header promises, or holds a non-finite value raises :class:`ReferenceFileError` naming it."""
    d = Path(ref_dir) if ref_dir is not None else reference_dir() / "models"
    jp, npz = d / f"{name}.json", d / f"{name}.npz"
    if not jp.is_file() or not npz.is_file():
        raise ArmguardError(f"no reference for {name!r} in {d}; write it with: {regenerate_command(name)}")
    try:
        header = json.loads(jp.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ReferenceFileError(jp, "", f"not valid JSON ({exc}); regenerate it with: {regenerate_command(name)}") from None
    if not isinstance(header, dict):
        raise ReferenceFileError(jp, "", f"expected a JSON object, got {type(header).__name__}")
    try:
        with np.load(npz, allow_pickle=False) as z:
            missing = [k for k in _ARRAYS if k not in z.files]
            if missing:
                raise ReferenceFileError(npz, missing[0], f"array missing (has {sorted(z.files)}); regenerate it with: "
                                         f"{regenerate_command(name)}")
            arrays = {k: z[k] for k in _ARRAYS}
    except ReferenceFileError:
        raise
    except Exception as exc:  # noqa: BLE001 - zipfile, zlib, EOF and format errors of a damaged .npz
        raise ReferenceFileError(npz, "", f"cannot read ({type(exc).__name__}: {exc}); regenerate it with: "
                                 f"{regenerate_command(name)}") from None
    ref = Reference(name, header, *(arrays[k] for k in _ARRAYS))
    check_reference(ref, jp, npz)
    return ref


def check_reference(ref: Reference, json_file=None, npz_file=None) -> None:
    """Raise :class:`ReferenceFileError` unless ``ref`` holds every row and pair its header promises
    (``configurations``: neutral + random rows; ``n_pairs`` and ``pairs`` of three strings; ``nq``;
    counts that are integers >= 0; ``files`` and ``meshes`` objects of strings), with finite float
    configurations, distances and witness points and boolean verdicts."""
    jf = json_file if json_file is not None else f"reference {ref.name!r} (json)"
    nf = npz_file if npz_file is not None else f"reference {ref.name!r} (npz)"
    h = ref.header
    try:
        counts = {k: h["configurations"][k] for k in ("neutral", "random")} | {k: h[k] for k in ("n_pairs", "nq")}
        pairs = h["pairs"]
    except (KeyError, TypeError) as exc:
        raise ReferenceFileError(jf, "", f"a key is missing or invalid: {exc!r}") from None
    for k, v in counts.items():
        if not (isinstance(v, int) and not isinstance(v, bool) and v >= 0):
            raise ReferenceFileError(jf, k, f"expected a count (an integer >= 0), got {v!r}")
    K, n, nq = counts["neutral"] + counts["random"], counts["n_pairs"], counts["nq"]
    if not isinstance(pairs, list):
        raise ReferenceFileError(jf, "pairs", f"expected a list of [link, link, category], got {type(pairs).__name__}")
    for i, pr in enumerate(pairs):
        if not (isinstance(pr, list) and len(pr) == 3 and all(isinstance(x, str) for x in pr)):
            raise ReferenceFileError(jf, f"pairs[{i}]", f"expected [link, link, category] (three strings), got {pr!r}")
    if len(pairs) != n:
        raise ReferenceFileError(jf, "pairs", f"{len(pairs)} pairs, n_pairs says {n}")
    for k in ("files", "meshes"):
        v = h.get(k)
        if not (isinstance(v, dict) and all(isinstance(x, str) for kv in v.items() for x in kv)):
            raise ReferenceFileError(jf, k, f"expected an object of file: sha256 strings, got {type(v).__name__}")
    expect = {"q": (K, nq), "distance": (K, n), "p_WA": (K, n, 3), "p_WB": (K, n, 3), "verdict": (K,)}
    for k, shape in expect.items():
        a = np.asarray(getattr(ref, k))
        if a.shape != shape:
            raise ReferenceFileError(nf, k, f"shape {a.shape}; the header promises {shape} ({K} configurations, "
                                     f"{n} pairs, nq {nq})")
        if k == "verdict":
            if a.dtype != np.bool_:
                raise ReferenceFileError(nf, k, f"expected booleans, got {a.dtype}")
        elif a.dtype.kind != "f":
            raise ReferenceFileError(nf, k, f"expected real numbers (float), got {a.dtype}")
        elif not np.all(np.isfinite(a)):
            bad = np.argwhere(~np.isfinite(a))[0]
            raise ReferenceFileError(nf, k, f"{int(np.count_nonzero(~np.isfinite(a)))} non-finite values "
                                     f"(first at {tuple(int(i) for i in bad)}); a golden file must hold numbers")


class SourceStatus(str, enum.Enum):
    CURRENT = "current"  # every file and mesh hashes as recorded
    STALE = "stale"  # a file changed, appeared or went: regenerate


@dataclass
class SourceCheck:
    status: SourceStatus
    changed: list = field(default_factory=list)  # labels whose sha256 differs, or that are new / gone
    command: str = ""

    @property
    def message(self) -> str:
        if self.status is SourceStatus.CURRENT:
            return "reference is current"
        return (f"the model's files changed since its reference was recorded ({', '.join(self.changed)}); "
                f"regenerate it with: {self.command}")


def check_sources(model, ref: Reference) -> SourceCheck:
    """Whether ``model``'s files and meshes still hash as ``ref`` recorded."""
    files, meshes = source_hashes(model)
    changed = []
    for now, then in ((files, ref.header["files"]), (meshes, ref.header["meshes"])):
        for k in sorted(set(now) | set(then)):
            if now.get(k) != then.get(k):
                changed.append(k)
    status = SourceStatus.STALE if changed else SourceStatus.CURRENT
    return SourceCheck(status, changed, regenerate_command(ref.name))


class DiffStatus(str, enum.Enum):
    MATCH = "match"
    DIFFERS = "differs"


@dataclass
class ReferenceDiff:
    """A live backend against the recorded answers.

    ``pairs_match``: same pair names in the same order; ``verdict_mismatches``: configurations whose
    ``collides`` answer differs with the recorded least distance outside ``band``;
    ``distance_over``: separated (both ``> band``) entries off by more than the pair's tolerance
    (or ``distance_tol`` when given); ``max_separated_error``, ``max_point_error`` (m, unique points);
    ``worst``: ``(config, pair, live d, recorded d)`` of the largest separated error;
    ``nonfinite``: live distances or witness points that are NaN or infinite (any makes it DIFFERS);
    ``sign_disagreements``: entries apart (``> band``) by one and inside (``< -band``) by the other, or out
    of the band by one only and off by more than the pair's tolerance (:func:`._compare.sign_disagreements`;
    any makes it DIFFERS: a pair said 0.3 m apart where the record is 0.17 m deep matched, its
    configuration colliding in another pair).
    """

    status: DiffStatus
    pairs_match: bool
    verdict_mismatches: int
    distance_over: int
    max_separated_error: float
    point_over: int
    max_point_error: float
    worst: tuple | None
    nonfinite: int = 0
    sign_disagreements: int = 0

    @property
    def message(self) -> str:
        return (f"{self.status.value}: pairs match {self.pairs_match}, verdict mismatches {self.verdict_mismatches}, "
                f"separated distances over tolerance {self.distance_over} (max error {self.max_separated_error:.3e} m), "
                f"unique witness points over tolerance {self.point_over} (max {self.max_point_error:.3e} m), "
                f"sign disagreements {self.sign_disagreements}, non-finite live answers {self.nonfinite}; worst {self.worst}")


def compare_to_reference(model, checker, ref: Reference, *, tol: Tolerances = DEFAULT_TOLERANCES,
                         distance_tol: float | None = None, points: bool = True) -> ReferenceDiff:
    """Hold ``checker`` (any backend's) to ``ref`` on ``model`` (see :class:`ReferenceDiff`).  ``ref`` must hold
    every row its header promises, all finite (:func:`check_reference`; else ReferenceFileError)."""
    from ._compare import sign_disagreements, unique_witness_mask

    check_reference(ref)
    band = tol.differential_contact_band
    pairs_match = np.array_equal(model.pairs.names, ref.pairs)
    if not pairs_match or ref.q.shape[1] != model.nq:
        return ReferenceDiff(DiffStatus.DIFFERS, False, 0, 0, float("nan"), 0, float("nan"), None)
    K, n = ref.distance.shape
    d = np.empty((K, n))
    pa = np.empty((K, n, 3))
    pb = np.empty((K, n, 3))
    for i, q in enumerate(ref.q):
        r = checker.pair_distances(q)
        d[i], pa[i], pb[i] = r.distance, r.p_WA, r.p_WB
    v = np.asarray(checker.collides(ref.q), dtype=bool)
    nonfinite = int(np.count_nonzero(~np.isfinite(d)) + np.count_nonzero(~np.isfinite(pa)) + np.count_nonzero(~np.isfinite(pb)))
    out_band = (np.abs(ref.distance.min(axis=1)) > band) | (np.abs(d.min(axis=1)) > band)  # excused when both are in it
    verdict_bad = int(((v != ref.verdict) & out_band).sum())
    tol_pair = pair_distance_tolerance(model, tol) if distance_tol is None else np.full(n, float(distance_tol))
    sep = (d > band) & (ref.distance > band)
    sign = int(sign_disagreements(d, ref.distance, band, tol_pair[None, :]).sum())
    err = np.where(sep, np.abs(d - ref.distance), 0.0)
    over = int((err > tol_pair[None, :]).sum())
    worst = None
    if err.size and err.max() > 0:
        i, k = np.unravel_index(int(np.argmax(err)), err.shape)
        worst = (int(i), tuple(ref.pairs[k]), float(d[i, k]), float(ref.distance[i, k]))
    point_over, max_point = 0, 0.0
    if points:
        u = unique_witness_mask(model, ref.q, ref.distance, tol)
        dp = np.maximum(np.linalg.norm(pa - ref.p_WA, axis=2), np.linalg.norm(pb - ref.p_WB, axis=2))[u]
        point_over = int((dp > tol.differential_unique_point).sum())
        max_point = float(dp.max()) if dp.size else 0.0
    ok = verdict_bad == 0 and over == 0 and point_over == 0 and nonfinite == 0 and sign == 0
    return ReferenceDiff(DiffStatus.MATCH if ok else DiffStatus.DIFFERS, True, verdict_bad, over,
                         float(err.max()) if err.size else 0.0, point_over, max_point, worst, nonfinite, sign)
