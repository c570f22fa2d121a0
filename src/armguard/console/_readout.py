"""What the operator reads: Ranger's distance panel (Bon & Seraji 1997, seed ``000`` section 6).

"The background of the distance panel is green for no obstacle within the detection threshold
distance, yellow for an obstacle within the threshold distance, and red if the arm has collided
with the obstacle."  :func:`readout_from_report` turns a detector report into a frozen
:class:`Readout` (panel colour, nearest distance / link / obstacle / points, one row per result
category); :func:`panel_html` renders it.  Plain Python: tests drive it without a browser.
"""

from __future__ import annotations

import enum
import html
import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "timing_line",
    "PanelStatus",
    "PANEL_COLORS",
    "LINE_COLORS",
    "CategoryRow",
    "Readout",
    "readout_from_report",
    "readout_off",
    "panel_html",
    "CATEGORIES",
    "with_terrain",
    "moving_link_first",
    "short_name",
    "NAME_CHARS",
]

CATEGORIES = ("arm", "environment", "workspace", "payload")
"""Result categories, in the detector's order."""


class PanelStatus(enum.Enum):
    """Status shown by the panel: the detector's status, plus ``OFF`` when detection is off."""

    CLEAR = "clear"
    WARNING = "warning"
    COLLISION = "collision"
    INCOMPLETE = "incomplete"
    OFF = "off"


PANEL_COLORS = {
    PanelStatus.CLEAR: "#2e9e44",  # green
    PanelStatus.WARNING: "#f2c200",  # yellow
    PanelStatus.COLLISION: "#d62828",  # red
    PanelStatus.INCOMPLETE: "#8a5cf6",  # violet: never shown as clear
    PanelStatus.OFF: "#7d7d7d",  # grey
}
"""Background colour of the distance panel per status (CSS hex)."""

WRAP = "overflow-wrap:anywhere;word-break:break-word"
"""CSS that lets a long name (``kinova/j2s6s200_link_finger_tip_2``) wrap at any character
instead of widening the control panel past its frame."""


LINE_COLORS = {"far": (255, 210, 0), "within": (220, 30, 30)}
"""Nearest-obstacle line: yellow beyond the threshold, red within it (RGB 0..255)."""


@dataclass(frozen=True)
class CategoryRow:
    """One row of the per-category table: ``distance`` m (``inf`` where the category is empty)."""

    category: str
    distance: float
    link: str
    obstacle: str


@dataclass(frozen=True)
class Readout:
    """The distance panel's content.

    ``p_WA`` / ``p_WB`` : (3,) float64, m, or None -- the nearest points on the arm link and the
    obstacle, in W.  ``within_threshold`` is True when the nearest distance is <= the threshold
    (the link and the line turn red).  ``owner_a`` is the arm-side owner
    (``"robot/link"`` or a payload name), the scene item to colour; ``owner_b`` the obstacle's
    owner and ``feature`` its nearest feature (``armguard.geometry.Feature`` or None).
    ``elapsed_us`` is the check alone (the detector's or the backend's own call), not the
    console's whole update.  ``backend`` names who computed it.
    """

    status: PanelStatus
    distance: float
    link: str
    obstacle: str
    owner_a: str
    p_WA: np.ndarray | None
    p_WB: np.ndarray | None
    threshold: float
    within_threshold: bool
    rows: tuple[CategoryRow, ...]
    elapsed_us: float
    backend: str = "analytic"
    owner_b: str = ""
    feature: object = None
    stopping_distance: float = 0.0

    @property
    def color(self) -> str:
        """CSS background colour of the panel."""
        return PANEL_COLORS[self.status]

    @property
    def alarm(self) -> bool:
        """The link and the line are drawn red: within the threshold, or a red (COLLISION) headline
        (inside the stopping distance beyond the threshold is red too)."""
        return self.within_threshold or self.status is PanelStatus.COLLISION

    @property
    def line_color(self) -> tuple[int, int, int]:
        """RGB of the nearest-obstacle line: red whenever :attr:`alarm`."""
        return LINE_COLORS["within" if self.alarm else "far"]

    @property
    def reason(self) -> str:
        """Why the headline has its colour, in words (``"within the stopping distance 300.0 mm"``)."""
        d, s = self.distance, self.stopping_distance
        if self.status is PanelStatus.OFF:
            return "detection off"
        if self.status is PanelStatus.INCOMPLETE:
            return "not every pair could be decided: never shown as clear"
        if self.status is PanelStatus.COLLISION:
            if s > 0.0 and math.isfinite(d) and 0.0 < d <= s:
                return f"within the stopping distance {_fmt_m(s)}"
            return "contact"
        if self.status is PanelStatus.WARNING:
            return f"within the threshold {_fmt_m(self.threshold)}"
        return f"nothing within the threshold {_fmt_m(self.threshold)}"


