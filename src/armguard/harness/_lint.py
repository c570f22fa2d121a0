"""``check_model_files``: lint a model's URDF, SRDF and meshes the way an engineer needs it linted.

Checks (each a :class:`Check`), on the files as written, then on the loaded model:

* ``load``: the model does not load (``load_model`` raises; a collision element Pinocchio would
  drop, a mesh not found, an SRDF name the URDF lacks): the error, as a finding;
* ``unparsed``: a collision element Pinocchio would drop (a plain ``<capsule>`` or other tag, an empty
  ``<geometry>``), a mesh not found (once: not where ``load`` says it), a ``<collision_checking>`` naming none;
* ``non-convex``: a mesh marked ``<convex>`` that is not convex — a solid whose volume is below
  ``convex_volume_ratio`` of its hull's, a mesh with vertices inside its hull, or a flat mesh
  (a polygon) with vertices inside its 2-D hull;
* ``zero-length-capsule``: a ``<capsule>``-marked cylinder of length 0 (a sphere: say so), or a
  ``<capsule>`` mark on something not a cylinder;
* ``srdf-name``: an SRDF link, joint or group name that matches nothing in the URDF (an error), or a
  ``group_state`` without ``group`` (a warning: read as the whole robot's state, as the loader does);
* ``srdf-certificate``: a pair the SRDF disables with a certificate (``armguard srdf``) that the
  URDF no longer matches -- a shape of either link or a joint between them edited -- is searched
  again (:func:`armguard.srdfgen.check_srdf`): an error with the configuration where it now
  collides, else a warning (still proven: refresh the SRDF with ``armguard srdf --update``; or
  undecided); and a pair the SRDF records as checked that the URDF now joins through links
  without geometry (MoveIt's Adjacent rule drops it from the checks: a warning);
* ``permanent-collision``: an active pair in collision (coal, ``d <= 0``) at the home pose and at more than
  ``permanent_fraction`` of ``n_configs`` seeded random configurations (an error; a ``<disable_collisions
  reason="Always">`` line is suggested, MoveIt's name for a pair its Setup Assistant finds in collision in at
  least 95 % of its samples); clear at home, such a pair is a ``home-collision`` warning, no Always suggested;
* ``home-collision``: an active pair in collision at the home pose but not permanently (a warning,
  with its share of the random configurations: the home pose or the shapes may be wrong);
* ``unread-element``: an element of a link, collision, visual or joint that nothing reads but that
  looks like one that is (``<orgin>``), or a repeated ``<origin>``, ``<limit>``, ``<axis>`` of which
  only the first is read (a warning; an error where it changes what is checked: a link's
  ``<colision>``, a collision's ``<orgin>`` or ``<geomtry>``);
* ``frozen-joint``: a revolute or prismatic joint whose ``<limit>`` lacks ``lower`` or ``upper``
  (urdfdom and Pinocchio read 0: a joint that cannot move, or only to one side; a warning, also
  given when the URDF loads);
* ``units``: a value that looks written in other units than the URDF's (metres and radians): an ``<origin rpy>``
  angle or a revolute joint's limit beyond what radians need (``rpy="0 0 90"``: degrees; a limit past 1000 reads
  as "unbounded" and is left alone), or a collision mesh, as scaled, a thousand times larger or smaller than the
  robot's kinematic chain (a millimetre mesh without ``scale="0.001"``, or a metre mesh with it): warnings;
* ``mimic-range``: a ``<mimic>`` joint whose coupling, over its leader's limits, takes it outside its
  own ``<limit>`` (Pinocchio moves it by the coupling and reads no limit of its own: the model then
  reaches configurations the robot cannot; a warning).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import ArmguardError
from .._tolerance import DEFAULT_TOLERANCES
from ._lint_report import Check, Finding, LintReport, LintStatus, Severity
from ._lint_values import _angle_units, _mimic_ranges

__all__ = ["Check", "Severity", "LintStatus", "Finding", "LintReport", "check_model_files", "mesh_convexity"]


def _sources(target) -> tuple:
    """``(load_model argument, srdf=, urdf path, srdf path)`` of a name, .urdf or sidecar .yaml."""
    import yaml

    from ..model._load import builtin_model_path
    from ..model._public import public_robot, public_robot_files

    s = str(target)
    if builtin_model_path(s) is None and public_robot(s) is not None:
        urdf, srdf = public_robot_files(s)
        return urdf, srdf, urdf, srdf
    p = Path(s)
    if p.suffix == "" and builtin_model_path(s) is not None:
        p = builtin_model_path(s)
    if p.suffix.lower() in (".yaml", ".yml"):
        try:
            side = yaml.safe_load(p.read_text(encoding="utf-8")) or {}
        except (OSError, yaml.YAMLError):
            return p, None, None, None
        m = side.get("model") if isinstance(side, dict) else None
        if not isinstance(m, dict) or "urdf" not in m:
            return p, None, None, None
        urdf = (p.parent / m["urdf"]).resolve()
        srdf = (p.parent / m["srdf"]).resolve() if m.get("srdf") else urdf.with_suffix(".srdf")
        return p, None, urdf, srdf if srdf.is_file() else None
    if p.suffix.lower() == ".urdf":
        srdf = p.with_suffix(".srdf")
        return p, None, p, srdf if srdf.is_file() else None
    raise ArmguardError(f"check-urdf {s!r}: expected a built-in model name, a public robot's name (armguard info lists them), a .urdf or a sidecar .yaml")


def mesh_convexity(path, *, volume_ratio: float = 0.99) -> tuple[bool, str]:
    """``(convex, how)`` of a mesh file: solids by volume against the hull's, flat meshes by their 2-D hull."""
    import trimesh
    from scipy.spatial import ConvexHull, QhullError

    mesh = trimesh.load(str(path), force="mesh", process=False)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    v = np.unique(v, axis=0)
    c = v - v.mean(axis=0)
    extent = float(np.abs(c).max()) or 1.0
    _, sv, vt = np.linalg.svd(c, full_matrices=False)
    if len(sv) < 3 or sv[2] <= 1e-9 * extent * np.sqrt(len(v)):  # flat: a polygon in its plane
        uv = c @ vt[:2].T
        try:
            hull = ConvexHull(uv)
        except QhullError:
            return True, "degenerate (collinear)"
        inside = len(v) - len(set(hull.vertices))
        return inside == 0, f"flat: {inside} of {len(v)} vertices inside the polygon's hull"
    hull = ConvexHull(v)
    inside = len(v) - len(set(hull.vertices))
    if mesh.is_watertight and mesh.volume > 0:
        ratio = float(abs(mesh.volume) / hull.volume)
        return ratio >= volume_ratio and inside == 0, f"volume {ratio:.4f} of its hull's, {inside} vertices inside the hull"
    return inside == 0, f"not a closed solid; {inside} of {len(v)} vertices inside its hull"


