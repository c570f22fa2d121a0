"""Pairs whose two elements never move: their rows computed once per build, copied at every check.

A pair of two static elements, of a static element and an element on a link fixed to W (a robot's
base link, or a link a chain of fixed joints carries: no joint value on its chain,
:func:`._seeds.pair_joints`), or of such an element and the workspace walls has one signed
distance and one pair of witness points in W at every configuration.  A cell's model lists such
pairs (a base against the table it stands on, a pedestal against a fence: puma560 has 9 of its 62,
gmf_s480 1 of 15); every check computed them again.  :func:`constant_rows` runs the same kernel
on them once, at the build, in the all-pairs mode, and keeps their rows (``"cst"``, ``"cstv"`` in
:mod:`._layout`); the all-pairs mode (``pair_distances``, ``pair_distances_many``, the Detector's
``pair_distances``) copies them (``._step.constant_step``): the same bits, as every pair's result
is a function of its two elements' poses alone.  The other modes (Ranger's checks, yes/no) prune by
bounds and still evaluate such a pair when they reach it.  A scene edit that moves one (a body
added or moved, a robot's base placed elsewhere) is a new revision, so a new build.
"""

from __future__ import annotations

import numpy as np

from . import _kernel as kn
from ._entry import detect_entry
from ._layout import EV_W
from ._scratch import _Scratch
from ._seeds import pair_joints

__all__ = ["constant_pairs", "constant_rows"]


def constant_pairs(tree, glink: np.ndarray, pair_a: np.ndarray, pair_b: np.ndarray) -> np.ndarray:
    """``"cst"``: per pair, -1, or its row of ``"cstv"`` (0, 1, ... in pair order) when neither of its
    elements moves (element ``g`` on link ``glink[g]``, -1: static; ``pair_b`` -1: the workspace
    walls).  A link is fixed when no joint value enters its pose (its chain has only fixed joints)."""
    fixed: dict = {-1: True}

    def still(link: int) -> bool:
        if link not in fixed:
            fixed[link] = not pair_joints(tree, link, -1)
        return fixed[link]

    cst = np.full(len(pair_a), -1, dtype=np.int64)
    n = 0
    for p, (a, b) in enumerate(zip(pair_a.tolist(), pair_b.tolist())):
        if still(int(glink[a])) and (b < 0 or still(int(glink[b]))):
            cst[p] = n
            n += 1
    return cst


def constant_rows(b) -> int:
    """Fill ``"cstv"`` of the build ``b`` (:mod:`._built`, its buffers made, before it is published)
    with the rows of its constant pairs, computed by the kernel's all-pairs mode at one configuration
    in the joint limits (any: these rows depend on none).  Where that call fails (GJK not converged),
    the pairs are left to every check (``"cst"`` -1), which reports the error as before.  Returns
    the number of pairs kept."""
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
    cstv = L.view(b.MF, "cstv").reshape(-1, EV_W)
    cstv[order] = s.ev[:len(sel)]
    cst[sel] = order
    return len(sel)
