"""One way to get a Dask client: a fresh LocalCluster of worker processes, or a scheduler's address."""

from __future__ import annotations

from contextlib import contextmanager

from ._errors import ArmguardError

__all__ = ["dask_client"]


@contextmanager
def dask_client(workers: int | None, scheduler: str | None, error: type = ArmguardError):
    """``(client, n_workers)`` for the block; the cluster (when made here) and client are closed after it.

    ``scheduler`` None: a ``distributed.LocalCluster`` of ``workers`` single-threaded processes (no
    dashboard); else a ``Client`` of the scheduler at that address (an unreachable one raises
    ``error`` naming it).  ``n_workers`` is the cluster's worker count (at least 1).
    """
    from distributed import Client, LocalCluster

    cluster = None
    if scheduler is None:
        cluster = _quiet_cluster(LocalCluster, int(workers))
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise error(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}") from exc
        except (ValueError, TypeError) as exc:  # not an address at all ("nonsense": no port number)
            raise error(f"scheduler {scheduler!r} is not a Dask scheduler's address (expected e.g. "
                        f"'tcp://10.0.0.5:8786'): {exc}") from exc
    try:
        yield client, max(1, len(client.scheduler_info().get("workers", {})) or int(workers or 1))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _quiet_cluster(LocalCluster, workers: int):
    """A LocalCluster whose worker processes ignore Ctrl-C: the terminal sends SIGINT to the whole process
    group, and each worker printed its KeyboardInterrupt traceback under the command's one-line
    "interrupted" (exit 130).  This process still takes the interrupt and closes the cluster; a process
    started while SIGINT is ignored keeps it ignored (Python installs its handler only where it is not).
    While the cluster starts (a few seconds) this process ignores Ctrl-C too: one pressed then is lost, and
    the next one, once the work runs, interrupts it."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():  # signal() works in the main thread only
        return LocalCluster(n_workers=workers, processes=True, threads_per_worker=1, dashboard_address=None)
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return LocalCluster(n_workers=workers, processes=True, threads_per_worker=1, dashboard_address=None)
    finally:
        signal.signal(signal.SIGINT, before)
