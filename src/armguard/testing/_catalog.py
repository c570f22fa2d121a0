"""Every check of the conformance suite, in the order :func:`armguard.testing.checks` runs them."""

from __future__ import annotations

from ._checks import (check_backend_protocol, check_bad_q_refused, check_capabilities_honoured, check_checker_protocol,
                      check_coal_distances, check_coal_verdicts, check_coal_verdicts_by_category,
                      check_collides_matches_distances, check_deterministic,
                      check_pair_distances_shapes, check_sign_convention, check_unknown_option_refused,
                      check_witness_on_surfaces, check_witness_relation)
from ._checks_margins import check_collides_pairs, check_margins_per_pair
from ._checks_optional import (check_distance_jacobian, check_model_as_made, check_optional_fast_paths,
                               check_pair_distances_many, check_pair_subset, check_results_kept, check_thread_safety)

__all__ = ["BACKEND_CHECKS", "MODEL_CHECKS"]

BACKEND_CHECKS = (check_backend_protocol, check_unknown_option_refused)
MODEL_CHECKS = (check_checker_protocol, check_pair_distances_shapes, check_witness_relation, check_witness_on_surfaces,
                check_sign_convention, check_bad_q_refused, check_capabilities_honoured, check_collides_matches_distances,
                check_margins_per_pair, check_collides_pairs,
                check_optional_fast_paths, check_deterministic, check_results_kept, check_coal_distances,
                check_coal_verdicts, check_coal_verdicts_by_category, check_pair_subset, check_pair_distances_many, check_distance_jacobian,
                check_model_as_made, check_thread_safety)
