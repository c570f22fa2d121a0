"""Interchangeable checkers: backends found by entry point, picked by one precedence.

``armguard.checker(model, backend=None, options=None)`` builds the Checker of a backend:
the explicit argument, else ``$ARMGUARD_BACKEND``, else ``armguard.toml`` (``[backend] name =
…`` and options, in the working directory or the file given by ``config=`` /
``$ARMGUARD_CONFIG``), else ``"analytic"``.  Backends register under the entry-point group
``armguard.backends`` (``importlib.metadata``): a third party adds one by installing a
package.  ``available()`` lists the installed ones, a backend whose package (or a package it needs)
does not import included: ``get_backend`` / ``checker`` then raise a BackendError naming it and the
missing module.

The entry points are discovered once per ``sys.path`` (``importlib.metadata`` reads every
installed distribution's metadata, ~3-6 ms, and ``get_backend`` runs on every Detector's
construction) and cached; a change of ``sys.path`` (a folder prepended, as a test installing a
package does) discovers them again.  A package installed into a folder already on the path while
the process runs is seen after ``available(refresh=True)`` (or :func:`refresh`).
"""

from __future__ import annotations

import contextvars
import os
import sys
import threading
import math
import tomllib
from importlib import metadata
from pathlib import Path
from typing import Mapping

from .._errors import ArmguardError, BackendError, DetectionError
from ._interface import (Backend, Capability, Checker, CheckerBase, NearestPair, PairDistances, PairDistancesMany, check_margin,
                         check_pairs, check_Q, check_q, check_unit_circle, subset_verdicts)
from ._margins import CATEGORIES, by_category, check_margins, collides_per_pair, collides_subset, pair_margins

__all__ = ["available", "refresh", "get_backend", "checker", "resolve", "command_line_choice", "option_value", "Backend", "Checker", "CheckerBase", "PairDistances",
           "PairDistancesMany", "NearestPair", "check_margin", "check_margins", "collides_per_pair", "collides_subset", "subset_verdicts", "pair_margins", "by_category",
           "CATEGORIES", "check_pairs", "Capability", "check_q", "check_Q", "check_unit_circle", "GROUP", "DEFAULT", "ENV"]

GROUP = "armguard.backends"
DEFAULT = "analytic"
ENV = "ARMGUARD_BACKEND"
CONFIG_ENV = "ARMGUARD_CONFIG"
CONFIG_FILE = "armguard.toml"


_EP_LOCK = threading.Lock()
_EP_CACHE: tuple = ((), None)  # (the sys.path they were discovered on, {name: entry point}); None: not yet


def _entry_points(refresh: bool = False) -> dict:
    """``{name: entry point}`` of the installed backends: discovered on the first call (under a lock:
    one thread scans, the others wait for its result) and again when ``sys.path`` has changed
    since, or when ``refresh``.  A copy: callers may add to it."""
    global _EP_CACHE
    path = tuple(sys.path)
    key, eps = _EP_CACHE
    if refresh or eps is None or key != path:
        with _EP_LOCK:
            key, eps = _EP_CACHE
            if refresh or eps is None or key != path:
                eps = {ep.name: ep for ep in metadata.entry_points(group=GROUP)}
                _EP_CACHE = (path, eps)
    return dict(eps)


def available(refresh: bool = False) -> tuple[str, ...]:
    """The names of the installed backends (sorted).  ``refresh``: scan the installed packages again
    (a backend installed while the process runs, into a folder already on ``sys.path``)."""
    return tuple(sorted(_entry_points(refresh)))


def refresh() -> tuple[str, ...]:
    """Forget the discovered backends and scan the installed packages again; returns :func:`available`'s
    names.  (The discovery is cached: see the module docstring.)"""
    return available(refresh=True)


def get_backend(name: str) -> Backend:
    """The installed backend ``name``; an unknown name lists the installed ones.  A backend whose
    package (or a package it needs) fails to import is a BackendError naming it and the module."""
    eps = _entry_points()
    if name not in eps:
        raise BackendError(f"unknown backend {name!r}; installed backends are {sorted(eps)}")
    ep = eps[name]
    where = f"entry point {name} = {getattr(ep, 'value', ep)!r}"
    try:
        obj = ep.load()
    except ImportError as exc:
        raise _load_error(name, exc, f"loading its {where}") from exc
    except Exception as exc:  # a misspelt object name, a package that raises on import: the backend's, named
        raise BackendError(f"backend {name!r} could not be loaded: {type(exc).__name__}: {exc} (raised while loading "
                           f"its {where}: an error in the backend's package)") from exc
    try:
        backend = obj() if isinstance(obj, type) else obj  # a class is made with no arguments
    except Exception as exc:
        raise BackendError(f"backend {name!r}: its {where} is a class that cannot be made with no arguments: "
                           f"{type(exc).__name__}: {exc}") from exc
    if not callable(getattr(backend, "build", None)):
        raise BackendError(f"backend {name!r}: its {where} gives a {type(backend).__name__}, which has no "
                           "build(model, options) method (docs/backends.md)")
    return backend


def _load_error(name: str, exc: ImportError, where: str) -> BackendError:
    """The BackendError of backend ``name`` whose import failed with ``exc`` while ``where``: it is listed
    by :func:`available` (its entry point is installed) but cannot be used."""
    why = "its package or a dependency is not installed" if isinstance(exc, ModuleNotFoundError) else \
        "its package or a dependency is installed but does not import (a broken or mismatched install)"
    return BackendError(f"backend {name!r} could not be loaded: {exc} ({why}; raised while {where})")


