"""``armguard srdf ROBOT --out FILE.srdf`` and ``armguard check-srdf ROBOT [SRDF]``: certified collision matrices.

``srdf`` writes MoveIt's ``disable_collisions`` entries (Adjacent, Default, Never, Always) with
*Never* proven by branch and bound (or sampled as MoveIt does, ``--method sampled``); the pairs
it keeps are listed with a configuration where they collide, or as undecided.  ``check-srdf``
lints an existing SRDF (``armguard.srdfgen``, ``docs/srdf.md``).
"""

from __future__ import annotations

import json
import math

import click

from . import main
from ._params import AT_LEAST_ONE, BACKEND, LENGTH, PATH, SAMPLES, refuse_unused
from ._exit import ExitCode, exit_epilog
from ._output import count


_FEW_SAMPLES = 10_000
"""Fewer samples than MoveIt Setup Assistant's default make ``--method sampled`` warn of its Never pairs."""


def _label(robot: str) -> str:
    """The progress bar's name for ROBOT as the user gave it (``talos_left_arm``, not its URDF's robot name
    ``talos``; a path's file name)."""
    from pathlib import Path

    return Path(robot).name or robot


def _q(model, q) -> str:
    """A witness ``q`` (Pinocchio's order, ``(cos, sin)`` for a continuous joint) as ``check --q`` takes it:
    one value a joint, in the scene's order (``Model.scene_q``)."""
    return "[" + ", ".join(f"{x:.4f}" for x in model.scene_q(q)) + "]"


@main.command("srdf", epilog=exit_epilog(ok="the SRDF written"))
@click.argument("robot")
@click.option("--out", "out", type=PATH, required=True, help="The .srdf file to write.")
@click.option("--margin", type=LENGTH, default=0.0, show_default=True,
              help="Never means never within this distance (m) anywhere within the joint limits.")
@click.option("--method", type=click.Choice(["certified", "sampled"]), default="certified", show_default=True,
              help="certified: Never proven by branch and bound; sampled: MoveIt Setup Assistant's rules.")
@click.option("--samples", type=SAMPLES, default=10_000, show_default=True, help="Random configurations of --method sampled.")
@click.option("--workers", type=AT_LEAST_ONE, default=None, help="Threads over the pairs (default: one); with --scheduler local, "
              "the Dask worker processes.")
@click.option("--scheduler", default=None, help="Search the pairs on Dask: 'local' (a LocalCluster of --workers "
              "processes) or a scheduler's address (tcp://host:8786); each worker loads ROBOT from its file.")
@click.option("--max-evaluations", type=AT_LEAST_ONE, default=200_000, show_default=True,
              help="Per pair, distance evaluations before it is left undecided (certified).")
@click.option("--evaluator", type=BACKEND, default="analytic", show_default=True,
              help="The backend whose distances are evaluated at cell centres (analytic, coal, ...).")
@click.option("--update", is_flag=True,
              help="--out is an SRDF written before: keep every pair whose certificate (its links' shapes, the joints "
                   "between them, margin and method) is unchanged, search the rest again; keep its groups, group "
                   "states, end effectors, virtual and passive joints (a hand-written MoveIt SRDF: all pairs searched).")
