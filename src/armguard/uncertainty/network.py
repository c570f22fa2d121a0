"""Networks of planar uncertain relations reduced to one relation (Smith & Cheeseman, Section 4.1).

Series relations are compounded (Eqns. 1–3) and parallel ones merged (Eqns. 5–7).  In one
dimension this is the paper's circuit analogy — variances are resistances, series ones add,
parallel ones combine by Eqn. (8) — and, as the paper says, "not all circuits can be analyzed
by a simple combination of serial and parallel calculations (e.g. the Wheatstone bridge)".  Its
remedy is followed here: "by deleting links in the uncertain transformation network, it is
possible to produce a reducible network ... By considering alternative deletions and finding the
set that gives the 'best' final covariance, it is usually possible to get an estimate that does
not significantly overestimate the final covariance."  ``reduce_network`` tries every deletion
and keeps the one whose result has the least generalised variance (``det C``, the volume of its
confidence ellipsoid; unit-consistent across m² and rad²).  Such estimates "are overestimates
because they do not utilize all the available information".

:func:`joint_estimate` uses all of it: the full joint least-squares estimate of every frame
relative to the source (Gauss–Newton on the relations' residuals, covariance the inverse of the
information matrix at the solution).  For linear relations it is the best linear unbiased
estimate, which series/parallel reduction equals on every reducible network; deletion equals it
on a bridge only when the deleted link carries no information (a balanced bridge).
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass
from typing import Hashable, Iterable

import numpy as np

from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from . import se2 as _se2
from ._validate import symmetrize
from .pose2 import UncertainPose2

__all__ = ["ReductionStatus", "NetworkReduction", "reduce_network", "reduce_network_report", "joint_estimate"]

MAX_DELETION_REDUCTIONS = 20_000  # series/parallel reductions the deletion search may run
_IRREDUCIBLE = ("delete", "joint", "raise")


class ReductionStatus(enum.Enum):
    """How :func:`reduce_network_report` reached its relation."""

    SERIES_PARALLEL = "series-parallel"  # reduced by series and parallel steps alone; nothing deleted
    DELETED = "deleted"  # irreducible: relations deleted (Section 4.1); the covariance is an overestimate
    JOINT = "joint"  # irreducible: the full joint least-squares estimate (every relation used)


@dataclass(frozen=True)
class NetworkReduction:
    """The relation source→target a network reduces to, and how.

    Attributes
    ----------
    pose : UncertainPose2 — target's relation to source (m, m, rad; covariance m², m·rad, rad²).
    status : ReductionStatus
    deleted : tuple of int — indices into the network of the relations deleted to make it
        reducible (sorted; empty unless ``status`` is DELETED).  A deleted relation may stand
        for a series or parallel group already reduced; all of its members are listed.
    alternatives : int — deletion sets whose reductions were compared (0 unless DELETED).
    """

    pose: UncertainPose2
    status: ReductionStatus
    deleted: tuple[int, ...] = ()
    alternatives: int = 0


def _parse(network: Iterable, source: Hashable, target: Hashable) -> list[tuple]:
    """(a, b, pose, frozenset of network indices) per relation, self-loops dropped; validated."""
    edges: list[tuple] = []
    for i, item in enumerate(network):
        try:
            a, b, pose = item
        except (TypeError, ValueError):
            raise UncertaintyError(f"network[{i}]: expected (a, b, UncertainPose2), got {item!r}") from None
        if not isinstance(pose, UncertainPose2):
            raise UncertaintyError(f"network[{i}]: relation must be an UncertainPose2, got {type(pose).__name__}")
        if a != b:
            edges.append((a, b, pose, frozenset((i,))))
    if source == target:
        raise UncertaintyError("reduce_network: source and target are the same frame")
    frames = {f for a, b, _, _ in edges for f in (a, b)}
    for name, f in (("source", source), ("target", target)):
        if f not in frames:
            raise UncertaintyError(f"reduce_network: {name} frame {f!r} is not in the network")
    return edges


def _oriented(edge, a) -> UncertainPose2:
    """The edge's relation as seen from frame ``a`` (reversed, Eqn. 4, when it points the other way)."""
    ea, _, p, _ = edge
    return p if ea == a else p.reverse()


def _connected(edges, source, target) -> bool:
    reach, grew = {source}, True
    while grew:
        grew = False
        for a, b, _, _ in edges:
            if (a in reach) != (b in reach):
                reach |= {a, b}
                grew = True
    return target in reach


