"""Building a forbidden-values map: serially or on a Dask cluster, resumable, with a progress bar.

The substructures are independent (:func:`._certify.certify_substructure` reads only the grid,
the clearance hook and the lever arms), so a build is a map over substructure numbers.  Each
finished one is appended to the journal ``<out>.partial`` (:class:`._format.Journal`); a build
interrupted and restarted with the same settings skips the substructures found there.  The file
is written at the end from the substructures in order, so serial and distributed builds give
the same bytes.
"""

from __future__ import annotations

import enum
import math
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._dask import dask_client
from .._errors import ForbiddenMapError, ForbiddenMapFileError
from .._io import check_not_input, check_target, make_folder
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number
from ._certify import certify_substructure
from ._clearance import CheckerClearance, map_links
from ._geometry_digest import geometry_digest
from ._format import FORMAT_VERSION, KERNEL_VERSION, Journal, check_substructure, write_map
from ._grid import MapGrid
from ._map import ForbiddenMap, model_file_hashes

__all__ = ["build", "BuildReport", "BuildStatus", "model_files_of"]

_TASKS_PER_WORKER = 8  # Dask: substructures are grouped in about this many tasks per worker
_WORKER_CACHE: dict = {}  # token -> clearance hook, one per worker process


class BuildStatus(enum.Enum):
    BUILT = "built"  #: every substructure computed in this run
    RESUMED = "resumed"  #: some substructures were read back from an interrupted build's journal


@dataclass(frozen=True)
class BuildReport:
    """What a build did.

    Attributes
    ----------
    status : BuildStatus
    computed, reused : int
        Substructures computed in this run / read back from the journal.
    evaluations : int
        Clearance evaluations of this run.
    elapsed_s : float
        Wall-clock time of this run.
    workers : int
        Dask workers (0: serial).
    size_bytes : int
        The map file's size.
    discarded : str
        Why a damaged tail of the journal was discarded and recomputed ("" when none was).
    """

    status: BuildStatus
    computed: int
    reused: int
    evaluations: int
    elapsed_s: float
    workers: int
    size_bytes: int
    discarded: str = ""


def model_files_of(model) -> list[str]:
    """The source files of ``model``: those of ``armguard.load_model(model)`` for a built-in name or a ``.yaml`` /
    ``.urdf`` path (the sidecar, URDF and SRDF of ``urdf/<name>/``), a Model's ``files``, or a list of paths."""
    from ..model import Model, load_model

    if isinstance(model, Model):
        return [str(p) for p in model.files]
    if isinstance(model, (list, tuple)):
        return [str(Path(p)) for p in model]
    return [str(p) for p in load_model(str(model)).files]


def resolve_model(model):
    """``(Model, spec)``: ``model`` (a built-in name, a ``.yaml`` / ``.urdf`` path, a Model or a Scene) as a Model, and
    the string a worker or a later check can load it from (None when there is none: a Scene or Model built in code)."""
    from ..model import Model, load_model, model_of
    from ..scene import Scene

    if isinstance(model, Model):
        spec = str(model.files[0]) if model.files else None
        return model, spec
    if isinstance(model, Scene):
        return model_of(model), None
    spec = str(model)
    if Path(spec).is_file():  # a file: recorded whole, for workers and later checks in another working directory
        spec = str(Path(spec).resolve())
    return load_model(spec), spec


def _armguard_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("armguard")
    except PackageNotFoundError:
        return "unknown"


def _journal_check(grid: MapGrid):
    """``(s, pointers, intervals) -> None``: raises ForbiddenMapFileError unless a journal record is a valid substructure ``s``."""
    n3 = int(grid.counts[2])

    def check(s: int, ptr, iv) -> None:
        if not 0 <= s < grid.n_substructures:
            raise ForbiddenMapFileError("journal", "record", f"substructure {s} is not in 0..{grid.n_substructures - 1}")
        i1a, i1b, i2a, i2b = grid.sub_cells(s)
        words = np.concatenate([np.asarray(ptr, dtype=np.uint16), np.asarray(iv, dtype=np.uint16).reshape(-1)])
        check_substructure("journal", f"substructure {s}", words, (i1b - i1a) * (i2b - i2a), n3)

    return check


def _task(token: str, source, robot, joints, links, tol, clearance, backend, job: dict, subs: list) -> list:
    """One Dask task: certify ``subs`` (the worker builds its clearance hook once per build)."""
    hook = _WORKER_CACHE.get(token)
    if hook is None:
        _WORKER_CACHE.clear()
        if clearance is None:
            model, _ = resolve_model(source)
            ml = map_links(model.scene_for(), robot, joints, links, tol)
            if "geometry" in job and geometry_digest(model, ml.robot, ml.links)[0] != job["geometry"]:
                import socket

                raise ForbiddenMapError(f"the worker on {socket.gethostname()} loaded {source!r} as another model (its "
                                        "links or the bodies they are checked against differ from the files the build "
                                        "was started with): every worker must read the same model files")
            hook = CheckerClearance(model, ml, *backend)
        else:
            hook = clearance
        _WORKER_CACHE[token] = hook
    grid = MapGrid.from_json(job["grid"])
    out = []
    for s in subs:
        r = certify_substructure(grid, s, hook, np.asarray(job["lever"]), job["m"], job["contact"], job["depth"])
        out.append((r.index, r.pointers, r.intervals, r.evaluations, r.unresolved))
    return out


