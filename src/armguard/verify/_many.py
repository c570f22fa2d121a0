"""Many trajectories: serially, or on a Dask cluster (a LocalCluster of processes, or an existing scheduler)."""

from __future__ import annotations

import math
import uuid
from collections.abc import Callable, Mapping

from ..model import scene_of
from .._dask import dask_client
from .._errors import ArmguardError, VerificationError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._report import VerificationReport
from ._verify import Verifier

__all__ = ["verify_many"]

_WORKER_CACHE: dict = {}  # token -> Verifier, one per worker process (the scene is sent once)


def _named(trajectories) -> list[tuple[str | None, object]]:
    if isinstance(trajectories, Mapping):
        return [(str(k), v) for k, v in trajectories.items()]
    out = []
    for item in trajectories:
        if isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str):
            out.append(item)
        else:
            out.append((None, item))
    return out


def _chunk_task(token: str, scene, ctor: dict, items: list, kwargs: dict) -> list:
    v = _WORKER_CACHE.get(token)
    if v is None:
        _WORKER_CACHE.clear()
        v = Verifier(scene, **ctor)
        _WORKER_CACHE[token] = v
    out = []
    for j, (name, traj) in enumerate(items):
        try:
            out.append(v.verify(traj, name=name, **kwargs))
        except ArmguardError as exc:  # the chunk's finished reports go back with the error (it pickles whole)
            exc.chunk_reports, exc.chunk_index = tuple(out), j
            raise
    return out


def _kept(exc: ArmguardError, reports: list, i: int, name, total: int) -> ArmguardError:
    """``exc`` of trajectory ``i`` with the reports already made kept on it (``exc.reports``: one per
    trajectory in input order, None where not verified) and a note naming the trajectory."""
    exc.reports = tuple(reports)
    exc.failed_index = i
    done = sum(r is not None for r in reports)
    exc.add_note(f"verifying trajectory {i}{f' ({name!r})' if name else ''} of {total}: the {done} reports already made "
                 "are kept on this error (.reports, None where not verified)")
    return exc


def verify_many(scene, trajectories, *, workers: int | None = None, scheduler: str | None = None,
                chunk_size: int | None = None, progress: Callable[[int, int], None] | None = None,
                stopping_distance=0.0, method: str = "certified", frequency: float | None = None,
                joint_step: float | None = None, robot: str | None = None, threshold: float | None = None,
                payload_mass: float = 0.0, q_others=None, source: str = "auto",
                tol: Tolerances = DEFAULT_TOLERANCES, backend: str | None = None,
                backend_options=None) -> tuple[VerificationReport, ...]:
    """Verify many trajectories of ``scene``; the reports come back in input order.

    Parameters
    ----------
    trajectories : sequence of Trajectory, of ``(name, Trajectory)``, or a mapping name -> Trajectory
    workers : int | None
        Run on a fresh Dask ``distributed.LocalCluster`` with this many worker processes (one
        thread each), closed afterwards.  ``None`` and no ``scheduler``: serially, here.
    scheduler : str | None
        Address of an existing Dask scheduler (``tcp://host:8786``) to run on instead.
    chunk_size : int | None
        Trajectories per task (default: about four tasks per worker).
    progress : callable(done, total) | None
        Called as results arrive.
    The other parameters are those of :func:`verify`, applied to every trajectory.

    Results are identical to the serial run's (but for ``elapsed_s``): each worker builds the
    same :class:`Verifier` from the same scene.

    A trajectory that cannot be verified (outside its limits, ...) raises its error, with the reports
    already made kept on it: ``err.reports`` (one per trajectory, in input order; None where not
    verified), ``err.failed_index`` and a note naming the trajectory.
    """
    scene = scene_of(scene, "verification")  # a Model: its scene
    items = _named(trajectories)
    if workers is not None and scheduler is not None:
        raise VerificationError("give workers (a new LocalCluster) or scheduler (an existing cluster), not both")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise VerificationError(f"workers: expected an integer >= 1, got {workers!r}")
    ctor = dict(robot=robot, q_others=q_others, source=source, tol=tol, backend=backend, backend_options=backend_options)
    kwargs = dict(stopping_distance=stopping_distance, method=method, frequency=frequency, joint_step=joint_step,
                  robot=robot, threshold=threshold, payload_mass=payload_mass)
    total = len(items)
    if workers is None and scheduler is None:
        v = Verifier(scene, **ctor)
        out: list = [None] * total
        for i, (name, traj) in enumerate(items):
            try:
                out[i] = v.verify(traj, name=name, **kwargs)
            except ArmguardError as exc:
                raise _kept(exc, out, i, name, total)
            if progress is not None:
                progress(i + 1, total)
        return tuple(out)
    from ..backends import resolve

    # the backend chosen here (argument, the command line's --backend / --config, $ARMGUARD_BACKEND, armguard.toml):
    # a worker resolving None itself sees none of them and took its own default (analytic where fcl was refused)
    ctor["backend"], ctor["backend_options"] = resolve(backend, backend_options)
    return _on_dask(scene, items, ctor, kwargs, workers, scheduler, chunk_size, progress)


def _on_dask(scene, items, ctor, kwargs, workers, scheduler, chunk_size, progress):
    from distributed import as_completed

    with dask_client(workers, scheduler, VerificationError) as (client, n_workers):
        size = chunk_size or max(1, math.ceil(len(items) / (4 * n_workers)))
        chunks = [items[i : i + size] for i in range(0, len(items), size)]
        token = uuid.uuid4().hex
        scene_f = client.scatter(scene, broadcast=True)
        futures = {client.submit(_chunk_task, token, scene_f, ctor, chunk, kwargs, pure=False): k for k, chunk in enumerate(chunks)}
        results: list = [None] * len(chunks)
        done = 0
        for fut in as_completed(list(futures)):
            k = futures[fut]
            try:
                results[k] = fut.result()
            except ArmguardError as exc:  # the finished chunks' reports and this chunk's are kept on it
                for f in futures:
                    f.cancel()
                j = getattr(exc, "chunk_index", 0)
                results[k] = list(getattr(exc, "chunk_reports", ()))
                flat = [r for c, chunk in zip(results, chunks) for r in (list(c) + [None] * (len(chunk) - len(c))
                                                                          if c is not None else [None] * len(chunk))]
                i = k * size + j
                raise _kept(exc, flat, i, items[i][0], len(items))
            done += len(chunks[k])
            if progress is not None:
                progress(done, len(items))
        return tuple(r for chunk in results for r in chunk)