def _relevant(edges: list, source, target) -> list:
    """The relations on some simple chain from source to target: those of the biconnected component
    that holds a virtual source-target relation (networkx).  The rest hang off a frame the chains
    all pass (a cut vertex) and carry no information about source→target, as a dangling frame
    does; a bridge network hanging there could not be reduced, and made an irrelevant relation
    the one deleted (or, beyond six frames, the deletion search too long)."""
    import networkx as nx

    g = nx.Graph()
    g.add_edges_from((a, b) for a, b, _, _ in edges)
    g.add_edge(source, target)
    for block in nx.biconnected_component_edges(g):
        keys = {frozenset(e) for e in block}
        if frozenset((source, target)) in keys:
            return [e for e in edges if frozenset((e[0], e[1])) in keys]
    return edges  # unreachable: the virtual relation is in one block


def _series_parallel(edges: list, source, target, tol: Tolerances) -> list:
    """Apply parallel merges and series compoundings until none applies; the edges that remain."""
    while True:
        # parallel: two relations between the same pair of frames
        seen: dict[frozenset, int] = {}
        hit = None
        for i, (a, b, _, _) in enumerate(edges):
            key = frozenset((a, b))
            if key in seen:
                hit = (seen[key], i)
                break
            seen[key] = i
        if hit is not None:
            i, j = hit
            a, b = edges[i][0], edges[i][1]
            if {a, b} == {source, target}:
                a, b = source, target  # the paper's "pointing in the desired direction"
            merged = _oriented(edges[i], a).merge(_oriented(edges[j], a), tol=tol)
            origins = edges[i][3] | edges[j][3]
            edges = [e for k, e in enumerate(edges) if k not in hit] + [(a, b, merged, origins)]
            continue
        degree: dict = {}
        for a, b, _, _ in edges:
            degree[a] = degree.get(a, 0) + 1
            degree[b] = degree.get(b, 0) + 1
        for node, n in degree.items():
            if node in (source, target) or n > 2:
                continue
            idx = [k for k, e in enumerate(edges) if node in (e[0], e[1])]
            if len(idx) == 1:  # a dangling frame carries no information about source→target
                edges = [e for k, e in enumerate(edges) if k != idx[0]]
            else:  # series: u -> node -> w compounded (Eqns. 1-3)
                e1, e2 = edges[idx[0]], edges[idx[1]]
                u = e1[0] if e1[1] == node else e1[1]
                w = e2[0] if e2[1] == node else e2[1]
                joined = _oriented(e1, u).compound(_oriented(e2, node))
                edges = [e for k, e in enumerate(edges) if k not in idx] + [(u, w, joined, e1[3] | e2[3])]
            break
        else:
            return edges


def _done(edges, source, target) -> bool:
    return len(edges) == 1 and {edges[0][0], edges[0][1]} == {source, target}


def _rank(pose: UncertainPose2) -> tuple[float, float]:
    """'Best' final covariance: least det C (generalised variance), then least positional trace."""
    sign, logdet = np.linalg.slogdet(pose.cov)
    return (logdet if sign > 0 else -np.inf, float(pose.cov[0, 0] + pose.cov[1, 1]))


def _best_deletion(edges, source, target, tol, memo, counter):
    """Best (rank, pose, deleted) over every sequence of single deletions that makes the stuck
    network reducible; None when every deletion disconnects source from target."""
    key = frozenset(e[3] for e in edges)
    if key in memo:
        return memo[key]
    best = None
    for k in range(len(edges)):
        rest = [e for j, e in enumerate(edges) if j != k]
        if not _connected(rest, source, target):
            continue
        counter[0] += 1
        if counter[0] > MAX_DELETION_REDUCTIONS:
            raise UncertaintyError(
                f"reduce_network: more than {MAX_DELETION_REDUCTIONS} deletion sets to compare "
                f"({len(edges)} relations remain irreducible); use irreducible='joint'"
            )
        rest = _series_parallel(rest, source, target, tol)
        if _done(rest, source, target):
            pose = _oriented(rest[0], source)
            found = (_rank(pose), pose, edges[k][3])
        else:
            sub = _best_deletion(rest, source, target, tol, memo, counter)
            if sub is None:
                continue
            found = (sub[0], sub[1], sub[2] | edges[k][3])
        if best is None or found[0] < best[0]:
            best = found
    memo[key] = best
    return best


