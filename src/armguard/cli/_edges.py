"""``armguard edges MODEL EDGES.npz``: certify a planner's edges (a roadmap's, a tree's) for every configuration."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from . import main
from ._exit import ExitCode, exit_epilog
from ._output import esc, output_console
from ._params import AT_LEAST_ONE, LENGTH

_CHUNK = 256  # edges per call between two updates of the progress bar


def read_edges(path) -> tuple:
    """``(Q0, Q1, joint_names or None)`` from an ``.npz`` holding ``Q0`` and ``Q1`` ``(M, n)`` (the scene's joint
    order, angles for continuous joints) and optionally ``joint_names`` ``(n,)``; an error names the file and
    what it lacks."""
    import zipfile

    import numpy as np

    from .._errors import VerificationError

    p = Path(path)
    if p.is_file() and not zipfile.is_zipfile(p):
        raise VerificationError(f"{p}: not an .npz file of edges (an archive of arrays Q0, Q1, as numpy.savez writes)")
    try:
        with np.load(p, allow_pickle=False) as f:
            keys = set(f.files)
            if not {"Q0", "Q1"} <= keys:
                raise VerificationError(f"{p}: expected arrays 'Q0' and 'Q1' (M, n) (and optionally 'joint_names'), "
                                        f"found {sorted(keys) or 'none'}")
            names = [str(x) for x in f["joint_names"]] if "joint_names" in keys else None
            return np.asarray(f["Q0"]), np.asarray(f["Q1"]), names
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        if isinstance(exc, VerificationError):
            raise
        raise VerificationError(f"{p}: not an .npz file of edges ({exc})") from None


@main.command("edges", epilog=exit_epilog(
        ok="every edge certified clear (every configuration at least --margin from every obstacle)",
        unsafe="an edge in collision (or within --margin)",
        incomplete="an edge not resolved within --max-evaluations, and none in collision"))
@click.argument("model")
@click.argument("edges_file", metavar="EDGES.npz", type=click.Path())
@click.option("--robot", default=None, help="The moving robot (default: the model's only one; '*': every robot, the "
              "scene's flat joint order).")
@click.option("--margin", type=LENGTH, default=0.0, show_default=True, help="Clearance every configuration must keep (m).")
@click.option("--first-contact", is_flag=True, help="Report each collision's first contact along its edge (more evaluations).")
@click.option("--continuous", type=click.Choice(["line", "shortest"]), default="line", show_default=True,
              help="Continuous joints along the angle's line, or turned the short way (as pinocchio.interpolate).")
@click.option("--max-evaluations", type=AT_LEAST_ONE, default=None,
              help="Evaluations per edge before it is INCOMPLETE (default: Tolerances.edge_max_evaluations, 1000).")
@click.option("--out", "out_path", type=click.Path(), default=None,
              help="Write the results here (.npz: code (0 clear, 1 collision, 2 incomplete), s_free, s, q (columns "
              "q_joint_names), distance, pair_a, pair_b, evaluations).")
def edges_cmd(model, edges_file, robot, margin, first_contact, continuous, max_evaluations, out_path) -> None:
    """Certify the straight joint-space edges Q0[i] -> Q1[i] of EDGES.npz on MODEL: each CLEAR (every
    configuration, not samples), COLLISION (with the prefix proven clear) or INCOMPLETE."""
    import io

    import numpy as np
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .._io import atomic_write
    from ..model import load_model
    from ..verify import EdgeStatus, Verifier

    from ._compile import warm_up

    console = output_console()
    if max_evaluations is not None and max_evaluations < 2:
        raise click.UsageError("--max-evaluations: at least 2 (both ends of an edge)")
    Q0, Q1, names = read_edges(edges_file)
    m = load_model(model)
    warm_up(console=console)
    verifier = Verifier(m)
    kw = dict(robot=robot, joints=names, margin=margin, max_evaluations=max_evaluations, first_contact=first_contact,
              continuous=continuous)
    parts = [verifier.check_edges(Q0[:_CHUNK], Q1[:_CHUNK], **kw)]  # the inputs refused (if so) before the long run
    with Progress(TextColumn("certifying edges"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=True, disable=len(Q0) <= _CHUNK) as bar:
        task = bar.add_task("edges", total=len(Q0), completed=len(parts[0]))
        for a in range(_CHUNK, len(Q0), _CHUNK):
            parts.append(verifier.check_edges(Q0[a:a + _CHUNK], Q1[a:a + _CHUNK], **kw))
            bar.update(task, completed=min(a + _CHUNK, len(Q0)))
    code = np.concatenate([r.code for r in parts])
    pairs = [p for r in parts for p in r.pair]
    n_clear, n_coll = int(np.sum(code == EdgeStatus.CLEAR)), int(np.sum(code == EdgeStatus.COLLISION))
    n_inc = len(code) - n_clear - n_coll
    ev = np.concatenate([r.evaluations for r in parts])
    console.print(f"{len(code)} edges of {esc(parts[0].robot)}: {n_clear} clear, {n_coll} in collision"
                  f"{'' if margin == 0.0 else f' or within {margin * 1e3:g} mm'}, {n_inc} incomplete; evaluations per "
                  f"edge: median {float(np.median(ev)) if len(ev) else 0:g}, max {int(ev.max()) if len(ev) else 0}",
                  highlight=False)
    s_free, s, d = (np.concatenate([getattr(r, k) for r in parts]) for k in ("s_free", "s", "distance"))
    for i in np.flatnonzero(code == EdgeStatus.COLLISION)[:10]:
        a, b = pairs[i]
        console.print(f"  edge {i}: {esc(a)} - {esc(b)} {d[i] * 1e3:.2f} mm at s = {s[i]:.4f}, clear up to "
                      f"{s_free[i]:.4f}", highlight=False)
    if n_coll > 10:
        console.print(f"  ({n_coll - 10} more in collision)", highlight=False)
    if out_path:
        sc = verifier.scene
        q_names = sc.joint_names if parts[0].robot == "*" else sc.robots[parts[0].robot].joint_names
        buf = io.BytesIO()
        np.savez(buf, code=code, s_free=s_free, s=s, q=np.concatenate([r.q for r in parts]), distance=d,
                 evaluations=ev, pair_a=np.array([p[0] if p else "" for p in pairs], dtype=str),
                 pair_b=np.array([p[1] if p else "" for p in pairs], dtype=str),
                 q_joint_names=np.array(q_names, dtype=str))
        atomic_write(Path(out_path), buf.getvalue(), parents=True)
        console.print(f"results: {esc(str(out_path))}", highlight=False)
    status = ExitCode.OK if n_clear == len(code) else ExitCode.UNSAFE if n_coll else ExitCode.INCOMPLETE
    sys.exit(int(status))