def _status_of(report) -> PanelStatus:
    value = getattr(report.status, "value", report.status)
    try:
        return PanelStatus(str(value).lower())
    except ValueError:
        return PanelStatus.INCOMPLETE


def readout_from_report(report) -> Readout:
    """Build the panel from a ``DetectionReport`` (see ``armguard.detect``)."""
    status = _status_of(report)
    near = report.nearest
    thr = float(report.threshold)
    rows = []
    by_cat = dict(report.by_category)
    for cat in CATEGORIES:
        if cat in by_cat:
            pr = by_cat[cat]
            rows.append(CategoryRow(cat, float(pr.distance), str(pr.link), str(pr.obstacle)))
    for cat in sorted(set(by_cat) - set(CATEGORIES)):
        pr = by_cat[cat]
        rows.append(CategoryRow(str(cat), float(pr.distance), str(pr.link), str(pr.obstacle)))
    stop = float(getattr(report, "stopping_distance", 0.0) or 0.0)
    if near is None:
        return Readout(status, math.inf, "", "", "", None, None, thr, False, tuple(rows), float(report.elapsed_us),
                       stopping_distance=stop)
    d = float(near.distance)
    return Readout(
        status=status,
        distance=d,
        link=str(near.link),
        obstacle=str(near.obstacle),
        owner_a=str(near.a),
        p_WA=np.array(near.p_WA, dtype=np.float64),
        p_WB=np.array(near.p_WB, dtype=np.float64),
        threshold=thr,
        within_threshold=d <= thr,
        rows=tuple(rows),
        elapsed_us=float(report.elapsed_us),
        owner_b=str(getattr(near, "b", "")),
        feature=getattr(near, "feature", None),
        stopping_distance=stop,
    )


_SEVERITY = {PanelStatus.OFF: -1, PanelStatus.CLEAR: 0, PanelStatus.WARNING: 1, PanelStatus.INCOMPLETE: 2,
             PanelStatus.COLLISION: 3}
"""Order of the statuses for the headline: the worst over every category wins."""


def with_terrain(r: Readout, rep) -> Readout:
    """``r`` (a backend's readout without the terrain) with the terrain category of ``rep`` (a
    :class:`armguard.terrain.TerrainReport`): a ``terrain`` row, and the headline the worst of
    both -- the worse status, and the terrain's pair (TerrainReport.distance) when it is the nearer."""
    from dataclasses import replace

    status = _status_of(rep)
    d = float(rep.distance)
    link = "" if rep.link is None else str(rep.link)
    rows = tuple(x for x in r.rows if x.category != "terrain") + (CategoryRow("terrain", d, link, "terrain"),)
    worst = status if _SEVERITY[status] > _SEVERITY[r.status] else r.status
    if d < r.distance and rep.p_WA is not None:
        return replace(r, status=worst, distance=d, link=link, obstacle="terrain", owner_a=link,
                       p_WA=np.array(rep.p_WA, dtype=np.float64), p_WB=np.array(rep.p_WB, dtype=np.float64),
                       within_threshold=d <= r.threshold, rows=rows, owner_b="terrain", feature=None)
    return replace(r, status=worst, rows=rows)