@click.option("--json", "as_json", is_flag=True, help="Print the matrix as JSON.")
def srdf_cmd(robot, out, margin, method, samples, workers, scheduler, max_evaluations, evaluator, update, as_json) -> None:
    """Write the collision matrix of ROBOT (a built-in name, a public robot's name, or a .urdf) as an SRDF."""
    from pathlib import Path

    from ..model import load_model
    from ..srdfgen import collision_matrix

    from ..srdfgen._io import other_elements, read_previous

    if update and not Path(out).is_file():
        raise click.BadParameter(f"{out} is not a file: --update rewrites an SRDF written before", param_hint="--out")
    if Path(out).is_file():  # a URDF (or no XML) is never rewritten as an SRDF
        from .._errors import SceneFileError
        from ..model._srdf import read_srdf

        try:
            read_srdf(out, partial=True)
        except SceneFileError as exc:
            raise click.BadParameter(f"{exc}; --out names the SRDF to write", param_hint="--out") from None
    keep = other_elements(out) if Path(out).is_file() else []
    if keep and not update:  # a MoveIt SRDF's groups and states: never lost to a rewrite
        tags = sorted({el.tag for el in keep if isinstance(el.tag, str)})
        if tags:
            raise click.BadParameter(f"{out} holds elements a collision matrix does not make ({', '.join(tags)}): "
                                     "--update keeps them and replaces its disable_collisions; or write to another file",
                                     param_hint="--out")
    from .._io import check_writable

    check_writable(out)  # refused before minutes of work (a missing folder is made with the file, as verify --report makes its)
    model = load_model(robot, srdf=False)
    if update:  # its groups and states are kept: they must be this robot's
        from .._errors import SceneFileError
        from ..srdfgen._io import check_fits

        try:
            check_fits(out, model)
        except SceneFileError as exc:
            raise click.BadParameter(str(exc), param_hint="--out") from None
    before = read_previous(out) if update else {}
    said = []  # what --update read from the file rather than from the command line
    if update:  # the file's margin and method, unless given: a rewrite at another one searches every pair again
        import xml.etree.ElementTree as ET

        from ..model._certificate import MARGIN_ATTR, METHOD_ATTR

        root = ET.parse(out).getroot()
        src = click.get_current_context().get_parameter_source
        if src("margin") is click.core.ParameterSource.DEFAULT and root.get(MARGIN_ATTR) is not None:
            margin = float(root.get(MARGIN_ATTR))
            said.append(f"margin {margin:g} m")
        if src("method") is click.core.ParameterSource.DEFAULT and root.get(METHOD_ATTR) in ("certified", "sampled"):
            method = root.get(METHOD_ATTR)
            said.append(f"method {method}")
    _refuse_unused(method)  # the method the run uses (given, or with --update the file's): before the search
    cm = collision_matrix(model, margin=margin, method=method, samples=samples, workers=workers,
                          max_evaluations=max_evaluations, backend=evaluator, progress=False if as_json else _label(robot),
                          previous=out if update else None, scheduler=scheduler)
    changed = [(before[frozenset((e.link1, e.link2))], e) for e in cm.entries if frozenset((e.link1, e.link2)) in before
               and (before[frozenset((e.link1, e.link2))].reason, before[frozenset((e.link1, e.link2))].status)
               != (e.reason, e.status)]
    gone = []
    if update:  # and the disabled pairs the matrix does not search (static bodies, a link against an obstacle)
        keep = other_elements(out, searched={frozenset((e.link1, e.link2)) for e in cm.entries})
        import pinocchio as pin

        links = {f.name for f in model.pin_model.frames if f.type == pin.BODY}
        gone = [el for el in keep if el.tag == "disable_collisions" and not {el.get("link1"), el.get("link2")} <= links]
        keep = [el for el in keep if not any(el is g for g in gone)]  # a renamed or removed link's: dropped, said below
    from .._io import make_folder

    make_folder(Path(out).parent)
    cm.write_srdf(out, keep if update else ())
    c = cm.counts()
    if as_json:
        click.echo(json.dumps({"model": cm.model, "method": cm.method, "margin": cm.margin, "out": str(out),
                               "elapsed_s": cm.elapsed_s, "counts": c, "joint_names": list(cm.joint_names),
                               "kept": [list(p) for p in cm.kept],
                               "changed": [{"link1": e.link1, "link2": e.link2, "was": o.reason or o.status,
                                            "now": e.reason or e.status} for o, e in changed],
                               "pairs": [{"link1": e.link1, "link2": e.link2, "reason": e.reason, "status": e.status,
                                          "q": None if e.q is None else list(e.q),
                                          "distance": e.distance if e.distance is not None and math.isfinite(e.distance) else None,
                                          "how": e.how}
                                         for e in cm.entries]}, default=float, allow_nan=False))
        return
    click.echo(f"wrote {out}: {len(cm.disabled)} of {c['pairs']} pairs disabled (Adjacent {c['Adjacent']}, "
               f"Default {c['Default']}, Never {c['Never']}, Always {c['Always']}); checked: {c['witnessed']} witnessed, "
               f"{c['undecided']} undecided; {cm.method}, {cm.elapsed_s:.1f} s")
    if method == "sampled" and c["Never"] and samples < _FEW_SAMPLES:
        click.echo(f"warning: {count(c['Never'], 'pair')} disabled as Never from {count(samples, 'sample')}: a pair "
                   f"no sample brought together may still collide (MoveIt's default is {_FEW_SAMPLES:,}; "
                   "--method certified proves Never)", err=True)
    if c["pairs"] and len(cm.disabled) == c["pairs"]:
        click.echo(f"warning: every pair is disabled: a model loaded with {out} has no pair to check, and "
                   "armguard refuses it", err=True)
    if update:
        click.echo(f"  --update: {len(cm.kept)} pairs kept (certificate unchanged), "
                   f"{c['pairs'] - c['Adjacent'] - c['Default'] - len(cm.kept)} searched again"
                   + ("" if before else f" ({out} carried no armguard certificates)"))
        if said:
            click.echo(f"  --update: {' and '.join(said)} from {out} (give --margin / --method to change them)")
        for el in gone:
            click.echo(f"  --update: dropped the disable_collisions of {el.get('link1')} - {el.get('link2')}: "
                       "the URDF has no such link (renamed or removed)")
        kept_tags = [el.tag if el.tag != "disable_collisions" else f"disable_collisions ({el.get('reason') or 'no reason'}, "
                     "not searched)" for el in keep if isinstance(el.tag, str)]
        if kept_tags:
            counts = {t: kept_tags.count(t) for t in dict.fromkeys(kept_tags)}
            click.echo("  --update: kept " + ", ".join(f"{n} {t}" for t, n in counts.items()) + f" of {out}")
        for o, e in changed:
            click.echo(f"  changed {e.link1} - {e.link2}: {o.reason or o.status} -> {e.reason or e.status}")
            if e.reason == "Default":  # disabled because the edit put them in contact at home: said, not only listed
                click.echo(f"warning: {e.link1} - {e.link2} are in contact at home now ({e.distance * 1e3:.1f} mm) and are "
                           f"disabled as Default (MoveIt's rule; they were {o.reason or o.status}): did a shape grow or a "
                           "joint move in the edit?", err=True)
    for e in cm.entries:
        if e.status == "witnessed":
            click.echo(f"  checked {e.link1} - {e.link2}: distance {e.distance:.4f} m at q = {_q(model, e.q)}")
        elif e.status == "undecided":
            click.echo(f"  checked {e.link1} - {e.link2}: undecided ({e.how})")


