"""The verification report: verdict, first collision, minimum clearance, clearance profile, outputs."""

from __future__ import annotations

import enum
import json
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "VerificationStatus",
    "Collision",
    "Clearance",
    "ClearanceProfile",
    "MethodDetails",
    "VerificationReport",
]


class VerificationStatus(enum.Enum):
    """SAFE: proven (certified) or sampled clear; COLLISION: a collision was found; INCOMPLETE:
    the check could not finish (evaluation budget spent) — never read as safe."""

    SAFE = "safe"
    COLLISION = "collision"
    INCOMPLETE = "incomplete"


class CollisionKind(enum.Enum):
    """What a reported collision is: CONTACT, the shapes touch or penetrate (signed distance within
    the contact tolerance); STOPPING_DISTANCE, they are apart but closer than the stopping distance
    in force then (Hermes's definition of a collision: the arm could not brake before touching)."""

    CONTACT = "contact"
    STOPPING_DISTANCE = "stopping distance"


@dataclass(frozen=True)
class Collision:
    """The first collision along a trajectory (Hermes's collision report).

    Attributes
    ----------
    time : float, s
        When it happens (the first instant the clearance reaches the stopping distance).
    q : (n_joints,) float64, rad or m
        The moving robot's configuration then.
    distance : float, m
        The pair's signed distance then (<= the stopping distance; < 0 penetrating).
    link : str | None
        The arm link involved (for payload-obstacle: ``None``; see ``payload``).
    obstacle : str
        The other object: a body, another link ``"robot/link"``, a payload, or ``"workspace"``.
    payload : str | None
        The payload involved, if any.
    feature : armguard.geometry.Feature | None
        The obstacle's face / edge / vertex at its witness point (``None`` where not defined).
    p_W : (3,) float64, m
        The collision point: the midpoint of the two witness points (the intersection point
        when they touch).
    p_WA, p_WB : (3,) float64, m
        Witness points on the arm side (``a``) and on the obstacle (``b``).
    a, b : str
        Owner names of the two sides.
    category : str
        Detector category: "arm", "environment", "workspace" or "payload".
    check : str
        Hermes's check: "link-obstacle", "link-link", "payload-obstacle", "payload-link" (or
        "link-workspace", "payload-workspace", "payload-payload").
    objects : tuple[str, str]
        The kinds of object involved, Hermes's "arm, obstacle, payload".
    segment : int
        Index of the trajectory segment (of the trajectory as given: a :class:`Subdivided` one's pieces are
        counted in the segment they divide).
    stopping_distance : float, m
        The stopping distance in force then (the segment's, from its peak speed; 0 at rest).
    kind : CollisionKind
        A contact, or a violation of the stopping distance by shapes still apart.
    fixed : bool
        No joint of any robot moves either side (a base link on its table, a payload on a fixed
        link, a base link and the workspace walls): no path changes the pair's clearance, and the
        summary says how to disable the pair (or enlarge the workspace) where that is by design.
    """

    time: float
    q: np.ndarray
    distance: float
    link: str | None
    obstacle: str
    payload: str | None
    feature: object
    p_W: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    a: str
    b: str
    category: str
    check: str
    objects: tuple[str, str]
    segment: int
    stopping_distance: float = 0.0
    kind: CollisionKind = CollisionKind.CONTACT
    fixed: bool = False

    def describe(self) -> str:
        """"contact (distance -3.1 mm)" or "within stopping distance 70 mm: 60.0 mm"; a clearance that reaches
        the stopping distance only to within the certified verifier's contact tolerance (``verify_contact``, 1 µm
        by default: advancement approaches the limit, never lands on it) says so: "reaches the stopping distance
        100.0000 mm (clearance 100.0008 mm, within the verifier's contact tolerance)"."""
        if self.kind is CollisionKind.STOPPING_DISTANCE:
            sd, d = self.stopping_distance * 1e3, self.distance * 1e3
            if d >= sd:  # a violation only to within the tolerance: not a clearance "below" the limit
                return f"reaches the stopping distance {sd:.4f} mm (clearance {d:.4f} mm, within the verifier's contact tolerance)"
            if sd - d < 0.05:  # at the stopping distance to the verifier's resolution: say so, in full
                return f"at the stopping distance {sd:.4f} mm: {d:.4f} mm"
            return f"within stopping distance {sd:.0f} mm: {d:.1f} mm"
        return f"contact (distance {self.distance * 1e3:.1f} mm)"


@dataclass(frozen=True)
class Clearance:
    """A clearance value and where it happens: ``distance`` (m) at ``time`` (s) between owners ``a`` and ``b``."""

    distance: float
    time: float
    a: str
    b: str
    category: str
    q: np.ndarray


