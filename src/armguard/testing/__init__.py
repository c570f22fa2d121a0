"""A conformance suite for backend authors: the Checker contract and a differential suite against coal.

Like scikit-learn's ``check_estimator``: one call runs every check on a backend, and each check is
also an object pytest can parametrize over.

>>> from armguard.testing import check_backend
>>> report = check_backend("analytic", models=["puma560"], n_configs=4)  # doctest: +SKIP
>>> print(report)  # doctest: +SKIP
backend 'analytic': 16 passed, 2 not applicable, ...

From the command line (the ``armguard`` pytest plugin, registered under ``pytest11``)::

    pytest --pyargs armguard.testing --backend NAME [--backend-option KEY=VALUE ...]
           [--conformance-models ranger,panda] [--conformance-configs 8]

What is checked, per model (:data:`DEFAULT_MODELS`: the five built-in models,
example-robot-data's Panda and UR5, Kinova's arm (continuous joints) and ``"panda+edits"``: that
Panda edited in process with a body of every shape kind, a payload and a second arm appended, a
Model with no file behind it) and on the neutral pose plus seeded random in-limit configurations:

* the Backend/Checker protocol: ``name``, ``model``, ``capabilities``; ``build`` refuses an unknown
  option with BackendError listing the accepted ones;
* ``pair_distances(q)``: pairs in ``model.pairs`` order, shapes and dtypes, finite values; the
  witness relation ``|p_WA - p_WB| == |distance|`` to 1e-9 m; witness points on the shapes'
  surfaces, separated and penetrating; the sign convention;
* NaN, infinite, wrongly shaped ``q`` / ``Q``, a continuous joint off the unit circle and bad
  margins refused with BackendError, never a verdict;
* ``collides(Q, margin)`` consistent with the distances at the margin; batches as rows (160 rows
  too); determinism, a fresh Checker's first call included; answers that stay the caller's;
* capabilities declared vs behaviour: a verdicts-only backend refuses distances with BackendError;
* agreement with coal (distances within 1e-6 m, 1e-5 m on hulls; verdicts outside the contact
  band; a verdicts-only backend never says clear where coal says collision);
* where the Checker has them: ``pair_distances(q, pairs=idx)`` equals rows of the full answer,
  ``pair_distances_many(Q)`` equals row by row; ``nearest`` and ``min_distance_many`` agree;
  ``pair_distances(q, jacobian=True)`` agrees with central differences of the distances;
* margins: ``collides(Q, margin=...)`` with margins per pair or by category equals the brute force
  from the distances (``margins_per_pair``); ``collides(Q, pairs=rows)`` decides on those pairs only
  (``collides_pairs``); the default margin is 0;
* the Model's pairs of one category at a time against coal (``coal_verdicts_by_category``: a
  ``collides`` that skipped a category, e.g. the workspace walls, passes on the whole Model);
* the Checker answers for the Model as made, not its scene edited afterwards (``model_as_made``),
  and the arrays it returns stay the caller's (``results_kept``);
* thread safety: 4 threads on one Checker give the single-threaded answers.

A Checker may declare checks it is known to fail, with the reason, in a ``conformance_xfail``
mapping (``{"check": reason}`` or ``{"check[model]": reason}``): pytest reports them as xfail (and
XPASS once they pass), :func:`check_backend` lists them in its report.  The tolerances are
:data:`armguard.DEFAULT_TOLERANCES`' ``differential_*`` fields.
"""

from __future__ import annotations

from ._suite import (
    DEFAULT_MODELS,
    Check,
    ConformanceError,
    ConformanceReport,
    NotApplicable,
    check_backend,
    checks,
    load_conformance_model,
)
from ._threads import run_in_threads

__all__ = ["check_backend", "checks", "Check", "ConformanceError", "ConformanceReport", "NotApplicable",
           "DEFAULT_MODELS", "load_conformance_model", "check_names", "run_check", "run_in_threads"]


def run_check(check, request) -> None:
    """Run one :class:`Check` as a pytest test (``request``: the test's pytest fixture): not applicable
    -> skipped with the reason; a failure the Checker declares (``conformance_xfail``) -> xfail (XPASS
    once it passes); anything else as it comes.  For a backend package's own tests (docs/backends.md)."""
    from ._plugin import run_check as run

    run(check, request)


def check_names() -> tuple[str, ...]:
    """Every check's name, backend-wide ones first."""
    from ._catalog import BACKEND_CHECKS, MODEL_CHECKS

    return tuple(f.__name__.removeprefix("check_") for f in (*BACKEND_CHECKS, *MODEL_CHECKS))
