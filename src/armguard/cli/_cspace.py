"""``armguard cspace build | info | plot``: Hermes's forbidden-values maps."""

from __future__ import annotations

import math

from pathlib import Path

import click

from . import main
from ._params import AT_LEAST_ONE, COUNT, LENGTH, MAX_SAMPLES, PATH
from ._exit import ExitCode, exit_epilog
from ._output import json_text, output_console


def _angle(value: str) -> float:
    from ..cspace import parse_angle

    return parse_angle(value)


def _step(text: str, option: str) -> float:
    """A grid step of ``option`` in rad: with its unit, or a bare number of rad; a bare number over half a
    radian (a 29 deg cell) is refused with both readings (``--resolution 5`` meant 5 deg, not 286)."""
    from .._errors import ForbiddenMapError

    try:
        value = _angle(text)
    except (ValueError, ForbiddenMapError) as exc:  # a usage error (2), as every other option value
        raise click.BadParameter(str(exc), param_hint=option) from None
    if not (math.isfinite(value) and value > 0.0):
        raise click.BadParameter(f"{text!r}: expected a finite angle > 0 ('1deg', '0.01rad')", param_hint=option)
    if not text.strip().lower().endswith(("deg", "°", "rad")) and value > 0.5:
        raise click.BadParameter(f"{text} is read as {value:g} rad ({math.degrees(value):.4g} deg); write '{text}deg' for "
                                 f"degrees, or '{text}rad' to mean radians", param_hint=option)
    return value


def _one_angle(text: str, option: str) -> float:
    """One angle of ``option`` (deg unless it carries its unit) in rad; not a finite number: an error naming the option."""
    from .._errors import ForbiddenMapError

    text = text.strip()
    try:
        value = _angle(text) if text.endswith(("deg", "°", "rad")) else math.radians(float(text))
    except (ValueError, ForbiddenMapError):
        value = math.nan
    if not math.isfinite(value):  # a usage error (2), as every other option value
        raise click.BadParameter(f"{text!r} is not a finite angle (e.g. 30, 30deg, 0.5rad)", param_hint=option)
    return value


def _angles(text: str | None):
    """``"180,30,-20"`` (deg, unless each value carries its unit) -> (3,) rad."""
    if text is None:
        return None
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3:
        raise click.BadParameter(f"expected three angles (joints 1-3), got {text!r}", param_hint="--q")
    return [_one_angle(p, "--q") for p in parts]


@main.group("cspace")
def cspace() -> None:
    """Forbidden-values maps (Hermes): certified joint-space maps of links 1-3 vs the obstacles."""


@cspace.command("build", epilog=exit_epilog(ok="the map written (whole: a temporary file, fsync, rename)"))
@click.argument("model")
@click.option("--out", "out", type=PATH, required=True, help="The .agmap file to write.")
@click.option("--resolution", default="1deg", show_default=True, help="Cell width of joints 1, 2 ('1deg', '0.5°', '0.01rad'; a bare number is rad).")
@click.option("--j3-resolution", default=None, help="Joint-3 quantum (default: the resolution).")
@click.option("--cell", default="10deg", show_default=True, help="Substructure extent over joints 1, 2.")
@click.option("--stopping-distance", type=LENGTH, default=0.0, show_default=True, help="Worst-case stopping distance (m).")
@click.option("--robot", default=None, help="The robot (default: the scene's only one).")
@click.option("--max-depth", type=COUNT, default=None, help="Halvings below one cell x bin box (default: Tolerances).")
@click.option("--workers", type=AT_LEAST_ONE, default=None, help="Build on a Dask LocalCluster with N worker processes.")
@click.option("--scheduler", default=None, help="Build on an existing Dask cluster (scheduler address).")
@click.option("--no-resume", is_flag=True, help="Ignore a partial build at OUT.partial.")
def build_cmd(model, out, resolution, j3_resolution, cell, stopping_distance, robot, max_depth, workers, scheduler,
              no_resume) -> None:
    """Build the map of MODEL (a built-in scene name or a .yaml / .urdf file) and write it to OUT."""

    from ..cspace import ForbiddenMap

    console = output_console()
    c = _step(cell, "--cell")
    try:
        fmap = ForbiddenMap.build(model, out=out, robot=robot, resolution=_step(resolution, "--resolution"),
                                  j3_resolution=None if j3_resolution is None else _step(j3_resolution, "--j3-resolution"),
                                  cell=(c, c), stopping_distance=stopping_distance, workers=workers, scheduler=scheduler,
                                  max_depth=max_depth, resume=not no_resume, progress=True)
    except KeyboardInterrupt:  # the journal keeps what was finished: said, with how to go on
        journal = Path(out).with_name(Path(out).name + ".partial")
        if journal.is_file():
            again = ("the same command without --no-resume resumes from them" if no_resume else
                     "the same command resumes from them (--no-resume starts afresh)")
            click.echo(f"\n{out} not written; the finished substructures are kept in {journal}: {again}", err=True)
        raise
    r = fmap.build_report
    console.print(f"wrote {out}: {r.size_bytes} bytes, {fmap.grid.n_substructures} substructures "
                  f"({r.computed} computed, {r.reused} resumed), {r.evaluations} clearance evaluations, "
                  f"{r.elapsed_s:.1f} s" + (f" on {r.workers} workers" if r.workers else ""))
    warn = _nearly_all_forbidden(fmap)
    if warn:
        console.print(warn, style="yellow")