def build(model, *, out, robot: str | None = None, joints=None, links=None, resolution: float = math.radians(1.0),
          j3_resolution: float | None = None, cell=(math.radians(10.0), math.radians(10.0)),
          stopping_distance: float = 0.0, workers: int | None = None, scheduler: str | None = None,
          model_files=None, clearance=None, backend: str | None = None, backend_options=None,
          max_depth: int | None = None, resume: bool = True, progress=False,
          tol: Tolerances = DEFAULT_TOLERANCES) -> ForbiddenMap:
    """Build the certified forbidden-values map of ``model`` and write it to ``out``; returns it opened.

    Parameters
    ----------
    model : str | Model | Scene
        A built-in model name (``"hermes"``: ``urdf/hermes/``), a ``.yaml`` / ``.urdf`` path, a Model
        (``armguard.load_model``), or a Scene (then ``model_files`` names its source files).  The
        header records the sha256 of the model's files (a Model's ``files``).
    out : path
        The ``.agmap`` file to write (``out.partial`` is the journal while building).
    robot, joints, links :
        The robot (default: the only one), joints 1–3 (default: its first three) and the mapped
        links (default: those moved by joints 1–3 alone; :func:`._clearance.map_links`).
    resolution : float, rad
        Cell width of joints 1 and 2.
    j3_resolution : float | None, rad
        The joint-3 quantum (default: ``resolution``).
    cell : (2,) float, rad
        Substructure extent over joints 1, 2 (rounded to whole cells; Hermes: 10° × 10°).
    stopping_distance : float, m
        The worst-case stopping distance the obstacles grow by (the map is built off-line).
    workers : int | None
        Build on a new Dask ``LocalCluster`` with this many worker processes.
    scheduler : str | None
        Build on the Dask cluster at this address.
    model_files : list of paths | None
        The model's source files hashed into the header (default: ``model``'s own files).
    clearance : callable (Q (M, 3) rad) -> (M,) m | None
        A clearance hook replacing the backend's (must be picklable for a Dask build).
    backend, backend_options :
        The backend whose signed distances give the clearances (:class:`._clearance.CheckerClearance`):
        any installed one that answers distances; None: ``armguard.checker``'s precedence (argument,
        ``$ARMGUARD_BACKEND``, ``armguard.toml``, ``"analytic"``).  The header records the name.
    max_depth : int | None
        Halvings below one cell × bin box (default ``tol.cspace_max_depth``).
    resume : bool
        Continue from ``out.partial`` when its settings match (else start afresh).
    progress : bool | callable(done, total)
        A rich progress bar (True), a callback, or nothing.
    """
    t0 = time.perf_counter()
    if workers is not None and scheduler is not None:
        raise ForbiddenMapError("give workers (a new LocalCluster) or scheduler (an existing cluster), not both")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise ForbiddenMapError(f"workers: expected an integer >= 1, got {workers!r}")
    m = number(stopping_distance, "stopping_distance", ForbiddenMapError, low=0.0, unit=" (m)")
    depth = tol.cspace_max_depth if max_depth is None else max_depth
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not 0 <= depth <= 20:
        raise ForbiddenMapError(f"max_depth: expected an integer 0..20, got {depth!r}")
    depth = int(depth)
    if clearance is not None and (backend is not None or backend_options):
        raise ForbiddenMapError("give a clearance hook or a backend, not both")
    from ..scene import Scene

    mdl, spec = resolve_model(model)
    scene = mdl.scene
    if model_files is None:
        model_files = None if isinstance(model, Scene) else model_files_of(mdl)
        if not model_files:
            raise ForbiddenMapError("model is a Scene object (or a Model without source files): pass model_files= "
                                    "(its source files), so the map can refuse another model")
    else:
        model_files = model_files_of(list(model_files) if not isinstance(model_files, (str, Path)) else [model_files])
        if not model_files:
            raise ForbiddenMapError("model_files: empty; name the model's source files, so the map can refuse "
                                    "another model")
    ml = map_links(scene, robot, joints, links, tol)
    rob = scene.robots[ml.robot]
    lo = np.asarray(rob.lower, dtype=np.float64)[list(ml.joint_index)]
    hi = np.asarray(rob.upper, dtype=np.float64)[list(ml.joint_index)]
    grid = MapGrid.create(lo, hi, resolution, resolution if j3_resolution is None else j3_resolution, cell)
    digest, bodies = geometry_digest(mdl, ml.robot, ml.links)
    header = {
        "format_version": FORMAT_VERSION,
        "kernel_version": KERNEL_VERSION,
        "armguard": _armguard_version(),
        "model": spec,
        "model_files": model_file_hashes(model_files),
        "robot": ml.robot,
        "joints": list(ml.joints),
        "joint_index": list(ml.joint_index),
        "links": list(ml.links),
        "geometry": digest,  # what map_model compares a model or scene against
        "bodies": bodies,
        "lever": ml.lever.tolist(),
        "grid": grid.to_json(),
        "stopping_distance": m,
        "max_depth": depth,
        "contact": tol.cspace_contact,
    }
    hook = None
    if clearance is None:
        from ..backends import resolve

        name, opts = resolve(backend, backend_options)
        if workers is None and scheduler is None:
            hook = CheckerClearance(mdl, ml, name, opts)  # refuses a verdicts-only backend before any work
        header["clearance"] = "backend"
        header["backend"] = name
        if opts:
            header["backend_options"] = {k: opts[k] for k in sorted(opts)}
    else:
        header["clearance"] = getattr(clearance, "__qualname__", type(clearance).__qualname__)
    out = Path(out)
    check_not_input(out, model_files)  # the map written over the model it was built from: refused
    make_folder(out.parent)
    check_target(out)  # a FIFO, device or folder at OUT is refused before the build, not replaced after it
    journal = Journal(out.with_name(out.name + ".partial"), header, resume=resume, check=_journal_check(grid))
    reused = len(journal.done)
    todo = [s for s in range(grid.n_substructures) if s not in journal.done]
    job = {"grid": header["grid"], "lever": header["lever"], "m": m, "contact": tol.cspace_contact, "depth": depth,
           "geometry": digest}  # a worker's model checked against it
    evaluations = 0
    n_workers = 0
    bar = _Progress(progress, grid.n_substructures, reused)
    try:
        if workers is None and scheduler is None:
            hook = clearance if clearance is not None else hook
            for s in todo:
                r = certify_substructure(grid, s, hook, ml.lever, m, tol.cspace_contact, depth)
                journal.append(r.index, r.pointers, r.intervals, r.evaluations, r.unresolved)
                evaluations += r.evaluations
                bar.advance(1)
        else:
            source = spec if spec is not None else scene
            chosen = None if clearance is not None else (header["backend"], header.get("backend_options"))
            args = (source, ml.robot, ml.joints, ml.links, tol, clearance, chosen, job)
            evaluations, n_workers = _on_dask(args, todo, journal, bar, workers, scheduler)
    finally:
        bar.close()
        # a journal that holds nothing (a scheduler never reached, a failure before the first substructure)
        # is no build to resume: removed, not left for a later build with other settings to refuse
        journal.close(remove=not journal.done)
    subs, ev_all, un_all = [], 0, 0
    for s in range(grid.n_substructures):
        ptr, iv, ev, un = journal.done[s]
        subs.append((ptr, iv))
        ev_all += ev
        un_all += un
    header["stats"] = {"evaluations": ev_all, "unresolved": un_all}
    size = write_map(out, header, subs)
    journal.close(remove=True)
    fmap = ForbiddenMap.load(out, model=model_files)
    fmap.build_report = BuildReport(BuildStatus.RESUMED if reused else BuildStatus.BUILT, len(todo), reused,
                                    evaluations, time.perf_counter() - t0, n_workers, size, journal.discarded)
    return fmap