def moving_link_first(r: Readout, is_static) -> Readout:
    """``r`` with its nearest pair and rows named moving link first: where the arm side
    (``owner_a`` / a row's link) is a static body of an arm (``is_static(owner)``, e.g. Puma's
    pedestal) and the other side is not, the sides swap -- the moving link is the "link" the view
    colours, the pedestal the "obstacle" (points swapped with them, the distance unchanged)."""
    from dataclasses import replace

    def swap(a: str, b: str) -> bool:
        return bool(a) and bool(b) and is_static(a) and not is_static(b)

    rows = tuple(CategoryRow(c.category, c.distance, c.obstacle, c.link) if swap(c.link, c.obstacle) else c
                 for c in r.rows)
    if not swap(r.owner_a, r.owner_b or r.obstacle):
        return replace(r, rows=rows)
    b = r.owner_b or r.obstacle
    return replace(r, link=r.obstacle, obstacle=r.link, owner_a=b, owner_b=r.owner_a, p_WA=r.p_WB, p_WB=r.p_WA,
                   feature=None, rows=rows)


def readout_off(threshold: float) -> Readout:
    """The panel when detection is switched off (grey, no nearest obstacle)."""
    return Readout(PanelStatus.OFF, math.inf, "", "", "", None, None, float(threshold), False, (), 0.0)


def no_negative_zero(x: float, decimals: int) -> float:
    """``x`` rounded to ``decimals`` places, a value that rounds to zero as ``+0.0`` (never shown ``-0.0``)."""
    v = round(float(x), decimals)
    return 0.0 if v == 0.0 else v


