"""The conformance suite as pytest tests: ``pytest --pyargs armguard.testing --backend NAME``.

One test per check and model (ids ``check[model]``); see :mod:`armguard.testing` for what each
checks and :mod:`armguard.testing._plugin` for the options.
"""

from __future__ import annotations

from armguard.testing import checks
from armguard.testing._plugin import options_from_config, run_check


def pytest_generate_tests(metafunc):
    if "conformance_check" in metafunc.fixturenames:
        found = checks(**options_from_config(metafunc.config))
        metafunc.parametrize("conformance_check", found, ids=[c.id for c in found])


def test_conformance(conformance_check, request):
    run_check(conformance_check, request)
