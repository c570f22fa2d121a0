"""``armguard info SCENE``: what a scene holds, and its compiled size beside Hermes's database; ``armguard info``:
the model names armguard knows."""

from __future__ import annotations

import math

import click

from . import main
from ._output import esc, output_console
from ._params import scene_of, srdf_option

# Sciomachen & Magnani (seed 001): "The memory required for the database, in the case of the
# Hermes model described above, is about 3 kbytes"; "the memory available on board is about 40 kbytes".
HERMES_DATABASE_BYTES = 3 * 1024
HERMES_MEMORY_BYTES = 40 * 1024


def _shape_counts(shape) -> tuple[int, int]:
    """(faces, vertices) of a shape, faces as merged planar polygons (0 faces for spheres and capsules)."""
    from ..geometry import Box, ConvexPolyhedron, Polygon, Prism

    if isinstance(shape, (Box, Prism)):
        p = shape.as_polyhedron()
        return len(p.faces), len(p.vertices)
    if isinstance(shape, ConvexPolyhedron):
        return len(shape.faces), len(shape.vertices)
    if isinstance(shape, Polygon):
        return 1, len(shape.vertices)
    return 0, len(shape.core_points)


def _limit(v: float, revolute: bool, deg: bool) -> str:
    if math.isinf(v):
        return "-inf" if v < 0 else "inf"
    return f"{math.degrees(v):.1f}°" if revolute and deg else (f"{v:.4g} rad" if revolute else f"{v:.4g} m")


def _print_known_models() -> None:
    """The names ``load_model`` takes: built-in and public robots, whether each is installed, its file."""
    from rich.table import Table

    from ..model._public import known_models

    con = output_console()
    t = Table(title="known models (armguard info NAME describes one; any .urdf or .yaml path loads too)",
              title_justify="left")
    for col in ("name", "source", "available", "file"):
        t.add_column(col, overflow="fold")
    for m in known_models():
        name = m.name + (f" ({', '.join(m.aliases)})" if m.aliases else "")
        t.add_row(esc(name), esc(m.source), "yes" if m.available else "no", esc(str(m.path) if m.available else m.reason))
    con.print(t)


def _print_srdf(con, scene, given: str, srdf: str | None = None) -> None:
    """Which SRDF the model was loaded with, how it was found, and its lenient readings."""
    model = getattr(scene, "_model_of_record", None)
    if model is None:
        return
    if srdf is not None and srdf.strip().lower() == "none":  # a sidecar keeps its SRDF's groups (the arms), not its pairs
        kept = "" if model.srdf is None else f" of pairs ({model.srdf.file} names the arms and their home only)"
        con.print(f"SRDF: none{kept} (--srdf none: every pair but adjacent links is checked)", markup=False,
                  highlight=False, soft_wrap=True)
    elif model.srdf is not None:
        con.print(f"SRDF: {model.srdf.file} ({model.srdf.found})", markup=False, highlight=False, soft_wrap=True)
        for w in model.srdf.warnings:
            con.print(f"  warning: {w}", markup=False, highlight=False, soft_wrap=True)
    elif given.lower().endswith(".urdf") or any(str(f).endswith(".urdf") for f in getattr(model, "files", ())):
        con.print("SRDF: none found (looked beside the URDF, in ../srdf/ and under the robot's name; "
                  "every pair but adjacent links is checked)", markup=False, highlight=False, soft_wrap=True)
    hc = getattr(model, "hull_cache", None)
    if hc:
        n_hit, n_new, n_stored = hc.get("hits", 0), hc.get("computed", 0), hc.get("stored", 0)
        stored = "and stored" if n_stored == n_new else f"({n_stored} stored: the cache could not be written)"
        where = (f"hull cache {hc['folder']}: {n_hit} read, {n_new} computed {stored}" if hc.get("folder")
                 else f"{n_new} computed (hull cache off: ARMGUARD_HULL_CACHE=0)")
        con.print(f"Mesh hulls: {where}", markup=False, highlight=False, soft_wrap=True)


