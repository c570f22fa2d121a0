"""Value checks of :func:`armguard.harness.check_model_files` on the URDF as written: angles and limits
that look written in degrees (``units``), and mimic joints whose coupling leaves their own limits
(``mimic-range``); see :mod:`armguard.harness._lint`'s docstring."""

from __future__ import annotations

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES
from ._lint_report import Check, Finding, LintReport, Severity


def _mimic_ranges(root, f: str, report: LintReport) -> None:
    """``mimic-range`` (module docstring): each mimic joint's range over its leader's limits against its own."""
    joints = {j.get("name"): j for j in root.findall("joint")}

    def limits(j):
        lim = j.find("limit") if j is not None else None
        try:
            return float(lim.get("lower")), float(lim.get("upper"))
        except (AttributeError, TypeError, ValueError):
            return None

    for name, j in joints.items():
        m = j.find("mimic")
        own, lead = limits(j), limits(joints.get(m.get("joint"))) if m is not None else None
        if m is None or own is None or lead is None or j.get("type") not in ("revolute", "prismatic"):
            continue
        try:
            mult, off = float(m.get("multiplier", "1")), float(m.get("offset", "0"))
        except ValueError:
            continue  # the loader refuses it, located
        lo, hi = sorted((off + mult * lead[0], off + mult * lead[1]))
        if lo < own[0] - DEFAULT_TOLERANCES.joint_limit or hi > own[1] + DEFAULT_TOLERANCES.joint_limit:
            report.findings.append(Finding(
                Check.MIMIC_RANGE, Severity.WARNING, f"{f}: joint[{name}].mimic",
                f"follows {m.get('joint')!r} as {off:g} + {mult:g} x its value: over its limits [{lead[0]:g}, {lead[1]:g}] "
                f"it reaches [{lo:.6g}, {hi:.6g}], outside its own limits [{own[0]:g}, {own[1]:g}] (Pinocchio moves it by "
                "the coupling alone: the model reaches configurations the robot cannot)",
                "narrow the leader's limits, or correct the multiplier and offset"))


_RPY_MAX = 2.0 * np.pi + 1e-3  # one turn: no rpy angle needs more (1e-3: 2 pi written to 4 places, 6.2832)
_LIMIT_MAX = 4.0 * np.pi + 1e-3  # two turns each way: joints such as UR's +-2 pi stay below it


def _floats(text: str | None) -> list:
    try:
        return [float(x) for x in (text or "").split()]
    except ValueError:
        return []


def _angle_units(root, f: str, report: LintReport) -> None:
    """``rpy`` angles and revolute limits larger than radians need: written in degrees (module docstring)."""
    def rad(text):
        return " ".join(f"{np.radians(x):.6g}" for x in _floats(text))

    for kind in ("link", "joint"):
        for el in root.findall(kind):
            origins = [(f"{kind}[{el.get('name')}].origin", o) for o in el.findall("origin")]
            origins += [(f"{kind}[{el.get('name')}].{c.tag}[{k}].origin", o) for c in el if c.tag in ("collision", "visual")
                        for k, o in enumerate(c.findall("origin"))]
            for where, o in origins:
                rpy = _floats(o.get("rpy"))
                if rpy and max(abs(x) for x in rpy) > _RPY_MAX:
                    report.findings.append(Finding(
                        Check.UNITS, Severity.WARNING, f"{f}: {where}",
                        f'rpy="{o.get("rpy")}": URDF angles are radians, and {max(abs(x) for x in rpy):g} rad is more '
                        "than a turn (degrees?)", f'rpy="{rad(o.get("rpy"))}" if these are degrees'))
    for j in root.findall("joint"):
        lim = j.find("limit")
        if j.get("type") != "revolute" or lim is None:
            continue
        vals = _floats(lim.get("lower")) + _floats(lim.get("upper"))
        if vals and _LIMIT_MAX < max(abs(x) for x in vals) <= 1000.0:  # beyond 1000: "unbounded" (1e16), not degrees
            report.findings.append(Finding(
                Check.UNITS, Severity.WARNING, f"{f}: joint[{j.get('name')}].limit",
                f"lower={lim.get('lower')} upper={lim.get('upper')}: a revolute joint's limits are radians, and "
                f"{max(abs(x) for x in vals):g} rad is more than two turns (degrees?)",
                f'lower="{rad(lim.get("lower"))}" upper="{rad(lim.get("upper"))}" if these are degrees'))
