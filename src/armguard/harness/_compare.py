"""Backend against backend: verdicts, distance errors, nearest points and timings, per category.

Definitions (every count is over (configuration, pair) entries unless it says configurations):

* **reference** of a backend pair: ``coal`` when it is one of the two, else the second.
* **verdict disagreement**: a configuration where the two ``collides(Q)`` answers differ and the
  reference's least distance is outside the contact band (``|d| > contact_band``); those inside
  it are counted apart (``in_band``).  Per category, the verdict is "the category's least
  distance ``<= 0``" from ``pair_distances``.
* **separated** entries: both distances ``> contact_band``; **penetrating**: both ``< -contact_band``;
  **sign disagreements**: the rest whose reference distance is outside the band.
* **the slow reference's word**: each of the worst distance entries (``worst``, ``why == "distance"``)
  whose two distances differ by more than the pair's tolerance also carries ``slow_reference``: the
  signed distance of the two shapes as Pinocchio places them, by the support-function reference
  (:mod:`armguard.geometry._support_reference`: no GJK, no EPA, no kernel of any backend; a workspace
  pair: the shape against the box's six walls), and each backend's error against it -- which of the
  two is off (coal's EPA depths on cylinders, for one).  Made once per (configuration, pair) entry,
  whichever backend pairs list it.
* **unique nearest points** (as ``tests/test_backends.py`` defines them): both sides capsules or
  spheres, the reference distance above ``unique_min_distance`` and, for two capsules,
  ``|sin(angle between axes)| > parallel``.  There |Δp_WA|, |Δp_WB| are measured; elsewhere each
  backend's points are checked against the witness contract on their own,
  ``| |p_WA - p_WB| - |d| | <= tol`` (``tol`` the pair's distance tolerance: ``hull`` for a Convex side).

A backend pair with a verdicts-only side (no ``Capability.DISTANCES``: ``clip``, ``forbidden``) has no
distances or witness points to compare: :mod:`._verdicts` judges its verdicts against the distance
side's (unsafe and conservative answers, undecided shares, false-forbidden), with
``max_abs_distance_error`` None.
"""

from __future__ import annotations

import enum
import itertools
import shlex
from dataclasses import dataclass, field

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._tolerances import pair_distance_tolerance, pair_kinds
from ._verdicts import verdict_backend_summary, verdict_pair_summary

__all__ = ["PairStatus", "Comparison", "compare_answers", "capsule_axes", "unique_witness_mask", "reference_of",
           "reproduce_command", "reference_distance", "judged", "REFERENCE_METHOD", "REFERENCE_WALLS"]

REFERENCE_METHOD = "support functions, 6,000 directions and Nelder-Mead; no GJK, no EPA"
"""How the slow reference that arbitrates the worst distance entries works (``worst[..]["slow_reference"]``)."""
REFERENCE_WALLS = "support functions along the six walls' normals"
"""The same for a workspace pair (a shape against the workspace box's walls)."""


class PairStatus(str, enum.Enum):
    AGREE = "agree"  # no verdict disagreement outside the band, separated distances within tolerance
    DIFFER = "differ"


@dataclass
class Comparison:
    """The harness's result: ``summary`` is ``compare.json``; the arrays stay for the plots.

    ``answers``: ``{backend: BackendAnswers}``; ``status``: ``{"a/b": PairStatus}``.
    """

    model: object
    spec: str
    configs: object
    answers: dict
    summary: dict
    status: dict = field(default_factory=dict)

    @property
    def pair_keys(self) -> list:
        return list(self.summary["pairs"])


def reference_of(a: str, b: str) -> str:
    return "coal" if "coal" in (a, b) else b


def capsule_axes(model, Q) -> dict:
    """``{geometry index: (M, 3) float64}``: each capsule's axis direction in W at every row of ``Q``."""
    import pinocchio as pin

    cm = model.collision_model
    caps = [i for i, go in enumerate(cm.geometryObjects) if type(go.geometry).__name__ == "Capsule"]
    if not caps:
        return {}
    data = model.pin_model.createData()
    joints = sorted({int(cm.geometryObjects[i].parentJoint) for i in caps})
    R = {j: np.empty((len(Q), 3, 3)) for j in joints}
    for m, q in enumerate(Q):
        pin.forwardKinematics(model.pin_model, data, q)
        for j in joints:
            R[j][m] = data.oMi[j].rotation
    out = {}
    for i in caps:
        go = cm.geometryObjects[i]
        out[i] = R[int(go.parentJoint)] @ go.placement.rotation[:, 2]
    return out


