"""A visible, documented cache of mesh hulls between runs (``docs/models.md``, "The hull cache").

A URDF's collision meshes are read and hulled on every load (:func:`._hull.mesh_polytope`; most
of so101's load).  The result depends only on the mesh file's bytes, the URDF's scale and this
code, so it is kept, one ``.npz`` file per mesh, in::

    $ARMGUARD_CACHE_DIR/hulls/            when ARMGUARD_CACHE_DIR is set, else
    <user cache folder>/armguard/hulls/   (~/.cache/armguard/hulls on Linux, $XDG_CACHE_HOME honoured)

named by the SHA-256 of the file's bytes (and of the files it reads its geometry from: a glTF's
buffers, :func:`mesh_dependencies`), the scale (three float64) and :data:`HULL_FORMAT`.
``ARMGUARD_HULL_CACHE=0`` turns it off (nothing read or written).  An entry is written
atomically (:func:`armguard._io.atomic_write`) and holds its own key and a SHA-256 of its arrays;
an entry that cannot be read, is another mesh's (a renamed or copied file), was edited, or does
not hold a well-formed hull is ignored with an :class:`~armguard.ArmguardWarning` naming it, and
the hull is computed again (and the entry rewritten).  A mesh whose files change while its hull
is computed is hashed and hulled again, and never stored under the old bytes' key.  A folder
that cannot be written is a warning, not an error: the model loads as without the cache.
Deleting the folder clears the cache.  The folder is trusted as the installed package is: its
checks find accidents (a copied entry, a hand edit), not someone who rewrites an entry whole.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import warnings
from pathlib import Path

import numpy as np

from .._errors import ArmguardError, ArmguardWarning
from ._hull import MeshPolytope, _readonly_polytope

__all__ = ["hull_cache_dir", "cached_polytope", "mesh_dependencies", "HULL_FORMAT", "CACHE_DIR_ENV", "HULL_CACHE_ENV"]

HULL_FORMAT = "armguard-hull-2"
"""Part of every key: changed whenever :func:`._hull.mesh_polytope`'s result for a file changes."""
CACHE_DIR_ENV = "ARMGUARD_CACHE_DIR"
HULL_CACHE_ENV = "ARMGUARD_HULL_CACHE"


def hull_cache_dir() -> Path | None:
    """The folder of cached hulls, or None when ``ARMGUARD_HULL_CACHE=0`` turns the cache off."""
    if os.environ.get(HULL_CACHE_ENV, "1").strip().lower() in ("0", "false", "no", "off"):
        return None
    root = os.environ.get(CACHE_DIR_ENV)
    if root:
        return Path(root).expanduser() / "hulls"
    from numba.misc.appdirs import AppDirs

    return Path(AppDirs(appname="armguard", appauthor=False).user_cache_dir) / "hulls"


def hull_key(file_sha256: str, scale) -> str:
    """The entry's name: SHA-256 of the mesh file's SHA-256 (hex), the scale and :data:`HULL_FORMAT`."""
    h = hashlib.sha256(file_sha256.encode())
    h.update(np.asarray(scale, dtype="<f8").reshape(-1).tobytes())
    h.update(HULL_FORMAT.encode())
    return h.hexdigest()


def mesh_dependencies(mesh_path, data: bytes | None = None) -> tuple[Path, ...]:
    """The other files mesh file ``mesh_path`` reads its geometry from, that exist: a glTF's
    buffers given by a file name (``buffers[].uri``, not a ``data:`` URI; the JSON chunk of a
    ``.glb``).  An STL, OBJ (its ``.mtl`` holds no geometry), PLY or COLLADA file holds its own.
    ``data``: the file's bytes, when already read."""
    suffix = Path(mesh_path).suffix.lower()
    if suffix not in (".gltf", ".glb"):
        return ()
    try:
        raw = Path(mesh_path).read_bytes() if data is None else data
        if suffix == ".glb":  # 12-byte header, then the JSON chunk: length, type "JSON", bytes
            n = int.from_bytes(raw[12:16], "little")
            raw = raw[20:20 + n] if raw[16:20] == b"JSON" else b"{}"
        doc = json.loads(raw)
        uris = [b.get("uri") for b in doc.get("buffers", ()) if isinstance(b, dict)]
    except (OSError, ValueError, AttributeError, TypeError):
        return ()  # the loader's own error names what is wrong with the file
    from urllib.parse import unquote

    folder = Path(mesh_path).parent
    found = [folder / unquote(u) for u in uris if isinstance(u, str) and u and not u.startswith("data:")]
    return tuple(dict.fromkeys(p for p in found if p.is_file()))


