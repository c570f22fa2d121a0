"""A forbidden-values map read from its file: lookups, the 3 × 3 neighbourhood, facts about it.

``ForbiddenMap.load(path)`` reads the header and the directory, reads the data section once and
keeps those bytes (a file mapped instead could be overwritten or shrunk under the lookups after
its checks), and checks every section once (CRC-32s, the substructures' pointers and bins; a
damaged file raises :class:`ForbiddenMapFileError` naming the section);
:meth:`ForbiddenMap.neighbourhood` copies the 3 × 3 block of substructures around a configuration
out of those bytes (Hermes's loading strategy kept only these 9 substructures in memory; here the
whole map's bytes are held: a few kB to MB, see ``docs/cspace.md``); :meth:`ForbiddenMap.prepare` (named, idempotent; run by the first whole-map lookup)
gathers every substructure into two flat arrays for :meth:`allowed_many`.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from .._errors import ForbiddenMapError, ForbiddenMapFileError
from ._certify import decode_intervals
from ._format import KERNEL_VERSION, check_data, check_substructures, read_header, sha256_file
from ._grid import MapGrid

__all__ = ["ForbiddenMap", "Neighbourhood", "MapInfo", "Lookup", "model_file_hashes", "model_file_changes"]


class Lookup(enum.IntEnum):
    """Per-configuration answer codes of the lookup kernel."""

    FORBIDDEN = 0  #: some configuration of its cell × bin box may collide
    ALLOWED = 1  #: every configuration of its cell × bin box is proven clear
    OUTSIDE_LIMITS = 2  #: outside the joint limits of joints 1–3 (or NaN): not allowed
    OUTSIDE_BLOCK = 3  #: within the limits but outside the loaded block (a neighbourhood)


@njit(cache=True, nogil=True)
def _lookup(Q, cols, lo, hi, step, counts, r1a, r1b, r2a, r2b, cell_start, iv, out):
    """``out (M,) int8`` :class:`Lookup` codes for ``Q (M, n) rad`` (columns ``cols`` are joints 1–3).

    ``cell_start ((r1b - r1a) (r2b - r2a) + 1,) int64`` indexes ``iv (K, 2) uint16`` forbidden bin
    intervals per cell of the loaded block ``[r1a, r1b) × [r2a, r2b)`` (row-major)."""
    n2 = r2b - r2a
    for m in range(Q.shape[0]):
        code = 1
        idx = np.empty(3, np.int64)
        for k in range(3):
            x = Q[m, cols[k]]
            if not (x >= lo[k] and x <= hi[k]):
                code = 2
                break
            i = int(math.floor((x - lo[k]) / step[k]))
            if i >= counts[k]:
                i = counts[k] - 1
            idx[k] = i
        if code == 1:
            i1 = idx[0]
            i2 = idx[1]
            if i1 < r1a or i1 >= r1b or i2 < r2a or i2 >= r2b:
                code = 3
            else:
                c = (i1 - r1a) * n2 + (i2 - r2a)
                b = idx[2]
                for t in range(cell_start[c], cell_start[c + 1]):
                    if b < iv[t, 0]:
                        break
                    if b < iv[t, 1]:
                        code = 0
                        break
        out[m] = code


def model_file_hashes(files) -> list[dict]:
    """``[{"name", "path", "sha256"}]`` of the model source files ``files`` (paths)."""
    out = []
    for f in files:
        p = Path(f)
        if not p.is_file():
            raise ForbiddenMapError(f"model file {p} not found")
        out.append({"name": p.name, "path": str(p.resolve()), "sha256": sha256_file(p)})
    return out


def model_file_changes(recorded, now, *, limit: int = 8) -> str:
    """What differs between the model files a map ``recorded`` and those ``now`` (both as
    :func:`model_file_hashes` gives them), in words; "" when they are the same.

    Files are matched by name and content (a multiset of ``(name, sha256)``): an edited file, a
    missing or new one, and two files that exchanged their contents (which a bare set of hashes
    would not see) all differ.  The paths do not count, so a model copied elsewhere still matches."""
    from collections import Counter

    key = Counter((r["name"], r["sha256"]) for r in recorded)
    key_now = Counter((r["name"], r["sha256"]) for r in now)
    gone, new = sorted((key - key_now).elements()), sorted((key_now - key).elements())
    new_by_name: dict[str, list[str]] = {}
    for name, sha in new:
        new_by_name.setdefault(name, []).append(sha)
    changed, missing = [], []
    for name, sha in gone:
        if new_by_name.get(name):
            changed.append(f"{name} (sha256 {sha[:12]} in the map, {new_by_name[name].pop(0)[:12]} now)")
        else:
            missing.append(f"{name} {sha[:12]}")
    added = [f"{name} {sha[:12]}" for name, shas in new_by_name.items() for sha in shas]

    def words(label: str, items: list[str]) -> str:
        more = f" and {len(items) - limit} more" if len(items) > limit else ""
        return f"{label}: {', '.join(items[:limit])}{more}"

    return "; ".join(words(label, items) for label, items in
                     (("changed", changed), ("in the map only", missing), ("new", added)) if items)


@dataclass(frozen=True)
class MapInfo:
    """Facts about a map (no sampling; see :func:`armguard.cspace.check_exactness` for that).

    Attributes
    ----------
    size_bytes : int
        File size.
    n_cells, n_substructures, n_bins, n_intervals : int
    substructure_bytes_max : int
        The largest substructure's payload (the paper: about 1.5 KB at 1°, 10° × 10°).
    neighbourhood_bytes_max : int
        The largest 3 × 3 block's payload (the paper: 13.5 KB).
    forbidden_fraction : float
        Forbidden share of the joint-1 × joint-2 × joint-3 grid volume (clipped to the limits).
    evaluations, unresolved : int
        Build statistics: clearance evaluations; boxes marked forbidden at the depth limit.
    """

    size_bytes: int
    n_cells: int
    n_substructures: int
    n_bins: int
    n_intervals: int
    substructure_bytes_max: int
    neighbourhood_bytes_max: int
    forbidden_fraction: float
    evaluations: int
    unresolved: int


def forbidden_share(g, mask_of) -> float:
    """The forbidden share of the grid ``g``'s joint box, in [0, 1]: every forbidden cell's volume (clipped
    to the limits), ``mask_of(s)`` the substructure ``s``'s mask, over the box's.  The sum of a full box's
    cells rounds to 1 + 1e-15 or so: read as "more than all of it" (``cspace info``), so it is clipped."""
    widths = np.diff(g.bin_edges())
    forb = 0.0
    for s in range(g.n_substructures):
        i1a, i1b, i2a, i2b = g.sub_cells(s)
        w1 = np.minimum(g.lower[0] + g.step[0] * np.arange(i1a + 1, i1b + 1), g.upper[0]) - (g.lower[0] + g.step[0] * np.arange(i1a, i1b))
        w2 = np.minimum(g.lower[1] + g.step[1] * np.arange(i2a + 1, i2b + 1), g.upper[1]) - (g.lower[1] + g.step[1] * np.arange(i2a, i2b))
        forb += float(np.einsum("i,j,ijk,k->", w1, w2, mask_of(s), widths))
    return min(1.0, forb / float(np.prod(g.upper - g.lower)))


class _Block:
    """Flat lookup arrays over a block of cells ``[r1a, r1b) × [r2a, r2b)``."""

    def __init__(self, fmap: "ForbiddenMap", r1a: int, r1b: int, r2a: int, r2b: int) -> None:
        g = fmap.grid
        self.region = (r1a, r1b, r2a, r2b)
        n1, n2 = r1b - r1a, r2b - r2a
        counts = np.zeros(n1 * n2, dtype=np.int64)
        pieces = {}
        nbytes = 0
        for k1 in range(r1a // g.per_sub[0], -(-r1b // g.per_sub[0])):
            for k2 in range(r2a // g.per_sub[1], -(-r2b // g.per_sub[1])):
                s = k1 * int(g.n_sub[1]) + k2
                ptr, iv = fmap._raw_sub(s)
                nbytes += ptr.nbytes + iv.nbytes
                i1a, i1b, i2a, i2b = g.sub_cells(s)
                c = np.diff(ptr.astype(np.int64)).reshape(i1b - i1a, i2b - i2a)
                counts.reshape(n1, n2)[i1a - r1a:i1b - r1a, i2a - r2a:i2b - r2a] = c
                pieces[s] = (ptr.astype(np.int64), iv)
        self.cell_start = np.zeros(n1 * n2 + 1, dtype=np.int64)
        np.cumsum(counts, out=self.cell_start[1:])
        self.iv = np.zeros((int(self.cell_start[-1]), 2), dtype=np.uint16)
        start2 = self.cell_start[:-1].reshape(n1, n2)
        for s, (ptr, iv) in pieces.items():
            i1a, i1b, i2a, i2b = g.sub_cells(s)
            w = i2b - i2a
            for r in range(i1b - i1a):  # one row of the substructure is contiguous in the block, too
                dst = int(start2[i1a - r1a + r, i2a - r2a])
                a, b = int(ptr[r * w]), int(ptr[(r + 1) * w])
                self.iv[dst:dst + b - a] = iv[a:b]
        self.nbytes = nbytes

    def codes(self, fmap: "ForbiddenMap", Q) -> np.ndarray:
        Q = fmap._as_rows(Q)
        out = np.empty(len(Q), dtype=np.int8)
        g = fmap.grid
        _lookup(Q, fmap._cols_for(Q), g.lower, g.upper, g.step, g.counts, *self.region, self.cell_start, self.iv, out)
        return out


class ForbiddenMap:
    """A certified forbidden-values map (see :mod:`armguard.cspace`); open one with :meth:`load`.

    Attributes
    ----------
    path : Path
    header : dict
        The file's header (see :mod:`armguard.cspace._format`).
    grid : MapGrid
    robot : str
    joints : (3,) tuple of str
    links : tuple of str
    stopping_distance : float, m
    """

    def __init__(self, path, header: dict, offsets: np.ndarray, crcs: np.ndarray, data_off: int) -> None:
        self.path = Path(path)
        self.header = header
        kernel = header.get("kernel_version")
        if kernel != KERNEL_VERSION:
            raise ForbiddenMapFileError(self.path, "header", f"built by map kernel version {kernel}; this armguard's is "
                                        f"{KERNEL_VERSION}: rebuild the map")
        try:
            self.grid = MapGrid.from_json(header["grid"])
            self.robot = header["robot"]
            self.joints = tuple(header["joints"])
            self.links = tuple(header["links"])
            self.joint_index = tuple(header["joint_index"])
            self.stopping_distance = float(header["stopping_distance"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ForbiddenMapFileError(self.path, "header", f"a field is missing or invalid: {exc!r}") from None
        self.build_report = None  # set by ForbiddenMap.build
        if len(crcs) != self.grid.n_substructures:
            raise ForbiddenMapFileError(self.path, "directory", f"{len(crcs)} substructures; the grid has "
                                        f"{self.grid.n_substructures}")
        self._dir = np.asarray(offsets, dtype=np.int64)
        try:  # one read, kept: every section is checked before any lookup, and the lookups read these
            with open(self.path, "rb") as f:  # bytes (a file mapped instead could change or shrink under them)
                f.seek(data_off)
                raw = f.read()
        except OSError as exc:
            raise ForbiddenMapFileError(self.path, "data", f"cannot read it ({exc.strerror or exc})") from None
        self._data = np.frombuffer(raw, dtype=np.uint8)
        check_data(self.path, raw, self._dir, crcs)
        odd = np.flatnonzero(self._dir % 2)
        if len(odd):
            raise ForbiddenMapFileError(self.path, f"data, substructure {max(0, int(odd[0]) - 1)}", "an odd number of bytes")
        g = self.grid
        w = [np.minimum((np.arange(int(g.n_sub[k])) + 1) * g.per_sub[k], g.counts[k]) - np.arange(int(g.n_sub[k])) * g.per_sub[k]
             for k in (0, 1)]
        cells = np.outer(w[0], w[1]).ravel().astype(np.int64)  # cells of each substructure (row-major, as sub_cells)
        check_substructures(self.path, np.frombuffer(raw, dtype="<u2"), self._dir // 2, cells, int(self.grid.counts[2]))
        self._full: _Block | None = None

    # ------------------------------------------------------------------ opening
    @classmethod
    def load(cls, path, *, model=None) -> "ForbiddenMap":
        """Open the map at ``path`` and check that it was built for the model.

        ``model``: the model source files now (a path or a list of paths: the scene YAML, URDFs),
        or a built-in scene name; None re-hashes the files recorded in the header.  Files that differ
        from those recorded (by name and sha256: :func:`model_file_changes`) raise
        :class:`ForbiddenMapError` saying what changed — the map was built for other model files and
        answers nothing; so does a map that records no model files.
        """
        fmap = cls(path, *read_header(path))
        fmap.check_model(model)
        return fmap

    def check_model(self, model=None) -> None:
        """Raise :class:`ForbiddenMapError` unless the model files' sha256 equal the header's (see :meth:`load`)."""
        from ._build import model_files_of

        recorded = self.header.get("model_files") or []
        if not recorded:
            raise ForbiddenMapError(f"{self.path}: the map records no model files, so it cannot be checked against "
                                    "any model; rebuild the map")
        if model is None:
            files = [r["path"] for r in recorded]
            missing = [f for f in files if not Path(f).is_file()]
            if missing:
                raise ForbiddenMapError(f"{self.path}: cannot check the model: {missing} not found; pass model= (--model)")
        else:
            files = model_files_of(model)
        changes = model_file_changes(recorded, model_file_hashes(files))
        if changes:
            raise ForbiddenMapError(f"{self.path}: built for other model files ({changes}); rebuild the map for "
                                    "this model")

    # ------------------------------------------------------------------ storage
    def _raw_sub(self, s: int) -> tuple[np.ndarray, np.ndarray]:
        i1a, i1b, i2a, i2b = self.grid.sub_cells(s)
        n = (i1b - i1a) * (i2b - i2a) + 1
        a, b = int(self._dir[s]), int(self._dir[s + 1])
        words = np.frombuffer(self._data[a:b], dtype="<u2")
        return words[:n], words[n:].reshape(-1, 2)

    def substructure(self, s: int) -> tuple[np.ndarray, np.ndarray]:
        """``(pointers (n_cells + 1,) uint16, intervals (K, 2) uint16)`` of substructure ``s`` (copies)."""
        ptr, iv = self._raw_sub(self._sub_index(s))
        return ptr.copy(), iv.copy()

    def _sub_index(self, s) -> int:
        """``s`` as a substructure number of this map, else a ForbiddenMapError saying the range."""
        if isinstance(s, (bool, np.bool_)) or not isinstance(s, (int, np.integer)):
            raise ForbiddenMapError(f"substructure: expected an integer, got {s!r}")
        if not 0 <= int(s) < self.grid.n_substructures:
            raise ForbiddenMapError(f"substructure {s} is not in 0..{self.grid.n_substructures - 1}")
        return int(s)

    def substructure_mask(self, s: int) -> np.ndarray:
        """``(c1, c2, n3) bool``: forbidden bins of every cell of substructure ``s``."""
        s = self._sub_index(s)
        i1a, i1b, i2a, i2b = self.grid.sub_cells(s)
        ptr, iv = self._raw_sub(int(s))
        return decode_intervals(ptr, iv, (i1b - i1a, i2b - i2a, int(self.grid.counts[2])))

    def mask(self) -> np.ndarray:
        """``(n1, n2, n3) bool``: the whole map's forbidden bins (for plots and tests; reads every substructure)."""
        g = self.grid
        out = np.zeros(tuple(int(c) for c in g.counts), dtype=bool)
        for s in range(g.n_substructures):
            i1a, i1b, i2a, i2b = g.sub_cells(s)
            out[i1a:i1b, i2a:i2b] = self.substructure_mask(s)
        return out

    @property
    def size_bytes(self) -> int:
        return self.path.stat().st_size

    # ------------------------------------------------------------------ lookups
    def prepare(self) -> "ForbiddenMap":
        """Gather every substructure into the flat lookup arrays (idempotent; the first :meth:`allowed_many` runs it)."""
        if self._full is None:
            g = self.grid
            self._full = _Block(self, 0, int(g.counts[0]), 0, int(g.counts[1]))
        return self

    def _as_rows(self, Q) -> np.ndarray:
        Q = np.asarray(Q, dtype=np.float64)
        if Q.ndim == 1:
            Q = Q[None, :]
        if Q.ndim != 2 or Q.shape[1] < 3:
            raise ForbiddenMapError(f"Q: expected (M, 3) joints 1-3 or (M, n) joint vectors of {self.robot!r}, got {Q.shape}")
        return np.ascontiguousarray(Q)

    def _cols_for(self, Q: np.ndarray) -> np.ndarray:
        if Q.shape[1] == 3:
            return np.arange(3, dtype=np.int64)
        if Q.shape[1] <= max(self.joint_index):
            raise ForbiddenMapError(f"Q: {Q.shape[1]} columns do not hold joints {self.joint_index} of {self.robot!r}")
        return np.array(self.joint_index, dtype=np.int64)

    def lookup_many(self, Q) -> np.ndarray:
        """``(M,) int8`` :class:`Lookup` codes for ``Q`` (``(M, 3)`` joints 1–3, or ``(M, n)`` robot joint vectors; rad)."""
        return self.prepare()._full.codes(self, Q)

    def allowed_many(self, Q) -> np.ndarray:
        """``(M,) bool``: True where the map proves links 1–3 clear of the obstacles by more than the stopping distance."""
        return self.lookup_many(Q) == Lookup.ALLOWED

    def allowed(self, q) -> bool:
        """One configuration ``q`` (``(3,)`` or the robot's ``(n,)``, rad): see :meth:`allowed_many`."""
        return bool(self.allowed_many(_one_row(q))[0])

    def neighbourhood(self, q) -> "Neighbourhood":
        """The 3 × 3 block of substructures around ``q`` (fewer at the grid's edges), read from the file alone."""
        q = np.asarray(q, dtype=np.float64).reshape(-1)
        cols = self._cols_for(q[None, :])
        cell = self.grid.cell_of(q[cols])
        if cell is None:
            raise ForbiddenMapError(f"q = {q[cols]} rad is outside the map's joint limits")
        g = self.grid
        k1, k2 = cell[0] // int(g.per_sub[0]), cell[1] // int(g.per_sub[1])
        a1, b1 = max(0, k1 - 1), min(int(g.n_sub[0]), k1 + 2)
        a2, b2 = max(0, k2 - 1), min(int(g.n_sub[1]), k2 + 2)
        r = (a1 * int(g.per_sub[0]), min(b1 * int(g.per_sub[0]), int(g.counts[0])),
             a2 * int(g.per_sub[1]), min(b2 * int(g.per_sub[1]), int(g.counts[1])))
        return Neighbourhood(self, _Block(self, *r), ((a1, b1), (a2, b2)))

    # ------------------------------------------------------------------ facts
    def forbidden_intervals(self, i1: int, i2: int) -> np.ndarray:
        """``(K, 2) float64, rad``: cell ``(i1, i2)``'s forbidden joint-3 intervals (bin edges, clipped to the limits)."""
        g = self.grid
        n1, n2 = int(g.counts[0]), int(g.counts[1])
        for name, i, n in (("i1", i1, n1), ("i2", i2, n2)):  # -1 once read the last cell, a plausible answer
            if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)) or not 0 <= int(i) < n:
                raise ForbiddenMapError(f"cell ({i1!r}, {i2!r}) is not a cell of this map: {name} must be an integer in "
                                        f"0..{n - 1} (the grid is {n1} x {n2} cells)")
        i1, i2 = int(i1), int(i2)
        s = g.sub_of(i1, i2)
        i1a, _, i2a, i2b = g.sub_cells(s)
        ptr, iv = self._raw_sub(s)
        c = (i1 - i1a) * (i2b - i2a) + (i2 - i2a)
        e = g.bin_edges()
        sel = iv[int(ptr[c]):int(ptr[c + 1])].astype(np.int64)
        return np.stack([e[sel[:, 0]], e[sel[:, 1]]], axis=1) if len(sel) else np.zeros((0, 2))

    def info(self) -> MapInfo:
        g = self.grid
        sizes = np.diff(self._dir)
        grid_sizes = sizes.reshape(int(g.n_sub[0]), int(g.n_sub[1]))
        pad = np.pad(grid_sizes, 1)
        nb = sum(pad[i:i + grid_sizes.shape[0], j:j + grid_sizes.shape[1]] for i in range(3) for j in range(3))
        n_iv = sum(len(self._raw_sub(s)[1]) for s in range(g.n_substructures))
        st = self.header.get("stats", {})
        return MapInfo(self.size_bytes, g.n_cells, g.n_substructures, int(g.counts[2]), n_iv, int(sizes.max()),
                       int(nb.max()), forbidden_share(g, self.substructure_mask),
                       int(st.get("evaluations", 0)), int(st.get("unresolved", 0)))

    def __repr__(self) -> str:
        g = self.grid
        return (f"ForbiddenMap({str(self.path)!r}: {self.robot} {self.joints}, links {self.links}, "
                f"{math.degrees(g.step[0]):.4g}° × {math.degrees(g.step[2]):.4g}°, {g.n_substructures} substructures, "
                f"stopping distance {self.stopping_distance} m, {self.size_bytes} bytes)")


