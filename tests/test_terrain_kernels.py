"""The terrain kernels: the division-free claim of the JPL brief (seed 002), read off the compiled
LLVM IR, and the specialised box test against the library's OBB test and exact geometry."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from numba import njit
from scipy.spatial.transform import Rotation

from armguard.geometry import Box, Prism, distance
from armguard.geometry._pair_box_box import box_box_overlap
from armguard.terrain import ElevationMap, TerrainPyramid
from armguard.terrain import _kernels as K
from armguard.terrain._volumes import pack_rows

# floating-point and integer division, square root and the transcendental functions, as LLVM
# instructions or as calls into libm / LLVM intrinsics
FORBIDDEN = re.compile(
    r"\b(fdiv|sdiv|udiv|frem|srem|urem)\b"
    r"|@(llvm\.)?(sqrt|sin|cos|tan|asin|acos|atan|atan2|exp|exp2|log|log2|log10|pow|hypot|sinh|cosh|tanh)(\.f(32|64))?\b"
)


def _ir(dispatcher) -> str:
    """The LLVM IR of every compiled signature of ``dispatcher``, recompiled without numba's cache
    (numba does not keep the IR of kernels loaded from its on-disk cache)."""
    assert dispatcher.signatures, f"{dispatcher.__name__} was not compiled"
    fresh = njit(cache=False)(dispatcher.py_func)
    for sig in dispatcher.signatures:
        fresh.compile(sig)
    return "\n".join(fresh.inspect_llvm(sig) for sig in fresh.signatures)


def _compile_all():
    pyr = TerrainPyramid(ElevationMap.from_heights(np.random.default_rng(0).random((9, 7)) * 0.2, 0.1))
    v = [Prism([0.3, 0.3, 0.1], np.eye(3), 0.05, 0.1), Box([0.5, 0.2, 0.1], [0.1, 0.1, 0.1])]
    pyr.check(v)
    pyr.check_flat(v)
    rows, _ = pack_rows(v, 0.0, 1e-12)
    K.aabb_obb_overlap(pyr.boxes, 0, rows, 0)
    K.aabb_obp_overlap(pyr.boxes, 0, rows, 0, 4)


@pytest.mark.parametrize("name", ["aabb_obb_overlap", "aabb_obp_overlap", "descend", "flat_hits"])
def test_kernel_ir_has_no_division_sqrt_or_transcendental(name):
    _compile_all()
    ir = _ir(getattr(K, name))
    found = sorted({m.group(0) for m in FORBIDDEN.finditer(ir)})
    assert not found, f"{name}: {found}"
    assert "fabs" in ir  # the IR is the kernel's (the SAT's abs), not an empty module


def test_the_ir_check_catches_what_it_forbids():
    """The pattern fires on kernels that do divide, take a square root or call atan2."""
    div = njit(lambda a, b: a / b)
    root = njit(lambda a: math.sqrt(a))
    ang = njit(lambda a, b: math.atan2(a, b))
    idiv = njit(lambda a, b: a // b)
    div(1.0, 3.0), root(2.0), ang(1.0, 2.0), idiv(7, 2)
    for f in (div, root, ang, idiv):
        assert FORBIDDEN.search(_ir(f)), f


def _random_pair(rng):
    c = rng.uniform(-0.5, 0.5, 3)
    h = rng.uniform(0.02, 0.4, 3)
    R = Rotation.random(random_state=rng.integers(2**31)).as_matrix()
    if rng.random() < 0.2:  # axis-aligned and near-parallel cases too
        R = np.eye(3) if rng.random() < 0.5 else Rotation.from_rotvec(rng.normal(size=3) * 1e-9).as_matrix()
    link = Box(c, h, R)
    tc, th = rng.uniform(-0.5, 0.5, 3), rng.uniform(0.02, 0.4, 3)
    return link, Box(tc, th)


def test_aabb_kernel_agrees_with_obb_test_and_exact_distance():
    rng = np.random.default_rng(5)
    n_overlap = n_apart = 0
    for _ in range(3000):
        link, terr = _random_pair(rng)
        rows, _ = pack_rows([link], 0.0, 1e-12)
        boxes = np.concatenate([terr.center, terr.half_extents])[None, :]
        got = K.aabb_obb_overlap(boxes, 0, rows, 0)
        ref = box_box_overlap(link.center, link.half_extents, link.rotation, terr.center, terr.half_extents,
                              np.eye(3), 1e-12)
        assert got == ref
        d = distance(link, terr).distance
        if abs(d) > 1e-9:
            assert got == (d < 0.0), d
            n_overlap += d < 0.0
            n_apart += d > 0.0
    assert n_overlap > 300 and n_apart > 300  # both verdicts exercised


def test_obp_kernel_is_the_union_of_its_boxes_and_matches_the_prism():
    rng = np.random.default_rng(6)
    seen = set()
    for _ in range(1500):
        R = Rotation.random(random_state=rng.integers(2**31)).as_matrix()
        p = Prism(rng.uniform(-0.4, 0.4, 3), R, rng.uniform(0.03, 0.2), rng.uniform(0.05, 0.3), 8)
        terr = Box(rng.uniform(-0.4, 0.4, 3), rng.uniform(0.02, 0.3, 3))
        rows, rs = pack_rows([p], 0.0, 1e-12)
        assert rs[-1] == 4  # the octagon is four OBBs (the brief's Figure 1)
        boxes = np.concatenate([terr.center, terr.half_extents])[None, :]
        got = K.aabb_obp_overlap(boxes, 0, rows, 0, 4)
        d = distance(p, terr).distance  # the prism as a convex polyhedron
        if abs(d) > 1e-9:
            assert got == (d < 0.0), d
            seen.add(bool(got))
    assert seen == {True, False}
