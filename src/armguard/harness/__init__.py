"""The backend harness, ``reference/`` and the model linter.

* :func:`run_compare` (``armguard compare``, ``tools/compare.py``): every backend on the same
  configurations, per backend pair and category: verdict disagreements, distance errors,
  nearest points, timings; ``compare.json``, a table, plots.  A verdicts-only backend (``clip``,
  ``forbidden``) is judged by its verdicts against a distance backend's (:mod:`._verdicts`).
* :mod:`._reference` (``tools/make_reference.py``): coal's answers at a fixed set of
  configurations per model, with the source files' sha256, and the check against them.
* :func:`check_model_files` (``armguard check-urdf``, ``tools/check_urdf.py``): lint a model.
* The differential tolerances are :class:`armguard.Tolerances`' ``differential_*`` fields.
"""

from ._compare import Comparison, PairStatus, compare_answers, reproduce_command, unique_witness_mask
from ._configs import ConfigSet, build_configs, trajectory_q
from ._evaluate import BackendAnswers, answers_distances, build_checkers, evaluate, parse_backend_options, verdict_detail
from ._models import EXTRA_MODELS, reference_dir, reference_model_names, repo_root, resolve_model, seed_data
from ._run import compare_at, run_compare, summary_table, write_outputs
from ._lint import Check, Finding, LintReport, LintStatus, Severity, check_model_files, mesh_convexity
from ._tolerances import pair_distance_tolerance, pair_kinds

__all__ = ["run_compare", "compare_at", "summary_table", "write_outputs", "Comparison", "PairStatus", "compare_answers",
           "reproduce_command", "unique_witness_mask", "ConfigSet", "build_configs", "trajectory_q", "BackendAnswers",
           "build_checkers", "evaluate", "parse_backend_options", "answers_distances", "verdict_detail", "EXTRA_MODELS", "reference_dir",
           "reference_model_names", "repo_root", "resolve_model", "seed_data",
           "pair_distance_tolerance", "pair_kinds", "check_model_files", "mesh_convexity", "Check", "Finding",
           "LintReport", "LintStatus", "Severity"]
