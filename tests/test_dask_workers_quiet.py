"""A LocalCluster's workers ignore Ctrl-C: the terminal's SIGINT reaches the whole process group, and each
worker printed a KeyboardInterrupt traceback under the command's one-line "interrupted" (exit 130)."""

from __future__ import annotations

import signal


def _sigint_ignored() -> bool:
    import signal as s

    return s.getsignal(s.SIGINT) == s.SIG_IGN


def test_workers_ignore_sigint_and_this_process_keeps_its_handler():
    from armguard._dask import dask_client

    before = signal.getsignal(signal.SIGINT)
    with dask_client(1, None) as (client, n):
        assert n == 1
        assert signal.getsignal(signal.SIGINT) is before  # the command still takes Ctrl-C
        assert list(client.run(_sigint_ignored).values()) == [True]
    assert signal.getsignal(signal.SIGINT) is before