class Neighbourhood:
    """The 3 × 3 substructures around a configuration, loaded alone from the map file.

    Attributes
    ----------
    substructures : ((k1a, k1b), (k2a, k2b))
        The loaded substructure ranges (end exclusive).
    nbytes : int
        Bytes of the substructures read (the paper: 9 × 1.5 KB = 13.5 KB).
    """

    def __init__(self, fmap: ForbiddenMap, block: _Block, subs) -> None:
        self._map = fmap
        self._block = block
        self.substructures = subs
        self.nbytes = int(block.nbytes)

    def lookup_many(self, Q) -> np.ndarray:
        """``(M,) int8`` :class:`Lookup` codes; ``OUTSIDE_BLOCK`` where a row lies outside the loaded block."""
        return self._block.codes(self._map, Q)

    def allowed_many(self, Q) -> np.ndarray:
        """``(M,) bool`` as :meth:`ForbiddenMap.allowed_many`; a row outside the block raises ForbiddenMapError."""
        codes = self.lookup_many(Q)
        if np.any(codes == Lookup.OUTSIDE_BLOCK):
            raise ForbiddenMapError("a configuration lies outside the loaded neighbourhood; load the one around it")
        return codes == Lookup.ALLOWED

    def allowed(self, q) -> bool:
        return bool(self.allowed_many(_one_row(q))[0])


def _one_row(q) -> np.ndarray:
    """``q`` (one configuration: numbers, rad) as a ``(1, n)`` float64 row; else a ForbiddenMapError."""
    try:
        a = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError):
        raise ForbiddenMapError(f"q: expected joint values (rad), got {q!r}") from None
    if a.ndim != 1 or a.size == 0:
        raise ForbiddenMapError(f"q: expected one configuration, (3,) joints 1-3 or the robot's (n,), got {q!r}")
    return a[None, :]