def reduce_network_report(network: Iterable, source: Hashable, target: Hashable, *,
                          irreducible: str = "delete", tol: Tolerances = DEFAULT_TOLERANCES) -> NetworkReduction:
    """Reduce a network of uncertain relations to the one relation source→target (Section 4.1).

    ``network`` is an iterable of ``(a, b, pose)``: ``pose`` (:class:`UncertainPose2`) is
    frame ``b``'s relation to frame ``a``; frames are any hashable names.  Relations are
    assumed independent (Sections 3.2 and 4.2).  Repeatedly, until one relation joins source
    and target:

    * parallel relations between the same two frames are merged (Eqns. 5–7), reversing
      (Eqn. 4) those that point the other way (towards source→target when the pair is
      source and target, else the first-listed relation's direction; reversal is
      nonlinear, so the direction matters beyond first order);
    * a frame other than source/target joined by exactly two relations is eliminated by
      compounding them (Eqns. 1–3), reversing as needed;
    * a frame other than source/target joined by one relation only is dropped with it (it
      carries no information about source→target).

    A network these steps cannot reduce (the paper's Wheatstone bridge) is handled by
    ``irreducible``:

    * ``"delete"`` (the paper's remedy): every way of deleting relations one at a time until
      the rest reduces is tried, and the result with the least ``det C`` is kept (at most
      :data:`MAX_DELETION_REDUCTIONS` reductions, else :class:`~armguard.UncertaintyError`);
    * ``"joint"``: :func:`joint_estimate`, every relation used;
    * ``"raise"``: :class:`~armguard.UncertaintyError`.

    A network with no chain from source to target raises in every case.
    """
    if irreducible not in _IRREDUCIBLE:
        raise UncertaintyError(f"reduce_network: irreducible must be one of {_IRREDUCIBLE}, got {irreducible!r}")
    network = list(network)  # read once: a generator is read again by joint_estimate
    edges = _parse(network, source, target)
    if not _connected(edges, source, target):
        raise UncertaintyError(f"reduce_network: no chain of relations joins {source!r} to {target!r}")
    rest = _series_parallel(_relevant(edges, source, target), source, target, tol)
    if _done(rest, source, target):
        return NetworkReduction(_oriented(rest[0], source), ReductionStatus.SERIES_PARALLEL)
    if irreducible == "raise":
        raise UncertaintyError(
            f"reduce_network: the network is not series-parallel reducible between {source!r} and {target!r} "
            f"({len(rest)} relations remain, e.g. a Wheatstone bridge); delete relations until it is "
            "(Section 4.1), or pass irreducible='delete' or 'joint'"
        )
    if irreducible == "joint":
        return NetworkReduction(joint_estimate(network, source, target, tol=tol), ReductionStatus.JOINT)
    counter = [0]
    best = _best_deletion(rest, source, target, tol, {}, counter)
    if best is None:  # unreachable: deleting any one relation of a cycle keeps source and target joined
        raise UncertaintyError(f"reduce_network: no deletion leaves {source!r} joined to {target!r}")
    return NetworkReduction(best[1], ReductionStatus.DELETED, tuple(sorted(best[2])), counter[0])


def reduce_network(network: Iterable, source: Hashable, target: Hashable, *,
                   irreducible: str = "delete", tol: Tolerances = DEFAULT_TOLERANCES) -> UncertainPose2:
    """Target's relation to source; :func:`reduce_network_report`'s ``pose`` (see there)."""
    return reduce_network_report(network, source, target, irreducible=irreducible, tol=tol).pose


