"""The exit status of every ``armguard`` command: one meaning per code, defined here only.

A script can tell "unsafe" (1) from "could not finish" (5) from "could not check at all" (2, 3,
4, 130) without reading the output.  ``run_guarded`` maps what a command raises to its code:
an :class:`armguard.ArmguardError` (a file or value armguard refuses, an output it cannot write)
and an ``OSError`` are one located line and 3; any other exception is one line and 4, with the
traceback under ``armguard --traceback ...`` or ``ARMGUARD_DEBUG=1``; Ctrl-C is 130 (128 + SIGINT,
the shell's convention); output into a pipe closed early (``| head``) is 141 (128 + SIGPIPE).  Click's own usage errors keep click's 2.
"""

from __future__ import annotations

import enum
import errno
import os
import sys
import traceback

import click

from .._errors import ArmguardError

__all__ = ["ExitCode", "exit_epilog", "run_guarded", "DEBUG_ENV"]

DEBUG_ENV = "ARMGUARD_DEBUG"
"""Environment variable: set to 1 to print the traceback of an internal error (as ``--traceback``)."""


class ExitCode(enum.IntEnum):
    """What an ``armguard`` command's exit status means (the same for every command)."""

    OK = 0
    """Done: clear, safe, the backends agree, the file written."""
    UNSAFE = 1
    """A verdict that is not safe: a collision, a stopping-distance violation, backends that differ,
    an error-level lint finding."""
    USAGE = 2
    """A bad option or argument (click's usage error)."""
    INPUT = 3
    """A file or value armguard refuses (it names the file and the place), or an output it cannot write."""
    INTERNAL = 4
    """An unexpected error inside armguard (a bug: rerun with --traceback and report it)."""
    INCOMPLETE = 5
    """The check could not finish (a budget ran out before a verdict): never read as safe, nor as a collision."""
    INTERRUPTED = 130
    """Interrupted (Ctrl-C, SIGINT): nothing half-written is left in place of an output."""
    OUTPUT_CLOSED = 141
    """The output was closed before the command had printed everything (``armguard check ur5 | head -1``):
    128 + SIGPIPE, the shell's convention; never 0 or 1, since what was not printed may hold the verdict."""


_GENERIC = {
    ExitCode.USAGE: "usage error (a bad option or argument)",
    ExitCode.INPUT: "a file or value refused (named in the message), or an output that cannot be written",
    ExitCode.INTERNAL: f"internal error (rerun as armguard --traceback ..., or with {DEBUG_ENV}=1)",
    ExitCode.INTERRUPTED: "interrupted (Ctrl-C)",
    ExitCode.OUTPUT_CLOSED: "the output was closed before everything was printed (| head)",
}


def exit_epilog(ok: str = "done", unsafe: str | None = None, incomplete: str | None = None) -> str:
    """The "Exit status" table of a command's ``--help`` (click's epilog): ``ok``, ``unsafe`` and
    ``incomplete`` are the command's own meanings of 0, 1 and 5 (None: the command never exits so)."""
    rows = {ExitCode.OK: ok}
    if unsafe is not None:
        rows[ExitCode.UNSAFE] = unsafe
    rows.update(_GENERIC)
    if incomplete is not None:
        rows[ExitCode.INCOMPLETE] = incomplete
    rows = dict(sorted(rows.items()))
    # "\b": click prints the paragraph as written (no rewrapping)
    return "Exit status:\n\n\b\n" + "\n".join(f"{int(c):<4d} {text}" for c, text in rows.items())


def _debug(ctx) -> bool:
    return bool(ctx.params.get("traceback")) or os.environ.get(DEBUG_ENV, "").strip() not in ("", "0")


def _error(message: str, code: ExitCode):
    click.secho(f"error: {message}", fg="red", err=True)
    sys.exit(int(code))


def _output_closed():
    """Exit with :attr:`ExitCode.OUTPUT_CLOSED` after a write to a closed pipe: stdout is pointed at
    the null device first, so that the interpreter's last flush does not fail again (click's own
    handling exits 1, which here means "unsafe")."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    except (OSError, ValueError):  # no file descriptor behind stdout (a test's capture)
        pass
    sys.exit(int(ExitCode.OUTPUT_CLOSED))


def run_guarded(ctx, invoke, located):
    """``invoke()``, with what it raises turned into one line on stderr and its :class:`ExitCode`;
    ``located(message)`` words an ArmguardError's message in the command's terms."""
    try:
        return invoke()
    except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
        raise  # click's own: usage errors (2), ctx.exit(), its abort
    except KeyboardInterrupt:
        click.echo("\ninterrupted", err=True)
        sys.exit(int(ExitCode.INTERRUPTED))
    except ArmguardError as exc:
        _error(located(str(exc)), ExitCode.INPUT)
    except OSError as exc:
        if exc.errno == errno.EPIPE:
            _output_closed()
        if _debug(ctx):
            traceback.print_exc()
        where = exc.filename if exc.filename is not None else ""
        _error(f"{where}: {exc.strerror or exc}" if where else f"{exc.strerror or exc}", ExitCode.INPUT)
    except Exception as exc:
        if _debug(ctx):
            traceback.print_exc()
            _error(f"internal error: {type(exc).__name__}: {exc}", ExitCode.INTERNAL)
        first = (str(exc).strip().splitlines() or [""])[0]
        _error(f"internal error: {type(exc).__name__}: {first} (rerun as armguard --traceback ..., or with "
               f"{DEBUG_ENV}=1, for the traceback)", ExitCode.INTERNAL)
