"""Certified collision matrices: an SRDF whose *Never* pairs are proven, and a lint for existing SRDFs.

* :func:`collision_matrix` -- every link pair of a robot as MoveIt's Setup Assistant classifies it
  (Adjacent, Default, Never, Always), with *Never* proven by branch and bound over the pair's
  joints (the certified verifier's lever-arm bounds, :mod:`._prove`), or sampled as MoveIt does
  (``method="sampled"``); :meth:`CollisionMatrix.write_srdf` writes it;
* :func:`check_srdf` -- an SRDF's disabled pairs that can collide (with a witness configuration),
  and its checked pairs that never do.

``docs/srdf.md`` describes both and the findings on public robots' SRDFs.
"""

from ._io import srdf_text, write_srdf
from ._lint import SrdfLint, check_srdf
from ._matrix import METHODS, REASONS, CollisionMatrix, MatrixEntry, PairEvaluator, collision_matrix
from ._pairs import LinkPair, PairSetup, matrix_scene, pair_setup
from ._prove import PairProof, PairVerdict, prove_pair

__all__ = [
    "collision_matrix",
    "CollisionMatrix",
    "MatrixEntry",
    "PairEvaluator",
    "check_srdf",
    "SrdfLint",
    "write_srdf",
    "srdf_text",
    "prove_pair",
    "PairProof",
    "PairVerdict",
    "pair_setup",
    "PairSetup",
    "LinkPair",
    "matrix_scene",
    "REASONS",
    "METHODS",
]