def _load_said(report: LintReport, *parts: str, file: str | None = None) -> bool:
    """The LOAD finding (on ``file``, if given) already says it: its message holds every one of ``parts``."""
    return any(x.check == Check.LOAD and all(p in x.message for p in parts) and file in (None, Path(x.where).name)
               for x in report.findings)


def _unparsed(report: LintReport, f: str, what: str, exc: Exception) -> None:
    """An UNPARSED finding for file ``f``, unless LOAD says it is not well-formed XML (its column counted from 1)."""
    if not _load_said(report, "not well-formed XML", file=f):
        report.findings.append(Finding(Check.UNPARSED, Severity.ERROR, f, f"{what} does not parse: {exc}"))


def _xml_checks(urdf: Path, srdf: Path | None, report: LintReport, mesh_paths: dict, volume_ratio: float,
                partial: bool = False) -> None:
    from ..model._urdf import resolve_mesh

    from xml.parsers import expat

    from ..model._urdf_check import parse_with_lines

    f = urdf.name
    try:
        root, lines = parse_with_lines(urdf.read_bytes())
    except (expat.ExpatError, OSError) as exc:
        _unparsed(report, f, "URDF", exc)
        return
    links, joints = {ln.get("name") for ln in root.findall("link")}, {j.get("name") for j in root.findall("joint")}
    from ..model._urdf import frozen_joint_text

    _unread_elements(root, lines, f, report)
    _angle_units(root, f, report)
    _mimic_ranges(root, f, report)
    for j in root.findall("joint"):  # a <limit> without lower/upper: urdfdom reads 0, and the joint cannot move
        lim = j.find("limit")
        if j.get("type") in ("revolute", "prismatic") and j.find("mimic") is None and lim is not None \
                and not (lim.get("lower") and lim.get("upper")):
            report.findings.append(Finding(Check.FROZEN_JOINT, Severity.WARNING, f"{f}: joint[{j.get('name')}].limit",
                                           frozen_joint_text(lim)))
    for link in root.findall("link"):
        ln = link.get("name")
        entries = {}
        for k, c in enumerate(link.findall("collision")):
            w = f"{f}: link[{ln}].collision[{k}]"
            g = c.find("geometry")
            kids = list(g) if g is not None else []
            name = c.get("name", "")
            if len(kids) != 1:
                report.findings.append(Finding(Check.UNPARSED, Severity.ERROR, w, "expected one shape inside <geometry>"))
                continue
            el = kids[0]
            entries[name] = (el, w)
            if el.tag not in ("box", "sphere", "cylinder", "mesh"):
                sug = ('<cylinder radius="…" length="…"/> plus <collision_checking><capsule name="'
                       f'{name or "NAME"}"/></collision_checking>') if el.tag == "capsule" else "box, sphere, cylinder or mesh"
                report.findings.append(Finding(Check.UNPARSED, Severity.ERROR, w,
                                               f"<{el.tag}> is dropped by Pinocchio (no collision geometry)", sug))
            elif el.tag == "mesh":
                fn = el.get("filename", "")
                mp = mesh_paths.get(name) or resolve_mesh(fn, urdf.parent, ())  # package:// searched above the URDF by itself
                if mp is None:  # once: the LOAD finding may already say it, at the same place
                    if not _load_said(report, f"{w.split(': ', 1)[1]} (line", f"mesh file not found: {fn!r}"):
                        report.findings.append(Finding(Check.UNPARSED, Severity.ERROR, w, f"mesh file not found: {fn!r}"))
                else:
                    entries[name] = (el, w, Path(mp))
        for cc in link.findall("collision_checking"):
            for mark in cc:
                n = mark.get("name")
                wm = f"{f}: link[{ln}].collision_checking.{mark.tag}[{n}]"
                if n not in entries:
                    report.findings.append(Finding(Check.UNPARSED, Severity.ERROR, wm,
                                                   f"names no <collision> of link {ln!r} (it has {sorted(entries)})"))
                    continue
                el, w = entries[n][0], entries[n][1]
                if mark.tag == "capsule":
                    if el.tag != "cylinder":
                        report.findings.append(Finding(Check.ZERO_LENGTH_CAPSULE, Severity.ERROR, w,
                                                       f"<capsule> mark on a <{el.tag}>: only a cylinder becomes a capsule"))
                    elif float(el.get("length", "0")) <= DEFAULT_TOLERANCES.length:
                        report.findings.append(Finding(
                            Check.ZERO_LENGTH_CAPSULE, Severity.WARNING, w,
                            f"zero-length capsule (radius {el.get('radius')}, length {el.get('length')})",
                            f'<sphere radius="{el.get("radius")}"/>'))
                elif mark.tag == "convex" and el.tag == "mesh" and len(entries[n]) == 3:
                    ok, how = mesh_convexity(entries[n][2], volume_ratio=volume_ratio)
                    if not ok:
                        report.findings.append(Finding(
                            Check.NON_CONVEX, Severity.ERROR, w, f"mesh {entries[n][2].name} is marked <convex> but is not "
                            f"convex ({how})", "drop the <convex> mark (it is then checked as its hull) or split the mesh"))
    if srdf is not None:
        shaped = {ln.get("name") for ln in root.findall("link") if ln.find("collision") is not None}
        _srdf_checks(srdf, links, joints, report, partial, shaped)


