"""The certified search of a collision matrix on a Dask cluster (``armguard srdf --scheduler``).

Each worker process loads the model from the file it was loaded from (without its SRDF), makes
the same pair setup and evaluator once (kept per process, under the SHA-256 of every file the
caller's model was loaded from: a worker of a long-running cluster never searches a model it
loaded before the URDF or a mesh was edited; and a worker whose files hash otherwise than the
caller's refuses the task), and searches the pairs it is given
with the same limits and seeds as :func:`~._matrix.collision_matrix` does here, so the verdicts
are the same as a run in one process.  The pairs go out one task each; results come back as
:class:`~._prove.PairProof` (plain data).
"""

from __future__ import annotations

from pathlib import Path

from .._dask import dask_client
from .._errors import VerificationError

__all__ = ["prove_on_dask"]

_WORKER: dict = {}  # (source, files' SHA-256, backend) -> (setup, evaluator), one per worker process


def _source(model) -> str:
    """The file ``model`` was loaded from (a URDF or a sidecar / scene YAML)."""
    if not model.files:
        raise VerificationError(f"model {model.name!r} was not loaded from a file: a Dask worker cannot load it")
    return str(model.files[0])


def _files_sha256(model) -> tuple:
    """The SHA-256 of every file ``model`` was read from but an SRDF (the workers load without one),
    sorted: the same bytes wherever a worker's files resolve (another machine's mesh folders)."""
    srdf = str(Path(model.srdf.file).resolve()) if getattr(model, "srdf", None) is not None and model.srdf.file else None
    return tuple(sorted(h for f, h in model.sha256.items() if f != srdf))


def _prove_task(source: str, files: tuple, backend, names: tuple, k: int, limits: dict):
    from ..model import load_model
    from ._matrix import PairEvaluator, prove_one
    from ._pairs import pair_setup

    key = (source, files, backend)
    got = _WORKER.get(key)
    if got is None:
        model = load_model(source, srdf=False)
        if _files_sha256(model) != files:
            raise VerificationError(f"{source}: a worker read files other than the caller's (edited since the caller "
                                    "loaded it, or not the same files on the worker's machine); load it again and rerun")
        setup = pair_setup(model)
        got = (setup, PairEvaluator(model, setup, backend))
        _WORKER.clear()  # one model per worker process at a time
        _WORKER[key] = got
    setup, ev = got
    p = setup.pairs[k]
    if (p.link1, p.link2) != names:  # the worker's model is not the one the caller has
        raise VerificationError(f"{source}: a worker's pair {k} is {p.link1}-{p.link2}, the caller's {names[0]}-{names[1]}"
                                " (the file changed since it was loaded?)")
    return prove_one(setup, ev, k, limits)


def prove_on_dask(model, todo, limits: dict, backend, workers, scheduler: str, advance) -> dict:
    """``{k: PairProof}`` for the link pairs ``todo`` of ``model``'s pair setup, searched on a Dask
    cluster: ``scheduler="local"`` a fresh LocalCluster of ``workers`` processes, else the scheduler
    at that address."""
    from distributed import as_completed

    from ._pairs import pair_setup

    source, files = _source(model), _files_sha256(model)
    setup = pair_setup(model)
    local = scheduler == "local"
    with dask_client(int(workers or 2) if local else None, None if local else scheduler, VerificationError) as (client, _):
        futures = {client.submit(_prove_task, source, files, backend, (setup.pairs[k].link1, setup.pairs[k].link2), k, limits,
                                 pure=False): k for k in todo}
        out = {}
        for fut in as_completed(futures):
            out[futures[fut]] = fut.result()
            advance()
    return out