_CHOICE: contextvars.ContextVar = contextvars.ContextVar("armguard_backend_choice", default=(None, None))


def command_line_choice(backend: str | None, config=None):
    """Make ``backend`` (and ``config``) the explicit choice until the returned callable is called
    (the command line's ``--backend`` / ``--config``)."""
    token = _CHOICE.set((backend, config))
    return lambda: _CHOICE.reset(token)


def option_value(text: str):
    """A backend option given as text (``--backend-option KEY=VALUE`` of ``armguard compare`` and of the
    conformance suite's pytest plugin): ``"1"`` -> 1, ``"1e-9"`` -> 1e-9, ``"true"``/``"false"`` -> bool,
    anything else the string itself (``"nan"``, ``"inf"`` included: no finite number, for the backend to
    refuse by name; as a float it reached compare.json, which holds no NaN)."""
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    for kind in (int, float):
        try:
            value = kind(text)
        except ValueError:
            continue
        return value if math.isfinite(value) else text
    return text


def read_config(config=None) -> dict:
    """The ``[backend]`` table of ``armguard.toml`` (``config``, ``$ARMGUARD_CONFIG`` or the working directory)."""
    path = config or _CHOICE.get()[1] or os.environ.get(CONFIG_ENV)
    p = Path(path) if path else Path.cwd() / CONFIG_FILE
    if not p.is_file():
        if path:
            raise BackendError(f"{p}: configuration file not found")
        return {}
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise BackendError(f"{p}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:  # TOML is UTF-8 text
        raise BackendError(f"{p}: not valid TOML: not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    except RecursionError:
        raise BackendError(f"{p}: not valid TOML: nested too deeply to read") from None
    except OSError as exc:
        raise BackendError(f"{p}: cannot read this configuration file ({exc.strerror or exc})") from None
    table = data.get("backend", {})
    if not isinstance(table, dict):
        raise BackendError(f"{p}: [backend] must be a table (name = ..., options)")
    return {"file": str(p), **table}


def resolve(backend: str | None = None, options: Mapping | None = None, *, config=None) -> tuple[str, dict]:
    """``(name, options)`` by the precedence: argument > ``$ARMGUARD_BACKEND`` > ``armguard.toml`` > default."""
    cfg = read_config(config)
    if backend is None:
        backend = _CHOICE.get()[0]  # the command line's --backend counts as the argument
    if backend is not None:
        name = str(backend)
    elif os.environ.get(ENV):
        name = os.environ[ENV]
    elif "name" in cfg:
        name = str(cfg["name"])
    else:
        name = DEFAULT
    opts = {}
    if cfg.get("name", name) == name:  # the file's options belong to the backend it names
        opts.update({k: v for k, v in cfg.items() if k not in ("name", "file")})
        opts.update(cfg.get(name, {}) if isinstance(cfg.get(name), dict) else {})
    opts.pop(name, None)
    opts.update(dict(options or {}))
    return name, opts


def require_pairs(model) -> None:
    """A :class:`~armguard.DetectionError` when ``model`` has no active pair, or none with a shape the
    configuration moves: a check of it could only say "clear" (or the same verdict at every
    configuration) without having looked at the arm (an SRDF that disables every pair, or every pair
    but one between two fixed links; a robot alone)."""
    pairs, scene = model.pairs, model.scene
    moving = sum(1 for oa, ob in zip(pairs.owner_a, pairs.owner_b) if scene.moves(oa) or scene.moves(ob))
    if moving == 0:
        srdf = getattr(model, "srdf", None)
        why = f" (its SRDF {srdf.file} disables {len(srdf.disabled)} pairs)" if srdf is not None and srdf.disabled else ""
        what = "no pair to check" if len(pairs) == 0 else \
            f"no pair to check with a shape the configuration moves ({len(pairs)} pairs, all between fixed shapes)"
        raise DetectionError(f"model {model.name!r} has {what}{why}: no verdict can be given; "
                             "enable a pair, add a body or a workspace box")


def checker(model, backend: str | None = None, options: Mapping | None = None, *, config=None) -> Checker:
    """The Checker of ``backend`` (see :func:`resolve`) for ``model`` (a Model or anything ``load_model`` takes)."""
    from ..model import Model, load_model
    from ..model._entry import warn_edited

    if not isinstance(model, Model):
        model = load_model(model)
    else:
        warn_edited(model, "checker")
    require_pairs(model)
    name, opts = resolve(backend, options, config=config)
    try:
        return get_backend(name).build(model, opts)
    except ImportError as exc:  # a backend that imports its dependency on build (fcl: python-fcl)
        raise _load_error(name, exc, "building its checker") from exc
    except BackendError as exc:  # an option the backend refuses: named with the file it came from
        source = _options_file(name, options, config)
        if source is None or isinstance(exc.__cause__, ImportError):  # a failed import is no option's fault
            raise
        raise BackendError(f"{source}: [backend]: {exc}") from None
    except ArmguardError:
        raise  # a refusal of another kind (a model the backend cannot take), as it is
    except Exception as exc:  # the backend's own failure, named (it read as an internal error of armguard)
        raise BackendError(f"backend {name!r} failed to build a checker for model {model.name!r}: "
                           f"{type(exc).__name__}: {exc} (an error in the backend)") from exc


def _options_file(name: str, options, config) -> str | None:
    """The armguard.toml whose ``[backend]`` options :func:`resolve` gave backend ``name``, or None."""
    cfg = read_config(config)
    mine = {k for k in cfg if k not in ("name", "file")} if cfg.get("name", name) == name else set()
    return cfg.get("file") if mine - set(options or {}) else None
