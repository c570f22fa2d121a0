"""The ``.agmap`` file: one header, a directory, and the substructures as quantised integers.

Layout (little-endian)::

    magic        8 bytes   b"AGMAP\\r\\n\\x1a"
    version      uint32    FORMAT_VERSION
    header_len   uint32    bytes of the header that follows
    header       JSON (UTF-8), padded with spaces to a multiple of 8 bytes
    directory    (n_sub + 1,) uint64  byte offset of each substructure from the start of the data
    data         per substructure: pointers (n_cells + 1,) uint16, then intervals (K, 2) uint16

A substructure's ``pointers[c] .. pointers[c + 1]`` index its forbidden joint-3 intervals
``[start, end)`` (bin numbers) of cell ``c`` (row-major over its (joint 1, joint 2) cells): Hermes's
"integer pointers and angular values".  The header records the format version, the robot, joints
and links, the grid, the stopping distance, the build settings and the sha256 of every model
source file (``model_files``), so a map built for another model file refuses to answer.

A build in progress writes ``<out>.partial``: a journal of finished substructures (magic, a
fingerprint of the build settings, then one record per substructure) that a restarted build
reads back, skipping what is already done.
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
from pathlib import Path

import numpy as np

from .._errors import ForbiddenMapError

__all__ = ["FORMAT_VERSION", "sha256_file", "write_map", "read_header", "Journal"]

FORMAT_VERSION = 1
MAGIC = b"AGMAP\r\n\x1a"
JOURNAL_MAGIC = b"AGMAPJ1\n"
_PRE = struct.Struct("<8sII")
_REC = struct.Struct("<IIIQQ")  # substructure, n_pointers, n_intervals, evaluations, unresolved


def sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _header_bytes(header: dict) -> bytes:
    raw = json.dumps(header, sort_keys=True, separators=(",", ":")).encode("utf-8")
    return raw + b" " * (-len(raw) % 8)


def write_map(path, header: dict, subs: list) -> int:
    """Write the map file atomically; ``subs``: per substructure ``(pointers uint16, intervals (K, 2) uint16)``. Returns its size (bytes)."""
    path = Path(path)
    hb = _header_bytes(header)
    offsets = np.zeros(len(subs) + 1, dtype="<u8")
    for k, (ptr, iv) in enumerate(subs):
        offsets[k + 1] = offsets[k] + 2 * (len(ptr) + 2 * len(iv))
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        f.write(_PRE.pack(MAGIC, FORMAT_VERSION, len(hb)))
        f.write(hb)
        f.write(offsets.tobytes())
        for ptr, iv in subs:
            f.write(np.ascontiguousarray(ptr, dtype="<u2").tobytes())
            f.write(np.ascontiguousarray(iv, dtype="<u2").tobytes())
    os.replace(tmp, path)
    return path.stat().st_size


def read_header(path) -> tuple[dict, int, int]:
    """``(header, directory_offset, data_offset)`` of the map file at ``path`` (bytes from the file start)."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            pre = f.read(_PRE.size)
            if len(pre) < _PRE.size or pre[:8] != MAGIC:
                raise ForbiddenMapError(f"{path}: not a forbidden-values map (.agmap) file")
            _, version, n = _PRE.unpack(pre)
            if version != FORMAT_VERSION:
                raise ForbiddenMapError(f"{path}: map format version {version}; this armguard reads version {FORMAT_VERSION}")
            raw = f.read(n)
    except FileNotFoundError:
        raise ForbiddenMapError(f"{path}: no such map file") from None
    try:
        header = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ForbiddenMapError(f"{path}: the map header is not valid JSON: {exc}") from None
    d0 = _PRE.size + n
    n_sub = int(np.prod(header["grid"]["n_sub"]))
    return header, d0, d0 + 8 * (n_sub + 1)


class Journal:
    """The append-only record of finished substructures of one build (``<out>.partial``).

    ``fingerprint``: the build settings (a JSON-able dict); a journal written with other settings
    is refused (ForbiddenMapError) unless ``resume`` is False, which starts it afresh.
    """

    def __init__(self, path, fingerprint: dict, *, resume: bool = True) -> None:
        self.path = Path(path)
        self.done: dict[int, tuple] = {}
        fp = _header_bytes(fingerprint)
        if resume and self.path.exists():
            self._read(fp)
        else:
            with open(self.path, "wb") as f:
                f.write(JOURNAL_MAGIC + struct.pack("<I", len(fp)) + fp)
        self._f = open(self.path, "ab")

    def _read(self, fp: bytes) -> None:
        data = self.path.read_bytes()
        head = JOURNAL_MAGIC + struct.pack("<I", len(fp)) + fp
        if not data.startswith(head):
            raise ForbiddenMapError(f"{self.path}: a partial build with other settings (or model files) is there; "
                                    "remove it, or build with resume=False")
        pos = len(head)
        while pos + _REC.size <= len(data):
            s, n_ptr, n_iv, ev, un = _REC.unpack_from(data, pos)
            end = pos + _REC.size + 2 * (n_ptr + 2 * n_iv)
            if end > len(data):
                break  # a record cut short by the interruption: redone
            body = np.frombuffer(data, dtype="<u2", count=n_ptr + 2 * n_iv, offset=pos + _REC.size)
            self.done[int(s)] = (body[:n_ptr].copy(), body[n_ptr:].reshape(-1, 2).copy(), int(ev), int(un))
            pos = end
        if pos != len(data):
            with open(self.path, "r+b") as f:
                f.truncate(pos)

    def append(self, s: int, ptr: np.ndarray, iv: np.ndarray, evaluations: int, unresolved: int) -> None:
        self._f.write(_REC.pack(int(s), len(ptr), len(iv), int(evaluations), int(unresolved)))
        self._f.write(np.ascontiguousarray(ptr, dtype="<u2").tobytes())
        self._f.write(np.ascontiguousarray(iv, dtype="<u2").tobytes())
        self._f.flush()
        self.done[int(s)] = (ptr, iv, int(evaluations), int(unresolved))

    def close(self, *, remove: bool = False) -> None:
        self._f.close()
        if remove:
            self.path.unlink(missing_ok=True)