def unique_witness_mask(model, Q, d_ref, tol: Tolerances = DEFAULT_TOLERANCES, axes=None) -> np.ndarray:
    """``(M, n) bool``: where the nearest points are unique (see the module docstring)."""
    kinds = pair_kinds(model)
    ok_kind = np.isin(kinds, ["Capsule", "Sphere"]).all(axis=1)
    mask = ok_kind[None, :] & (d_ref > tol.differential_unique_min_distance)
    both_caps = np.flatnonzero(ok_kind & (kinds == "Capsule").all(axis=1))
    if both_caps.size:
        axes = capsule_axes(model, Q) if axes is None else axes
        names = model.pairs.names
        for k in both_caps:
            ia, ib = model.geometry_index(names[k, 0]), model.geometry_index(names[k, 1])
            s = np.linalg.norm(np.cross(axes[ia], axes[ib]), axis=1)
            mask[:, k] &= s > tol.differential_parallel
    return mask


def _quant(x: np.ndarray) -> dict:
    if x.size == 0:
        return {"n": 0, "max": None, "p99": None, "median": None}
    return {"n": int(x.size), "max": float(x.max()), "p99": float(np.quantile(x, 0.99)), "median": float(np.median(x))}


def reproduce_command(spec: str, backends, q, pair=None, options=None, as_json: bool = False) -> str:
    """One shell line that prints every backend's answer at ``q`` (pin order) for ``pair`` (``as_json``: as JSON,
    the form that shows a verdicts-only backend's answers)."""
    parts = ["armguard", "compare", spec, "--backends", ",".join(backends), "--q", ",".join(repr(float(v)) for v in q)]
    if pair is not None:
        parts += ["--pair", f"{pair[0]},{pair[1]}"]
    for b, opts in (options or {}).items():
        for k, v in opts.items():
            parts += ["--backend-option", f"{b}.{k}={v}"]
    if as_json:
        parts.append("--json")
    return " ".join(shlex.quote(p) for p in parts)


def sign_disagreements(da: np.ndarray, db: np.ndarray, band: float, tol) -> np.ndarray:
    """Entries apart (``> band``) by one answer and inside (``< -band``) by the other, or out of the contact
    band by one only and farther than ``tol`` from the other (0.25 m against -0.12 m; not 1.1 against 0.9 µm,
    both apart, one in the band)."""
    opposite = ((da > band) & (db < -band)) | ((da < -band) & (db > band))
    one_out = (np.abs(da) > band) != (np.abs(db) > band)
    return opposite | (one_out & (np.abs(da - db) > tol))


def _contract(ans, cols, nonunique, tol_pair) -> dict:
    gap = np.linalg.norm(ans.p_WA[:, cols] - ans.p_WB[:, cols], axis=2)
    viol = np.abs(gap - np.abs(ans.distance[:, cols]))
    sel = nonunique[:, cols]
    bad = sel & (viol > tol_pair[cols][None, :])
    sep = ans.distance[:, cols] > 0
    return {"checked": int(sel.sum()), "violations": int(bad.sum()), "violations_separated": int((bad & sep).sum()),
            "max_violation": float(viol[sel].max()) if sel.any() else None}


