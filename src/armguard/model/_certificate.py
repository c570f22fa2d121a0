"""Certificates of an SRDF's disabled pairs: what a verdict on a link pair depends on, hashed.

A collision matrix's verdict on a pair of links A, B (:mod:`armguard.srdfgen`: *Never* proven,
*Default*, *Adjacent*) holds for the geometry and the kinematics it was made for.  It depends on

* the shapes of A and of B, each in its joint's frame (type, size, placement; a mesh by the
  vertices of the hull that is checked);
* every joint that changes the pair's relative pose: the joints that support one link and not the
  other (Pinocchio's ``model.supports``), each with its type, placement in its parent, position
  limits and ``q`` slot (a mimic joint's coupling and an unaligned axis included);
* the margin and the method the matrix was made with;
* the verdict itself: the disabled pair's reason (*Never*, *Default*, *Adjacent*), or ``checked``
  for a pair the matrix checks (its comment), so a certificate moved onto another verdict (a
  checked pair's comment turned into a ``<disable_collisions reason="Never">``) does not hold.

An *Adjacent* pair is disabled whatever its shapes (MoveIt's rule) for as long as it is adjacent: one
link the other's parent, or joined through links without geometry; once a link between them has
geometry, its certificate is stale too.

:func:`pair_fingerprint` hashes exactly these (SHA-256, the first 16 hex digits), so an edit of
anything else in the URDF -- another link's mesh, a joint below both links, inertias -- keeps the
certificate, and an edit of anything the verdict depends on voids it.  ``armguard srdf`` writes
the fingerprint as an ``armguard_fingerprint`` attribute of ``<disable_collisions>`` (MoveIt's
and Pinocchio's readers ignore attributes they do not know); :func:`stale_certificates` lists the
disabled pairs whose certificate no longer matches the model (``load_model`` warns of them,
``armguard check-urdf`` proves them again, ``armguard srdf --update`` rewrites them).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .._errors import SceneFileError, unclosed_text

__all__ = ["FINGERPRINT_ATTR", "FORMAT_ATTR", "CERTIFICATE_FORMAT", "older_certificates", "MARGIN_ATTR", "METHOD_ATTR", "pair_fingerprint", "pair_digest", "verdict_fingerprint",
           "certificate_verdict", "read_certificates", "Certificate", "StaleCertificate", "stale_certificates"]

FINGERPRINT_ATTR = "armguard_fingerprint"
FORMAT_ATTR = "armguard_certificates"  # on <robot>: the certificate format the file was written with
CERTIFICATE_FORMAT = "2"
MARGIN_ATTR = "armguard_margin"
METHOD_ATTR = "armguard_method"
_VERSION = b"armguard-pair-certificate-2"  # 2: the verdict hashed too
_SHAPE_ATTRS = ("radius", "halfLength", "halfSide", "radii", "n", "d")


def _floats(h, x) -> None:
    """Hash numbers to 12 decimals (m, rad), so a file re-saved with the same values keeps its print."""
    a = np.round(np.asarray(x, dtype=np.float64).ravel(), 12) + 0.0  # +0.0: no negative zero
    h.update(a.tobytes())


def _shape(h, geometry) -> None:
    h.update(type(geometry).__name__.encode())
    for name in _SHAPE_ATTRS:
        if hasattr(geometry, name):
            v = getattr(geometry, name)
            if not callable(v):
                h.update(name.encode())
                _floats(h, v)
    if hasattr(geometry, "points") and callable(geometry.points):  # a convex hull: its vertices, in order
        _floats(h, geometry.points())


def certificate_verdict(reason) -> str:
    """What a certificate vouches for: ``"disabled:<reason>"`` for a ``<disable_collisions>`` element
    (its reason as written, none included), ``"checked"`` for a checked pair's comment (``reason``
    None: witnessed or undecided, checked either way).  Two namespaces: a checked pair's print copied
    onto an element, with any reason or none, does not hold."""
    return "checked" if reason is None else f"disabled:{reason}"


def pair_fingerprint(pin_model, collision_model, link1: str, link2: str, *, margin: float, method: str,
                     verdict: str) -> str | None:
    """The fingerprint (16 hex digits) of verdict ``verdict`` (:func:`certificate_verdict`) on
    ``link1``-``link2`` (see the module docstring); None when either name is not a frame of
    ``pin_model``."""
    base = pair_digest(pin_model, collision_model, link1, link2, margin=margin, method=method)
    return None if base is None else verdict_fingerprint(base, verdict)


def verdict_fingerprint(base: bytes, verdict: str) -> str:
    """The fingerprint of ``verdict`` on a pair whose :func:`pair_digest` is ``base``."""
    return hashlib.sha256(base + b" verdict " + certificate_verdict(verdict).encode()).hexdigest()[:16]


def pair_digest(pin_model, collision_model, link1: str, link2: str, *, margin: float, method: str) -> bytes | None:
    """SHA-256 of what a verdict on ``link1``-``link2`` depends on but the verdict (None: a name is
    not a frame of ``pin_model``); :func:`verdict_fingerprint` adds the verdict."""
    ids = []
    for name in sorted((link1, link2)):  # the pair's print does not depend on its order
        if not pin_model.existFrame(name, pin.BODY):
            return None
        ids.append((name, pin_model.getFrameId(name, pin.BODY)))
    h = hashlib.sha256(_VERSION)
    h.update(f"{method} {float(margin)!r}".encode())
    joints = set()
    for name, fid in ids:
        j = int(pin_model.frames[fid].parentJoint)
        joints.symmetric_difference_update(int(x) for x in pin_model.supports[j])
        h.update(b"link " + name.encode())
        for go in collision_model.geometryObjects:
            if int(go.parentFrame) == fid:
                h.update(b"shape")
                _floats(h, go.placement.homogeneous)
                _shape(h, go.geometry)
    lo, hi = pin_model.lowerPositionLimit, pin_model.upperPositionLimit
    for j in sorted(joints):
        jm = pin_model.joints[j]
        h.update(b"joint " + pin_model.names[j].encode() + b" " + jm.shortname().encode())
        _floats(h, pin_model.jointPlacements[j].homogeneous)
        q = slice(int(jm.idx_q), int(jm.idx_q) + int(jm.nq))
        h.update(f"q {q.start} {q.stop} parent {pin_model.names[pin_model.parents[j]]}".encode())
        _floats(h, lo[q])
        _floats(h, hi[q])
        own = jm.extract()  # the joint's own type: Pinocchio's generic JointModel shows none of these
        for attr in ("axis", "scaling", "offset"):  # an unaligned axis, a mimic joint's coupling
            if hasattr(own, attr):
                h.update(attr.encode())
                _floats(h, np.atleast_1d(getattr(own, attr)))
        if jm.shortname() == "JointModelMimic":  # the motion it makes: the mimicked joint's axis times its scaling
            jd = jm.createData()
            jm.calc(jd, pin.neutral(pin_model))
            _floats(h, np.asarray(jd.S))
            # and the range it makes it over: its leader's limits (its own slice is empty: nq = 0), the leader
            # perhaps above the pair's common ancestor, so in no other part of this print
            lead = next((k for k in range(1, pin_model.njoints) if pin_model.joints[k].nq > 0
                         and int(pin_model.joints[k].idx_q) == int(jm.idx_q)), None)
            if lead is not None:
                lq = slice(int(jm.idx_q), int(jm.idx_q) + int(pin_model.joints[lead].nq))
                h.update(b"leader " + pin_model.names[lead].encode())
                _floats(h, lo[lq])
                _floats(h, hi[lq])
    return h.digest()


@dataclass(frozen=True)
class Certificate:
    """One ``<disable_collisions>`` with a fingerprint: the pair, its reason, the print, the element."""

    link1: str
    link2: str
    reason: str
    fingerprint: str
    margin: float
    method: str
    where: str


def read_certificates(srdf_file) -> tuple[Certificate, ...]:
    """The disabled pairs of ``srdf_file`` that carry an ``armguard_fingerprint`` (written by
    ``armguard srdf``); none for an SRDF made otherwise.  A file that does not parse is a located error."""
    from xml.parsers import expat

    from ._urdf_check import parse_with_lines

    try:
        data = Path(srdf_file).read_bytes()
        root, lines = parse_with_lines(data)
    except expat.ExpatError as exc:
        raise SceneFileError(str(srdf_file), f"line {exc.lineno}, column {exc.offset + 1}",
                             f"not well-formed XML: {expat.ErrorString(exc.code)}{unclosed_text(data, exc.code)}",
                             line=exc.lineno) from None
    except OSError as exc:
        raise SceneFileError(str(srdf_file), "", f"cannot read the SRDF ({exc.strerror or exc})") from None
    default_margin = root.get(MARGIN_ATTR, "0")
    default_method = root.get(METHOD_ATTR, "certified")
    out = []
    for k, el in enumerate(root.iter("disable_collisions")):
        fp = el.get(FINGERPRINT_ATTR)
        if not fp:
            continue
        line = lines.get(id(el))
        where = f"disable_collisions[{k}]" + (f" (line {line})" if line else "")
        try:
            margin = float(el.get(MARGIN_ATTR, default_margin))
        except ValueError:
            raise SceneFileError(str(srdf_file), where, f"{MARGIN_ATTR}: expected a length (m)") from None
        out.append(Certificate(el.get("link1", ""), el.get("link2", ""), el.get("reason", ""), fp, margin,
                               el.get(METHOD_ATTR, default_method), where))
    return tuple(out)


def older_certificates(srdf_file) -> bool:
    """Whether ``srdf_file`` carries certificates written before the verdict was hashed into them
    (``<robot>`` without ``armguard_certificates="2"``): every one of them reads as stale, whatever
    the URDF.  False for an SRDF without certificates, or one that does not parse (its reader says so)."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(srdf_file).getroot()
    except (ET.ParseError, OSError):
        return False
    return root.get(FORMAT_ATTR) != CERTIFICATE_FORMAT and any(
        el.get(FINGERPRINT_ATTR) for el in root.iter("disable_collisions"))


