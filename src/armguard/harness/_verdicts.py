"""A verdicts-only backend against a distance backend: wrong answers by kind, undecided shares, per category.

A backend without ``Capability.DISTANCES`` (``clip``, ``forbidden``) is judged by its ``collides(Q)``
against the truth of a distance backend, the pair's **reference** (the other side of the pair; where
both sides answer verdicts only, ``coal`` if the run has it, else the run's first distance backend).
Counts are over configurations unless they say pairs; ``band`` is the contact band (m).

* **truth**: the reference's least signed distance ``d_min`` (m) over the active pairs (of a
  category) is ``<= band``: a configuration collides (touching within the band counts as a collision).
* **unsafe** ("said clear but collides"): ``collides`` False where the truth collides — must be 0;
  ``unsafe_in_band``: those with ``|d_min| <= band``.
* **conservative** ("said collision but clear"): ``collides`` True where ``d_min > band``; its share
  of all configurations and of the clear ones.
* **verdict disagreements** (as for distance pairs): ``collides != (d_min <= 0)`` where
  ``|d_min| > band``; those inside the band counted apart.
* **three-valued** answers where the backend exposes them (clip's ``check_pairs``: CLEAR /
  INTERSECTED / MAYBE, after the 8 steps and with the second level; forbidden's ``verdicts``: FREE /
  COLLISION / MAP_FORBIDDEN): the definite answers that are wrong (CLEAR where it collides,
  INTERSECTED or COLLISION where it is clear) and the undecided share (``maybe_share``; forbidden:
  MAP_FORBIDDEN, whose clear part is the **false-forbidden** rate).
* **per category** where the backend answers per pair (clip): a category's code is INTERSECTED if
  one of its pairs is, else MAYBE if one is, else CLEAR, against the category's ``d_min``.
* **status**: DIFFER when an answer is unsafe or a definite answer is wrong (per configuration, per
  category or per pair); MAYBE and MAP_FORBIDDEN are conservative by design and never a difference.
"""

from __future__ import annotations

import numpy as np

from ._evaluate import CLEAR, COLLISION, UNDECIDED, combine_codes

__all__ = ["verdict_pair_summary", "verdict_backend_summary", "truth_backend", "code_names", "NA"]

NA = "n/a (verdicts only)"


def truth_backend(answers: dict):
    """The run's distance backend that judges two verdicts-only ones: ``coal`` if present, else the first; or None."""
    dist = [b for b, ans in answers.items() if not ans.verdicts_only]
    return "coal" if "coal" in dist else (dist[0] if dist else None)


def code_names(forbidden: bool) -> dict:
    """``{code: name}`` of the three-valued codes: clip's, or (``forbidden``) the forbidden backend's."""
    if forbidden:
        return {CLEAR: "free", COLLISION: "collision", UNDECIDED: "map_forbidden"}
    return {CLEAR: "clear", COLLISION: "intersected", UNDECIDED: "maybe"}


def verdict_backend_summary(ans) -> dict:
    """A verdicts-only backend's own figures (no reference needed): its undecided share per configuration,
    and the time of its three-valued query ``detail_s`` (s; not part of its yes/no rate)."""
    out = {"detail_s": ans.t_detail}
    if ans.codes is not None:
        und = _share(ans.codes == UNDECIDED)
        if ans.map_forbidden is not None:
            out["map_forbidden_share"] = und
        else:
            out["maybe_share"] = und
            if ans.codes_first is not None:
                out["maybe_share_first_level"] = _share(ans.codes_first == UNDECIDED)
    return out


def _share(mask, of=None) -> float:
    n = mask.size if of is None else int(of)
    return float(mask.sum()) / n if n else 0.0


def _levels(codes, truth) -> dict:
    """Counts of one three-valued answer ``(M,) int8`` against ``truth (M,) bool``."""
    und = codes == UNDECIDED
    return {"clear": int((codes == CLEAR).sum()), "collision": int((codes == COLLISION).sum()), "undecided": int(und.sum()),
            "undecided_share": _share(und), "clear_but_collides": int(((codes == CLEAR) & truth).sum()),
            "collision_but_clear": int(((codes == COLLISION) & ~truth).sum()),
            "undecided_colliding": int((und & truth).sum()), "undecided_clear": int((und & ~truth).sum())}