def _unread_elements(root, lines: dict, f: str, report: LintReport) -> None:
    """Elements of a link, collision or joint that no reader reads although they look like one that is
    (``<orgin>``: the shape then sits at the link's origin), and a repeated one of which only the first
    is read (``<origin>``, ``<limit>``, ``<axis>``): warnings, and errors where they change what is
    checked (a link's ``<colision>``: no geometry from it; a collision's ``<orgin>``).  An unknown element unlike any (a
    simulator's ``<contact>``) is left alone.  The tables are the loader's
    (:data:`armguard.model._urdf_check.READ`, :data:`~armguard.model._urdf_check.CHANGES_CHECKS`)."""
    import difflib

    from ..model._urdf_check import CHANGES_CHECKS, READ

    def scan(el, kind: str, where: str) -> None:
        seen: dict = {}
        for c in el:
            if not isinstance(c.tag, str):
                continue
            seen[c.tag] = seen.get(c.tag, 0) + 1
            if c.tag not in READ[kind]:
                near = difflib.get_close_matches(c.tag, READ[kind], n=1, cutoff=0.75)
                checked = (kind, near[0] if near else None) in CHANGES_CHECKS
                if near:  # an error where it changes what is checked (load_model warns of those too)
                    line = lines.get(id(c))
                    report.findings.append(Finding(Check.UNREAD_ELEMENT, Severity.ERROR if checked else Severity.WARNING,
                                                   f"{f}: {where}.{c.tag}" + (f" (line {line})" if line else ""),
                                                   f"<{c.tag}> is read by nothing: did you mean <{near[0]}>?"
                                                   + (" (it changes what is checked)" if checked else "")))
        for tag, n in seen.items():
            if n > 1 and tag in ("origin", "geometry", "limit", "axis", "parent", "child", "mimic"):
                report.findings.append(Finding(Check.UNREAD_ELEMENT, Severity.WARNING, f"{f}: {where}.{tag}",
                                               f"{n} <{tag}> elements: only the first is read"))

    for link in root.findall("link"):
        scan(link, "link", f"link[{link.get('name')}]")
        for kind in ("collision", "visual"):
            for k, c in enumerate(link.findall(kind)):
                scan(c, kind, f"link[{link.get('name')}].{kind}[{k}]")
    for j in root.findall("joint"):
        scan(j, "joint", f"joint[{j.get('name')}]")


