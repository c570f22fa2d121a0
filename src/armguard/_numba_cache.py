"""Where numba may cache armguard's kernels, when the installed package is read-only.

numba caches a ``@njit(cache=True)`` kernel in ``__pycache__`` beside its source, else in the
user's cache folder (``~/.cache/numba``), else it refuses to define the kernel ("no locator
available"), and armguard would not import.  :func:`ensure_numba_cache` runs first on
``import armguard``: when ``$NUMBA_CACHE_DIR`` is unset and neither of numba's two folders is
writable (a read-only site-packages and no writable home, as in some containers), it points
numba at ``<temp dir>/armguard-numba-<user>`` instead -- a folder this user owns, that no one
else may write and that is no link (numba reads its index files with pickle: a folder another
user made first could run their code here); when that name is taken otherwise, at a fresh
private folder (``tempfile.mkdtemp``: compiled again in each process).  Otherwise it changes
nothing (and does not import numba).
"""

from __future__ import annotations

import getpass
import os
import tempfile
from pathlib import Path

__all__ = ["ensure_numba_cache", "signature", "writable"]


def writable(folder: Path) -> bool:
    """Whether ``folder`` could be created (when missing) and written to."""
    p = Path(folder)
    while not p.exists():
        if p.parent == p:
            return False
        p = p.parent
    return p.is_dir() and os.access(p, os.W_OK | os.X_OK)


def _user_cache_dir() -> Path:
    from numba.misc.appdirs import AppDirs

    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)


def _user() -> str:
    try:
        return getpass.getuser()
    except (KeyError, OSError):  # no name for this uid (a container)
        return str(os.getuid()) if hasattr(os, "getuid") else "user"


def ensure_numba_cache(package_dir: Path | None = None) -> Path | None:
    """Point numba at a temp folder when it could cache armguard's kernels nowhere (see the module
    docstring); returns that folder, or None when numba's own choice stands."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    package_dir = Path(package_dir) if package_dir is not None else Path(__file__).resolve().parent
    if writable(package_dir / "__pycache__") or writable(_user_cache_dir()):
        return None
    folder = _private_folder(Path(tempfile.gettempdir()) / f"armguard-numba-{_user()}")
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    from numba.core import config

    config.CACHE_DIR = str(folder)  # numba read the environment when it was imported above
    return folder


def _private_folder(folder: Path) -> Path:
    """``folder``, made mode 0700 when missing, when it is a real folder of this user that no one else
    may write (one that was open to others may hold what they put there: it is not chmod-ed and
    trusted); else a fresh folder of ``tempfile.mkdtemp`` (0700), removed at exit."""
    try:
        os.mkdir(folder, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return _fresh_private()
    try:
        st = os.lstat(folder)
    except OSError:
        return _fresh_private()
    import stat

    own = not hasattr(os, "getuid") or st.st_uid == os.getuid()
    if stat.S_ISDIR(st.st_mode) and own and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return folder
    return _fresh_private()


def _fresh_private() -> Path:
    """A new 0700 folder, removed when the process ends (its kernels are compiled again next time)."""
    import atexit
    import shutil

    folder = Path(tempfile.mkdtemp(prefix="armguard-numba-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def signature(codes: str) -> tuple:
    """The numba argument types of a kernel signature written in codes, as the first-run warm-up's
    plans give them (:mod:`armguard.cli._compile`; a backend's ``warm_up_leaves``): F1/F2 float64
    C arrays (1-D/2-D), I1/I2 int64 ones, f float64, i int64, b boolean."""
    from numba import types

    kinds = {"F1": types.float64[::1], "F2": types.float64[:, ::1], "I1": types.int64[::1],
             "I2": types.int64[:, ::1], "f": types.float64, "i": types.int64, "b": types.boolean}
    try:
        return tuple(kinds[c] for c in codes.split())
    except KeyError as exc:
        raise ValueError(f"unknown signature code {exc.args[0]!r} in {codes!r} (known: {sorted(kinds)})") from None