def _pair_summary(model, configs, A, B, R, a, b, cats, tol, tol_pair, unique, n_worst, spec, options, refs) -> tuple:
    band = tol.differential_contact_band
    err = np.abs(A.distance - B.distance)
    out = {"a": a, "b": b, "reference": reference_of(a, b)}
    n_cfg = len(configs)
    dmin_a = A.distance.min(axis=1) if A.distance.size else np.zeros(n_cfg)
    dmin_b = B.distance.min(axis=1) if B.distance.size else np.zeros(n_cfg)
    differ = A.verdict != B.verdict
    out_band = differ & ((np.abs(dmin_a) > band) | (np.abs(dmin_b) > band))  # in the band only when both are
    out["verdict_disagreements"] = int(out_band.sum())
    out["verdict_disagreements_in_band"] = int((differ & ~out_band).sum())
    out["max_abs_distance_error"] = float(err.max()) if err.size else 0.0
    groups = {"all": np.arange(len(model.pairs))}
    groups.update({c: np.flatnonzero(cats == c) for c in dict.fromkeys(model.pairs.category)})
    per = {}
    sep_all = (A.distance > band) & (B.distance > band)
    pen_all = (A.distance < -band) & (B.distance < -band)
    for c, cols in groups.items():
        da, db = A.distance[:, cols], B.distance[:, cols]
        e = err[:, cols]
        sep, pen = sep_all[:, cols], pen_all[:, cols]
        sign = sign_disagreements(da, db, band, tol_pair[cols][None, :])
        ma, mb = da.min(axis=1), db.min(axis=1)
        cat_out = ((ma <= 0) != (mb <= 0)) & ((np.abs(ma) > band) | (np.abs(mb) > band))
        u = unique[:, cols]
        dpa = np.linalg.norm(A.p_WA[:, cols] - B.p_WA[:, cols], axis=2)[u]
        dpb = np.linalg.norm(A.p_WB[:, cols] - B.p_WB[:, cols], axis=2)[u]
        per[c] = {
            "pairs": int(len(cols)),
            "verdict_disagreements": int(cat_out.sum()),
            "sign_disagreements": int(sign.sum()),
            "separated": _quant(e[sep]),
            "penetrating": _quant(e[pen]),
            "separated_over_tolerance": int((e > tol_pair[cols][None, :])[sep].sum()),
            "unique_points": {"n": int(u.sum()), "p_WA": _quant(dpa), "p_WB": _quant(dpb),
                              "over_tolerance": int(((dpa > tol.differential_unique_point) | (dpb > tol.differential_unique_point)).sum())},
            "witness_contract": {x: _contract(X, cols, ~unique, tol_pair) for x, X in ((a, A), (b, B))},
        }
    out["categories"] = per
    out["speed_ratio"] = {"distances": A.us_per_config and B.us_per_config / A.us_per_config,
                          "yes_no": B.yes_no_per_s and A.yes_no_per_s / B.yes_no_per_s}
    out["worst"] = _worst(model, configs, A, B, a, b, err, out_band, tol_pair, n_worst, spec, options, refs)
    al = per["all"]
    out["unjudged"] = {"penetrating": int(pen_all.sum())}  # depths: reported (``penetrating``), not judged
    ok = (out["verdict_disagreements"] == 0 and al["separated_over_tolerance"] == 0 and al["sign_disagreements"] == 0
          and al["unique_points"]["over_tolerance"] == 0
          and all(w["violations_separated"] == 0 for w in al["witness_contract"].values()))
    return out, PairStatus.AGREE if ok else PairStatus.DIFFER


def _entry(model, configs, A, B, a, b, i, k, spec, options, why):
    q = configs.Q[i]
    pair = tuple(model.pairs.names[k])
    return {"why": why, "config": configs.number(i), "source": str(configs.source[i]), "q": q.tolist(), "pair": list(pair),
            "category": model.pairs.category[k],
            a: {"distance": float(A.distance[i, k]), "p_WA": A.p_WA[i, k].tolist(), "p_WB": A.p_WB[i, k].tolist(),
                "collides": bool(A.verdict[i])},
            b: {"distance": float(B.distance[i, k]), "p_WA": B.p_WA[i, k].tolist(), "p_WB": B.p_WB[i, k].tolist(),
                "collides": bool(B.verdict[i])},
            "abs_distance_error": float(abs(A.distance[i, k] - B.distance[i, k])),
            "reproduce": reproduce_command(spec, (a, b), q, pair, options)}


def _worst(model, configs, A, B, a, b, err, out_band, tol_pair, n_worst, spec, options, refs: dict) -> list:
    rows = []
    for i in np.flatnonzero(out_band)[:n_worst]:
        k = int(np.argmin(np.minimum(A.distance[i], B.distance[i])))
        rows.append(_entry(model, configs, A, B, a, b, i, k, spec, options, "verdict"))
    if err.size:
        flat = np.argsort(err, axis=None)[::-1][:n_worst]
        for f in flat:
            i, k = (int(x) for x in np.unravel_index(f, err.shape))
            row = _entry(model, configs, A, B, a, b, i, k, spec, options, "distance")
            if err[i, k] > tol_pair[k]:
                if (i, k) not in refs:  # once per entry, whichever backend pairs list it
                    refs[i, k] = reference_distance(model, configs.Q[i], k)
                row["slow_reference"] = judged(refs[i, k], {a: A.distance[i, k], b: B.distance[i, k]})
            rows.append(row)
    return rows


