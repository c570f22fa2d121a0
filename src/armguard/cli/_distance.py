"""``armguard distance``: a table of signed distances for a few shape pairs (the demo)."""

from __future__ import annotations

import click

from . import main


@main.command("distance")
def distance_cmd() -> None:
    """Print signed distance and witness points for a few example shape pairs."""
    from ..geometry import _demo

    _demo.print_table()
