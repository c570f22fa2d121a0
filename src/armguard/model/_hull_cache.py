"""A visible, documented cache of mesh hulls between runs (``docs/models.md``, "The hull cache").

A URDF's collision meshes are read and hulled on every load (:func:`._hull.mesh_polytope`; most
of so101's load).  The result depends only on the mesh file's bytes, the URDF's scale and this
code, so it is kept, one ``.npz`` file per mesh, in::

    $ARMGUARD_CACHE_DIR/hulls/            when ARMGUARD_CACHE_DIR is set, else
    <user cache folder>/armguard/hulls/   (~/.cache/armguard/hulls on Linux, $XDG_CACHE_HOME honoured)

named by the SHA-256 of the file's bytes, the scale (three float64) and :data:`HULL_FORMAT`.
``ARMGUARD_HULL_CACHE=0`` turns it off (nothing read or written).  An entry is written
atomically (:func:`armguard._io.atomic_write`); an entry that cannot be read or does not hold a
well-formed hull is ignored with an :class:`~armguard.ArmguardWarning` naming it, and the hull
is computed again (and the entry rewritten).  A folder that cannot be written is a warning, not
an error: the model loads as without the cache.  Deleting the folder clears the cache.
"""

from __future__ import annotations

import hashlib
import io
import os
import warnings
from pathlib import Path

import numpy as np

from .._errors import ArmguardError, ArmguardWarning
from ._hull import MeshPolytope, _readonly_polytope

__all__ = ["hull_cache_dir", "cached_polytope", "HULL_FORMAT", "CACHE_DIR_ENV", "HULL_CACHE_ENV"]

HULL_FORMAT = "armguard-hull-1"
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


def _to_npz(mp: MeshPolytope):
    lens = np.fromiter(map(len, mp.faces), dtype=np.int64, count=len(mp.faces))
    loops = np.concatenate(mp.faces) if mp.faces else np.zeros(0, dtype=np.int64)

    def write(buf):
        np.savez(buf, format=np.array(HULL_FORMAT), vertices=mp.vertices, planes=mp.planes, triangles=mp.triangles,
                 face_lengths=lens, face_loops=loops, flat=np.array(mp.flat))
    return write


def _from_npz(data: bytes) -> MeshPolytope:
    """The hull of an entry; ValueError when it is not a well-formed one."""
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        if str(z["format"]) != HULL_FORMAT:
            raise ValueError(f"format {str(z['format'])!r}, expected {HULL_FORMAT!r}")
        v, planes, tri = z["vertices"], z["planes"], z["triangles"]
        lens, loops, flat = z["face_lengths"], z["face_loops"], bool(z["flat"])
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
        data = Path(mesh_path).read_bytes()
    except OSError:
        mp = compute()  # the loader's own error, naming the file
        _count(stats, "computed")
        return mp
    digest = hashlib.sha256(data).hexdigest()
    if stats is not None:
        stats.setdefault("sha256", {})[str(mesh_path)] = digest  # the Model's record of the file (Model.sha256)
    entry = folder / f"{hull_key(digest, scale)}.npz"
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
            mp = _from_npz(raw)
            _count(stats, "hits")
            return mp
        except Exception as exc:  # noqa: BLE001 - any unreadable entry is recomputed, never trusted
            warnings.warn(f"hull cache entry {entry} is not a readable hull ({type(exc).__name__}: {exc}); the hull "
                          f"of {mesh_path} is computed again and the entry rewritten", ArmguardWarning, stacklevel=3)
    mp = compute()
    _count(stats, "computed")
    from .._io import atomic_write, make_folder

    try:
        make_folder(folder)
        atomic_write(entry, _to_npz(mp))
        _count(stats, "stored")
    except (ArmguardError, OSError) as exc:
        if stats is not None:
            if stats.get("unwritable"):
                return mp  # said once per load
            stats["unwritable"] = True
        warnings.warn(f"the hull cache {folder} could not be written ({exc}); set {CACHE_DIR_ENV} to a writable "
                      f"folder or {HULL_CACHE_ENV}=0", ArmguardWarning, stacklevel=3)
    return mp


def _count(stats, what: str) -> None:
    if stats is not None:
        stats[what] = stats.get(what, 0) + 1
