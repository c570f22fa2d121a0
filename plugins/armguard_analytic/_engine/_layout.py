"""Packing of the detector's arrays into a few flat buffers (one numba call per check).

A numba call costs roughly 50-100 ns per array argument to unbox; the detector needs ~60
arrays, which would cost more than the whole check.  So the model is packed into one float64
and one int64 buffer, the per-call scratch and outputs into one float64 and one int64 buffer,
and a small int64 header ``H`` records where each named segment starts and how many rows it
has (``H[2 k]`` offset, ``H[2 k + 1]`` rows, ``k`` the segment's number below).  The kernel
takes views with :func:`seg1` / :func:`seg2` / :func:`seg3`; Python keeps NumPy views of the
same memory to read the outputs without copies.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

__all__ = ["Layout", "COHERENT_STEP", "at", "iview1", "seg1", "seg2", "seg3", "view1", "view2", "view3"]

# Segment numbers are compiled into _kernel.py, _narrow.py and _pair_jacobian.py as constants and numba
# caches key on the defining file only: a change to these tuples must come with an edit of those files.
# model floats
MF = ("X_pre", "axis", "X_post", "offset", "term_coeff", "radius", "verts_L", "box_L", "fn_L", "ed_L",
      "sph_L", "static_lo", "static_hi", "bvh_lo", "bvh_hi", "lever", "ws", "pv", "ppl", "pbis", "pcen")
# model ints
MI = ("parent", "jtype", "has_post", "term_start", "term_joint", "glink", "core", "vstart", "pstart",
      "estart", "mov_idx", "st_idx", "bvh_left", "bvh_right", "bvh_start", "bvh_count", "bvh_items",
      "pair_a", "pair_b", "pair_cat", "pair_of", "mov_ids", "ped", "poly_of", "pvs", "pps", "pes", "all_p", "st_mov", "st_cat",
      "rob_l", "rob_j", "parent_loc", "yn_mov", "yn_cat")
# scratch / state / output floats
SFN = ("Xs", "vW", "boxW", "fnW", "edW", "sphW", "out9", "work", "gap", "ev", "plb", "last_d",
       "last_q", "best", "seg", "fk_q")
# scratch / state / output ints
SIN = ("summary", "ev_p", "pflag", "stack", "order", "has_last", "stamp", "pstamp", "fk_ok")
# scalar slots after the segments
SCALARS = ("n_q", "n_explicit", "n_mov", "n_st", "n_links", "stamp_now")

# segments added later, whose header slots follow the scalar slots (so that the numbers above,
# compiled into _kernel.py, stay put): the vertex graphs of the polytope elements (GJK and EPA
# climb them) and their surface triangles, each with CSR offsets per element (an empty range:
# no graph, supports scan), model ints; "obb_L", model floats: the moving polytope elements'
# oriented boxes in their link frames (the yes/no cull, see ._hulls.link_obbs); "qlim", model
# floats ``(n_q, 2)``: each joint's [lower, upper] widened by Tolerances.joint_limit (a row outside
# it is refused before any bound that assumes the limits is used); "gdir", model ints, with CSR
# offsets "gdirs": each graph element's support table (armguard.geometry._pack.support_table: where
# a cold climb along a direction starts; ._narrow.narrow_rel); "spair" (model ints, ``(n_pairs, 6)``),
# "sgrid" (model floats, ``(n_pairs, 6)``) and "sdt" (model ints, ``(cells, 7)``): the seed tables of
# the pairs GJK checks in link frames whose relative pose depends on one or two joints (._seeds);
# "lseed" (scratch floats, ``(n_pairs, 7)``, read and written as int64 through :func:`iview1`): each
# pair's final GJK simplex at this thread's previous check, in a seed row's layout, and "coh" (scratch
# floats, 2): [1.0 where the thread's checks may start from "lseed" (the analytic Checker's option
# warm_start), 1.0 when this check's joint values are also within ``COHERENT_STEP`` of the previous
# check's] (._narrow.narrow_rel then starts GJK from "lseed"); "cst" (model ints, one per pair: -1, or
# the pair's row of "cstv") and "cstv" (model floats, ``(rows, EV_W)``): the rows of the pairs whose two
# elements never move (._constant: computed once per build, copied by the all-pairs mode)
MI_LATE = ("gadj", "gadjs", "gtri", "gtris", "obb_L", "qlim", "gdir", "gdirs", "spair", "sgrid", "sdt", "lseed",
           "coh", "cst", "cstv")

_ALL = MF + MI + SFN + SIN
K = {name: k for k, name in enumerate(_ALL)}
S0 = 2 * len(_ALL)  # first scalar slot
SC = {name: S0 + k for k, name in enumerate(SCALARS)}
_LATE0 = (S0 + len(SCALARS) + 1) // 2
K.update({name: _LATE0 + k for k, name in enumerate(MI_LATE)})
H_SIZE = 2 * (_LATE0 + len(MI_LATE))

COHERENT_STEP = 0.2
"""rad (m for a prismatic joint): with the Checker's option ``warm_start``, a check whose every joint
value is within this of the same thread's previous check starts each link-frame GJK from the simplex
that pair ended with there ("lseed"), instead of its seed table's node (._seeds) or a cold start.  Any
simplex of support pairs is a valid start (``_pair_gjk._gjk_body``'s ``seed``): this changes
iterations, never the answer beyond ``gjk_epsilon`` -- but its last bits then depend on the thread's
previous check, so it is off by default (the same call, the same bits).  The step is generous: on
ur3's paths of steps up to 0.17 rad the warm start still took less time than the tables
(``python -m bench robots`` with ``bench.robots.PATH_STEP`` raised)."""

# summary slots (SI "summary" segment, followed by "ev_p": one copy reads both)
SUM_BEST = 0  # 4 entries: best pair per category (-1 none)
SUM_NEVAL = 4  # number of evaluated pairs (rows of "ev" / entries of "ev_p")
SUM_STATUS = 5
SUM_ERR = 6
SUM_BSLOT = 7  # 4 entries: row of "ev" holding the best pair per category (-1 none)
SUM_SIZE = 11
EV_W = 7  # "ev" rows: [distance, p_WA (3), p_WB (3)] of the evaluated pairs, in evaluation order


class Layout:
    """Builds the header and the four buffers from named arrays (rows x flattened columns)."""

    def __init__(self) -> None:
        self.H = np.zeros(H_SIZE, dtype=np.int64)
        self._parts = {"MF": [], "MI": [], "SF": [], "SI": []}
        self._size = {"MF": 0, "MI": 0, "SF": 0, "SI": 0}
        self._shape: dict[str, tuple] = {}

    def add(self, group: str, name: str, arr) -> None:
        dtype = np.float64 if group in ("MF", "SF") else np.int64
        a = np.ascontiguousarray(np.asarray(arr, dtype=dtype))
        rows = a.shape[0] if a.ndim else 1
        k = K[name]
        self.H[2 * k] = self._size[group]
        self.H[2 * k + 1] = rows
        self._parts[group].append(a.ravel())
        self._size[group] += a.size
        self._shape[name] = (group, self._size[group] - a.size, a.shape)

    def scalar(self, name: str, value: int) -> None:
        self.H[SC[name]] = int(value)

    def buffers(self):
        out = []
        for g, dt in (("MF", np.float64), ("MI", np.int64), ("SF", np.float64), ("SI", np.int64)):
            parts = self._parts[g]
            buf = np.concatenate(parts) if parts else np.zeros(0, dt)
            out.append(np.ascontiguousarray(np.concatenate([buf, np.zeros(1, dt)])))  # never empty
        return (self.H, *out)

    def view(self, buf: np.ndarray, name: str) -> np.ndarray:
        """NumPy view of segment ``name`` of ``buf`` (a buffer of the segment's group)."""
        _, off, shape = self._shape[name]
        n = int(np.prod(shape)) if shape else 1
        return buf[off:off + n].reshape(shape)


@intrinsic
def at(typingctx, buf, offset):  # pragma: no cover - compiled
    """Pointer to element ``offset`` of the 1-D array ``buf`` (for :func:`numba.carray`)."""
    sig = types.CPointer(buf.dtype)(buf, offset)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, args[0])
        return builder.gep(ary.data, [args[1]])

    return sig, codegen


def _view_codegen(ndim: int, dtype=None):
    """Typing and code generation of an ``ndim``-dimensional C view (the ``view*`` intrinsics); with
    ``dtype``, of that type over the same bytes (the buffer's and ``dtype``'s items of one size)."""

    def typer(typingctx, buf, offset, *dims):
        dt = buf.dtype if dtype is None else dtype
        arr = types.Array(dt, ndim, "C")

        def codegen(context, builder, signature, args):
            src = context.make_array(signature.args[0])(context, builder, args[0])
            data = builder.gep(src.data, [args[1]])
            if dtype is not None:
                data = builder.bitcast(data, context.get_data_type(dt).as_pointer())
            item = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(dt)))
            shape = [context.cast(builder, a, t, types.intp) for a, t in zip(args[2:], signature.args[2:])]
            strides, acc = [], item
            for n in reversed(shape):
                strides.insert(0, acc)
                acc = builder.mul(acc, n)
            out = context.make_array(arr)(context, builder)
            populate_array(out, data=data, shape=cgutils.pack_array(builder, shape),
                           strides=cgutils.pack_array(builder, strides), itemsize=item, meminfo=None)
            return out._getvalue()

        return arr(buf, offset, *dims), codegen

    return typer


