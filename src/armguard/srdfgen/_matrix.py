"""The collision matrix of a robot: which link pairs a checker may skip, and why.

Reasons are MoveIt's (its Setup Assistant's ``disable_collisions`` entries):

* **Adjacent** -- the links are joined by one joint, or through links without geometry;
* **Default** -- the pair is in contact (signed distance <= 0) at the home configuration;
* **Never** -- ``method="certified"``: *proven* never to come within ``margin`` anywhere within the
  joint limits, by branch and bound over the pair's joints with the certified verifier's lever-arm
  bounds (:mod:`._prove`); ``method="sampled"``: not seen within ``margin`` in ``samples`` random
  configurations (MoveIt's rule, 10^4 by default; :mod:`._sampled`);
* **Always** -- ``method="sampled"`` only: in contact in more than 95 % of 200 random configurations
  (MoveIt's rule).  The certified method gives none: a pair in contact everywhere is in contact at
  home, hence *Default* first.

Every other pair stays checked: *witnessed* (with a configuration where it comes within the margin)
or *undecided* (the search reached its box-width or evaluation limit; reported, never disabled).

The distances come from any backend that answers them (``backend``: analytic by default, coal
as the reference), over a Model whose active pairs are the robot's own link pairs
(:func:`armguard.cspace._clearance.checker_over`).
"""

from __future__ import annotations

import math

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from .._errors import VerificationError
from .._values import number, whole_number
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ..model._certificate import pair_digest, verdict_fingerprint
from ._io import read_previous
from ._pairs import pair_setup
from ._prove import PairVerdict, prove_pair

__all__ = ["MatrixEntry", "CollisionMatrix", "collision_matrix", "PairEvaluator", "REASONS", "METHODS"]

REASONS = ("Adjacent", "Default", "Never", "Always")
METHODS = ("certified", "sampled")


@dataclass(frozen=True)
class MatrixEntry:
    """One link pair: ``reason`` (one of :data:`REASONS`) when it is disabled, else None (checked).

    ``status``: ``"disabled"``, ``"witnessed"`` (checked: ``q`` is a configuration, in ``pin_model``'s
    order, where it comes within the margin, ``distance`` m there) or ``"undecided"`` (checked).
    ``how`` says how the verdict was established; ``evaluations`` the distance evaluations spent.
    """

    link1: str
    link2: str
    reason: str | None
    status: str
    q: tuple | None = None
    distance: float = float("nan")
    how: str = ""
    evaluations: int = 0
    fingerprint: str = ""  # what the verdict depends on, hashed (armguard.model._certificate)


@dataclass(frozen=True)
class CollisionMatrix:
    """The collision matrix of one model (see the module docstring)."""

    model: str
    method: str
    margin: float
    entries: tuple
    elapsed_s: float
    samples: int = 0
    joint_names: tuple = field(default=())
    kept: tuple = field(default=())  # (link1, link2) taken unchanged from ``previous`` (their certificate held)

    @property
    def disabled(self) -> tuple:
        """``(link1, link2, reason)`` of every disabled pair."""
        return tuple((e.link1, e.link2, e.reason) for e in self.entries if e.reason is not None)

    def count(self, key: str) -> int:
        """Entries whose reason or status is ``key`` (``"Never"``, ``"witnessed"``, ...)."""
        return sum(1 for e in self.entries if e.reason == key or e.status == key)

    def counts(self) -> dict:
        out = {r: self.count(r) for r in REASONS}
        out.update(witnessed=self.count("witnessed"), undecided=self.count("undecided"), pairs=len(self.entries))
        return out

    def write_srdf(self, path, keep=()) -> None:
        """Write the matrix as an SRDF (:func:`armguard.srdfgen.write_srdf`), with the elements ``keep``
        (``armguard.srdfgen._io.other_elements`` of the SRDF it replaces) first."""
        from ._io import write_srdf

        write_srdf(self, path, keep)