def _on_dask(args, todo, journal, bar, workers, scheduler):
    from distributed import as_completed

    evaluations = 0
    with dask_client(workers, scheduler, ForbiddenMapError) as (client, n_workers):
        size = max(1, math.ceil(len(todo) / (_TASKS_PER_WORKER * n_workers)))
        chunks = [todo[i:i + size] for i in range(0, len(todo), size)]
        token = uuid.uuid4().hex
        futures = [client.submit(_task, token, *args, chunk, pure=False) for chunk in chunks]
        for fut in as_completed(futures):
            for s, ptr, iv, ev, un in fut.result():
                journal.append(s, ptr, iv, ev, un)
                evaluations += ev
                bar.advance(1)
        return evaluations, n_workers


class _Progress:
    """A rich progress bar (``progress=True``), a ``callback(done, total)``, or nothing."""

    def __init__(self, progress, total: int, done: int) -> None:
        self.total, self.done = total, done
        self._cb = progress if callable(progress) else None
        self._bar = None
        if progress is True:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._bar = Progress(TextColumn("substructures"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                 TimeRemainingColumn(), transient=True)
            self._bar.start()
            self._task = self._bar.add_task("build", total=total, completed=done)

    def advance(self, n: int) -> None:
        self.done += n
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done)
        if self._cb is not None:
            self._cb(self.done, self.total)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None