@intrinsic
def view1(typingctx, buf, offset, n):  # pragma: no cover - compiled
    """The ``n`` elements of the 1-D array ``buf`` from ``offset``: a C array without a meminfo, as
    ``numba.carray(at(buf, offset), (n,))``, but built in place, so that a kernel compiled without
    reference counting may take one (numba refuses ``carray`` there: its implementation is a
    function that returns a new array).  :func:`seg1` to :func:`seg3` are built the same way."""
    return _view_codegen(1)(typingctx, buf, offset, n)


@intrinsic
def iview1(typingctx, buf, offset, n):  # pragma: no cover - compiled
    """:func:`view1` of a float64 buffer read as int64 (the same 8 bytes an item): a thread's scratch
    floats holding integers ("lseed": vertex indices, kept as their bit patterns, not converted)."""
    return _view_codegen(1, types.int64)(typingctx, buf, offset, n)


@intrinsic
def view2(typingctx, buf, offset, n, w):  # pragma: no cover - compiled
    """:func:`view1` with shape ``(n, w)``."""
    return _view_codegen(2)(typingctx, buf, offset, n, w)


@intrinsic
def view3(typingctx, buf, offset, n, w1, w2):  # pragma: no cover - compiled
    """:func:`view1` with shape ``(n, w1, w2)``."""
    return _view_codegen(3)(typingctx, buf, offset, n, w1, w2)


# The segments are views of the buffers without a meminfo (as numba.carray's): they carry no
# reference to the buffer's memory, so creating and passing them costs no atomic operation (a sliced
# and reshaped view costs two and a reshape helper call, ~25-30 ns: the ~55 views the kernel takes
# per call cost more than the check itself, ~1.7 us).  They are only used inside a kernel
# call while the caller holds the buffers; no kernel returns one.
@njit(cache=True, inline="always")
def seg1(buf, H, k):  # pragma: no cover - compiled
    return view1(buf, H[2 * k], H[2 * k + 1])


@njit(cache=True, inline="always")
def seg2(buf, H, k, w):  # pragma: no cover - compiled
    return view2(buf, H[2 * k], H[2 * k + 1], w)


@njit(cache=True, inline="always")
def seg3(buf, H, k, w1, w2):  # pragma: no cover - compiled
    return view3(buf, H[2 * k], H[2 * k + 1], w1, w2)
