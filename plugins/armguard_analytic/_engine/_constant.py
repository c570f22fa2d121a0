"""Pairs whose relative pose never changes: their rows computed once per build, copied at every check.

A pair of two static elements, of a static element and an element on a link fixed to W (a robot's
base link, or a link a chain of fixed joints carries: no joint value on its chain,
:func:`._seeds.pair_joints`), or of such an element and the workspace walls has one signed
distance and one pair of witness points in W at every configuration.  A cell's model lists such
pairs (a base against the table it stands on, a pedestal against a fence: puma560 has 9 of its 62,
gmf_s480 1 of 15); every check computed them again.  So does a pair of two elements whose links no
joint value moves apart (links joined by fixed joints: kinova's 6 of 45 pairs, talos_left_arm's 3
of 23): its distance never changes and its witness points move with link A.  :func:`constant_rows`
runs the same kernel on them once, at the build, in the all-pairs mode, and keeps their rows
(``"cst"``, ``"cstv"`` in :mod:`._layout`: the witness points in W, or in link A's frame); the
all-pairs mode (``pair_distances``, ``pair_distances_many``, the Detector's ``pair_distances``)
copies them (``._step.constant_step``; the rigid pairs' witness points moved by link A's pose):
the same bits for a pair fixed in W, as every pair's result is a function of its two elements'
poses alone, and the same answer to rounding (1e-15 m) for a rigid pair, whose relative pose the
kernel otherwise recomputes from two link poses at every check.  The other modes (Ranger's checks,
yes/no) prune by bounds and still evaluate such a pair when they reach it.  A scene edit that moves
one (a body added or moved, a robot's base placed elsewhere) is a new revision, so a new build.
"""

from __future__ import annotations

import numpy as np

from . import _kernel as kn
from ._entry import detect_entry
from ._scratch import _Scratch
from ._seeds import pair_joints

__all__ = ["CST_W", "constant_pairs", "constant_rows"]

CST_W = 8
"""``"cstv"`` row: ``[frame, distance, p_A (3), p_B (3)]``, ``frame`` -1 (the points in W) or the link
whose frame holds them (a rigid pair's link A)."""


def constant_pairs(tree, glink: np.ndarray, pair_a: np.ndarray, pair_b: np.ndarray) -> tuple:
    """``(cst, frame)``: per pair, -1 or its row of ``"cstv"`` (0, 1, ... in pair order) when its relative
    pose never changes, and per row the frame of its witness points (-1: W, where neither element moves;
    else link A, where both move together).  Element ``g`` is on link ``glink[g]`` (-1: static;
    ``pair_b`` -1: the workspace walls).  A link is fixed when no joint value enters its pose."""
    fixed: dict = {-1: True}

    def still(link: int) -> bool:
        if link not in fixed:
            fixed[link] = not pair_joints(tree, link, -1)
        return fixed[link]

    cst = np.full(len(pair_a), -1, dtype=np.int64)
    frame: list = []
    for p, (a, b) in enumerate(zip(pair_a.tolist(), pair_b.tolist())):
        la = int(glink[a])
        lb = int(glink[b]) if b >= 0 else -1
        if still(la) and (b < 0 or still(lb)):
            frame.append(-1)
        elif b >= 0 and la >= 0 and lb >= 0 and not pair_joints(tree, la, lb):
            frame.append(la)  # no joint value between the two links: they move as one body
        else:
            continue
        cst[p] = len(frame) - 1
    return cst, np.array(frame, dtype=np.int64)


def constant_rows(b, frame: np.ndarray) -> int:
    """Fill ``"cstv"`` of the build ``b`` (:mod:`._built`, its buffers made, before it is published)
    with the rows of its constant pairs (``frame``: :func:`constant_pairs`'), computed by the kernel's
    all-pairs mode at one configuration in the joint limits (any: these rows depend on none but through
    link A's pose, which the rigid rows leave out).  Where that call fails (GJK not converged), the pairs
    are left to every check (``"cst"`` -1), which reports the error as before.  Returns the number of
    pairs kept."""
    L = b.layout
    cst = L.view(b.MI, "cst")
    sel = np.flatnonzero(cst >= 0).astype(np.int64)
    if not len(sel):
        return 0
    order = cst[sel].copy()
    cst[:] = -1  # computed now, not copied from the zeros
    s = _Scratch(b)
    qlim = L.view(b.MF, "qlim").reshape(-1, 2)
    s.q1[0] = np.clip(0.0, qlim[:, 0], qlim[:, 1])
    ip = s.iprm_by_mode[kn.MODE_ALL]
    _, _, err = detect_entry(b.fn, s.q1, b.H, b.MF, b.MI, s.SF, s.SI, b.prm, ip, sel)
    if err:
        return 0
    rows = s.ev[:len(sel)].copy()  # [d, p_WA, p_WB], in sel's order
    Xs = L.view(s.SF, "Xs").reshape(-1, 4, 4)  # the link poses of that check
    for k, r in enumerate(order):
        link = int(frame[r])
        if link >= 0:  # into link A's frame: p_L = R^T (p_W - t)
            R, t = Xs[link, :3, :3], Xs[link, :3, 3]
            rows[k, 1:4] = R.T @ (rows[k, 1:4] - t)
            rows[k, 4:7] = R.T @ (rows[k, 4:7] - t)
    cstv = L.view(b.MF, "cstv").reshape(-1, CST_W)
    cstv[order, 0] = frame[order]
    cstv[order, 1:] = rows
    cst[sel] = order
    return len(sel)