def _side(V, R, groups, band) -> dict:
    """One verdicts-only backend's answers ``V`` against the reference ``R`` (both BackendAnswers)."""
    M = len(V.verdict)
    D = R.distance
    dmin = D.min(axis=1) if D.shape[1] else np.full(M, np.inf)
    truth = dmin <= band
    said = V.verdict
    in_band = np.abs(dmin) <= band
    wrong = said != (dmin <= 0)
    unsafe = ~said & truth
    cons = said & ~truth
    n_clear = int((~truth).sum())
    out = {"configurations": M, "reference_collisions": int(truth.sum()), "said_collision": int(said.sum()),
           "verdict_disagreements": int((wrong & ~in_band).sum()), "verdict_disagreements_in_band": int((wrong & in_band).sum()),
           "unsafe_disagreements": int(unsafe.sum()), "unsafe_in_band": int((unsafe & in_band).sum()),
           "conservative_disagreements": int(cons.sum()), "conservative_share": _share(cons),
           "conservative_share_of_clear": _share(cons, n_clear),
           "maybe_share": None, "maybe_share_first_level": None, "three_valued": None, "false_forbidden": None,
           "pair_level": None}
    wrong_definite = 0
    if V.codes is not None:
        levels = {"second_level": _levels(V.codes, truth)}
        if V.codes_first is not None:
            levels["first_level"] = _levels(V.codes_first, truth)
        out["three_valued"] = {"names": {str(k): v for k, v in code_names(V.map_forbidden is not None).items()}, **levels}
        wrong_definite += levels["second_level"]["clear_but_collides"] + levels["second_level"]["collision_but_clear"]
        if V.map_forbidden is None:
            out["maybe_share"] = levels["second_level"]["undecided_share"]
            if "first_level" in levels:
                out["maybe_share_first_level"] = levels["first_level"]["undecided_share"]
    if V.map_forbidden is not None:
        ff = V.map_forbidden & ~truth
        out["false_forbidden"] = {"n": int(ff.sum()), "share": _share(ff), "share_of_clear": _share(ff, n_clear),
                                  "map_forbidden_share": _share(V.map_forbidden),
                                  "reached_geometric_share": 1.0 - _share(V.map_forbidden)}
    cats = {"all": {"pairs": int(D.shape[1]), "reference_collisions": int(truth.sum()), "clear_but_collides": int(unsafe.sum()),
                    "collision_but_clear": None, "conservative_share": _share(cons),
                    "undecided_share": None, "undecided_share_first_level": None}}
    if V.codes is not None:
        cats["all"]["collision_but_clear"] = out["three_valued"]["second_level"]["collision_but_clear"]
        cats["all"]["undecided_share"] = out["three_valued"]["second_level"]["undecided_share"]
        if "first_level" in out["three_valued"]:
            cats["all"]["undecided_share_first_level"] = out["three_valued"]["first_level"]["undecided_share"]
    if V.pair_codes is not None:
        pt = D <= band
        pc = V.pair_codes
        out["pair_level"] = {"entries": int(pc.size), "clear_but_collides": int(((pc == CLEAR) & pt).sum()),
                             "collision_but_clear": int(((pc == COLLISION) & ~pt).sum()),
                             "maybe_share": _share(pc == UNDECIDED),
                             "maybe_share_first_level": _share(V.pair_codes_first == UNDECIDED)
                             if V.pair_codes_first is not None else None}
        wrong_definite += out["pair_level"]["clear_but_collides"] + out["pair_level"]["collision_but_clear"]
        for c, cols in groups.items():
            if c == "all":
                continue
            t = D[:, cols].min(axis=1) <= band if len(cols) else np.zeros(M, bool)
            code = combine_codes(pc[:, cols])
            first = combine_codes(V.pair_codes_first[:, cols]) if V.pair_codes_first is not None else None
            cats[c] = {"pairs": int(len(cols)), "reference_collisions": int(t.sum()),
                       "clear_but_collides": int(((code == CLEAR) & t).sum()),
                       "collision_but_clear": int(((code == COLLISION) & ~t).sum()),
                       "conservative_share": _share((code != CLEAR) & ~t), "undecided_share": _share(code == UNDECIDED),
                       "undecided_share_first_level": _share(first == UNDECIDED) if first is not None else None}
            wrong_definite += cats[c]["clear_but_collides"] + cats[c]["collision_but_clear"]
        out["per_category"] = "per pair (check_pairs)"
    else:
        out["per_category"] = "n/a (the backend answers per configuration only)"
    out["categories"] = cats
    out["_wrong"] = out["unsafe_disagreements"] + wrong_definite
    out["_masks"] = (dmin, truth, unsafe, cons)
    return out


