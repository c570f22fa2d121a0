"""OBB-OBB overlap by the separating-axis theorem, with no divisions or square roots.

Leger, JPL NASA Tech Brief NPO-30356 (seed ``002``): OBBs and OBPs (unions of OBBs) are tested
"without any divisions or transcendental functions".  The brief gives no formulas; we use the
15-axis test of Gottschalk, Lin & Manocha (OBBTree, 1996): the three face axes of each box and
the nine cross products of an axis of A with an axis of B, each compared as
``|t . L| > r_A(L) + r_B(L)`` using only products and sums.  ``eps_par`` is added to
``|R_ij|`` so that near-parallel axes (where ``A_i x B_j`` degenerates to zero) cannot report a
false separation -- the usual robustness term.  Touching counts as overlapping.
"""

from __future__ import annotations

from numba import njit

__all__ = ["box_box_overlap", "box_box_overlap_scalar", "box_box_overlap_packed"]


@njit(cache=True)
def box_box_overlap_scalar(
    acx, acy, acz, ah0, ah1, ah2, a00, a01, a02, a10, a11, a12, a20, a21, a22,
    bcx, bcy, bcz, bh0, bh1, bh2, b00, b01, b02, b10, b11, b12, b20, b21, b22, eps_par,
):  # pragma: no cover - compiled
    """True when the boxes overlap or touch; ``aij`` is ``R_WA[i, j]`` (columns are axes)."""
    # R = R_WA^T R_WB: R[i][j] = A_i . B_j
    r00 = a00 * b00 + a10 * b10 + a20 * b20
    r01 = a00 * b01 + a10 * b11 + a20 * b21
    r02 = a00 * b02 + a10 * b12 + a20 * b22
    r10 = a01 * b00 + a11 * b10 + a21 * b20
    r11 = a01 * b01 + a11 * b11 + a21 * b21
    r12 = a01 * b02 + a11 * b12 + a21 * b22
    r20 = a02 * b00 + a12 * b10 + a22 * b20
    r21 = a02 * b01 + a12 * b11 + a22 * b21
    r22 = a02 * b02 + a12 * b12 + a22 * b22
    dx = bcx - acx
    dy = bcy - acy
    dz = bcz - acz
    t0 = a00 * dx + a10 * dy + a20 * dz
    t1 = a01 * dx + a11 * dy + a21 * dz
    t2 = a02 * dx + a12 * dy + a22 * dz
    q00 = abs(r00) + eps_par
    q01 = abs(r01) + eps_par
    q02 = abs(r02) + eps_par
    q10 = abs(r10) + eps_par
    q11 = abs(r11) + eps_par
    q12 = abs(r12) + eps_par
    q20 = abs(r20) + eps_par
    q21 = abs(r21) + eps_par
    q22 = abs(r22) + eps_par
    # A's face axes
    if abs(t0) > ah0 + bh0 * q00 + bh1 * q01 + bh2 * q02:
        return False
    if abs(t1) > ah1 + bh0 * q10 + bh1 * q11 + bh2 * q12:
        return False
    if abs(t2) > ah2 + bh0 * q20 + bh1 * q21 + bh2 * q22:
        return False
    # B's face axes
    if abs(t0 * r00 + t1 * r10 + t2 * r20) > ah0 * q00 + ah1 * q10 + ah2 * q20 + bh0:
        return False
    if abs(t0 * r01 + t1 * r11 + t2 * r21) > ah0 * q01 + ah1 * q11 + ah2 * q21 + bh1:
        return False
    if abs(t0 * r02 + t1 * r12 + t2 * r22) > ah0 * q02 + ah1 * q12 + ah2 * q22 + bh2:
        return False
    # A_i x B_j
    if abs(t2 * r10 - t1 * r20) > ah1 * q20 + ah2 * q10 + bh1 * q02 + bh2 * q01:
        return False
    if abs(t2 * r11 - t1 * r21) > ah1 * q21 + ah2 * q11 + bh0 * q02 + bh2 * q00:
        return False
    if abs(t2 * r12 - t1 * r22) > ah1 * q22 + ah2 * q12 + bh0 * q01 + bh1 * q00:
        return False
    if abs(t0 * r20 - t2 * r00) > ah0 * q20 + ah2 * q00 + bh1 * q12 + bh2 * q11:
        return False
    if abs(t0 * r21 - t2 * r01) > ah0 * q21 + ah2 * q01 + bh0 * q12 + bh2 * q10:
        return False
    if abs(t0 * r22 - t2 * r02) > ah0 * q22 + ah2 * q02 + bh0 * q11 + bh1 * q10:
        return False
    if abs(t1 * r00 - t0 * r10) > ah0 * q10 + ah1 * q00 + bh1 * q22 + bh2 * q21:
        return False
    if abs(t1 * r01 - t0 * r11) > ah0 * q11 + ah1 * q01 + bh0 * q22 + bh2 * q20:
        return False
    if abs(t1 * r02 - t0 * r12) > ah0 * q12 + ah1 * q02 + bh0 * q21 + bh1 * q20:
        return False
    return True


@njit(cache=True)
def box_box_overlap(ca, ha, R_WA, cb, hb, R_WB, eps_par):  # pragma: no cover - compiled
    """JPL OBB-OBB overlap: ``ca, cb : (3,) m``, ``ha, hb : (3,) m`` half extents, ``R_W* : (3, 3)``.

    Returns True when the boxes overlap or touch.  No divisions, no square roots.
    """
    return box_box_overlap_scalar(
        ca[0], ca[1], ca[2], ha[0], ha[1], ha[2],
        R_WA[0, 0], R_WA[0, 1], R_WA[0, 2], R_WA[1, 0], R_WA[1, 1], R_WA[1, 2], R_WA[2, 0], R_WA[2, 1], R_WA[2, 2],
        cb[0], cb[1], cb[2], hb[0], hb[1], hb[2],
        R_WB[0, 0], R_WB[0, 1], R_WB[0, 2], R_WB[1, 0], R_WB[1, 1], R_WB[1, 2], R_WB[2, 0], R_WB[2, 1], R_WB[2, 2],
        eps_par,
    )


@njit(cache=True)
def box_box_overlap_packed(a, b, eps_par):  # pragma: no cover - compiled
    """Packed boxes ``[c, h, R row-major]`` (15,)."""
    return box_box_overlap_scalar(
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], a[14],
        b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13], b[14],
        eps_par,
    )