def _reach(pin_model) -> float:
    """The length of the robot's kinematic chain: every joint's and link's offset from its parent, summed."""
    import pinocchio as pin

    n = sum(float(np.linalg.norm(pin_model.jointPlacements[j].translation)) for j in range(1, pin_model.njoints))
    return n + sum(float(np.linalg.norm(fr.placement.translation)) for fr in pin_model.frames if fr.type == pin.BODY)


def _mesh_scale_checks(model, report: LintReport) -> None:
    """A collision mesh, as scaled, 30 times the robot's chain or a 3000th of it (a link's mesh is a fraction
    of the chain; one in millimetres read as metres is 1000 times its size): a warning each."""
    reach = _reach(model.pin_model)
    if not reach > 0.0:
        return
    urdf = Path(report.urdf).name if report.urdf else model.name
    for go in model.collision_model.geometryObjects:
        if not go.meshPath or not Path(go.meshPath).is_file():  # a primitive's meshPath is "BOX", "CYLINDER", ...
            continue
        go.geometry.computeLocalAABB()
        size = float(np.max(go.geometry.aabb_local.max_ - go.geometry.aabb_local.min_))
        if not (np.isfinite(size) and size > 0.0) or reach / 3000.0 <= size <= 30.0 * reach:
            continue
        s = np.asarray(go.meshScale, dtype=float).ravel()
        big = size > reach
        hint = " ".join(f"{x * (1e-3 if big else 1e3):g}" for x in s)
        report.findings.append(Finding(
            Check.UNITS, Severity.WARNING, f"{urdf}: link[{model.pin_model.frames[go.parentFrame].name}] mesh {go.name}",
            f"{Path(go.meshPath).name} with scale=\"{' '.join(f'{x:g}' for x in s)}\" is {size:.4g} m across, "
            f"against a kinematic chain of {reach:.3g} m: a mesh in other units than its scale assumes?",
            f'scale="{hint}" if the mesh is ' + ("in millimetres" if big else "already in metres")))