def _nearly_all_forbidden(fmap) -> str | None:
    """A warning when the map forbids nearly all of its joint box (a map that cannot plan), else None."""
    info = fmap.info()
    if info.forbidden_fraction < 0.99:
        return None
    coarse = (f"{info.unresolved} boxes were left unresolved at this resolution and depth (forbidden: a finer "
              "--resolution or a deeper --max-depth resolves them), " if info.unresolved else "")
    return (f"warning: the map forbids {info.forbidden_fraction:.2%} of the joint box: nearly nothing is left to plan in. "
            f"{coarse.capitalize()}{'or ' if coarse else ''}the stopping distance ({fmap.stopping_distance:g} m) leaves no "
            "free box, or an obstacle that a link stays close to wherever it moves (a base or shoulder link a few mm above "
            "its table) forbids them all, as the boxes are certified with one motion bound per joint over links 1-3: "
            "disable such a pair if it is by design (pairs: disable), or check configurations exactly (armguard check, verify)")


@cspace.command("info", epilog=exit_epilog(
    ok="read (and, with --samples, no sampled configuration the map allows collides)",
    unsafe="with --samples: a configuration the map allows collides (the map is not conservative there)"))
@click.argument("map_path")
@click.option("--model", default=None, help="Check against these model files / this scene (default: the recorded files).")
@click.option("--samples", type=click.IntRange(0, MAX_SAMPLES), default=10_000, show_default=True,
              help="Random configurations compared with the exact check (0: skip).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def info_cmd(map_path, model, samples, as_json) -> None:
    """Size, cells and conservativeness of the map at MAP_PATH."""
    import dataclasses
    import json

    from ..cspace import ForbiddenMap, check_exactness

    fmap = ForbiddenMap.load(map_path, model=model)
    info = fmap.info()
    g = fmap.grid
    out = {"path": str(map_path), "robot": fmap.robot, "joints": list(fmap.joints), "links": list(fmap.links),
           "resolution_deg": math.degrees(g.step[0]), "j3_resolution_deg": math.degrees(g.step[2]),
           "stopping_distance_m": fmap.stopping_distance, **dataclasses.asdict(info)}
    if samples > 0:
        rep = check_exactness(fmap, model if model is not None else None, n=samples)
        out["exactness"] = {k: (v.value if hasattr(v, "value") else v) for k, v in dataclasses.asdict(rep).items()}
    unsafe = samples > 0 and out["exactness"]["allowed_but_colliding"] > 0
    if as_json:
        click.echo(json_text(out, indent=2))
        if unsafe:
            raise SystemExit(int(ExitCode.UNSAFE))
        return
    click.echo(f"{map_path}: {info.size_bytes} bytes ({info.size_bytes / 1024:.1f} KB), format {fmap.header['format_version']}")
    click.echo(f"  {fmap.robot}: joints {', '.join(fmap.joints)}; links {', '.join(fmap.links)}; stopping distance "
               f"{fmap.stopping_distance} m")
    click.echo(f"  grid: {g.counts[0]} x {g.counts[1]} cells of {out['resolution_deg']:.4g} deg, {info.n_bins} joint-3 bins "
               f"of {out['j3_resolution_deg']:.4g} deg; {info.n_substructures} substructures of {g.per_sub[0]} x {g.per_sub[1]} "
               f"cells (largest {info.substructure_bytes_max} B, largest 3 x 3 block {info.neighbourhood_bytes_max} B)")
    click.echo(f"  {info.n_intervals} forbidden intervals; forbidden share of the joint box {info.forbidden_fraction:.4f}; "
               f"built with {info.evaluations} clearance evaluations, {info.unresolved} boxes unresolved (forbidden)")
    warn = _nearly_all_forbidden(fmap)
    if warn:
        click.echo(f"  {warn}")
    if samples > 0:
        e = out["exactness"]
        click.echo(f"  {e['n']} random configurations vs the exact check: {e['allowed_but_colliding']} allowed but colliding "
                   f"({e['status']}); truly colliding {e['colliding'] / e['n']:.4f}; false-forbidden share "
                   f"{e['false_forbidden_share']:.4f} ({e['false_forbidden_of_free']:.4f} of the free ones)")
    if unsafe:
        raise SystemExit(int(ExitCode.UNSAFE))


@cspace.command("plot", epilog=exit_epilog(ok="the plot written (whole, or the previous file left as it was)"))
@click.argument("map_path")
@click.option("--q2", required=True, help="Joint 2 of the slice ('30deg', '30°', rad; a bare number is deg).")
@click.option("--q", "q", default=None, help="Configuration to mark: joints 1-3 as 'a,b,c' (deg unless suffixed).")
@click.option("--model", default=None, help="Check against these model files / this scene (default: the recorded files).")
@click.option("--out", "out", type=PATH, required=True,
              help="The plot to write: .png, or another format matplotlib writes (.pdf, .svg).")
def plot_cmd(map_path, q2, q, model, out) -> None:
    """A joint-1 x joint-3 slice of MAP_PATH at joint 2 = Q2: forbidden bins red, the configuration Q marked
    (its joint 2 must lie in the slice's cell)."""
    from ..cspace import ForbiddenMap, plot_slice

    q2r = _one_angle(q2, "--q2")
    qq = _angles(q)
    fmap = ForbiddenMap.load(map_path, model=model)
    plot_slice(fmap, q2r, out, q=qq)
    click.echo(f"wrote {out}")