def _worst(model, configs, V, R, v, r, side, band, n_worst, spec, options, reproduce_command) -> list:
    """Unsafe answers (deepest first), wrong definite collisions and conservative ones (clearest first),
    per-pair unsafe codes: ``n_worst`` of each, with the line that reproduces each."""
    dmin, truth, unsafe, cons = side["_masks"]
    D = R.distance
    names = code_names(V.map_forbidden is not None)
    rows = []

    def entry(why, i, k):
        """Configuration ``i``; pair ``k``, else the reference's nearest among the pairs the backend
        answers as the entry says (CLEAR for an unsafe one, else not CLEAR), where it answers per pair."""
        q = configs.Q[i]
        if k is None:
            d = D[i].copy()
            if V.pair_codes is not None:
                sel = (V.pair_codes[i] == CLEAR) if why == "unsafe" else (V.pair_codes[i] != CLEAR)
                if why == "wrong_collision":
                    sel = V.pair_codes[i] == COLLISION
                if sel.any():
                    d[~sel] = np.inf
            k = int(np.argmin(d))
        pair = tuple(model.pairs.names[k])
        mine = {"collides": bool(V.verdict[i]),
                "verdict": names[int(V.codes[i])] if V.codes is not None else None,
                "pair_verdict": names[int(V.pair_codes[i, k])] if V.pair_codes is not None else None}
        return {"why": why, "config": configs.number(i), "source": str(configs.source[i]), "q": q.tolist(), "pair": list(pair),
                "category": model.pairs.category[k], v: mine,
                r: {"distance": float(D[i, k]), "least_distance": float(dmin[i]), "p_WA": R.p_WA[i, k].tolist(),
                    "p_WB": R.p_WB[i, k].tolist(), "collides": bool(R.verdict[i])},
                "reproduce": reproduce_command(spec, (v, r), q, pair, options, as_json=True)}

    for i in np.flatnonzero(unsafe)[np.argsort(dmin[unsafe], kind="stable")][:n_worst]:
        rows.append(entry("unsafe", i, None))
    if V.codes is not None:
        bad = (V.codes == COLLISION) & ~truth
        for i in np.flatnonzero(bad)[np.argsort(-dmin[bad], kind="stable")][:n_worst]:
            rows.append(entry("wrong_collision", i, None))
    if V.pair_codes is not None:
        bad = (V.pair_codes == CLEAR) & (D <= band)
        for i, k in np.argwhere(bad & ~unsafe[:, None])[:n_worst]:
            rows.append(entry("unsafe_pair", int(i), int(k)))
    for i in np.flatnonzero(cons)[np.argsort(-dmin[cons], kind="stable")][:n_worst]:
        rows.append(entry("conservative", i, None))
    return rows


def verdict_pair_summary(model, configs, answers, a, b, groups, tol, n_worst, spec, options, reproduce_command) -> tuple:
    """``(summary dict, ok)`` of backend pair ``a/b`` where at least one side answers verdicts only."""
    band = tol.differential_contact_band
    A, B = answers[a], answers[b]
    if A.verdicts_only != B.verdicts_only:
        sides = [a] if A.verdicts_only else [b]
        ref = b if A.verdicts_only else a
    else:
        sides, ref = [a, b], truth_backend(answers)
    out = {"a": a, "b": b, "reference": ref, "answers": "verdicts", "verdicts_only": sides,
           "distances": NA, "witness_points": NA, "max_abs_distance_error": None}
    yn = B.yes_no_per_s and A.yes_no_per_s / B.yes_no_per_s
    out["speed_ratio"] = {"distances": None, "yes_no": yn}
    if ref is None:  # two verdicts-only backends and no distance backend to judge them
        differ = A.verdict != B.verdict
        out.update(verdict_disagreements=int(differ.sum()), verdict_disagreements_in_band=0, unsafe_disagreements=None,
                   maybe_share=None, categories={"all": {"pairs": len(model.pairs), "disagreements": int(differ.sum())}},
                   worst=[], note="no backend of the run answers distances to judge them: they agree only where "
                                  "their verdicts are the same (add coal or analytic to judge which is wrong)")
        return out, not differ.any()  # an unjudged disagreement is not "agree"
    R = answers[ref]
    per = {}
    for s in sides:
        per[s] = _side(answers[s], R, groups, band)
    worst = []
    for s in sides:
        worst += _worst(model, configs, answers[s], R, s, ref, per[s], band, n_worst, spec, options, reproduce_command)
    wrong = sum(per[s].pop("_wrong") for s in sides)
    for s in sides:
        per[s].pop("_masks")
    if len(sides) == 1:
        out.update(per[sides[0]])
    else:
        dmin = R.distance.min(axis=1) if R.distance.shape[1] else np.full(len(configs), np.inf)
        differ = A.verdict != B.verdict
        out.update(verdict_disagreements=int((differ & (np.abs(dmin) > band)).sum()),
                   verdict_disagreements_in_band=int((differ & (np.abs(dmin) <= band)).sum()),
                   unsafe_disagreements=sum(per[s]["unsafe_disagreements"] for s in sides), maybe_share=None,
                   categories={"all": {"pairs": len(model.pairs), "disagreements": int(differ.sum())}}, sides=per)
    out["worst"] = worst
    return out, wrong == 0


