"""``armguard edges MODEL EDGES.npz``: certify a planner's edges (a roadmap's, a tree's) for every configuration."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click

from . import main
from ._exit import ExitCode, exit_epilog
from ._output import esc, output_console
from ._params import LENGTH, PATH

_LISTED = 10  # edges listed per verdict (collision, incomplete)


def read_edges(path) -> tuple:
    """``(Q0, Q1, joint_names)`` from an ``.npz`` holding ``Q0`` and ``Q1`` ``(M, n)`` or ``(n,)`` and optionally
    ``joint_names``: ``(n,)`` strings, or one string (an SRDF group); None without.  An error names the file and
    what it lacks."""
    import zipfile
    import zlib

    import numpy as np

    from .._errors import VerificationError

    p = Path(path)
    if not p.exists():
        raise VerificationError(f"{p}: no such file")
    if not p.is_file() or not zipfile.is_zipfile(p):
        raise VerificationError(f"{p}: not an .npz file of edges (an archive of arrays Q0, Q1, as numpy.savez writes)")
    def array(f, key: str, what: str):
        try:
            return np.asarray(f[key])
        except ValueError as exc:
            if "Object arrays" in str(exc):  # pickled objects: never unpickled from a file
                raise VerificationError(f"{p}: {key}: expected {what}, got an object array (pickled objects are "
                                        "not read)") from None
            raise VerificationError(f"{p}: {key}: cannot read this array ({exc})") from None
        except (OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:  # a damaged or truncated member
            raise VerificationError(f"{p}: {key}: cannot read this array ({type(exc).__name__}: {exc})") from None

    try:
        f = np.load(p, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise VerificationError(f"{p}: not an .npz file of edges ({exc})") from None
    with f:
        keys = set(f.files)
        if not {"Q0", "Q1"} <= keys:
            raise VerificationError(f"{p}: expected arrays 'Q0' and 'Q1' (M, n) (and optionally 'joint_names'), "
                                    f"found {sorted(keys) or 'none'}")
        if "joint_names" not in keys:  # a misspelt joint_names would leave the columns read in the robot's order
            import difflib

            for k in sorted(keys - {"Q0", "Q1"}):  # (a roadmap's other arrays, its costs or ids, are left alone)
                if difflib.get_close_matches(k, ["joint_names"], n=1, cutoff=0.6) or k.lower() == "joint_names":
                    raise VerificationError(f"{p}: unknown array {k!r}: did you mean 'joint_names'? (an edges file "
                                            "holds 'Q0', 'Q1' and optionally 'joint_names', naming Q's columns)")
        Q0, Q1 = array(f, "Q0", "numbers (M, n)"), array(f, "Q1", "numbers (M, n)")
        names = array(f, "joint_names", "strings (numpy.savez(..., joint_names=np.array(names, dtype=str)))") \
            if "joint_names" in keys else None
    for key, Q in (("Q0", Q0), ("Q1", Q1)):
        if Q.size == 0:
            raise VerificationError(f"{p}: {key} holds no configuration (shape {Q.shape}): no edge to certify")
    if names is None:
        return Q0, Q1, None
    if names.dtype.kind not in "US":
        raise VerificationError(f"{p}: joint_names: expected strings, got dtype {names.dtype}")
    if names.ndim > 1:
        raise VerificationError(f"{p}: joint_names: expected one name per column (n,), or one SRDF group's name, "
                                f"got shape {names.shape}")
    if names.dtype.kind == "S":  # bytes (numpy.savez of b'...' names): read as UTF-8 text, not as "b'j1'"
        try:
            names = np.char.decode(names, "utf-8")
        except UnicodeDecodeError:
            raise VerificationError(f"{p}: joint_names: bytes that are not UTF-8 text") from None
    return Q0, Q1, str(names) if names.ndim == 0 else [str(x) for x in names]


@main.command("edges", epilog=exit_epilog(
        ok="every edge certified clear (every configuration at least --margin from every checked pair)",
        unsafe="an edge in collision (or within --margin)",
        incomplete="an edge not resolved within --max-evaluations, and none in collision"))
@click.argument("model")
@click.argument("edges_file", metavar="EDGES.npz", type=PATH)
@click.option("--robot", default=None, help="The moving robot (default: the model's only one; '*': every robot at once, "
              "the scene's flat joint order).")
@click.option("--margin", type=LENGTH, default=0.0, show_default=True,
              help="Clearance every configuration must keep, on every checked pair: obstacles and the robot's own "
                   "links (m); --category-margin sets a category's own.")
@click.option("--category-margin", "category_margins", multiple=True, metavar="CATEGORY=M",
              help="The clearance of one category of pairs instead (m; repeatable): e.g. arm-arm=0 with --margin "
                   "0.02 keeps 2 cm from everything but the arm's own links (armguard info MODEL lists the categories).")
@click.option("--first-contact", is_flag=True, help="Report each collision's first contact along its edge (more evaluations).")
@click.option("--continuous", type=click.Choice(["line", "shortest"]), default="line", show_default=True,
              help="Continuous joints along the angle's line, or turned the short way (as pinocchio.interpolate).")
@click.option("--max-evaluations", type=click.IntRange(min=2), default=None,
              help="Evaluations per edge before it is INCOMPLETE (default: Tolerances.edge_max_evaluations, 1000).")
@click.option("--out", "out_path", type=PATH, default=None,
              help="Write the results here (.npz: code (0 clear, 1 collision, 2 incomplete), s_free, s, q (columns "
              "q_joint_names), distance, pair_a, pair_b, evaluations, robot, margin, joint_names, held_names, "
              "held_values; with --category-margin, margin_categories and margins, each category's, in place of margin).")
def edges_cmd(model, edges_file, robot, margin, category_margins, first_contact, continuous, max_evaluations,
              out_path) -> None:
    """Certify the straight joint-space edges Q0[i] -> Q1[i] of EDGES.npz on MODEL: each CLEAR (every
    configuration, not samples), COLLISION (with the prefix proven clear) or INCOMPLETE.

    EDGES.npz holds arrays Q0 and Q1, (M, n) or (n,) (one side may be a single configuration), in
    radians (m for prismatic joints), in the scene's joint order: the robot's joints (armguard info
    MODEL lists them), or with --robot '*' every robot's, as scene.joint_names ('left_arm/j1', ...;
    named by joint_names where Pinocchio orders them otherwise, as on ranger); not Pinocchio's
    configuration (model.scene_q converts one). An optional joint_names names the columns: a subset
    of the robot's joints in any order (the others held at home), or one string, an SRDF group of
    MODEL."""
    import io

    import numpy as np
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .._errors import ArmguardError, VerificationError
    from .._io import atomic_write, check_writable
    from ..model import load_model
    from ..verify import ALL_ROBOTS, EdgeStatus, Verifier

    from ._compile import warm_up

    console = output_console()
    if out_path:
        check_writable(out_path, [edges_file, model])  # unwritable, or the input itself: refused before the work
    if category_margins:  # before any work: a bad one is a usage error (exit status 2)
        margin = {"*": margin, **_category_margins(category_margins)}
    Q0, Q1, names = read_edges(edges_file)
    m = load_model(model)
    group = names if isinstance(names, str) else None
    if group is not None:
        try:  # an SRDF group (an unknown one is named by group_robot_joints): its robot's, checked by check_edges
            g_robot, names = m.group_robot_joints(group)
        except ArmguardError as exc:
            raise VerificationError(f"{edges_file}: joint_names: {exc}") from None
        names = list(names)
        robot = g_robot if robot is None else robot  # the group says whose edges these are
    width = Q0.shape[-1] if Q0.ndim else None
    if names is not None and width is not None and len(names) != width:
        raise VerificationError(f"{edges_file}: joint_names names {len(names)} joints, Q0 has {width} columns")
    if robot == ALL_ROBOTS and names is None and width == m.pin_model.nq and list(m.q_index) != list(range(width)):
        raise VerificationError(f"{edges_file}: model {m.name!r} orders its joints for Pinocchio otherwise than its scene: "
                                "name the columns with joint_names (scene.joint_names, e.g. "
                                f"{m.scene.joint_names[0]!r}), or convert Pinocchio configurations with model.scene_q")
    warm_up(console=console)
    verifier = Verifier(m)
    M = max(len(np.atleast_2d(Q0)), len(np.atleast_2d(Q1)))
    with Progress(TextColumn("certifying edges"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console, transient=True, disable=M <= 256 or not console.is_terminal) as bar:
        task = bar.add_task("edges", total=M)
        try:
            res = verifier.check_edges(Q0, Q1, robot=robot, joints=group or names, margin=margin, max_evaluations=max_evaluations,
                                       first_contact=first_contact, continuous=continuous,
                                       progress=lambda done, total: bar.update(task, completed=done))
        except VerificationError as exc:  # said in the command line's words, with the file
            text = str(exc).replace("pass robot= ", "pass --robot ").replace("robot='*'", "--robot '*'").replace(
                "name its columns with joints= (a list, or an SRDF group's name)",
                "name its columns with the file's joint_names array (the joints' names, or an SRDF group's name)")
            raise VerificationError(f"{edges_file}: {text.replace('joints: ', 'joint_names: ')}") from None
    # the file first: a reader that closes the pipe early (| head) must not cost the results
    if out_path:
        sc = verifier.scene
        q_names = sc.joint_names if res.robot == ALL_ROBOTS else sc.robots[res.robot].joint_names
        buf = io.BytesIO()
        np.savez(buf, code=res.code, s_free=res.s_free, s=res.s, q=res.q, distance=res.distance,
                 evaluations=res.evaluations, pair_a=np.array([p[0] if p else "" for p in res.pair], dtype=str),
                 pair_b=np.array([p[1] if p else "" for p in res.pair], dtype=str),
                 q_joint_names=np.array(q_names, dtype=str), robot=np.array(res.robot),
                 **_margin_arrays(res.margin),
                 joint_names=np.array(res.joint_names, dtype=str), held_names=np.array(list(res.held), dtype=str),
                 held_values=np.array(list(res.held.values()), dtype=float))
        atomic_write(Path(out_path), buf.getvalue(), parents=True)
    console.print(res.summary(), highlight=False, markup=False)
    for label, code in (("in collision", EdgeStatus.COLLISION), ("incomplete", EdgeStatus.INCOMPLETE)):
        which = np.flatnonzero(res.code == code)
        for i in which[:_LISTED]:
            a, b = res.pair[i]
            free = (f"clear up to {res.s_free[i]:.4f}" if np.isfinite(res.s_free[i])
                    else "its start Q0 itself within the margin")  # s_free = -inf: no prefix is clear
            console.print(f"  edge {i} {label}: {esc(a)} - {esc(b)} {res.distance[i] * 1e3:.2f} mm at s = {res.s[i]:.4f}, "
                          f"{free}", highlight=False)
        if len(which) > _LISTED:
            console.print(f"  ({len(which) - _LISTED} more {label})", highlight=False)
    if out_path:
        console.print(f"results: {esc(str(out_path))}", highlight=False)
    c = res.counts()
    status = ExitCode.UNSAFE if c["collision"] else ExitCode.INCOMPLETE if c["incomplete"] else ExitCode.OK
    sys.exit(int(status))


def _category_margins(items) -> dict:
    """``--category-margin`` values ``CATEGORY=M`` as ``{category: M}`` (a bad one: a usage error naming it)."""
    from ..backends import CATEGORIES

    out = {}
    for item in items:
        cat, eq, value = item.partition("=")
        try:
            m = float(value) if eq and cat.strip() else math.nan
        except ValueError:
            m = math.nan
        if not (math.isfinite(m) and m >= 0.0):
            raise click.BadParameter(f"expected CATEGORY=M with M a finite number >= 0 (m), got {item!r}",
                                     param_hint="--category-margin")
        cat = cat.strip()
        if cat == "*":
            raise click.BadParameter("'*' is --margin's (the categories not named)", param_hint="--category-margin")
        if cat not in CATEGORIES:
            raise click.BadParameter(f"{cat!r} is not a pair category; the categories: {', '.join(CATEGORIES)}",
                                     param_hint="--category-margin")
        if cat in out:
            raise click.BadParameter(f"category {cat!r} given twice", param_hint="--category-margin")
        out[cat] = m
    return out


def _margin_arrays(margin) -> dict:
    """The results file's margin fields: ``margin`` (one for every pair), or per category
    ``margin_categories`` and ``margins`` (and no single ``margin``)."""
    import numpy as np

    if isinstance(margin, dict):
        cats = sorted(margin)
        return {"margin_categories": np.array(cats, dtype=str), "margins": np.array([margin[c] for c in cats])}
    return {"margin": np.array(margin)}