@main.command("info")
@click.argument("scene", required=False)
@click.option("--rad", is_flag=True, help="Print revolute joint limits in radians (default: degrees).")
@srdf_option("SCENE")
def info_cmd(scene: str | None, rad: bool, srdf: str | None) -> None:
    """Describe SCENE (a built-in or public robot name, a .yaml scene or a .urdf): bodies, robots, joints,
    pairs, size, and the SRDF used.  Without SCENE: list the model names armguard knows, and whether each
    is installed."""
    from rich.table import Table

    from ..scene import compile_scene

    if scene is None:
        if srdf is not None:
            raise click.UsageError("--srdf goes with a SCENE")
        _print_known_models()
        return
    s = scene_of(scene, srdf)
    c = compile_scene(s)
    con = output_console()
    con.print(f"[bold]{esc(s.name)}[/bold]: {esc(s.description)}" if s.description else f"[bold]{esc(s.name)}[/bold]")
    _print_srdf(con, s, scene, srdf)

    if not s.bodies:  # a robot on its own (a public robot's URDF): no table of nothing
        con.print("static bodies: none (the robot's own links only)")
    else:
        t = Table(title="bodies")
        for col in ("body", "category", "shapes", "faces", "vertices"):
            t.add_column(col)
        tot = [0, 0, 0]
        for b in s.bodies.values():
            f = v = 0
            for sh in b.shapes:
                ff, vv = _shape_counts(sh)
                f, v = f + ff, v + vv
            tot = [tot[0] + len(b.shapes), tot[1] + f, tot[2] + v]
            t.add_row(esc(b.name), esc(b.category), str(len(b.shapes)), str(f), str(v))
        t.add_row("[bold]total[/bold]", "", *(str(x) for x in tot))
        con.print(t)

    for rname, robot in s.robots.items():
        t = Table(title=f"robot {esc(rname)}: {robot.n_joints} joints, {len(robot.link_names)} links")
        for col in ("joint", "type", "lower", "upper", "max velocity", "home"):
            t.add_column(col)
        home = s.home(rname)
        for k, j in enumerate(robot.joint_names):
            rev = robot.joint_types[k].value == "revolute"
            vel = robot.max_velocity[k]
            vtxt = "inf" if math.isinf(vel) else f"{_limit(vel, rev, not rad)}/s"  # °/s, rad/s or m/s
            kind = "continuous" if rev and robot.lower[k] == -math.inf and robot.upper[k] == math.inf else robot.joint_types[k].value
            t.add_row(esc(j), kind, _limit(robot.lower[k], rev, not rad),
                      _limit(robot.upper[k], rev, not rad), vtxt, _limit(home[k], rev, not rad))
        for cp in robot.couplings:
            terms = " ".join(f"{v:+g}·{k}" for k, v in cp.terms.items())
            t.add_row(esc(cp.joint), "coupled", esc(f"= {cp.offset:+.4g} {terms}"), "", "", "")
        con.print(t)
        shaped = [ln for ln in robot.link_names if robot.link_shapes.get(ln)]
        con.print(f"  links with shapes: {esc(', '.join(shaped)) or 'none'}")

    if s.payloads:
        for p in s.payloads.values():
            con.print(f"payload [bold]{esc(p.name)}[/bold]: {len(p.shapes)} shapes on {esc(p.robot)}/{esc(p.link)}")
    if s.workspace is not None:
        con.print(f"workspace box: lo {s.workspace.lo.tolist()} hi {s.workspace.hi.tolist()} m")

    t = Table(title="pair filters and checked pairs")
    t.add_column("what")
    t.add_column("value")
    t.add_row("adjacent links excluded", str(s.exclude_adjacent))
    for rname, pairs in s.self_pairs.items():
        t.add_row(f"listed link pairs of {esc(rname)}", esc(", ".join(f"{a}-{b}" for a, b in sorted(pairs))))
    for rname in s.robots:  # own-link pairs left after the SRDF's rules (Hermes: only 1-3, 1-4, ...)
        if rname in s.self_pairs:
            continue
        own = sorted(tuple(sorted((p.a.split("/", 1)[1], p.b.split("/", 1)[1]))) for p in s.allowed_pairs()
                     if p.a.startswith(rname + "/") and p.b.startswith(rname + "/"))
        if own:
            t.add_row(f"checked link pairs of {esc(rname)}", esc(", ".join(f"{a}-{b}" for a, b in own)))
    for p in sorted(sorted(x) for x in s.disabled_pairs):
        t.add_row("disabled", esc(" - ".join(p)))
    for cat, pairs in s.allowed_pairs_by_category().items():
        if pairs:
            t.add_row(f"checked {cat.value}", str(len(pairs)))
    con.print(t)
    if s.trajectories:
        con.print("trajectories: " + ", ".join(f"{n} ({tr.duration:.2f} s)" for n, tr in s.trajectories.items()))
    if s.canned_tests:
        con.print(f"canned tests: {len(s.canned_tests)} ({', '.join(s.canned_tests)})")
    con.print(
        f"compiled size: {c.nbytes} bytes ({c.n_elements} elements, {c.n_faces} faces, {len(c.pair_a)} owner pairs, "
        f"{len(c.elem_pair_a)} element pairs); Hermes's on-board database: ~{HERMES_DATABASE_BYTES} bytes "
        f"in {HERMES_MEMORY_BYTES} bytes of memory"
    )