def _refuse_unused(method: str) -> None:
    """The options of the other method, given: a usage error (they were accepted and silently ignored)."""
    ctx = click.get_current_context()
    if method == "certified":
        refuse_unused(ctx, ["samples"], "goes with --method sampled (certified proves each pair by branch and bound)")
    else:
        refuse_unused(ctx, ["max_evaluations", "workers", "scheduler"],
                      "goes with --method certified (sampled draws --samples configurations, here, once)")


@main.command("check-srdf", epilog=exit_epilog(
    ok="linted (findings, if any, are printed)",
    unsafe="with --strict: a disabled pair other than Adjacent or Default can collide, or a disabled pair names "
           "a link the robot lacks (unless the SRDF was found under the robot's name: one of a larger robot), or "
           "load_model refuses the SRDF (a group state naming a joint the robot lacks or outside its limits)"))
@click.argument("robot")
@click.argument("srdf", type=PATH, required=False)
@click.option("--margin", type=LENGTH, default=0.0, show_default=True, help="Collide means within this distance (m).")
@click.option("--workers", type=AT_LEAST_ONE, default=None, help="Threads over the pairs (default: one).")
@click.option("--max-evaluations", type=AT_LEAST_ONE, default=200_000, show_default=True,
              help="Per pair, distance evaluations before it is left undecided.")
@click.option("--evaluator", type=BACKEND, default="analytic", show_default=True, help="The backend whose distances are evaluated.")
@click.option("--strict", is_flag=True, help="Exit 1 when a pair disabled for a reason other than Adjacent or Default can "
              "collide, a disabled pair names a link the robot lacks, or load_model refuses the SRDF (a group state "
              "naming a joint the robot lacks or outside its limits).")
@click.option("--json", "as_json", is_flag=True,
              help="Print a JSON object: can_collide [{link1, link2, reason, q (pin_model order, as joint_names), distance, "
                   "coal_distance (coal's distance at q; null where coal is not installed or is the evaluator)}], never_checked, proven_disabled, undecided, "
                   "adjacent, skipped, joint_names, refused (why load_model refuses the SRDF, other than its disabled "
                   "pairs; null: it does not), ... (docs/srdf.md).")