def _srdf_checks(srdf: Path, links: set, joints: set, report: LintReport, partial: bool = False, shaped=None) -> None:
    """Names of the SRDF that match nothing in the URDF: errors, or for an SRDF of a larger robot found
    under the robot's name (``partial``: the loader skips them) warnings."""
    from xml.parsers import expat

    from ..model._srdf import renamed_to
    from ..model._urdf_check import parse_with_lines

    f = srdf.name
    try:
        root, lines = parse_with_lines(srdf.read_bytes())
    except (expat.ExpatError, OSError) as exc:
        _unparsed(report, f, "SRDF", exc)
        return
    groups = {g.get("name") for g in root.findall("group")}
    # the SRDF's virtual joint (a floating base: MoveIt's) and Pinocchio's root_joint name no URDF joint: the loader
    # reads no value of them (fixed-base models) and warns; so does the lint, never an error (a1, go2, bolt)
    floating = {vj.get("name") for vj in root.findall("virtual_joint")} | {"root_joint"}
    named = {el.get(a) for el in root.iter() for a in ("link1", "link2", "link", "parent_link", "base_link", "tip_link", "name")}
    where_el: dict = {}  # the element each place names, for its line

    def need(name, kind, where, pool, from_pair=False):
        if kind == "joint" and name in floating and name not in pool:
            report.findings.append(Finding(Check.SRDF_NAME, Severity.WARNING, f"{f}: {where}", f"joint {name!r} is a "
                                           "floating base's, not the URDF's: armguard's models are fixed-base (it is "
                                           "not read)"))
            return
        if name not in pool:  # a rename's new name: one the SRDF never names (of a pair: a link with shapes)
            near = renamed_to(name, [x for x in pool if not from_pair or shaped is None or x in shaped], named)
            line = lines.get(id(where_el.get("el")))
            at = f" (line {line})" if line else ""
            report.findings.append(Finding(Check.SRDF_NAME, Severity.WARNING if partial else Severity.ERROR, f"{f}: {where}{at}",
                                           f"{kind} {name!r} matches nothing in the URDF"
                                           + (" (an SRDF of a larger robot: skipped when it loads)" if partial else ""),
                                           f"a {kind} renamed {near!r}? then update the SRDF" if near else None))
    for ee in root.findall("end_effector"):
        where_el["el"] = ee
        for attr in ("parent_link", "group", "parent_group"):
            if ee.get(attr) is not None:
                need(ee.get(attr), "group" if "group" in attr else "link", f"end_effector[{ee.get('name')}].{attr}",
                     groups if "group" in attr else links)

    for k, g in enumerate(root.findall("group")):
        w = f"group[{g.get('name')}]"
        for ch in g.findall("chain"):
            where_el["el"] = ch
            need(ch.get("base_link"), "link", f"{w}.chain.base_link", links)
            need(ch.get("tip_link"), "link", f"{w}.chain.tip_link", links)
        for ln in g.findall("link"):
            where_el["el"] = ln
            need(ln.get("name"), "link", f"{w}.link", links)
        for j in g.findall("joint"):
            where_el["el"] = j
            need(j.get("name"), "joint", f"{w}.joint", joints)
        for sub in g.findall("group"):
            where_el["el"] = sub
            need(sub.get("name"), "group", f"{w}.group", groups)
    for k, el in enumerate(root.iter("disable_collisions")):
        where_el["el"] = el
        for side in ("link1", "link2"):
            need(el.get(side), "link", f"disable_collisions[{k}].{side}", links, True)
    for k, st in enumerate(root.iter("group_state")):
        if st.get("group") is None:  # as the loader reads it (armguard.model._srdf): the whole robot's state
            report.findings.append(Finding(Check.SRDF_NAME, Severity.WARNING, f"{f}: group_state[{st.get('name')}]",
                                           "no attribute 'group'; read as a state of the whole robot (as Pinocchio "
                                           "does)", f'<group_state name="{st.get("name")}" group="...">'))
        else:
            where_el["el"] = st
            need(st.get("group"), "group", f"group_state[{st.get('name')}].group", groups)
        for j in st.findall("joint"):
            where_el["el"] = j
            need(j.get("name"), "joint", f"group_state[{st.get('name')}].joint", joints)