class PairEvaluator:
    """Signed distance of each link pair of a :class:`~._pairs.PairSetup` at flat scene configurations.

    ``__call__(k, Q (M, n_q)) -> (M,)``: the least distance over the geometry pairs of link pair ``k``;
    ``all(Q) -> (M, n_pairs)`` every link pair at once.
    """

    def __init__(self, model, setup, backend: str | None = "analytic", options=None) -> None:
        from ..cspace._clearance import checker_over

        from .._errors import ForbiddenMapError

        self.model = model
        self.setup = setup
        try:
            self.checker = checker_over(model, setup.scene, backend, options, need_distances=True,
                                        needs="proving pairs Never needs")
        except ForbiddenMapError as exc:
            raise VerificationError(str(exc)) from None
        self.backend = self.checker.name
        if getattr(self.checker, "distances_may_run_long", False):  # python-fcl: may never return on overlapping shapes
            raise VerificationError(f"evaluator {self.backend!r}: its distances may not return on overlapping shapes "
                                    "(python-fcl hung on hermes's adjacent cylinders); proving pairs Never needs "
                                    "distances that always return: use analytic or coal")
        gp = self.checker.model.pairs
        where: dict = {}
        for row, (a, b) in enumerate(zip(gp.owner_a, gp.owner_b)):
            where.setdefault(frozenset((a, b)), []).append(row)
        self.rows = [np.asarray(where.get(frozenset((p.owner1, p.owner2)), []), dtype=np.int64) for p in setup.pairs]
        missing = [(p.link1, p.link2) for p, r in zip(setup.pairs, self.rows) if not len(r)]
        if missing:
            raise VerificationError(f"backend {self.backend!r} checks no geometry of link pairs {missing[:3]}")
        self._all = np.concatenate(self.rows)
        self._owner = np.concatenate([np.full(len(r), k) for k, r in enumerate(self.rows)])

    def pin(self, Q: np.ndarray) -> np.ndarray:
        return self.checker.model.pin_q(Q)

    def __call__(self, k: int, Q: np.ndarray) -> np.ndarray:
        res = self.checker.pair_distances_many(self.pin(Q), pairs=self.rows[k])
        return np.min(res.distance, axis=1)

    def all(self, Q: np.ndarray, chunk: int = 2000, pairs=None) -> np.ndarray:
        """``(M, n_pairs)``, or ``(M, len(pairs))`` for the link pairs ``pairs`` only (their geometry
        alone is evaluated: an adjacent pair's overlapping meshes cost deep-penetration searches)."""
        if pairs is None:
            rows, owner, n = self._all, self._owner, len(self.rows)
        else:
            pairs = [int(k) for k in pairs]
            rows = np.concatenate([self.rows[k] for k in pairs]) if pairs else np.zeros(0, np.int64)
            owner = np.concatenate([np.full(len(self.rows[k]), i) for i, k in enumerate(pairs)]) if pairs else rows
            n = len(pairs)
        out = np.empty((len(Q), n))
        if n == 0:
            return out
        for s in range(0, len(Q), chunk):
            d = self.checker.pair_distances_many(self.pin(Q[s:s + chunk]), pairs=rows).distance
            block = np.full((len(d), n), np.inf)
            np.minimum.at(block.T, owner, d.T)
            out[s:s + chunk] = block
        return out


def _progress(progress, total: int, name: str, what: str):
    """``(advance(), close())`` of a rich progress bar labelled ``"<name>: <what>"`` (``progress=True``; a string:
    that name in place of the model's, e.g. the one the user gave), a callback, or nothing."""
    if progress is True or isinstance(progress, str):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        label = f"{progress if isinstance(progress, str) else name}: {what}"

        from rich.console import Console

        # on stderr: on stdout the bar went into piped output, and a closed pipe (| head -1) exited 1 ("unsafe")
        bar = Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), transient=False,
                       console=Console(stderr=True))
        bar.start()
        task = bar.add_task(label, total=total)
        return (lambda: bar.advance(task)), bar.stop
    if callable(progress):
        done = [0]

        def advance():
            done[0] += 1
            progress(done[0], total)

        return advance, (lambda: None)
    return (lambda: None), (lambda: None)


