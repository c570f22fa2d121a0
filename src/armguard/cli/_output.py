"""The console a command prints its tables to, and how its warnings read.

In a terminal: rich's own (the terminal's width).  Piped into a file, a log or ``make``'s output,
rich would fold every table into 80 columns and cut its headers and names to ``…``; there the
console is :data:`PIPED_WIDTH` columns wide instead, so a log keeps whole names and columns.

Names and messages from the user's files go into rich's markup through :func:`esc`.

An :class:`armguard.ArmguardWarning` (a lenient reading of an input: its message names the file
and the element) is one line on stderr, ``warning: <message>``, not Python's form with the
library's source line under it.
"""

from __future__ import annotations

import errno
import json
import math
import sys
import warnings

__all__ = ["PIPED_WIDTH", "count", "esc", "output_console", "one_line_warnings"]

PIPED_WIDTH = 200
"""Columns of a command's output when it does not go to a terminal."""


def output_console():
    """A ``rich.console.Console`` on stdout: the terminal's width, or :data:`PIPED_WIDTH` when piped.

    A write into a pipe closed early (``| head``) raises ``BrokenPipeError`` for the command's exit
    status (``_exit.ExitCode.OUTPUT_CLOSED``): rich's own handling exits 1, which here means "unsafe"."""
    from rich.console import Console

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            self.quiet = True
            raise BrokenPipeError(errno.EPIPE, "output closed")

    console = _Console()
    return console if console.is_terminal else _Console(width=PIPED_WIDTH)


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``"1 finding"``, ``"2 findings"``: ``n`` and the noun in its number (``plural``: else noun + s)."""
    return f"{n} {noun if n == 1 else (plural or noun + 's')}"


def esc(value) -> str:
    """``value`` as text that rich prints as it is: names and messages come from the user's files, and
    rich would read ``[...]`` in them as markup and drop it (``group_state[home]`` printed as
    ``group_state``)."""
    from rich.markup import escape

    return escape(str(value))


def one_line_warnings() -> None:
    """Show :class:`armguard.ArmguardWarning` as ``warning: <message>`` on stderr (other warnings as
    Python shows them); called once by the ``armguard`` command, never by the library."""
    from .._errors import ArmguardWarning

    shown = warnings.showwarning
    if getattr(shown, "_armguard_one_line", False):
        return

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, ArmguardWarning):
            print(f"warning: {message}", file=file or sys.stderr)
        else:
            shown(message, category, filename, lineno, file, line)

    show._armguard_one_line = True
    warnings.showwarning = show


def json_text(obj, **kwargs) -> str:
    """``obj`` as strict JSON: a NaN or an infinity (an incomplete check's lower bound of -inf, an undefined
    figure) is ``null``, as JSON has no such numbers and strict parsers refuse Python's ``-Infinity``; numpy
    scalars and arrays are numbers and lists."""
    return json.dumps(_finite(obj), allow_nan=False, **kwargs)


def _finite(x):
    import numpy as np

    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return _finite(x.tolist())
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    return x