def _certificate_checks(model, report: LintReport) -> None:
    """Search again every disabled pair whose certificate the URDF no longer matches (module docstring)."""
    from ..model._certificate import older_certificates, stale_certificates
    from ..srdfgen import check_srdf

    srdf = Path(model.srdf.file)
    _dropped_checks(model, srdf, report)
    stale = stale_certificates(model.pin_model, model.collision_model, srdf)
    if not stale:
        return
    if older_certificates(srdf):  # every certificate reads as stale: searched again below, whatever the URDF
        report.findings.append(Finding(Check.SRDF_CERTIFICATE, Severity.WARNING, srdf.name, f"certificates of an older "
                                       f"armguard: its {len(stale)} certified pairs are searched again", "armguard srdf --update"))
    where = {frozenset((s.link1, s.link2)): s for s in stale}
    margins = sorted({c.margin for c in _certs(srdf) if frozenset((c.link1, c.link2)) in where})
    for margin in margins or [0.0]:
        lint = check_srdf(model, srdf, margin=margin, pairs=[(s.link1, s.link2) for s in stale])
        for d in lint.can_collide:
            s = where[frozenset((d["link1"], d["link2"]))]
            q = ", ".join(f"{x:.4f}" for x in d["q"])
            report.findings.append(Finding(
                Check.SRDF_CERTIFICATE, Severity.ERROR, f"{srdf.name}: {s.where}",
                f"disables {d['link1']} - {d['link2']} ({d['reason']}), certified for another geometry or kinematics; "
                f"the URDF as it is now brings them within {margin:g} m: distance {d['distance']:.4f} m at q = [{q}] "
                f"({', '.join(lint.joint_names)})", "armguard srdf --update (the pair is then checked)"))
        for d in lint.proven_disabled:
            s = where[frozenset((d["link1"], d["link2"]))]
            report.findings.append(Finding(
                Check.SRDF_CERTIFICATE, Severity.WARNING, f"{srdf.name}: {s.where}",
                f"disables {d['link1']} - {d['link2']} ({d['reason']}) with a certificate for another URDF; proven again: "
                "it still never collides", "armguard srdf --update (records the new certificate)"))
        for d in lint.undecided:
            if d["disabled"]:
                report.findings.append(Finding(
                    Check.SRDF_CERTIFICATE, Severity.WARNING, f"{srdf.name}: {where[frozenset((d['link1'], d['link2']))].where}",
                    f"disables {d['link1']} - {d['link2']} with a certificate for another URDF; neither proven nor "
                    "witnessed again", "armguard srdf --update (the pair is then checked)"))


def _dropped_checks(model, srdf: Path, report: LintReport) -> None:
    """Pairs the SRDF (one ``armguard srdf`` wrote) records as checked that the URDF now joins through links
    without geometry (MoveIt's Adjacent: no longer checked, without a word at load): warnings."""
    from ..model._certificate import _adjacent
    from ..srdfgen._io import read_previous

    try:
        before = read_previous(srdf)
    except ArmguardError:
        return  # not parsed: the SRDF's own findings say so
    for e in before.values():
        if e.status in ("witnessed", "undecided") and _adjacent(model.pin_model, model.collision_model, e.link1, e.link2):
            was = f"witnessed within the margin ({e.distance:.4f} m)" if e.status == "witnessed" else "undecided"
            report.findings.append(Finding(
                Check.SRDF_CERTIFICATE, Severity.WARNING, f"{srdf.name}: {e.link1} - {e.link2}",
                f"recorded as checked ({was}); the URDF now joins them through links without geometry (MoveIt's "
                "Adjacent), so they are no longer checked", "give the link between them its geometry back, or "
                "armguard srdf --update (records the pair Adjacent)"))


def _certs(srdf):
    from ..model._certificate import read_certificates

    return read_certificates(srdf)


