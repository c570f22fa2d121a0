"""Linting an SRDF against the certified search: disabled pairs that can collide, checked pairs that never do.

For every pair the SRDF disables (other than links joined by a joint, or through links without
geometry, which touch at their joint by construction) the certified search of :mod:`._prove`
either finds a configuration where it comes within the margin -- the SRDF hides a collision
there -- or proves it cannot.  For every pair the SRDF checks, a proof of *never* means the check
is wasted work.  Witness configurations are in ``pin_model``'s order.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import pinocchio as pin

from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number, whole_number
from ._matrix import PairEvaluator, _progress, prove_one
from ._pairs import pair_setup
from ._prove import PairVerdict

__all__ = ["SrdfLint", "check_srdf"]


@dataclass(frozen=True)
class SrdfLint:
    """The findings of :func:`check_srdf`.

    ``can_collide``: dicts ``{link1, link2, reason, q, distance}`` -- a pair the SRDF disables
    (``reason`` as it says) that comes within the margin at ``q`` (``pin_model`` order), signed
    ``distance`` m there (``< 0``: the penetration depth; ``coal_distance`` the reference's, where the evaluator is
    another backend).  ``never_checked``: ``{link1, link2}``
    pairs the SRDF checks that are proven never within the margin.  ``undecided``: pairs neither
    proven nor witnessed (``disabled`` says which side of the SRDF they are on).  ``adjacent``:
    disabled pairs joined by a joint (not searched); ``skipped``: disabled pairs not searched,
    ``{link1, link2, reason, why}``, ``why`` either ``"no geometry"`` (a link of the robot without
    collision geometry: nothing to check) or ``"unknown link"`` (a link the URDF lacks: a typo or
    an SRDF of another robot; ``load_model`` refuses such an SRDF unless it was found under the
    robot's name, see :attr:`unknown_links`).
    """

    model: str
    srdf: str
    margin: float
    joint_names: tuple
    can_collide: tuple
    never_checked: tuple
    undecided: tuple
    proven_disabled: tuple
    adjacent: tuple
    skipped: tuple
    elapsed_s: float

    def to_dict(self) -> dict:
        return {"model": self.model, "srdf": self.srdf, "margin": self.margin, "joint_names": list(self.joint_names),
                "can_collide": [dict(d) for d in self.can_collide], "never_checked": [dict(d) for d in self.never_checked],
                "undecided": [dict(d) for d in self.undecided], "proven_disabled": [dict(d) for d in self.proven_disabled],
                "adjacent": [dict(d) for d in self.adjacent], "skipped": [dict(d) for d in self.skipped],
                "elapsed_s": self.elapsed_s}

    @property
    def unknown_links(self) -> tuple:
        """The ``skipped`` pairs naming a link the URDF lacks (``why == "unknown link"``)."""
        return tuple(d for d in self.skipped if d["why"] == "unknown link")


def check_srdf(model, srdf, *, margin: float = 0.0, backend: str | None = "analytic", options=None,
               workers: int | None = None, min_width: float = 1e-3, max_evaluations: int = 200_000, progress=False,
               seed: int = 0, tol: Tolerances = DEFAULT_TOLERANCES, pairs=None) -> SrdfLint:
    """Lint the SRDF file ``srdf`` for ``model`` (a Model or a name / path, loaded without an SRDF);
    ``pairs``: only these ``(link1, link2)`` (``armguard check-urdf`` searches the pairs whose certificate broke);
    ``progress`` as :func:`collision_matrix` takes it."""
    from .._errors import VerificationError
    from ..model._srdf import read_srdf

    margin = number(margin, "margin", VerificationError, low=0.0, unit=" (m)")
    if workers is not None:
        workers = whole_number(workers, "workers", VerificationError, low=1)
    max_evaluations = whole_number(max_evaluations, "max_evaluations", VerificationError, low=1)
    min_width = number(min_width, "min_width", VerificationError, low=0.0, low_open=True, unit=" (rad)")
    if not hasattr(model, "pin_model"):
        from ..model import load_model

        model = load_model(model, srdf=False)
    sr = read_srdf(srdf)
    t0 = time.perf_counter()
    setup = pair_setup(model, tol)
    ev = PairEvaluator(model, setup, backend, options)
    index = {frozenset((p.link1, p.link2)): k for k, p in enumerate(setup.pairs)}
    disabled: dict = {}
    skipped = []
    links = {f.name for f in model.pin_model.frames if f.type == pin.FrameType.BODY}
    for a, b, reason in sr.disabled:
        k = index.get(frozenset((a, b)))
        if k is None:
            if a != b:
                why = "no geometry" if a in links and b in links else "unknown link"
                skipped.append({"link1": a, "link2": b, "reason": reason, "why": why})
            continue
        disabled.setdefault(k, reason)
    adjacent = [{"link1": setup.pairs[k].link1, "link2": setup.pairs[k].link2, "reason": disabled[k]}
                for k in disabled if setup.pairs[k].adjacent]
    only = None if pairs is None else {frozenset(p) for p in pairs}
    todo = [k for k in range(len(setup.pairs)) if not setup.pairs[k].adjacent
            and (only is None or frozenset((setup.pairs[k].link1, setup.pairs[k].link2)) in only)]
    advance, close = _progress(progress, len(todo), model.name, f"linting {_file_name(srdf)}")

    limits = dict(margin=margin, contact=tol.verify_contact, min_width=min_width, max_evaluations=max_evaluations,
                  seed=seed)

    def one(k: int):  # the search armguard srdf makes (the same limits and seeds: the same verdicts)
        r = prove_one(setup, ev, k, limits)
        advance()
        return r

    try:
        if workers and int(workers) > 1:
            with ThreadPoolExecutor(int(workers)) as ex:
                results = list(ex.map(one, todo))
        else:
            results = [one(k) for k in todo]
    finally:
        close()
    can, never, und, proven = [], [], [], []
    for k, r in zip(todo, results):
        p = setup.pairs[k]
        base = {"link1": p.link1, "link2": p.link2}
        if k in disabled:
            if r.verdict is PairVerdict.WITNESSED:
                q = [float(x) for x in ev.pin(r.witness[None, :])[0]]
                can.append({**base, "reason": disabled[k], "q": q, "distance": float(r.distance)})
            elif r.verdict is PairVerdict.NEVER:
                proven.append({**base, "reason": disabled[k]})
            else:
                und.append({**base, "disabled": True})
        else:
            if r.verdict is PairVerdict.NEVER:
                never.append({**base, "clearance_lower_bound": float(r.lower_bound)})
            elif r.verdict is PairVerdict.UNDECIDED:
                und.append({**base, "disabled": False})
    _confirm(model, setup, ev, can, [k for k, r in zip(todo, results) if r.verdict is PairVerdict.WITNESSED and k in disabled],
             [r for k, r in zip(todo, results) if r.verdict is PairVerdict.WITNESSED and k in disabled], options)
    return SrdfLint(model.name, str(srdf), float(margin), tuple(model.joint_names), tuple(can), tuple(never), tuple(und),
                    tuple(proven), tuple(adjacent), tuple(skipped), time.perf_counter() - t0)


def _file_name(p) -> str:
    from pathlib import Path

    return Path(str(p)).name


def _confirm(model, setup, ev, can: list, ks: list, proofs: list, options) -> None:
    """Add ``coal_distance`` to each witness: the reference's distance at ``q`` (None where coal is not installed
    or is the evaluator already)."""
    from .._errors import ArmguardError

    if not can:
        return
    ref = None
    if ev.backend != "coal":
        try:
            ref = PairEvaluator(model, setup, "coal")
        except ArmguardError:
            ref = None
    for d, k, r in zip(can, ks, proofs):
        if ref is None:
            d["coal_distance"] = d["distance"] if ev.backend == "coal" else None
        else:
            d["coal_distance"] = float(ref(k, r.witness[None, :])[0])