def uncertified_pairs(srdf_file) -> tuple[str, ...]:
    """``"link1-link2 (reason)"`` of each ``<disable_collisions>`` without a certificate in an SRDF that
    ``armguard srdf`` wrote (its ``<robot>`` marked ``armguard_certificates``): a line added by hand, whose
    verdict nothing vouches for.  None for an SRDF made otherwise (MoveIt's: no line has one)."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(srdf_file).getroot()
    except (ET.ParseError, OSError):
        return ()
    if root.get(FORMAT_ATTR) is None:
        return ()
    return tuple(f"{el.get('link1', '')}-{el.get('link2', '')} ({el.get('reason', '')})"  # (Static, Seed: pairs the
                 for el in root.iter("disable_collisions")  # matrix does not search, kept as written by --update)
                 if not el.get(FINGERPRINT_ATTR) and el.get("reason") not in ("Static", "Seed"))


@dataclass(frozen=True)
class StaleCertificate:
    """A disabled pair whose certificate does not match the model: ``recorded`` vs ``now`` (None: a link is gone)."""

    link1: str
    link2: str
    reason: str
    recorded: str
    now: str | None
    where: str


def _adjacent(pin_model, collision_model, link1: str, link2: str) -> bool:
    """MoveIt's *Adjacent*: one link the other's parent, or joined through links without geometry (a
    gone link: not adjacent)."""
    frames = pin_model.frames
    if not (pin_model.existFrame(link1, pin.BODY) and pin_model.existFrame(link2, pin.BODY)):
        return False
    shaped = {int(go.parentFrame) for go in collision_model.geometryObjects}

    def shaped_parent(name: str) -> str | None:
        f = pin_model.getFrameId(name, pin.BODY)
        while f != 0:
            f = int(frames[f].parentFrame)
            while f != 0 and frames[f].type != pin.BODY:  # the joint frames between two links
                f = int(frames[f].parentFrame)
            if f == 0 or f in shaped:
                break
        return frames[f].name if f != 0 else None

    return shaped_parent(link1) == link2 or shaped_parent(link2) == link1


def stale_certificates(pin_model, collision_model, srdf_file) -> tuple[StaleCertificate, ...]:
    """The certified disabled pairs of ``srdf_file`` whose fingerprint the model no longer gives (an
    *Adjacent* pair is disabled whatever its shapes, as MoveIt does, and is listed only when a link
    between them got geometry; a pair with a link that has no geometry, or no longer exists, cannot
    collide and is not listed)."""
    out = []
    shaped = {pin_model.frames[int(go.parentFrame)].name for go in collision_model.geometryObjects}
    for c in read_certificates(srdf_file):
        if c.link1 not in shaped or c.link2 not in shaped:
            continue  # a link without geometry (or gone: the SRDF's reader names it) collides with nothing
        if c.reason == "Adjacent":  # joined by a joint: disabled whatever their shapes (MoveIt's rule) while it holds
            if not _adjacent(pin_model, collision_model, c.link1, c.link2):  # a link between them got geometry
                out.append(StaleCertificate(c.link1, c.link2, c.reason, c.fingerprint, None, c.where))
            continue
        now = pair_fingerprint(pin_model, collision_model, c.link1, c.link2, margin=c.margin, method=c.method,
                               verdict=c.reason)
        if now != c.fingerprint:
            out.append(StaleCertificate(c.link1, c.link2, c.reason, c.fingerprint, now, c.where))
    return tuple(out)