@dataclass(frozen=True)
class ClearanceProfile:
    """Clearance along the trajectory at every evaluated configuration.

    ``time`` (M,) s, increasing; ``by_category`` maps "arm" / "environment" / "workspace" /
    "payload" (the categories the scene has) to ``(M,) float64, m``, the smallest signed
    distance of that category at each time; ``overall`` (M,) m the smallest of all.
    """

    time: np.ndarray
    overall: np.ndarray
    by_category: dict


@dataclass(frozen=True)
class MethodDetails:
    """How the verdict was reached.

    ``method`` "certified" or "sampled"; ``samples_evaluated`` configurations whose clearances
    were computed; ``intervals_certified`` joint-space intervals proven clear by the lever-arm
    bound (certified); ``frequency`` (Hz) or ``joint_step`` (rad) of sampled mode;
    ``max_speed`` (m/s) a bound on the speed of the fastest point of the arm;
    ``discretisation_error`` (m) Hermes's ``Ed = v / f`` for sampled mode (for joint-step
    sampling the most any pair's clearance can shrink between two samples, by the pair rates of
    :meth:`ClearanceModel.pair_rates`), 0 when certified;
    ``source`` "detector" or "reference"; ``lever_bound`` names the motion bound used.
    """

    method: str
    samples_evaluated: int
    intervals_certified: int
    frequency: float | None
    joint_step: float | None
    max_speed: float
    discretisation_error: float
    source: str
    lever_bound: str = "configuration-independent chain lever arms (sum of joint-to-link reach bounds)"
    backend: str = ""  # the detector's backend ("analytic", "coal", ...); "" for the reference distances


def _mm(d: float) -> str:
    """A clearance for the summary: mm to 0.01 mm, and µm below 0.01 mm (2 µm beside SAFE read "0.00 mm")."""
    return f"{d * 1e6:.3g} µm" if 0.0 < abs(d) < 1e-5 else f"{d * 1e3:.2f} mm"


def _jsonable(x):
    if is_dataclass(x) and not isinstance(x, type):
        return {f.name: _jsonable(getattr(x, f.name)) for f in fields(x)}
    if isinstance(x, enum.Enum):
        return x.value
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if np.isfinite(v) else ("inf" if v > 0 else "-inf") if not np.isnan(v) else None
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if hasattr(x, "to_dict"):
        return _jsonable(x.to_dict())
    if x is None or isinstance(x, (str, int, bool)):
        return x
    return str(x)


