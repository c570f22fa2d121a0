"""The conformance suite's machinery: checks, their context, the failure type and ``check_backend``.

A :class:`Check` is one named check on one model (or, for the backend-wide checks, on the first
model).  The checks of one :func:`checks` call share a :class:`Context` that loads each model, builds
the backend's Checker and coal's reference answers once, lazily (so pytest can list the checks
without loading anything).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from .._errors import ArmguardError
from .._values import whole_number

__all__ = ["Check", "Context", "ConformanceError", "NotApplicable", "ConformanceReport", "checks", "check_backend", "EDITED_MODELS",
           "DEFAULT_MODELS", "load_conformance_model"]

DEFAULT_MODELS = ("ranger", "hermes", "puma560", "gmf_s480", "rover", "panda", "ur5", "kinova", "panda+edits")
"""The built-in models, three public robots (example-robot-data's Panda and UR5, with their SRDFs,
and Kinova's arm, whose continuous joints Pinocchio holds as ``(cos, sin)``) and the Panda edited in
process (``"panda+edits"``: every shape kind added, a payload, a second arm appended;
:data:`EDITED_MODELS`)."""

REFERENCE = "coal"


class ConformanceError(AssertionError):
    """A backend broke the interface contract: names the backend, the check and the model.

    ``backend``, ``check`` and ``model`` (``None`` for a backend-wide check run before any model)
    say where; ``detail`` says what was expected and what came back."""

    def __init__(self, backend: str, check: str, model: str | None, detail: str) -> None:
        self.backend, self.check, self.model, self.detail = backend, check, model, detail
        on = f" on model {model!r}" if model else ""
        super().__init__(f"backend {backend!r} fails check {check!r}{on}: {detail}")


class NotApplicable(Exception):
    """The check does not apply to this backend (e.g. distances of a verdicts-only backend)."""


class _Failed(Exception):
    """Raised inside a check; turned into a :class:`ConformanceError` naming the check."""


def fail(detail: str):
    __tracebackhide__ = True  # pytest shows the check's line, not the suite's machinery
    raise _Failed(detail)


def expect(ok, detail) -> None:
    """Fail with ``detail`` (a string, or a callable giving one) unless ``ok``; never an ``assert``
    (those vanish under ``python -O``)."""
    __tracebackhide__ = True
    if not ok:
        raise _Failed(detail() if callable(detail) else detail)


# ---------------------------------------------------------------- shared, process-wide caches
_LOCK = threading.RLock()
_MODELS: dict = {}
_REFERENCE: dict = {}


PUBLIC_ROBOTS = ("panda", "ur5")
"""example-robot-data's robots the suite loads with their SRDF, found where :func:`armguard.load_model` finds
them (the package's metadata: a layered virtualenv's site-packages too)."""


def _edited_panda():
    """``"panda+edits"``: example-robot-data's Panda edited in process, as a user updates a model
    without a file (``Model.with_*``): a body of every shape kind (box, sphere, capsule, cylinder,
    convex polyhedron, prism, polygon) in reach, a payload in the hand, and a second arm (the
    built-in puma560, mounted 1.1 m away) appended to the kinematics."""
    from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
    from ..model import load_model

    panda = load_conformance_model("panda")
    rng = np.random.default_rng(11)
    c = np.array([0.45, 0.25, 0.35])
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0] * np.array([1.0, 1.0, -1.0])  # a right-handed turn
    R = R if np.linalg.det(R) > 0 else -R
    parts = [Box(c, [0.05, 0.08, 0.04], R), Sphere(c + [0.2, 0.0, 0.0], 0.04),
             Capsule(c + [0.0, 0.2, 0.0], c + [0.1, 0.25, 0.1], 0.03), Cylinder(c + [-0.2, 0.0, 0.0], R, 0.03, 0.08),
             ConvexPolyhedron(rng.normal(size=(25, 3)) * 0.05 + c + [0.0, -0.2, 0.0]),
             Prism(c + [0.0, 0.0, 0.2], R, 0.03, 0.05, 6),
             Polygon(c + np.array([[0.0, 0.0, -0.2], [0.1, 0.0, -0.2], [0.1, 0.1, -0.18], [0.0, 0.1, -0.18]]))]
    puma = next(iter(load_model("puma560").robots.values())).with_name("puma_2")
    X = np.eye(4)
    X[:3, 3] = [1.1, 0.0, 0.0]
    hand = panda.robots["panda"].link_names[-1]
    return (panda.with_body("parts", parts)
                 .with_robot(puma.with_base(X @ puma.X_WB))
                 .with_payload("tool", "panda", hand, [Box([0.0, 0.0, 0.05], [0.02, 0.02, 0.03], np.eye(3))]))


EDITED_MODELS = {"panda+edits": _edited_panda}
"""Models made in process by editing a loaded one (no source file), by name."""


def load_conformance_model(spec):
    """The Model of ``spec``: a Model as it is, ``"panda"`` / ``"ur5"`` (example-robot-data with its
    SRDF), a name of :data:`EDITED_MODELS` or anything :func:`armguard.load_model` takes.  Loaded
    once per process."""
    from ..model import Model, load_model

    if isinstance(spec, Model):
        return spec
    with _LOCK:
        if spec not in _MODELS:
            if spec in EDITED_MODELS:
                _MODELS[spec] = EDITED_MODELS[spec]()
            elif spec in PUBLIC_ROBOTS:
                from ..model._public import public_robot_files

                urdf, srdf = public_robot_files(spec)
                _MODELS[spec] = load_model(urdf, srdf=srdf)
            else:
                _MODELS[spec] = load_model(spec)
        return _MODELS[spec]


class Context:
    """What the checks of one backend share: its name and options, the models, the configurations,
    the built Checkers and coal's answers (each made once, on first use)."""

    def __init__(self, backend, options: Mapping | None, models: Sequence, n_configs: int, seed: int,
                 xfail: Mapping[str, str] | None) -> None:
        if isinstance(backend, str):
            self.backend, self.backend_object = backend, None
        else:  # a Backend object, not (yet) installed under an entry point
            self.backend, self.backend_object = str(getattr(backend, "name", type(backend).__name__)), backend
        self.options = dict(options or {})
        self.model_specs = {self._label(m): m for m in models}
        # n_configs 0: the neutral pose alone; a negative count failed every check as the backend's fault
        self.n_configs = whole_number(n_configs, "n_configs (--conformance-configs)", ArmguardError, low=0)
        self.seed = whole_number(seed, "seed (--conformance-seed)", ArmguardError, low=0)
        self.xfail = dict(xfail or {})
        self._checkers: dict = {}
        self._failed_build: dict = {}

    @staticmethod
    def _label(spec) -> str:
        return getattr(spec, "name", None) or str(spec)

    # ---------------------------------------------------------------- lazily made
    def model(self, label: str):
        return load_conformance_model(self.model_specs[label])

    def backend_impl(self):
        """The Backend: the object given, else the installed one of that name."""
        from ..backends import get_backend

        return self.backend_object if self.backend_object is not None else get_backend(self.backend)

    def build(self, label: str, options: Mapping | None = None):
        """A fresh Checker of the backend for model ``label`` (``options`` default: the suite's).  A backend
        whose optional dependency is not installed here makes every check not applicable, saying which
        module is missing (``fcl`` without python-fcl: the Backend declares ``requires = ("fcl",)``);
        any other missing module is the backend's failure (a typo, a dependency it forgot)."""
        return self.build_on(self.model(label), options)

    def build_on(self, model, options: Mapping | None = None):
        """A fresh Checker of the backend on the Model ``model`` (as :meth:`build`)."""
        try:
            return self.backend_impl().build(model, dict(self.options if options is None else options))
        except ModuleNotFoundError as exc:
            declared = tuple(getattr(self.backend_impl(), "requires", ()) or ())
            if not exc.name or exc.name.split(".")[0] not in declared:
                raise  # a module the backend does not declare optional: its failure
            raise NotApplicable(f"backend {self.backend!r} is not installed here: {exc} (it requires {list(declared)}; "
                                "e.g. pip install armguard[fcl] for python-fcl)") from None

    def checker(self, label: str):
        """The backend's Checker for model ``label``, built once."""
        with _LOCK:
            if label in self._failed_build:
                why = self._failed_build[label]
                if isinstance(why, NotApplicable):
                    raise why
                fail(f"building the Checker with options {self.options} failed: {why}")
            if label not in self._checkers:
                try:
                    self._checkers[label] = self.build(label)
                except NotApplicable as exc:  # not installed here: every check of it says so
                    self._failed_build[label] = exc
                    raise
                except Exception as exc:  # noqa: BLE001 - reported as this check's failure
                    self._failed_build[label] = f"{type(exc).__name__}: {exc}"
                    raise
            return self._checkers[label]

    def configs(self, label: str) -> np.ndarray:
        """``(1 + n_configs, nq)``: the model's neutral pose, then seeded random in-limit configurations."""
        m = self.model(label)
        return np.vstack([m.neutral()[None], m.random_q(self.n_configs, self.seed)])

    def reference(self, label: str):
        """``(coal Checker, [PairDistances per configuration], (M,) least distances)``, made once per
        process for each model, configuration count and seed."""
        from ..backends import get_backend

        key = (self.model_specs[label] if isinstance(self.model_specs[label], str) else id(self.model(label)),
               self.n_configs, self.seed)
        with _LOCK:
            if key not in _REFERENCE:
                ref = get_backend(REFERENCE).build(self.model(label), {})
                answers = [ref.pair_distances(q) for q in self.configs(label)]
                dmin = np.array([float(np.min(r.distance, initial=np.inf)) for r in answers])
                _REFERENCE[key] = (ref, answers, dmin)
            return _REFERENCE[key]

    def xfail_reason(self, check: str, label: str | None) -> str | None:
        """Why ``check`` is expected to fail: the suite's ``xfail`` mapping, else the Checker's own
        ``conformance_xfail`` declaration (keys ``"check"`` or ``"check[model]"``)."""
        declared = dict(self.xfail)
        if label is not None:
            try:
                declared = {**dict(getattr(self.checker(label), "conformance_xfail", {}) or {}), **declared}
            except Exception:  # noqa: BLE001 - a Checker that does not build fails its checks itself
                pass
        return declared.get(f"{check}[{label}]") or declared.get(check)


@dataclass(frozen=True)
class Check:
    """One check of the conformance suite, ready to run: ``check()`` passes, raises
    :class:`ConformanceError` naming itself, or :class:`NotApplicable`."""

    name: str
    model: str | None
    context: Context = field(repr=False, compare=False)
    func: Callable = field(repr=False, compare=False)
    doc: str = ""

    @property
    def id(self) -> str:
        """``name[model]`` (pytest's test id)."""
        return f"{self.name}[{self.model}]" if self.model else self.name

    def xfail_reason(self) -> str | None:
        return self.context.xfail_reason(self.name, self.model)

    def __call__(self) -> None:
        __tracebackhide__ = True
        try:
            self.func(self.context, self.model)
        except _Failed as exc:
            raise ConformanceError(self.context.backend, self.name, self.model, str(exc)) from None
        except (NotApplicable, ConformanceError):
            raise
        except Exception as exc:  # an unexpected exception is this check's failure too, and says so
            raise ConformanceError(self.context.backend, self.name, self.model,
                                   f"raised {type(exc).__name__}: {exc}") from exc


def checks(backend, *, options: Mapping | None = None, models: Sequence = DEFAULT_MODELS, n_configs: int = 8,
           seed: int = 0, xfail: Mapping[str, str] | None = None, only: Sequence[str] | None = None) -> list[Check]:
    """The suite's checks for ``backend`` (an installed backend's name, or a Backend object: ``name``
and ``build(model, options)``), one per check and model.

    ``options``: the backend's build options; ``models``: names (:data:`DEFAULT_MODELS`, anything
    :func:`armguard.load_model` takes) or Models; ``n_configs``: seeded random in-limit configurations
    per model (plus the neutral pose); ``xfail``: ``{"check" or "check[model]": reason}`` expected
    failures (added to the Checker's own ``conformance_xfail``); ``only``: check names to keep.
    Nothing is loaded until a check runs."""
    from ._catalog import BACKEND_CHECKS, MODEL_CHECKS

    models = list(models)
    if not models:
        raise ValueError("checks: at least one model is needed")
    ctx = Context(backend, options, models, n_configs, seed, xfail)
    labels = list(ctx.model_specs)
    known = {f.__name__.removeprefix("check_") for f in (*BACKEND_CHECKS, *MODEL_CHECKS)}
    unknown = sorted(set(only or ()) - known)
    if unknown:
        raise ValueError(f"checks: unknown check names {unknown}; checks are {sorted(known)}")
    out = []
    for f in BACKEND_CHECKS:
        out.append(Check(f.__name__.removeprefix("check_"), labels[0], ctx, f, (f.__doc__ or "").strip()))
    for label in labels:
        for f in MODEL_CHECKS:
            out.append(Check(f.__name__.removeprefix("check_"), label, ctx, f, (f.__doc__ or "").strip()))
    return [c for c in out if not only or c.name in only]


@dataclass
class ConformanceReport:
    """What :func:`check_backend` ran: check ids that passed, were not applicable (with why), failed
    as declared (with the declared reason) and passed although declared to fail."""

    backend: str
    passed: list = field(default_factory=list)
    not_applicable: dict = field(default_factory=dict)
    xfailed: dict = field(default_factory=dict)
    xpassed: dict = field(default_factory=dict)

    def __str__(self) -> str:
        lines = [f"backend {self.backend!r}: {len(self.passed)} passed, {len(self.not_applicable)} not applicable, "
                 f"{len(self.xfailed)} failed as declared, {len(self.xpassed)} passed though declared to fail"]
        lines += [f"  not applicable {k}: {v}" for k, v in self.not_applicable.items()]
        lines += [f"  failed as declared {k}: {v}" for k, v in self.xfailed.items()]
        lines += [f"  passed though declared to fail {k}: {v}" for k, v in self.xpassed.items()]
        return "\n".join(lines)


def check_backend(backend, **kwargs) -> ConformanceReport:
    """Run the whole suite on ``backend`` (keywords as :func:`checks`); raise the first
    :class:`ConformanceError` (an AssertionError naming the check and model) that was not declared
    expected, else return a :class:`ConformanceReport`."""
    found = checks(backend, **kwargs)
    report = ConformanceReport(found[0].context.backend)
    for c in found:
        try:
            c()
        except NotApplicable as exc:
            report.not_applicable[c.id] = str(exc)
            continue
        except ConformanceError as exc:
            reason = c.xfail_reason()
            if reason is None:
                raise
            report.xfailed[c.id] = f"{reason} (it failed: {exc.detail})"
            continue
        reason = c.xfail_reason()
        if reason is not None:
            report.xpassed[c.id] = reason
        else:
            report.passed.append(c.id)
    return report