def _collision_checks(model, report: LintReport, n_configs: int, seed: int, fraction: float) -> None:
    from ..backends import checker

    c = checker(model, "coal", {"threads": 1})
    names = model.pairs.names
    home = c.pair_distances(model.neutral()).distance
    Q = model.random_q(n_configs, seed)
    hits = np.zeros(len(names))
    for q in Q:
        hits += c.pair_distances(q).distance <= 0.0
    share = hits / max(1, len(Q))
    pm, cm = model.pin_model, model.collision_model

    def link(n):
        return "workspace" if n == "workspace" else pm.frames[cm.geometryObjects[model.geometry_index(n)].parentFrame].name

    for k in np.flatnonzero((home <= 0.0) | (share > fraction)):
        a, b = names[k]
        la, lb = link(a), link(b)
        perm = share[k] > fraction and home[k] <= 0.0  # clear at home: not permanent (bolt at 5 samples: 100 %)
        msg = (f"pair {a} / {b} ({model.pairs.category[k]}): {'in collision' if home[k] <= 0 else 'clear'} at the home "
               f"pose (d = {home[k]:.4g} m), in collision at {share[k]:.0%} of {len(Q)} random configurations")
        sug = None
        if perm and "workspace" not in (la, lb):
            sug = f'<disable_collisions link1="{la}" link2="{lb}" reason="Always"/>'
        if home[k] > 0.0:  # in collision in most samples only: a warning, with no Always to suggest
            msg += "; clear at the home pose, so not permanent (more --configs tell)"
        report.findings.append(Finding(Check.PERMANENT_COLLISION if perm else Check.HOME_COLLISION,
                                       Severity.ERROR if perm else Severity.WARNING, f"pair[{a}, {b}]", msg, sug))


def check_model_files(target, *, n_configs: int = 200, seed: int = 0, permanent_fraction: float = 0.95,
                      convex_volume_ratio: float = 0.99) -> LintReport:
    """Lint ``target`` (a built-in or public robot name, a .urdf or a sidecar .yaml); see the module docstring."""
    from ..model import load_model

    arg, srdf_arg, urdf, srdf = _sources(target)
    report = LintReport(str(target), str(urdf) if urdf else None, str(srdf) if srdf else None)
    model = refused = None
    try:
        model = load_model(arg, srdf=srdf_arg) if srdf_arg is not None else load_model(arg)
    except ArmguardError as exc:
        refused = Finding(Check.LOAD, Severity.ERROR, getattr(exc, "file", "") or str(arg), f"load_model fails: {exc}")
        if " is read by nothing: did you mean <" not in getattr(exc, "message", ""):  # else: unread-element, below
            report.findings.append(refused)
            refused = None
    mesh_paths = {}
    if model is not None:
        mesh_paths = {go.name: go.meshPath for go in model.collision_model.geometryObjects
                      if go.meshPath and Path(go.meshPath).is_file()}
    partial = False
    if model is not None and model.srdf is not None and Path(model.srdf.file).is_file():  # the SRDF it loads, as
        srdf, partial = Path(model.srdf.file), model.srdf.partial                        # load_model finds it
        report.srdf = str(srdf)
    if urdf is not None:
        _xml_checks(Path(urdf), Path(srdf) if srdf else None, report, mesh_paths, convex_volume_ratio, partial)
    if model is not None:
        if model.srdf is not None:
            _certificate_checks(model, report)
        _mesh_scale_checks(model, report)
        _collision_checks(model, report, n_configs, seed, permanent_fraction)
        report.summary = (f"{model.collision_model.ngeoms} geometries, {len(model.pairs)} active pairs, "
                          f"{n_configs} random configurations")
    else:
        report.summary = "the model does not load"
        said = 0 if refused is None else sum(f.check is Check.UNREAD_ELEMENT and f.message.split("?")[0] in refused.message
                                             for f in report.findings)
        if refused is not None and said < refused.message.count("is read by nothing"):  # one no check here reports (an
            report.findings.insert(0, refused)  # SRDF's element, an attribute): the refusal itself, never "clean"
    return report
