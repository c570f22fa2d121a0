"""The console a command prints its tables to.

In a terminal: rich's own (the terminal's width).  Piped into a file, a log or ``make``'s output,
rich would fold every table into 80 columns and cut its headers and names to ``…``; there the
console is :data:`PIPED_WIDTH` columns wide instead, so a log keeps whole names and columns.
"""

from __future__ import annotations

__all__ = ["PIPED_WIDTH", "output_console"]

PIPED_WIDTH = 200
"""Columns of a command's output when it does not go to a terminal."""


def output_console():
    """A ``rich.console.Console`` on stdout: the terminal's width, or :data:`PIPED_WIDTH` when piped."""
    from rich.console import Console

    console = Console()
    return console if console.is_terminal else Console(width=PIPED_WIDTH)