def check_srdf_cmd(robot, srdf, margin, workers, max_evaluations, evaluator, strict, as_json) -> None:
    """Lint SRDF for ROBOT: disabled pairs that can collide (with a witness), checked pairs proven never to.
    Without SRDF: the one armguard finds for ROBOT (as `armguard info ROBOT` names it)."""
    from ..model import load_model
    from ..srdfgen import check_srdf

    partial = False  # an SRDF found under the robot's name may describe a larger robot (load_model skips its other links)
    if srdf is None:
        found = load_model(robot).srdf
        if found is None:
            raise click.UsageError(f"armguard finds no SRDF for {robot!r} (docs/models.md says where it looks): give SRDF")
        srdf, partial = str(found.file), bool(found.partial)
        if not as_json:
            click.echo(f"SRDF: {srdf} ({found.found})")
    model = load_model(robot, srdf=False)
    refused = None if partial else _refusal(robot, srdf)
    lint = check_srdf(model, srdf, margin=margin, workers=workers, max_evaluations=max_evaluations, backend=evaluator,
                      progress=False if as_json else _label(robot))
    if as_json:
        click.echo(json.dumps({**lint.to_dict(), "refused": refused}))
    else:
        click.echo(f"{srdf}: {count(len(lint.can_collide), 'disabled pair')} can collide, {len(lint.proven_disabled)} proven never, "
                   f"{len(lint.never_checked)} checked pairs proven never, {len(lint.undecided)} undecided "
                   f"({lint.elapsed_s:.1f} s; q over {', '.join(model.scene.joint_names)})")
        for d in lint.can_collide:
            coal = "" if d.get("coal_distance") is None else f" (coal: {d['coal_distance']:.4f} m)"
            click.echo(f"  disabled ({d['reason'] or 'no reason given'}) {d['link1']} - {d['link2']}: distance {d['distance']:.4f} m{coal} at q = {_q(model, d['q'])}")
        for d in lint.never_checked:
            click.echo(f"  checked {d['link1']} - {d['link2']}: proven never (clearance >= {d['clearance_lower_bound']:.4f} m)")
        for d in lint.undecided:
            click.echo(f"  undecided {d['link1']} - {d['link2']} ({'disabled' if d['disabled'] else 'checked'})")
        unknown = lint.unknown_links
        if unknown and partial:
            click.echo(f"  {count(len(unknown), 'disabled pair')} name{'s' if len(unknown) == 1 else ''} links {robot} does not have (an SRDF of a larger robot: "
                       "not applied, as load_model skips them)")
        elif unknown:
            links = {x for d in unknown for x in (d["link1"], d["link2"])} - set(_links(model))
            click.echo(f"  {count(len(unknown), 'disabled pair')} name{'s' if len(unknown) == 1 else ''} links {robot} does not have ({', '.join(sorted(links))}): "
                       "not checked, and load_model refuses this SRDF")
            for d in unknown:
                click.echo(f"  disabled ({d['reason'] or 'no reason given'}) {d['link1']} - {d['link2']}: unknown link")
        if refused is not None:
            click.echo(f"  load_model refuses this SRDF: {refused}")
    bad_links = bool(lint.unknown_links) and not partial
    if strict and (bad_links or refused is not None
                   or any(d["reason"] not in ("Adjacent", "Default") for d in lint.can_collide)):
        raise SystemExit(int(ExitCode.UNSAFE))


def _refusal(robot, srdf) -> str | None:
    """Why ``load_model(robot, srdf=srdf)`` refuses the SRDF other than for its disabled pairs (a group state
    naming a joint the robot lacks, a value outside its limits: every other command refused the file that
    the lint passed), else None.  Its pairs naming links the robot lacks are the lint's own finding."""
    import warnings

    from .._errors import SceneFileError
    from ..model import load_model

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the lint's reading says what it finds; the load's warnings are check's
            load_model(robot, srdf=srdf)
    except SceneFileError as exc:
        return None if exc.where.startswith("disable_collisions") else str(exc)
    return None


def _links(model) -> list:
    """The URDF links of ``model`` (Pinocchio's body frames): the names an SRDF may use."""
    import pinocchio as pin

    return [f.name for f in model.pin_model.frames if f.type == pin.FrameType.BODY]