def _digest(mesh_path, data: bytes) -> tuple[str, str]:
    """``(own, whole)``: the SHA-256 of a mesh file's bytes, and that of them and of each file it
    reads its geometry from (name and bytes; ``own`` again when it reads no other): what its hull
    depends on."""
    h = hashlib.sha256(data)
    own = h.hexdigest()
    deps = mesh_dependencies(mesh_path, data)
    for p in deps:
        h.update(b"\0" + p.name.encode() + b"\0" + hashlib.sha256(p.read_bytes()).digest())
    return own, (h.hexdigest() if deps else own)


_ARRAYS = ("vertices", "planes", "triangles", "face_lengths", "face_loops", "flat")


def _arrays_sha256(arrays: dict) -> str:
    h = hashlib.sha256()
    for k in _ARRAYS:
        a = np.ascontiguousarray(arrays[k])
        h.update(f"{k}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _to_npz(mp: MeshPolytope, key: str):
    lens = np.fromiter(map(len, mp.faces), dtype=np.int64, count=len(mp.faces))
    loops = np.concatenate(mp.faces) if mp.faces else np.zeros(0, dtype=np.int64)
    arrays = dict(vertices=mp.vertices, planes=mp.planes, triangles=mp.triangles, face_lengths=lens,
                  face_loops=loops, flat=np.array(mp.flat))

    def write(buf):
        np.savez(buf, format=np.array(HULL_FORMAT), key=np.array(key), sha256=np.array(_arrays_sha256(arrays)),
                 **arrays)
    return write


def _from_npz(data: bytes, key: str) -> MeshPolytope:
    """The hull of an entry named ``key``; ValueError when it is another key's, its arrays are not
    the ones written (their SHA-256), or they are not a well-formed hull."""
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        if str(z["format"]) != HULL_FORMAT:
            raise ValueError(f"format {str(z['format'])!r}, expected {HULL_FORMAT!r}")
        if str(z["key"]) != key:
            raise ValueError(f"it is the entry of another mesh or scale ({str(z['key'])[:12]}...; a renamed or copied file)")
        arrays = {k: z[k] for k in _ARRAYS}
        if str(z["sha256"]) != _arrays_sha256(arrays):
            raise ValueError("its arrays are not the ones written (SHA-256 differs: the entry was edited)")
        v, planes, tri = arrays["vertices"], arrays["planes"], arrays["triangles"]
        lens, loops, flat = arrays["face_lengths"], arrays["face_loops"], bool(arrays["flat"])
    n_v = len(v)
    ok = (v.dtype == np.float64 and v.ndim == 2 and v.shape[1] == 3 and n_v >= 3 and np.isfinite(v).all()
          and planes.dtype == np.float64 and planes.ndim == 2 and planes.shape[1] == 4 and np.isfinite(planes).all()
          and tri.dtype == np.int64 and tri.ndim == 2 and tri.shape[1] == 3
          and lens.dtype == np.int64 and loops.dtype == np.int64 and lens.ndim == 1 and loops.ndim == 1
          and len(lens) == len(planes) and int(lens.sum()) == len(loops) and (lens >= 3).all()
          and (loops.size == 0 or (0 <= loops.min() and loops.max() < n_v))
          and (tri.size == 0 or (0 <= tri.min() and tri.max() < n_v)))
    if ok and not flat:
        ok = len(lens) >= 4 and len(tri) >= 4
    if ok and flat:
        ok = len(lens) == 0 and len(tri) == 0
    if not ok:
        raise ValueError("its arrays do not make a hull")
    loops.flags.writeable = False  # the faces are views of it
    ends = np.cumsum(lens).tolist()
    faces = tuple(loops[a:b] for a, b in zip([0, *ends[:-1]], ends))
    return _readonly_polytope(v, faces, planes, tri, flat)


def cached_polytope(mesh_path, scale, compute, stats: dict | None = None) -> MeshPolytope:
    """``compute()`` (the hull of the mesh file ``mesh_path`` at ``scale``), or its cached copy.

    ``stats``: counts ``"hits"``, ``"computed"`` and ``"stored"``, records ``"folder"`` (None: cache off) and the
    file's SHA-256 under ``"sha256"[str(mesh_path)]``."""
    folder = hull_cache_dir()
    if stats is not None:
        stats["folder"] = str(folder) if folder is not None else None
    if folder is None:
        mp = compute()
        _count(stats, "computed")
        return mp
    try:
        own, digest = _digest(mesh_path, Path(mesh_path).read_bytes())
    except OSError:
        mp = compute()  # the loader's own error, naming the file
        _count(stats, "computed")
        return mp
    key = hull_key(digest, scale)
    entry = folder / f"{key}.npz"
    try:
        raw = entry.read_bytes()
    except (FileNotFoundError, NotADirectoryError):  # no entry (or no folder: the write below says so)
        raw = None
    except OSError as exc:
        warnings.warn(f"hull cache entry {entry} could not be read ({exc.strerror or exc}); the hull of {mesh_path} "
                      "is computed again", ArmguardWarning, stacklevel=3)
        raw = None
    if raw is not None:
        try:
            mp = _from_npz(raw, key)
            _count(stats, "hits")
            _record(stats, mesh_path, own)
            return mp
        except Exception as exc:  # noqa: BLE001 - any unreadable entry is recomputed, never trusted
            warnings.warn(f"hull cache entry {entry} is not a readable hull ({type(exc).__name__}: {exc}); the hull "
                          f"of {mesh_path} is computed again and the entry rewritten", ArmguardWarning, stacklevel=3)
    mp, hashed = _computed_from(mesh_path, (own, digest), compute)
    _count(stats, "computed")
    if hashed is None:  # the file kept changing: hulled from one of its reads, stored under no key
        return mp
    _record(stats, mesh_path, hashed[0])
    if hashed[1] != digest:  # replaced before it was read: the hull is the new bytes', stored under their key
        key = hull_key(hashed[1], scale)
        entry = folder / f"{key}.npz"
    from .._io import atomic_write, make_folder

    try:
        make_folder(folder)
        atomic_write(entry, _to_npz(mp, key))
        _count(stats, "stored")
    except (ArmguardError, OSError) as exc:
        if stats is not None:
            if stats.get("unwritable"):
                return mp  # said once per load
            stats["unwritable"] = True
        warnings.warn(f"the hull cache {folder} could not be written ({exc}); set {CACHE_DIR_ENV} to a writable "
                      f"folder or {HULL_CACHE_ENV}=0", ArmguardWarning, stacklevel=3)
    return mp


def _computed_from(mesh_path, hashed: tuple[str, str], compute, tries: int = 3):
    """``(compute(), (own, whole))`` with the mesh's hashes (:func:`_digest`) read after it, equal
    to those read before it: the hull is that of those bytes (a file replaced while it was read, by
    a checkout or a build, is read again).  ``(hull, None)`` when they changed on every one of
    ``tries``: that hull is not to be stored under any key."""
    for _ in range(tries):
        mp = compute()
        try:
            now = _digest(mesh_path, Path(mesh_path).read_bytes())
        except OSError:
            return mp, None
        if now == hashed:
            return mp, now
        hashed = now
    warnings.warn(f"mesh {mesh_path} changed while its hull was computed ({tries} times); its hull is not cached",
                  ArmguardWarning, stacklevel=4)
    return mp, None


def _record(stats, mesh_path, own: str) -> None:
    """The Model's record of the mesh file's SHA-256 (``Model.sha256``), of the bytes its hull is of."""
    if stats is not None:
        stats.setdefault("sha256", {})[str(mesh_path)] = own


def _count(stats, what: str) -> None:
    if stats is not None:
        stats[what] = stats.get(what, 0) + 1
