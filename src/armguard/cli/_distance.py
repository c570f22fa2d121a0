"""``armguard distance``: a table of signed distances for a few shape pairs (the demo)."""

from __future__ import annotations

import click

from . import main
from ._output import output_console


@main.command("distance")
def distance_cmd() -> None:
    """Print signed distance and witness points for a few example shape pairs."""
    print_table()


def _fmt(p) -> str:
    return "(" + ", ".join(f"{x:+.4f}" for x in p) + ")"


def print_table() -> None:
    """Print a rich table: pair, kernel, signed distance, witness points and the B feature."""
    from rich.table import Table

    from ..geometry import distance, feature_at, kernel_name
    from ..geometry._demo import example_pairs
    from ._compile import warm_up

    console = output_console()
    rows = example_pairs()
    warm_up((("geometry kernels", lambda: [distance(a, b) for _, a, b in rows]),), console=console, side=())  # a bar only when compiling
    table = Table(title="armguard signed distance (m): > 0 apart, < 0 penetrating")
    for col in ("pair", "kernel", "distance", "p_WA", "p_WB", "feature of B"):
        table.add_column(col)
    for label, a, b in rows:
        r = distance(a, b)
        try:
            f = feature_at(b, r.p_WB)
            feat = f"{f.kind.value} {f.index}"
        except Exception:  # noqa: BLE001 - the table must print even if a point is off tolerance
            feat = "?"
        table.add_row(label, kernel_name(a, b), f"{r.distance:+.6f}", _fmt(r.p_WA), _fmt(r.p_WB), feat)
    console.print(table)
