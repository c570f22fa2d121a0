"""The ``.agmap`` file: one header, a directory, and the substructures as quantised integers.

Layout (little-endian), format version 2::

    magic        8 bytes   b"AGMAP\\r\\n\\x1a"
    version      uint32    FORMAT_VERSION
    header_len   uint32    bytes of the header that follows
    header_crc   uint32    CRC-32 of the header bytes
    directory_crc uint32   CRC-32 of the directory bytes
    header       JSON (UTF-8), padded with spaces to a multiple of 8 bytes
    directory    (n_sub + 1,) uint64  byte offset of each substructure from the start of the data,
                 then (n_sub,) uint32 the CRC-32 of each substructure's bytes (padded to 8 bytes)
    data         per substructure: pointers (n_cells + 1,) uint16, then intervals (K, 2) uint16

A substructure's ``pointers[c] .. pointers[c + 1]`` index its forbidden joint-3 intervals
``[start, end)`` (bin numbers) of cell ``c`` (row-major over its (joint 1, joint 2) cells): Hermes's
"integer pointers and angular values".  The header records the format version, the kernel version
(:data:`KERNEL_VERSION`, bumped whenever certification or clearances change), the robot, joints
and links, the grid, the stopping distance, the build settings and the sha256 of every model
source file (``model_files``: the sidecar, URDF, SRDF and every mesh), so a map built for another
model file refuses to answer.

Every section is checked when a map is opened (:func:`read_header`, :func:`check_data`): a flipped
bit or a truncation anywhere raises :class:`ForbiddenMapFileError` naming the file and the section,
and so does a file of format version 1 (no checksums: rebuild it).

A build in progress writes ``<out>.partial``: a journal of finished substructures (magic, a
fingerprint of the build settings and its CRC-32, then one record per substructure, each ending in
the CRC-32 of its bytes) that a restarted build reads back, skipping what is already done.  A
record that is cut short, fails its CRC or does not decode to a valid substructure is discarded
together with everything after it (those substructures are computed again): a resume never uses a
damaged record.  A damaged fingerprint refuses the journal.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
import contextlib
import struct
import zlib
from pathlib import Path

import numpy as np

from .._errors import ForbiddenMapError, ForbiddenMapFileError, OutputError
from .._io import atomic_write

__all__ = ["FORMAT_VERSION", "KERNEL_VERSION", "sha256_file", "write_map", "read_header", "check_data",
           "check_substructure", "check_substructures", "Journal"]

FORMAT_VERSION = 2
#: the version of what decides a map's bits (certification, clearance hooks, the lookup's meaning); a map
#: recorded with another kernel version is refused
KERNEL_VERSION = 1
MAGIC = b"AGMAP\r\n\x1a"
JOURNAL_MAGIC = b"AGMAPJ2\n"
_OLD_JOURNAL_MAGIC = b"AGMAPJ1\n"
_VER = struct.Struct("<8sI")
_PRE = struct.Struct("<8sIIII")  # magic, version, header_len, header_crc, directory_crc
_REC = struct.Struct("<IIIQQ")  # substructure, n_pointers, n_intervals, evaluations, unresolved
_CRC = struct.Struct("<I")


def _crc(*parts) -> int:
    c = 0
    for p in parts:
        c = zlib.crc32(p, c)
    return c & 0xFFFFFFFF


def sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _header_bytes(header: dict) -> bytes:
    raw = json.dumps(header, sort_keys=True, separators=(",", ":")).encode("utf-8")
    return raw + b" " * (-len(raw) % 8)


def _directory_bytes(offsets: np.ndarray, crcs: np.ndarray) -> bytes:
    raw = np.ascontiguousarray(offsets, dtype="<u8").tobytes() + np.ascontiguousarray(crcs, dtype="<u4").tobytes()
    return raw + b"\0" * (-len(raw) % 8)


def _directory_len(n_sub: int) -> int:
    n = 8 * (n_sub + 1) + 4 * n_sub
    return n + (-n % 8)


def write_map(path, header: dict, subs: list) -> int:
    """Write the map file atomically; ``subs``: per substructure ``(pointers uint16, intervals (K, 2) uint16)``. Returns its size (bytes)."""
    path = Path(path)
    hb = _header_bytes(header)
    blobs = [np.ascontiguousarray(ptr, dtype="<u2").tobytes() + np.ascontiguousarray(iv, dtype="<u2").tobytes()
             for ptr, iv in subs]
    offsets = np.zeros(len(subs) + 1, dtype="<u8")
    offsets[1:] = np.cumsum([len(b) for b in blobs], dtype=np.uint64)
    crcs = np.array([_crc(b) for b in blobs], dtype="<u4")
    db = _directory_bytes(offsets, crcs)
    blob = b"".join([_PRE.pack(MAGIC, FORMAT_VERSION, len(hb), _crc(hb), _crc(db)), hb, db, *blobs])
    atomic_write(path, blob)  # a temporary file beside it, every write checked, fsync, rename
    return len(blob)


def read_header(path) -> tuple[dict, np.ndarray, np.ndarray, int]:
    """``(header, offsets (n_sub + 1,) int64, crcs (n_sub,) uint32, data_offset)`` of the map file at ``path``.

    The preamble, the header and the directory are checked (magic, format version, CRC-32s, sizes);
    any failure raises :class:`ForbiddenMapFileError` naming the file and the section."""
    if not str(path).strip():  # Path('') is '.', the working directory
        raise ForbiddenMapFileError(path, "", "an empty path names no map file")
    path = Path(path)
    try:  # a FIFO blocked the open until killed; a pipe (<(cat map)) read as a truncated map: a map is a file
        mode = path.stat().st_mode
    except OSError:
        mode = None  # not there, or not readable: said by open() below
    if mode is not None and not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        raise ForbiddenMapFileError(path, "", "not a regular file (a FIFO, pipe or device): a map is read from a file, "
                                    "its parts when asked")
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            pre = f.read(_PRE.size)
            if len(pre) < _VER.size or pre[:8] != MAGIC:
                raise ForbiddenMapFileError(path, "preamble", "not a forbidden-values map (.agmap) file")
            _, version = _VER.unpack_from(pre)
            if version != FORMAT_VERSION:
                old = " (written without checksums)" if version < FORMAT_VERSION else ""
                raise ForbiddenMapFileError(path, "preamble", f"map format version {version}{old}; this armguard reads "
                                            f"version {FORMAT_VERSION}: rebuild the map (armguard cspace build ... --out {path})")
            if len(pre) < _PRE.size:
                raise ForbiddenMapFileError(path, "preamble", f"truncated: {len(pre)} bytes, the preamble is {_PRE.size}")
            _, _, n, header_crc, dir_crc = _PRE.unpack(pre)
            hb = f.read(n)
            if len(hb) < n:
                raise ForbiddenMapFileError(path, "header", f"truncated: {len(hb)} of {n} bytes")
            if _crc(hb) != header_crc:
                raise ForbiddenMapFileError(path, "header", "checksum mismatch (the header was edited or damaged); "
                                            "rebuild the map")
            try:
                header = json.loads(hb.decode("utf-8"))
                n_sub = int(np.prod(header["grid"]["n_sub"]))
            except (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
                raise ForbiddenMapFileError(path, "header", f"not a valid map header: {exc}") from None
            dl = _directory_len(n_sub)
            db = f.read(dl)
    except FileNotFoundError:
        raise ForbiddenMapFileError(path, "", "no such map file") from None
    except IsADirectoryError:
        raise ForbiddenMapFileError(path, "", "is a directory, not a map file") from None
    if len(db) < dl:
        raise ForbiddenMapFileError(path, "directory", f"truncated: {len(db)} of {dl} bytes ({n_sub} substructures)")
    if _crc(db) != dir_crc:
        raise ForbiddenMapFileError(path, "directory", "checksum mismatch (damaged); rebuild the map")
    offsets = np.frombuffer(db, dtype="<u8", count=n_sub + 1).astype(np.int64)
    crcs = np.frombuffer(db, dtype="<u4", count=n_sub, offset=8 * (n_sub + 1)).copy()
    data_off = _PRE.size + n + dl
    data_len = size - data_off
    if offsets[0] != 0 or np.any(np.diff(offsets) < 0) or int(offsets[-1]) != data_len:
        raise ForbiddenMapFileError(path, "data", f"truncated or corrupt: {data_len} bytes of data, the directory "
                                    f"says {int(offsets[-1])}")
    return header, offsets, crcs, data_off


def check_substructure(file, section: str, words: np.ndarray, n_cells: int, n_bins: int) -> tuple[np.ndarray, np.ndarray]:
    """``(pointers, intervals)`` decoded from one substructure's ``words`` (uint16), or ForbiddenMapFileError
    naming ``file`` and ``section`` unless they form a valid substructure of ``n_cells`` cells over ``n_bins``
    joint-3 bins (see :func:`check_substructures`)."""
    words = np.asarray(words, dtype=np.uint16)
    check_substructures(file, words, np.array([0, len(words)]), np.array([n_cells]), n_bins, sections=[section])
    n = n_cells + 1
    return words[:n], words[n:].reshape(-1, 2)


def check_substructures(file, words: np.ndarray, bounds: np.ndarray, n_cells: np.ndarray, n_bins: int, *,
                        sections=None) -> None:
    """Raise ForbiddenMapFileError (naming ``file`` and the first bad substructure) unless every substructure
    ``s`` — ``words[bounds[s]:bounds[s + 1]]`` (uint16; ``bounds`` from 0 to ``len(words)``) — holds ``n_cells[s] + 1`` pointers then whole
    intervals: ``pointers[0] = 0``, non-decreasing, ending at the interval count; every interval
    ``start < end <= n_bins``; a cell's intervals sorted and disjoint.  One vectorised pass over all."""
    bounds = np.asarray(bounds, dtype=np.int64)
    n_ptr = np.asarray(n_cells, dtype=np.int64) + 1
    start, length = bounds[:-1], np.diff(bounds)
    name = (lambda s: sections[s]) if sections is not None else (lambda s: f"data, substructure {s}")
    bad = np.flatnonzero((length < n_ptr) | ((length - n_ptr) % 2 != 0))
    if len(bad):
        s = int(bad[0])
        raise ForbiddenMapFileError(file, name(s), f"{int(length[s])} words do not hold {int(n_ptr[s])} pointers "
                                    "and whole intervals")
    n_iv = (length - n_ptr) // 2
    sub_of_ptr = np.repeat(np.arange(len(n_ptr)), n_ptr)
    first_ptr = np.concatenate([[0], np.cumsum(n_ptr)[:-1]])
    pidx = start[sub_of_ptr] + (np.arange(int(n_ptr.sum())) - first_ptr[sub_of_ptr])
    ptr = words[pidx].astype(np.int64)
    last = first_ptr + n_ptr - 1
    step_ok = np.ones(len(ptr), dtype=bool)
    step_ok[1:] = ptr[1:] >= ptr[:-1]
    step_ok[first_ptr] = True
    bad = (ptr[first_ptr] != 0) | (ptr[last] != n_iv) | ~np.logical_and.reduceat(step_ok, first_ptr)
    if np.any(bad):
        s = int(np.flatnonzero(bad)[0])
        raise ForbiddenMapFileError(file, name(s), f"pointers are not 0 .. {int(n_iv[s])} non-decreasing")
    is_ptr = np.zeros(len(words), dtype=bool)
    is_ptr[pidx] = True
    iv = words[~is_ptr].astype(np.int64).reshape(-1, 2)  # the substructures tile ``words``: their intervals, in order
    a, b = iv[:, 0], iv[:, 1]
    sub_of_iv = np.repeat(np.arange(len(n_iv)), n_iv)
    bad = (a >= b) | (b > n_bins)
    if np.any(bad):
        s = int(sub_of_iv[np.flatnonzero(bad)[0]])
        raise ForbiddenMapFileError(file, name(s), f"an interval is empty or beyond the {n_bins} joint-3 bins")
    if len(iv) > 1:
        base = np.concatenate([[0], np.cumsum(n_iv)[:-1]])
        cell_start = ptr + base[sub_of_ptr]  # global interval index where each cell (and each substructure) starts
        same_cell = np.ones(len(iv) - 1, dtype=bool)
        cs = cell_start[(cell_start > 0) & (cell_start < len(iv))]
        same_cell[cs - 1] = False  # pairs (t, t + 1) split by a cell start
        bad = same_cell & (a[1:] < b[:-1])
        if np.any(bad):
            s = int(sub_of_iv[np.flatnonzero(bad)[0]])
            raise ForbiddenMapFileError(file, name(s), "a cell's intervals are not sorted and disjoint")


