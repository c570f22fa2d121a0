"""The ``armguard`` pytest plugin (entry point group ``pytest11``): options for the conformance suite.

``pytest --pyargs armguard.testing --backend NAME`` collects :mod:`armguard.testing.test_backend`,
which runs :func:`armguard.testing.checks` for ``NAME`` (default: the backend
:func:`armguard.backends.resolve` picks: ``$ARMGUARD_BACKEND``, ``armguard.toml``, ``analytic``).

Options: ``--armguard-backend NAME`` and ``--armguard-backend-option KEY=VALUE`` (repeatable) always;
their short forms ``--backend`` / ``--backend-option`` only when the command line names
``armguard.testing`` (so that a project with its own ``--backend`` option is not disturbed);
``--conformance-models a,b,...`` (default :data:`armguard.testing.DEFAULT_MODELS`),
``--conformance-configs N`` (random configurations per model, default 8), ``--conformance-seed S``.
Nothing heavy is imported until a check runs.
"""

from __future__ import annotations

import warnings

import pytest

__all__ = ["pytest_addoption", "pytest_load_initial_conftests", "pytest_configure", "pytest_report_header",
           "options_from_config", "run_check"]


def pytest_addoption(parser) -> None:
    from ._suite import DEFAULT_MODELS

    group = parser.getgroup("armguard", "armguard backend conformance (pytest --pyargs armguard.testing)")
    group.addoption("--armguard-backend", dest="armguard_backend", default=None, metavar="NAME",
                    help="backend the conformance suite checks (default: as armguard.backends.resolve picks)")
    group.addoption("--armguard-backend-option", dest="armguard_backend_options", action="append", default=[],
                    metavar="KEY=VALUE", help="a build option of that backend (repeatable)")
    group.addoption("--conformance-models", dest="armguard_models", default=None, metavar="A,B,...",
                    help=f"models to check on (default: {','.join(DEFAULT_MODELS)})")
    group.addoption("--conformance-configs", dest="armguard_configs", type=int, default=8, metavar="N",
                    help="seeded random in-limit configurations per model, besides the neutral pose (default 8)")
    group.addoption("--conformance-seed", dest="armguard_seed", type=int, default=0, metavar="S",
                    help="seed of those configurations (default 0)")


def _names_the_suite(args) -> bool:
    for a in args:
        a = str(a).split("::")[0]
        if a == "armguard.testing" or a.startswith("armguard.testing.") or "armguard/testing" in a.replace("\\", "/"):
            return True
    return False


def pytest_load_initial_conftests(early_config, parser, args) -> None:
    """The short option names, only for a run of the conformance suite itself."""
    if _names_the_suite(args):
        parser.addoption("--backend", dest="armguard_backend", metavar="NAME",
                         help="backend the conformance suite checks (as --armguard-backend)")
        parser.addoption("--backend-option", dest="armguard_backend_options", action="append", metavar="KEY=VALUE",
                         help="a build option of that backend (as --armguard-backend-option)")


def options_from_config(config) -> dict:
    """The keyword arguments of :func:`armguard.testing.checks` that the command line gave."""
    from ..backends import option_value, resolve

    name = config.getoption("armguard_backend")
    opts = {}
    for item in config.getoption("armguard_backend_options") or ():
        key, sep, value = str(item).partition("=")
        if not sep or not key.strip():
            raise pytest.UsageError(f"--backend-option {item!r}: expected KEY=VALUE (e.g. fidelity=exact)")
        opts[key.strip()] = option_value(value)
    name, opts = resolve(name, opts)
    from ..backends import available

    if name not in available():
        raise pytest.UsageError(f"--backend {name!r}: unknown backend; installed backends are {list(available())}")
    models = config.getoption("armguard_models")
    kw = {"options": opts, "n_configs": config.getoption("armguard_configs"), "seed": config.getoption("armguard_seed")}
    if models:
        kw["models"] = [m.strip() for m in models.split(",") if m.strip()]
    return {"backend": name, **kw}


_COAL_NOTE = "enable_cached_gjk_guess has been marked as deprecated"


def run_check(check, request) -> None:
    """Run one :class:`armguard.testing.Check` as a pytest test: not applicable -> skip; a declared
    expected failure -> xfail (XPASS when it passes); anything else as it comes."""
    from ._suite import NotApplicable

    reason = check.xfail_reason()
    if reason is not None:
        from ._suite import ConformanceError

        request.node.add_marker(pytest.mark.xfail(reason=reason, raises=ConformanceError, strict=False))
    try:
        with warnings.catch_warnings():  # coal's deprecation note on its first calls, once per test otherwise
            warnings.filterwarnings("ignore", message=_COAL_NOTE, category=DeprecationWarning)
            check()
    except NotApplicable as exc:
        pytest.skip(f"not applicable: {exc}")


def pytest_configure(config) -> None:
    """coal's one switch that turns its cached GJK guess off warns that it is deprecated on every
    Checker's first call (``armguard_coal`` silences it for the process; pytest's own filters, reset
    for each test, let it through): a run of the suite would show it once per test.  Filtered in
    runs of the suite only (other projects' pytest runs keep their filters)."""
    if config.getoption("armguard_backend", None) or _names_the_suite(config.args):
        config.addinivalue_line("filterwarnings", f"ignore:{_COAL_NOTE}:DeprecationWarning")


def pytest_report_header(config):
    """The backend the suite checks, with its options and where they came from (``armguard.toml``)."""
    if not (config.getoption("armguard_backend") or _names_the_suite(config.args)):
        return None
    try:
        kw = options_from_config(config)
    except Exception:  # noqa: BLE001 - the run reports it as a usage error
        return None
    from ..backends import read_config

    cfg = read_config()
    given = config.getoption("armguard_backend_options") or ()
    from_file = (kw["options"] and not given and "file" in cfg and cfg.get("name", kw["backend"]) == kw["backend"])
    source = f" (from {cfg['file']})" if from_file else ""
    return f"armguard conformance: backend {kw['backend']!r}, options {kw['options']}{source}"