def joint_estimate(network: Iterable, source: Hashable, target: Hashable, *,
                   tol: Tolerances = DEFAULT_TOLERANCES, max_iterations: int = 100) -> UncertainPose2:
    """The full joint least-squares estimate of target's relation to source, every relation used.

    Unknowns: the relation ``x_f`` (m, m, rad) of every frame ``f`` joined to the source
    (source fixed at the identity); each relation ``(a, b, z)`` is a measurement of
    ``⊖x_a ⊕ x_b`` (Eqns. 1 and 4) with its covariance ``C``.  Gauss–Newton from the
    compounded relations of a breadth-first spanning tree minimises
    ``Σ rᵀ C⁻¹ r`` (angle residuals wrapped into (−π, π]); the covariance is the target's block
    of ``(Σ Jᵀ C⁻¹ J)⁻¹`` at the solution (the Jacobians are the paper's J⊕ and J⊖).  For
    linear relations this is the best linear unbiased estimate; a reducible network's
    series/parallel result equals it to first order, exactly on a chain.

    Every relation's covariance must be invertible (condition above
    :attr:`Tolerances.merge_conditioning`); :class:`~armguard.UncertaintyError` otherwise, and
    when the iteration does not converge within ``max_iterations``.
    """
    edges = _parse(network, source, target)
    adj: dict = {}
    for e in edges:
        adj.setdefault(e[0], []).append(e)
        adj.setdefault(e[1], []).append(e)
    x0 = {source: np.zeros(3)}  # spanning tree from the source
    queue = deque([source])
    while queue:
        f = queue.popleft()
        for e in adj[f]:
            g = e[1] if e[0] == f else e[0]
            if g not in x0:
                x0[g] = _se2._compound_mean(x0[f], _oriented(e, f).mean)
                queue.append(g)
    if target not in x0:
        raise UncertaintyError(f"joint_estimate: no chain of relations joins {source!r} to {target!r}")
    unknown = [f for f in x0 if f != source]
    col = {f: 3 * i for i, f in enumerate(unknown)}
    used = [e for e in edges if e[0] in x0]
    weights = []
    for a, b, p, origin in used:
        ev = np.linalg.eigvalsh(p.cov)
        if ev[-1] <= 0.0 or ev[0] < tol.merge_conditioning * ev[-1]:
            raise UncertaintyError(
                f"joint_estimate: network[{min(origin)}] ({a!r} -> {b!r}) has a singular covariance "
                f"(eigenvalues {ev}); the joint estimate weighs each relation by its inverse"
            )
        weights.append(np.linalg.inv(p.cov))
    x = np.concatenate([x0[f] for f in unknown])
    n = x.size

    def at(f):
        return np.zeros(3) if f == source else x[col[f]:col[f] + 3]

    def residual(p, xa, xb):
        ra = _se2._reverse_mean(xa)
        hb = _se2._compound_mean(ra, xb)
        r = hb - p.mean
        r[2] = _se2.wrap_angle(r[2])
        return ra, hb, r

    def cost(x_try) -> float:
        def at_try(f):
            return np.zeros(3) if f == source else x_try[col[f]:col[f] + 3]

        total = 0.0
        for (a, b, p, _), w in zip(used, weights):
            r = residual(p, at_try(a), at_try(b))[2]
            total += float(r @ w @ r)
        return total

    for _ in range(int(max_iterations)):
        h_mat, g_vec = np.zeros((n, n)), np.zeros(n)
        for (a, b, p, _), w in zip(used, weights):
            xa, xb = at(a), at(b)
            ra, hb, r = residual(p, xa, xb)
            j1, j2 = _se2._compound_jacobians(ra, xb, hb)
            blocks = ((a, j1 @ _se2._reverse_jacobian(xa, ra)), (b, j2))
            for f, jf in blocks:
                if f == source:
                    continue
                g_vec[col[f]:col[f] + 3] += jf.T @ w @ r
                for f2, jf2 in blocks:
                    if f2 != source:
                        h_mat[col[f]:col[f] + 3, col[f2]:col[f2] + 3] += jf.T @ w @ jf2
        step = np.linalg.solve(h_mat, -g_vec)
        # backtracking: the Gauss-Newton step halved until the weighted squared residuals do not grow
        # (with large angular errors the full step overshot: steps grew to 1e74 on loops with 1 rad noise)
        c0, t = cost(x), 1.0
        c1 = cost(x + step)
        while not c1 <= c0:
            t *= 0.5
            if t < 1e-6:  # no step along it lowers the residuals: a minimum to round-off (x is kept)
                break
            c1 = cost(x + t * step)
        else:
            x = x + t * step
            # go on while the step moves x and lowers the residuals by more than round-off
            if np.max(np.abs(step)) > 1e-13 * max(1.0, float(np.max(np.abs(x)))) and c0 - c1 > 1e-14 * c0:
                continue
        break
    else:
        raise UncertaintyError(f"joint_estimate: Gauss-Newton did not converge in {max_iterations} iterations")
    # the covariance at the solution
    cov = np.linalg.inv(h_mat)
    i = col[target]
    return UncertainPose2._trusted(at(target).copy(), symmetrize(cov[i:i + 3, i:i + 3]))
