"""Hermes's forbidden-values maps, certified: joint-space precompute of where links 1–3 may hit the obstacles.

Hermes (``001_…``, "Forbidden Values Method", §4) precomputes off-line, for every cell of the
first two joints, the forbidden ranges of the third joint for the first three links against the
obstacles grown by the worst-case stopping distance, stores them as a tree of substructures
(10° × 10° of joints 1 × 2), loads only the 3 × 3 neighbourhood of the current configuration,
and combines the map with the geometric method for every other check (Fig. 14).

Here the map is **certified**: a joint-3 bin of a cell is allowed only when every configuration
of that cell × bin box is proven clear by more than the stopping distance — the clearance at the
box centre minus the verifier's lever-arm bound on how far any point of the links moves within
the box, with boxes subdivided where that is inconclusive and forbidden where it stays so
(:mod:`._certify`).  Joints beyond joint 3 are irrelevant for the mapped links (their lever-arm
rows are zero: :func:`._clearance.map_links` refuses a link they move).

* :meth:`ForbiddenMap.build` (:func:`._build.build`): serial or on Dask, resumable;
* :class:`ForbiddenMap`: ``allowed(q)``, ``allowed_many(Q)``, ``neighbourhood(q)``, ``info()``;
* :class:`CombinedChecker`: Fig. 14 (map + a geometric backend for the rest; the ``forbidden``
  backend, ``armguard.checker(model, "forbidden", {"map": PATH})``, wraps it as a Checker);
* :class:`CheckerClearance`: the build's clearances from any backend that answers distances;
* :func:`check_exactness`: the map against the exact check on random configurations;
* :func:`ed_constant`: eq. (4-5)'s ``Ed / n`` from the model's link lengths (the paper's 11.4 cm/deg is its arm's).
"""

from __future__ import annotations

from ._build import BuildReport, BuildStatus, build, model_files_of
from ._clearance import CheckerClearance, DetectorClearance, MapLinks, map_links
from ._ed import PAPER_CM_PER_DEGREE, EdConstant, ed_constant
from ._combined import CombinedBatch, CombinedChecker, CombinedStatus, map_model
from ._exactness import ExactnessReport, ExactnessStatus, check_exactness, random_configurations
from ._format import FORMAT_VERSION
from ._grid import MAX_BINS, MAX_MAP_BINS, MapGrid, parse_angle
from ._map import ForbiddenMap, Lookup, MapInfo, Neighbourhood
from ._plot import plot_slice

ForbiddenMap.build = staticmethod(build)

__all__ = [
    "ForbiddenMap",
    "Neighbourhood",
    "MapInfo",
    "MapGrid",
    "Lookup",
    "BuildReport",
    "BuildStatus",
    "CombinedChecker",
    "CombinedBatch",
    "CombinedStatus",
    "ExactnessReport",
    "ExactnessStatus",
    "check_exactness",
    "random_configurations",
    "DetectorClearance",
    "CheckerClearance",
    "map_model",
    "MapLinks",
    "map_links",
    "model_files_of",
    "parse_angle",
    "MAX_BINS",
    "MAX_MAP_BINS",
    "plot_slice",
    "FORMAT_VERSION",
    "EdConstant",
    "ed_constant",
    "PAPER_CM_PER_DEGREE",
]