def check_data(path, data, offsets: np.ndarray, crcs: np.ndarray) -> None:
    """Raise :class:`ForbiddenMapFileError` unless every substructure's bytes match their CRC-32 (the data section)."""
    view = memoryview(data)
    o = np.asarray(offsets).tolist()
    for s, c in enumerate(np.asarray(crcs).tolist()):
        if zlib.crc32(view[o[s]:o[s + 1]]) != c:
            raise ForbiddenMapFileError(path, f"data, substructure {s}", "checksum mismatch (damaged); rebuild the map")


@contextlib.contextmanager
def _journal_writes(path: Path, *, remove: bool = False):
    """An OSError while writing the journal (a full disk, no permission) as an OutputError naming it;
    ``remove``: the journal is removed then."""
    try:
        yield
    except OSError as exc:
        if remove:
            with contextlib.suppress(OSError):
                path.unlink()
        if isinstance(exc, OutputError):
            raise
        raise OutputError(f"cannot write the build journal {path}: {exc.strerror or exc}") from None


class Journal:
    """The append-only record of finished substructures of one build (``<out>.partial``).

    ``fingerprint``: the build settings (a JSON-able dict); a journal written with other settings
    is refused (ForbiddenMapError) unless ``resume`` is False, which starts it afresh.  ``check``:
    ``(s, pointers, intervals) -> None`` raising ForbiddenMapFileError for a record that does not
    decode to substructure ``s`` of this build.  A damaged record and everything after it are
    discarded (and computed again); ``discarded`` then says which and why (else "").
    """

    def __init__(self, path, fingerprint: dict, *, resume: bool = True, check=None) -> None:
        self.path = Path(path)
        self.done: dict[int, tuple] = {}
        self.discarded = ""
        self._check = check
        fp = _header_bytes(fingerprint)
        head = JOURNAL_MAGIC + _CRC.pack(len(fp)) + fp + _CRC.pack(_crc(fp))
        try:  # a FIFO there blocked the build for ever; a link was followed and the file it names overwritten
            mode = os.lstat(self.path).st_mode
        except FileNotFoundError:
            mode = None
        except OSError as exc:
            raise ForbiddenMapFileError(self.path, "", f"cannot read the build journal: {exc.strerror or exc}") from None
        if mode is not None and not stat.S_ISREG(mode):
            what = ("a symbolic link" if stat.S_ISLNK(mode) else "a folder" if stat.S_ISDIR(mode) else
                    "a FIFO" if stat.S_ISFIFO(mode) else "something other than a file")
            raise ForbiddenMapFileError(self.path, "", f"the build journal's place holds {what}: a journal is a file the "
                                        "build writes there; move it away")
        if resume and self.path.exists():
            self._read(head)
        else:
            with _journal_writes(self.path, remove=True):  # none left behind that a resume would refuse
                with open(self.path, "wb") as f:
                    f.write(head)
        with _journal_writes(self.path):
            self._f = open(self.path, "ab")

    def _read(self, head: bytes) -> None:
        data = self.path.read_bytes()
        if not data.startswith(head):
            if data.startswith(_OLD_JOURNAL_MAGIC):
                raise ForbiddenMapFileError(self.path, "fingerprint", "a journal of an older armguard (no checksums); "
                                            "remove it, or build with resume=False (--no-resume)")
            ok = data.startswith(JOURNAL_MAGIC) and len(data) >= 12
            n = _CRC.unpack_from(data, 8)[0] if ok else 0
            ok = ok and len(data) >= 16 + n and _crc(data[12:12 + n]) == _CRC.unpack_from(data, 12 + n)[0]
            if not ok:
                raise ForbiddenMapFileError(self.path, "fingerprint", "damaged or not a build journal; remove it, "
                                            "or build with resume=False (--no-resume)")
            raise ForbiddenMapError(f"{self.path}: a partial build with other settings (or model files) is there; "
                                    "remove it, or build with resume=False (--no-resume)")
        pos = len(head)
        k = 0
        while pos < len(data):
            why = None
            if pos + _REC.size > len(data):
                why = "cut short"
            else:
                s, n_ptr, n_iv, ev, un = _REC.unpack_from(data, pos)
                end = pos + _REC.size + 2 * (n_ptr + 2 * n_iv)
                if end + _CRC.size > len(data):
                    why = "cut short"
                elif _crc(data[pos:end]) != _CRC.unpack_from(data, end)[0]:
                    why = "checksum mismatch"
            if why is None:
                body = np.frombuffer(data, dtype="<u2", count=n_ptr + 2 * n_iv, offset=pos + _REC.size)
                ptr, iv = body[:n_ptr].copy(), body[n_ptr:].reshape(-1, 2).copy()
                try:
                    if self._check is not None:
                        self._check(int(s), ptr, iv)
                except ForbiddenMapFileError as exc:
                    why = exc.message
            if why is not None:
                self.discarded = f"record {k} and after ({len(data) - pos} bytes): {why}; recomputed"
                break
            self.done[int(s)] = (ptr, iv, int(ev), int(un))
            pos = end + _CRC.size
            k += 1
        if pos != len(data):
            with open(self.path, "r+b") as f:
                f.truncate(pos)

    def append(self, s: int, ptr: np.ndarray, iv: np.ndarray, evaluations: int, unresolved: int) -> None:
        rec = (_REC.pack(int(s), len(ptr), len(iv), int(evaluations), int(unresolved))
               + np.ascontiguousarray(ptr, dtype="<u2").tobytes() + np.ascontiguousarray(iv, dtype="<u2").tobytes())
        with _journal_writes(self.path):  # a record cut short by a full disk is recomputed on resume
            self._f.write(rec + _CRC.pack(_crc(rec)))
            self._f.flush()
        self.done[int(s)] = (ptr, iv, int(evaluations), int(unresolved))

    def close(self, *, remove: bool = False) -> None:
        with _journal_writes(self.path):
            self._f.close()
        if remove:
            self.path.unlink(missing_ok=True)