def reference_distance(model, q, k: int) -> dict:
    """The slow reference's signed distance of pair ``k`` at ``q`` (Pinocchio's order): ``{"distance",
    "method"}`` (see the module docstring; a workspace pair: the shape against the box's six walls,
    :func:`armguard.geometry._support_reference.reference_wall_distance`), or ``{"distance": None,
    "why"}`` where a shape has no armguard equivalent (a coal geometry :func:`placed_shapes` refuses)."""
    from .._errors import GeometryError, SceneError
    from ..geometry._support_reference import reference_signed_distance, reference_wall_distance
    from ..model._model import WORKSPACE
    from ..model._shapes import placed_shapes

    na, nb = model.pairs.names[k]
    try:
        if nb == WORKSPACE:
            ws = model.workspace
            return {"distance": reference_wall_distance(placed_shapes(model, q, [na])[0], ws.lo, ws.hi),
                    "method": REFERENCE_WALLS}
        return {"distance": reference_signed_distance(*placed_shapes(model, q, (na, nb))), "method": REFERENCE_METHOD}
    except (SceneError, GeometryError) as e:  # no armguard shape for a geometry: say so, decide nothing
        return {"distance": None, "why": f"{type(e).__name__}: {e}"}


def judged(ref: dict, answers: dict) -> dict:
    """``ref`` (:func:`reference_distance`) with each backend's error against it (``answers``: backend
    -> signed distance, m)."""
    if ref["distance"] is None:
        return dict(ref)
    return {**ref, "error": {name: float(abs(v - ref["distance"])) for name, v in answers.items()}}


def compare_answers(model, configs, answers: dict, *, spec: str, options=None, tol: Tolerances = DEFAULT_TOLERANCES,
                    n_worst: int = 5) -> Comparison:
    """The :class:`Comparison` of every backend pair (in ``answers``' order) on ``configs``."""
    backends = list(answers)
    cats = np.asarray(model.pairs.category, dtype=object)
    tol_pair = pair_distance_tolerance(model, tol)
    axes = capsule_axes(model, configs.Q)
    per_backend = {}
    dist = [ans for ans in answers.values() if not ans.verdicts_only]
    fastest = min((ans.us_per_config for ans in dist), default=None)
    fastest_yn = max(ans.yes_no_per_s for ans in answers.values())
    for b, ans in answers.items():
        per_backend[b] = {"answers": "verdicts" if ans.verdicts_only else "distances",
                          "us_per_config": ans.us_per_config,
                          "us_per_config_of": "collides(Q)" if ans.verdicts_only else "pair_distances(q)",
                          "yes_no_configs_per_s": ans.yes_no_per_s,
                          "distances_vs_fastest": ans.us_per_config / fastest if fastest and not ans.verdicts_only else None,
                          "yes_no_vs_fastest": fastest_yn / ans.yes_no_per_s if ans.yes_no_per_s else None,
                          "options": dict((options or {}).get(b, {}))}
        if ans.verdicts_only:
            per_backend[b].update(verdict_backend_summary(ans))
    groups = {"all": np.arange(len(model.pairs))}
    groups.update({c: np.flatnonzero(cats == c) for c in dict.fromkeys(model.pairs.category)})
    pairs, status, refs = {}, {}, {}  # refs: (config, pair) -> the slow reference's answer, made once
    for a, b in itertools.combinations(backends, 2):
        key = f"{a}/{b}"
        if answers[a].verdicts_only or answers[b].verdicts_only:
            pairs[key], ok = verdict_pair_summary(model, configs, answers, a, b, groups, tol, n_worst, spec, options,
                                                  reproduce_command)
            status[key] = PairStatus.AGREE if ok else PairStatus.DIFFER
        else:
            R = answers[reference_of(a, b)]
            unique = unique_witness_mask(model, configs.Q, R.distance, tol, axes)
            pairs[key], status[key] = _pair_summary(model, configs, answers[a], answers[b], R, a, b, cats, tol, tol_pair,
                                                    unique, n_worst, spec, options, refs)
        pairs[key]["status"] = status[key].value
    summary = {
        "model": model.name, "spec": spec, "n_pairs": len(model.pairs),
        "categories": list(dict.fromkeys(model.pairs.category)),
        "configs": {"total": len(configs), "random": configs.n_random, "seed": configs.seed,
                    "trajectories": dict(configs.trajectories)},
        "tolerances": tol.differential(),
        "backends": per_backend,
        "pairs": pairs,
    }
    return Comparison(model, spec, configs, answers, summary, status)
