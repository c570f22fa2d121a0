"""The ``armguard distance`` demo: signed distance and witness points for a few shape pairs."""

from __future__ import annotations

import numpy as np

from ._dispatch import distance, kernel_name
from ._feature import feature_at
from ._shapes import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere

__all__ = ["example_pairs", "print_table"]


def example_pairs():
    """``[(label, A, B)]``: a few pairs covering every kernel family, apart and penetrating."""
    link = Capsule([0.0, 0.0, 0.0], [0.6, 0.0, 0.0], 0.05)
    return [
        ("link / link (apart)", link, Capsule([0.3, 0.4, -0.3], [0.3, 0.4, 0.3], 0.05)),
        ("link / link (crossing)", link, Capsule([0.3, 0.02, -0.3], [0.3, 0.02, 0.3], 0.05)),
        ("sphere / sphere", Sphere([0, 0, 0], 0.1), Sphere([0.25, 0, 0], 0.1)),
        ("link / box (apart)", link, Box([0.3, 0.0, 0.5], [0.2, 0.2, 0.2])),
        ("link / box (penetrating)", link, Box([0.3, 0.0, 0.2], [0.2, 0.2, 0.2])),
        ("link / prism (OBP)", link, Prism([0.3, 0.6, 0.0], np.eye(3), 0.1, 0.3, 8)),
        ("box / box", Box([0, 0, 0], [0.2, 0.2, 0.2]), Box([0.35, 0.1, 0.0], [0.2, 0.2, 0.2])),
        ("link / polyhedron", link, ConvexPolyhedron([[1, 0, 0], [1.2, 0, 0], [1, 0.2, 0], [1, 0, 0.2]])),
        ("link / face (Ranger)", link, Polygon([[0.0, -0.2, 0.2], [0.6, -0.2, 0.2], [0.6, 0.2, 0.2], [0.0, 0.2, 0.2]])),
    ]


def _fmt(p) -> str:
    return "(" + ", ".join(f"{x:+.4f}" for x in p) + ")"


def print_table() -> None:
    """Print a rich table: pair, kernel, signed distance, witness points and the B feature."""
    from rich.console import Console
    from rich.table import Table

    from ..cli._compile import warm_up

    console = Console()
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