def _fmt_m(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{no_negative_zero(x * 1000.0, 1):.1f} mm"


def _fmt_p(p: np.ndarray | None) -> str:
    return "—" if p is None else "(" + ", ".join(f"{no_negative_zero(v, 3):+.3f}" for v in p) + ") m"


def _fmt_feature(f) -> str:
    return "" if f is None else f" ({f})"


def _terrain_html(tv) -> str:
    rep = tv.report
    if rep is None:
        return ""
    e = html.escape
    d, link, note = float(rep.distance), rep.link, ""
    if math.isinf(d) and getattr(tv, "far", None) is not None:  # clear beyond the check's reach
        d, link, limit = tv.far
        note = f"; past the check's reach {_fmt_m(rep.reach)}"
        where = f"none within {_fmt_m(limit)}" if link is None else str(link)
        text = "—" if link is None else _fmt_m(d)
    else:
        where = "—" if link is None else f"{link}, {'unseen' if rep.unknown else 'seen'} cell {rep.cell or 'off the map'}"
        text = _fmt_m(d)
        if d < 0.0 and not getattr(tv, "depth_resolved", True):
            text = f"≤ {text}"
            note = "; deeper not resolved: one column's depth, a lower bound on the depth into the terrain"
    return (f'<div id="armguard-terrain" data-status="{e(rep.status.value)}" data-boxes="{tv.visited}" '
            f'data-distance="{d:.6g}" data-resolved="{int(getattr(tv, "depth_resolved", True))}" '
            'style="border:2px solid #8a6d3b;border-radius:6px;padding:4px;margin-top:4px;font-family:sans-serif;'
            f'font-size:0.9em;{WRAP}">'
            f"<div><b>terrain</b> {e(rep.status.value)}: {e(text)} ({e(where)}{e(note)})</div>"
            f"<div>pyramid: {tv.visited} boxes tested, decided at level {rep.level} of {tv.n_levels - 1}; "
            f"{rep.elapsed_us:.0f} µs</div></div>")


def _sigmas_html(rep) -> str:
    e = html.escape
    o = rep.overall
    if o is None:
        return ('<div id="armguard-sigmas" data-sigmas="" style="border:2px solid #7a3;border-radius:6px;'
                f'padding:4px;margin-top:4px;font-family:sans-serif;font-size:0.9em;{WRAP}">uncertain placements: '
                "no pair they move</div>")
    p = o.nearest
    sig = f"{p.sigmas:.3g}" if math.isfinite(p.sigmas) else "inf"
    return (f'<div id="armguard-sigmas" data-sigmas="{sig}" data-bound="{o.p_bound:.6g}" data-status="{e(o.status.value)}" '
            'style="border:2px solid #7a3;border-radius:6px;padding:4px;margin-top:4px;font-family:sans-serif;'
            f'font-size:0.9em;{WRAP}">'
            f"<div><b>uncertain</b> {e(p.a)} / {e(p.b)}: {e(_fmt_m(p.distance))} = <b>{e(sig)} σ</b> "
            f"(σ = {p.sigma * 1000.0:.1f} mm)</div>"
            f"<div>P(collision) ≤ {o.p_bound:.2e} ({e(o.status.value)} at {rep.confidence:.3g})</div></div>")


NAME_CHARS = 32
"""Longest name the per-category table shows whole; a longer one keeps its start and end around "…"
(the whole name in the cell's tooltip)."""

def short_name(name: str, active: str | None = None, limit: int = NAME_CHARS) -> str:
    """``name`` as the per-category table shows it: without the active arm's ``"robot/"`` prefix
    (``kinova/j2s6s200_link_6`` -> ``j2s6s200_link_6`` when ``kinova`` is active), and
    longer than ``limit`` characters cut in the middle (``"j2s6s200_l…inger_tip_2"``)."""
    if active and name.startswith(active + "/"):
        name = name[len(active) + 1:]
    if len(name) <= limit:
        return name
    head = (limit - 1) // 2
    return name[:head] + "…" + name[len(name) - (limit - 1 - head):]


def _name_cell(name: str, active: str | None) -> str:
    e = html.escape
    shown = short_name(name, active)
    title = f' title="{e(name)}"' if shown != name else ""
    text = e(shown).replace("/", "/<wbr>").replace("_", "_<wbr>")  # wrap after a "/" or "_" first
    return f"<td style='{WRAP}'{title}>{text}</td>"


def timing_line(r: Readout, update_us: float | None = None, draw_ms: float | None = None) -> str:
    """What the operator waits for after a change, in order: the **check** (the backend's call
    alone, µs), the console's **update** (the check, a comparison, the terrain, the sigmas; ms) and
    the **draw** (the last change's scene and panel messages prepared and sent, ms; the browser
    renders them after)."""
    parts = [f"check ({r.backend}) {r.elapsed_us:.0f} µs"]
    if update_us is not None:
        parts.append(f"update {update_us / 1000.0:.1f} ms")
    if draw_ms is not None:
        parts.append(f"draw {draw_ms:.1f} ms")
    return "waits: " + " · ".join(parts)


def panel_html(r: Readout, message: str = "", *, error: bool = True, compare=None, update_us: float | None = None,
               changes: str = "", terrain=None, sigmas=None, draw_ms: float | None = None,
               active: str | None = None, others=()) -> str:
    """The distance panel as HTML: a coloured status block and the per-category table.

    ``message`` is shown under the table, red when ``error`` else grey.  ``compare`` (a
    ``Comparison`` of :mod:`._backends`) adds the second backend's nearest distance and Δd;
    ``update_us`` the state's update (check, comparison, terrain, uncertainty) and ``draw_ms`` the
    last drawing (:func:`timing_line`, ``id="armguard-timing"``); ``changes`` the last
    model reload's summary (the message is marked ``data-reload="true"`` while it is that summary;
    a later message replaces it: the panel shows one message, the current one); ``terrain`` a ``TerrainView`` (the terrain category: distance, the
    pyramid's boxes tested and deciding level; ``id="armguard-terrain"``); ``sigmas`` a
    ``SigmaReport`` (the least clearance in sigmas and the collision-probability bound;
    ``id="armguard-sigmas"`` with ``data-sigmas``, ``data-bound``).  The status block carries ``id="armguard-status"``, ``data-status``
    (the status value), ``data-backend`` and ``data-distance`` (m) so a browser test can read it;
    the comparison ``id="armguard-compare"`` with ``data-delta`` (m).  Long names wrap rather than
    widen the panel; the table shows them without the ``active`` arm's prefix (:func:`short_name`).
    ``others``: the other arms within the threshold (:class:`~._notices.OtherArm`), a notice under
    the status block (``id="armguard-others"``).
    """
    from ._notices import others_html

    e = html.escape
    fg = "#000" if r.status is PanelStatus.WARNING else "#fff"
    dist = "" if not math.isfinite(r.distance) else f"{r.distance:.9g}"
    cycle = e(timing_line(r, update_us, draw_ms))
    head = (
        f'<div id="armguard-status" data-status="{r.status.value}" data-backend="{e(r.backend)}" '
        f'data-distance="{dist}" '
        f'style="background:{r.color};color:{fg};padding:8px;border-radius:6px;font-family:sans-serif;{WRAP}">'
        f'<div style="font-size:1.2em;font-weight:bold">{e(r.status.value.upper())} &nbsp; {e(_fmt_m(r.distance))}</div>'
        f'<div id="armguard-reason" data-reason="{e(r.reason)}"><b>{e(r.reason)}</b></div>'
        f"<div>backend: {e(r.backend)}</div>"
        f"<div>link: {e(r.link or '—')}</div><div>obstacle: {e(r.obstacle or '—')}{e(_fmt_feature(r.feature))}</div>"
        f"<div>arm point: {e(_fmt_p(r.p_WA))}</div><div>obstacle point: {e(_fmt_p(r.p_WB))}</div>"
        f"<div>threshold: {e(_fmt_m(r.threshold))} &nbsp; stopping distance: {e(_fmt_m(r.stopping_distance))}</div>"
        f"<div id='armguard-timing' style='font-size:0.85em'>{cycle}</div></div>"
    )
    cmp_html = ""
    if compare is not None:
        o = compare.readout
        delta = "" if not math.isfinite(compare.delta) else f"{compare.delta:.9g}"
        dd_mm = no_negative_zero(compare.delta * 1000.0, 4)
        dd = "—" if not delta else (f"{dd_mm:+.4f} mm" if dd_mm != 0.0 else "0.0000 mm")
        cmp_html = (
            f'<div id="armguard-compare" data-delta="{delta}" data-backend="{e(o.backend)}" '
            'style="border:2px solid #0aa;border-radius:6px;padding:4px;margin-top:4px;font-family:sans-serif;'
            f'{WRAP}">'
            f"<div><b>compare {e(o.backend)}</b> (cyan line): {e(_fmt_m(o.distance))} "
            f"{e(o.link or '—')} / {e(o.obstacle or '—')}</div>"
            f"<div>Δd = d({e(o.backend)}) − d({e(compare.primary)}) = <b>{e(dd)}</b></div>"
            f"<div style='font-size:0.85em'>check ({e(o.backend)}): {o.elapsed_us:.0f} µs</div></div>"
        )
    rows = "".join(
        f"<tr><td>{e(c.category)}</td><td style='text-align:right'>{e(_fmt_m(c.distance))}</td>"
        f"{_name_cell(c.link, active)}{_name_cell(c.obstacle, active)}</tr>"
        for c in r.rows
    )
    table = (  # fixed columns: the names wrap within them, never past the panel's right edge
        '<table id="armguard-categories" style="width:100%;table-layout:fixed;font-size:0.85em;'
        'font-family:sans-serif"><colgroup><col style="width:22%"><col style="width:20%"><col style="width:29%">'
        '<col style="width:29%"></colgroup>'
        "<tr><th>category</th><th>distance</th><th>link</th><th>obstacle</th></tr>"
        f"{rows}</table>"
    )
    msg = ""
    if message:
        # one message, the current one: a reload's summary only while it is that message
        reload = bool(changes) and message == changes and not error
        color = "#d62828" if error else ("#046" if reload else "#555")
        msg = (f'<div id="armguard-message" data-error="{str(error).lower()}" data-reload="{str(reload).lower()}" '
               f'style="color:{color};font-family:sans-serif;padding-top:4px;{WRAP}">{e(message)}</div>')
    extra = ("" if terrain is None else _terrain_html(terrain)) + ("" if sigmas is None else _sigmas_html(sigmas))
    return head + others_html(others) + cmp_html + extra + table + msg