@dataclass(frozen=True)
class VerificationReport:
    """The result of :func:`armguard.verify.verify`.

    Attributes
    ----------
    status : VerificationStatus
    first_collision : Collision | None
        ``None`` unless status is COLLISION.
    min_clearance : float, m
        The smallest clearance at any evaluated configuration (up to the first collision when
        there is one): an upper bound on the true minimum along the path.
    min_clearance_at : Clearance | None
        Where it happens.
    min_clearance_lower_bound : float, m
        Certified mode: a proven lower bound on the clearance over the whole verified part of
        the path (from the lever-arm bound between evaluations); ``-inf`` for sampled mode,
        which proves nothing between samples.
    profile : ClearanceProfile
    details : MethodDetails
    stopping_distance : float, m
        The largest stopping distance used (a constant, or the step function's largest value
        along the trajectory).
    threshold : float, m
        The warning threshold marked on the plot.
    scene, robot, trajectory : str
        Names (the trajectory's name when it has one, else "trajectory").
    duration : float, s
    elapsed_s : float, s
        Wall time of the verification.
    reason : str
        Why the status is what it is, in words (e.g. the evaluation budget ran out at t = …).
    stopping_times, stopping_values : (S + 1,) float64 s, (S,) float64 m
        The stopping distance in force on each segment ``[stopping_times[k], stopping_times[k + 1]]``
        (a step function of the segment's peak speed, or the constant).
    held_joints : dict[str, float]
        The robot's joints the trajectory does not name, each held at this value (the robot's
        home, rad or m) for the whole motion; empty when it names them all.
    over_speed : dict[str, tuple[float, float]]
        The robot's joints whose peak speed along the trajectory exceeds their ``max_velocity``:
        ``{joint: (peak, max_velocity)}`` (rad/s or m/s).  Not part of the collision verdict (the
        motion is verified as commanded, its stopping distance taken at the commanded speed), but
        the robot cannot follow it so: the summary says so.
    """

    status: VerificationStatus
    first_collision: Collision | None
    min_clearance: float
    min_clearance_at: Clearance | None
    min_clearance_lower_bound: float
    profile: ClearanceProfile
    details: MethodDetails
    stopping_distance: float
    threshold: float
    scene: str
    robot: str
    trajectory: str
    duration: float
    elapsed_s: float
    reason: str = ""
    stopping_distance_function: object = field(default=None, repr=False)
    stopping_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stopping_values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    held_joints: dict = field(default_factory=dict)
    over_speed: dict = field(default_factory=dict)

    def verdict(self) -> str:
        """The verdict in a few words: "safe", "incomplete", "collision" (a contact) or "unsafe
        (stopping distance)" (shapes apart but closer than the stopping distance)."""
        c = self.first_collision
        if self.status is VerificationStatus.COLLISION and c is not None and c.kind is CollisionKind.STOPPING_DISTANCE:
            return "unsafe (stopping distance)"
        return self.status.value

    @property
    def safe(self) -> bool:
        """True only for status SAFE (INCOMPLETE is not safe)."""
        return self.status is VerificationStatus.SAFE

    # ------------------------------------------------------------ outputs
    def to_dict(self) -> dict:
        """A JSON-ready dictionary (arrays as lists, enums as their values, inf as "inf")."""
        d = _jsonable(self)
        d["safe"] = self.safe
        return d

    def to_json(self, *, indent: int | None = 2) -> str:
        """The report as JSON text."""
        return json.dumps(self.to_dict(), indent=indent)

    def save_json(self, path) -> Path:
        """Write :meth:`to_json` to ``path`` (all or nothing: ``armguard._io.atomic_write``); returns the path."""
        from .._io import atomic_write

        return atomic_write(Path(path), self.to_json(), parents=True)

    def _verdict_words(self) -> str:
        if self.verdict() == "unsafe (stopping distance)":
            return ("UNSAFE: within the stopping distance, no contact (a collision by Hermes's rule: the arm "
                    "could not brake before touching)")
        if self.details.method == "sampled" and self.status.value == "safe":  # clear at the samples, unproven between
            return "SAFE at the samples (sampled: not proven between them; the certified method proves it)"
        return self.status.value.upper()

    def summary(self) -> str:
        """A readable multi-line summary."""
        d = self.details
        lines = [
            f"scene {self.scene!r}, robot {self.robot!r}, trajectory {self.trajectory!r} ({self.duration:.3f} s)",
            f"verdict: {self._verdict_words()}" + (f" — {self.reason}" if self.reason else ""),
            f"method: {d.method}"
            + (f" at {d.frequency:g} Hz" if d.frequency else f" every {d.joint_step:g} rad" if d.joint_step else "")
            + f"; {d.samples_evaluated} configuration{'' if d.samples_evaluated == 1 else 's'} evaluated"
            + (f", {d.intervals_certified} interval{'' if d.intervals_certified == 1 else 's'} certified"
               if d.method == "certified" else "")
            + f"; distances from the {d.source}" + (f" ({d.backend} backend)" if d.backend else ""),
            f"stopping distance: {'up to ' if self.stopping_distance_function is not None else ''}"
            f"{self.stopping_distance * 1e3:.1f} mm; fastest point ≤ {d.max_speed:.3f} m/s",
        ]
        for j, (peak, lim) in self.over_speed.items():
            lines.append(f"joint {j}: peak speed {peak:.4g} exceeds its max_velocity {lim:.4g} (rad/s or m/s): the robot "
                         "cannot follow this timing (the verdict is for the motion as commanded)")
        if self.held_joints:
            lines.append("held still, not in the trajectory (the Verifier's home, or its q_others): " + ", ".join(f"{j} = {v:.6g}" for j, v in self.held_joints.items()))
        if d.method == "sampled":
            how = "Ed = v/f" if d.frequency is not None else "the most a clearance can shrink between samples"
            ed_mm = d.discretisation_error * 1e3
            ed = f"{ed_mm:.1f} mm" if abs(ed_mm) < 1e6 else f"{ed_mm / 1e3:.3g} m"
            lines.append(f"discretisation error ({how}): {ed} (collisions shorter than this may be missed)")
        c = self.first_collision
        if c is not None:
            where = f"link {c.link}" if c.link else f"payload {c.payload}"
            feat = f", {c.feature}" if c.feature is not None else ""
            first = "first contact" if c.kind is CollisionKind.CONTACT else "first stopping-distance violation"
            lines.append(
                f"{first} at t = {c.time:.4f} s (segment {c.segment}): {where} ({c.a}) with {c.obstacle}{feat} "
                f"[{c.check}], {c.describe()} at p_W = ({c.p_W[0]:.4f}, {c.p_W[1]:.4f}, {c.p_W[2]:.4f}) m"
            )
            lines.append("q = [" + ", ".join(f"{x:.4f}" for x in c.q) + "]")
            if c.fixed and c.obstacle == "workspace":
                lines.append(f"no joint moves {c.a}, so no path changes its clearance to the workspace walls: enlarge "
                             "the workspace box (Scene.set_workspace, the scene file's workspace:) if this is by design")
            elif c.fixed:
                lines.append(f"no joint moves {c.a} or {c.obstacle}, so no path changes this clearance (only a smaller "
                             "stopping distance does); if that closeness is by design, disable the pair "
                             f"(Model.with_pair_disabled({c.a!r}, {c.b!r}), a scene file's pairs: disable: [[{c.a}, {c.b}]], "
                             "or <disable_collisions reason=\"Static\"/> in the SRDF)")
        m = self.min_clearance_at
        if m is not None:
            lines.append(f"minimum clearance {_mm(m.distance)} at t = {m.time:.4f} s between {m.a} and {m.b} ({m.category})")
        if np.isfinite(self.min_clearance_lower_bound):
            lines.append(f"proven lower bound on the clearance over the verified path: {_mm(self.min_clearance_lower_bound)}")
        lines.append(f"time taken: {self.elapsed_s * 1e3:.1f} ms")
        return "\n".join(lines)

    def plot(self, path, *, title: str | None = None) -> Path:
        """Write a plot of clearance against time per category, with the threshold and the stopping
        distance marked and the first collision flagged: a PNG, or the format ``path``'s suffix names
        (``.pdf``, ``.svg``, ...: ``armguard._io.figure_format``).  Returns the path."""
        from matplotlib.figure import Figure  # no pyplot: the caller's backend and figures are left alone

        from .._io import figure_format, save_figure

        p = Path(path)
        figure_format(p)
        fig = Figure(figsize=(8, 4.2), dpi=100)
        ax = fig.subplots()
        t = self.profile.time
        for cat, y in self.profile.by_category.items():
            finite = np.isfinite(y)
            if np.any(finite):
                ax.plot(t[finite], y[finite] * 1e3, lw=1.2, label=cat)
        ax.axhline(self.threshold * 1e3, color="orange", ls="--", lw=1, label=f"threshold {self.threshold * 1e3:.0f} mm")
        sv = np.asarray(self.stopping_values, dtype=np.float64)
        if len(sv) and float(np.ptp(sv)) > 0.0:  # speed-dependent: the step function over time
            ax.stairs(sv * 1e3, np.asarray(self.stopping_times, dtype=np.float64), color="red", ls=":", lw=1.2,
                      baseline=None, label=f"stopping distance (by speed, ≤ {self.stopping_distance * 1e3:.0f} mm)")
        elif self.stopping_distance > 0.0:
            ax.axhline(self.stopping_distance * 1e3, color="red", ls=":", lw=1.2,
                       label=f"stopping distance {self.stopping_distance * 1e3:.0f} mm")
        ax.axhline(0.0, color="black", lw=0.6)
        c = self.first_collision
        if c is not None:
            what = "first contact" if c.kind is CollisionKind.CONTACT else (
                f"within stopping distance {c.stopping_distance * 1e3:.0f} mm")
            ax.axvline(c.time, color="red", lw=1)
            ax.plot([c.time], [c.distance * 1e3], "rx", ms=10, mew=2, label=f"{what}, t = {c.time:.3f} s")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("clearance (mm)")
        ax.set_title(title or f"{self.scene} / {self.trajectory}: {self.verdict()} ({self.details.method})")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        save_figure(fig, p, parents=True)
        return p


def speeds_over_limits(trajectory, robot) -> dict:
    """``{joint: (peak speed, max_velocity)}`` of ``robot``'s joints that ``trajectory`` (over all of its
    joints, in its order) moves faster than their finite ``max_velocity`` allows (rad/s or m/s)."""
    peak = getattr(getattr(trajectory, "_t", trajectory), "peak_velocity", None)  # a Subdivided one: its trajectory's
    if peak is None:  # a time law of one's own without it: nothing said
        return {}
    v, lim = np.asarray(peak(), dtype=np.float64), np.asarray(robot.max_velocity, dtype=np.float64)
    over = np.isfinite(lim) & (v > lim * (1.0 + 1e-9))
    return {robot.joint_names[j]: (float(v[j]), float(lim[j])) for j in np.flatnonzero(over)}