def _pct(x) -> str:
    return "—" if x is None else f"{100 * x:.2f} %"


def _n(x) -> str:
    return "—" if x is None else str(x)


def verdict_tables(summary: dict, p: dict) -> list:
    """Rich renderables for a verdicts-only pair ``p`` of ``summary`` (compare.json): per category, then its
    wrong and conservative configurations with their reproduce lines."""
    from rich.table import Table

    v = ",".join(p["verdicts_only"])
    t = Table(title=f"{summary['model']}: {p['a']} vs {p['b']} — {v} answers verdicts only (truth: {p['reference']}'s "
                    f"least distance <= {summary['tolerances']['contact_band']:g} m), {summary['configs']['total']} "
                    f"configurations — {p['status']}", title_justify="left")
    und = "map-forbidden" if p.get("false_forbidden") else "MAYBE"
    for col in ("category", "pairs", "collide (reference)", "said clear, collides", "definite collision, clear",
                "conservative", f"{und} (first level)", und):
        t.add_column(col, justify="right" if col != "category" else "left")
    for c, r in p["categories"].items():
        if "reference_collisions" not in r:  # two verdicts-only backends
            t.add_row(c, str(r["pairs"]), "—", "—", f"{r['disagreements']} disagree", "—", "—", "—")
            continue
        t.add_row(c, str(r["pairs"]), str(r["reference_collisions"]), _n(r["clear_but_collides"]),
                  _n(r["collision_but_clear"]), _pct(r["conservative_share"]), _pct(r["undecided_share_first_level"]),
                  _pct(r["undecided_share"]))
    notes = [f"distances and witness points: {NA}", f"per category: {p.get('per_category', '—')}"]
    if p.get("unsafe_disagreements") is not None and "configurations" in p:
        notes.append(f"unsafe (said clear, collides): {p['unsafe_disagreements']} (within the band: {p['unsafe_in_band']}); "
                     f"said collision but clear: {p['conservative_disagreements']} = {_pct(p['conservative_share'])} of "
                     f"all, {_pct(p['conservative_share_of_clear'])} of the clear ones; verdict disagreements outside "
                     f"the band {p['verdict_disagreements']} (inside {p['verdict_disagreements_in_band']})")
    tv = p.get("three_valued")
    if tv:
        lv = tv["second_level"]
        notes.append(f"definite answers wrong: {lv['clear_but_collides']} clear but colliding, {lv['collision_but_clear']} "
                     f"{tv['names']['1']} but clear; {tv['names']['2']}: {lv['undecided']} ({_pct(lv['undecided_share'])}: "
                     f"{lv['undecided_colliding']} colliding, {lv['undecided_clear']} clear)")
    if p.get("pair_level"):
        pl = p["pair_level"]
        notes.append(f"per pair ({pl['entries']} checks): {pl['clear_but_collides']} clear but colliding, "
                     f"{pl['collision_but_clear']} intersected but clear; MAYBE {_pct(pl['maybe_share_first_level'])} -> "
                     f"{_pct(pl['maybe_share'])}")
    ff = p.get("false_forbidden")
    if ff:
        notes.append(f"false-forbidden (map refused, clear): {ff['n']} = {_pct(ff['share'])} of all, "
                     f"{_pct(ff['share_of_clear'])} of the clear ones; the map refused {_pct(ff['map_forbidden_share'])}, "
                     f"{_pct(ff['reached_geometric_share'])} reached the geometric check")
    yn = p["speed_ratio"]["yes_no"]
    notes.append(f"{p['b']}/{p['a']} yes/no time: " + ("—" if yn is None else f"{yn:.2f}×"))
    t.caption = "\n".join(notes)
    out = [t]
    if p["worst"]:
        from rich.text import Text

        out.append(Text(f"{p['a']} vs {p['b']}: wrong and conservative configurations", style="bold"))
        for e in p["worst"]:
            mine = next(e[b] for b in p["verdicts_only"] if b in e)
            ans = mine["verdict"] or ("collision" if mine["collides"] else "clear")
            if mine["pair_verdict"]:
                ans += f" (pair: {mine['pair_verdict']})"
            ref = e[p["reference"]]
            out.append(Text(f"  {e['why']:15s} #{e['config']} ({e['source']}) {e['pair'][0]} / {e['pair'][1]}: "
                            f"{ans}; {p['reference']} {ref['distance']:.6e} m (least {ref['least_distance']:.6e} m)"))
            out.append(Text(f"    {e['reproduce']}", style="dim", no_wrap=True, overflow="ignore"))
    return out