def collision_matrix(model, *, margin: float = 0.0, method: str = "certified", backend: str | None = "analytic",
                     options=None, workers: int | None = None, samples: int = 10_000, min_width: float = 1e-3,
                     max_evaluations: int = 200_000, progress=False, seed: int = 0,
                     tol: Tolerances = DEFAULT_TOLERANCES, previous=None, scheduler: str | None = None) -> CollisionMatrix:
    """The collision matrix of ``model`` (an :class:`armguard.Model`, or a name / path for
    :func:`armguard.load_model`, loaded without its SRDF).  See the module docstring.

    Parameters
    ----------
    margin : m, >= 0; a pair is *Never* only when proven (or seen) farther apart than this everywhere.
    method : "certified" | "sampled"
    workers : threads over the pairs (certified; None: one); with ``scheduler="local"`` the worker
        processes of a fresh Dask LocalCluster.
    scheduler : None (this process), ``"local"`` (a Dask LocalCluster of ``workers`` processes), or a
        Dask scheduler's address (``tcp://host:8786``): each worker loads the model from its file once
        and searches the pairs it is given (:mod:`._distributed`); the verdicts are the same.
    samples : random configurations of ``method="sampled"`` (MoveIt: 10^4 by default).
    min_width, max_evaluations : per pair, the certified search's limits (rad; distance evaluations).
    progress : True for a rich progress bar (labelled with the model's name; a string: with that name), or a
        ``callback(done, total)``.
    previous : an SRDF this command wrote before (``armguard srdf --update``): a pair whose fingerprint
        (:func:`armguard.model._certificate.pair_fingerprint`: its links' shapes, the joints between
        them, the margin and method) is the one recorded there keeps its verdict without a search.
    """
    if method not in METHODS:
        raise VerificationError(f"method: expected one of {list(METHODS)}, got {method!r}")
    margin = number(margin, "margin", VerificationError, low=0.0, unit=" (m)")
    if workers is not None:
        workers = whole_number(workers, "workers", VerificationError, low=1)
    samples = whole_number(samples, "samples", VerificationError, low=1)
    max_evaluations = whole_number(max_evaluations, "max_evaluations", VerificationError, low=1)
    min_width = number(min_width, "min_width", VerificationError, low=0.0, low_open=True, unit=" (rad)")
    if not hasattr(model, "pin_model"):
        from ..model import load_model

        model = load_model(model, srdf=False)
    t0 = time.perf_counter()
    setup = pair_setup(model, tol)
    ev = PairEvaluator(model, setup, backend, options)
    P = len(setup.pairs)
    d_home = ev.all(setup.home[None, :])[0]
    if not np.all(np.isfinite(d_home)):
        raise VerificationError("a distance at the home configuration is not finite: no verdict")
    home_pin = tuple(float(x) for x in ev.pin(setup.home[None, :])[0])
    digests = [pair_digest(model.pin_model, model.collision_model, p.link1, p.link2, margin=float(margin),
                           method=method) for p in setup.pairs]

    def certificate(k: int, reason) -> str:
        """Pair ``k``'s certificate of verdict ``reason`` (a disabled pair's; None: checked)."""
        return verdict_fingerprint(digests[k], reason) if digests[k] is not None else ""

    before = read_previous(previous) if previous is not None else {}
    entries: list = [None] * P
    todo = []
    kept = []
    for k, p in enumerate(setup.pairs):
        if p.adjacent:
            entries[k] = MatrixEntry(p.link1, p.link2, "Adjacent", "disabled", how="joined by a joint or through links without geometry")
        elif d_home[k] <= 0.0:
            entries[k] = MatrixEntry(p.link1, p.link2, "Default", "disabled", home_pin, float(d_home[k]), "in contact at home")
        elif (old := before.get(frozenset((p.link1, p.link2)))) is not None \
                and old.fingerprint == certificate(k, old.reason) \
                and old.reason not in ("Adjacent", "Default") and (old.q is None or len(old.q) == model.pin_model.nq):
            # (a witness of another configuration's size, after a joint became a mimic or was added: searched again)
            entries[k] = old
            kept.append((p.link1, p.link2))
        else:
            todo.append(k)
    advance, close = _progress(progress, len(todo), model.name, f"{method} collision matrix")
    try:
        if method == "certified":
            limits = dict(margin=float(margin), contact=tol.verify_contact, min_width=min_width,
                          max_evaluations=max_evaluations, seed=seed)
            if scheduler is not None:
                from ._distributed import prove_on_dask

                proofs = prove_on_dask(model, todo, limits, backend, workers, scheduler, advance)
                for k in todo:
                    entries[k] = _entry(setup.pairs[k], proofs[k], ev)
            else:
                def one(k: int) -> MatrixEntry:
                    r = prove_one(setup, ev, k, limits)
                    advance()
                    return _entry(setup.pairs[k], r, ev)

                if workers and int(workers) > 1:
                    with ThreadPoolExecutor(int(workers)) as ex:
                        for k, e in zip(todo, ex.map(one, todo)):
                            entries[k] = e
                else:
                    for k in todo:
                        entries[k] = one(k)
        else:
            from ._sampled import sampled

            sampled(ev, setup, todo, entries, float(margin), int(samples), seed, advance)
    finally:
        close()
    entries = [replace(e, fingerprint=certificate(k, e.reason)) for k, e in enumerate(entries)]
    return CollisionMatrix(model.name, method, float(margin), tuple(entries), time.perf_counter() - t0,
                           int(samples) if method == "sampled" else 0, tuple(model.joint_names), tuple(kept))


def prove_one(setup, ev, k: int, limits: dict):
    """The certified search of link pair ``k`` of ``setup`` (:func:`~._prove.prove_pair`) with ``limits``
    (margin, contact, min_width, max_evaluations, seed)."""
    p = setup.pairs[k]
    return prove_pair(lambda Q: ev(k, Q), setup.home, p.joints, setup.lower, setup.upper, p.weight,
                      margin=limits["margin"], contact=limits["contact"], min_width=limits["min_width"],
                      max_evaluations=limits["max_evaluations"], rng=np.random.default_rng(limits["seed"] + k))


def _entry(p, r, ev) -> MatrixEntry:
    """The matrix entry of link pair ``p`` from its search ``r``."""
    if r.verdict is PairVerdict.NEVER:
        return MatrixEntry(p.link1, p.link2, "Never", "disabled", None, r.lower_bound,
                           f"proven: {r.boxes} boxes over {len(p.joints)} joints, certified clearance >= "
                           f"{r.lower_bound:.4g} m", r.evaluations)
    if r.verdict is PairVerdict.WITNESSED:
        q = tuple(float(x) for x in ev.pin(r.witness[None, :])[0])
        return MatrixEntry(p.link1, p.link2, None, "witnessed", q, r.distance, "a configuration within the margin",
                           r.evaluations)
    return MatrixEntry(p.link1, p.link2, None, "undecided", None, float("nan"),
                       f"undecided after {r.evaluations} evaluations" + (f" (boxes down to {r.smallest_width:.2g} rad)"
                                                                         if math.isfinite(r.smallest_width) else " (no box split)"),
                       r.evaluations)
