"""The one tolerance dataclass.  Every numeric tolerance in armguard lives here, documented."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields

from ._errors import ToleranceError

__all__ = ["Tolerances", "DEFAULT_TOLERANCES"]


@dataclass(frozen=True)
class Tolerances:
    """Numeric tolerances, passed explicitly to the functions that need them.

    Every field is checked when a Tolerances is made (``dataclasses.replace`` included): a length, ratio
    or volume is a finite number > 0, a count an integer >= 1 (``edge_max_evaluations`` >= 2,
    ``max_prism_sides`` >= 3, ``ik_restarts`` and ``cspace_max_depth`` >= 0); anything else is a
    :class:`armguard.ToleranceError` naming the field, before a verdict is computed with it.

    Attributes
    ----------
    length : float, m
        Two points closer than this are the same point; a segment shorter than this is a point.
        Also the contact tolerance: a signed distance ``<= length`` is a contact, for
        ``geometry.intersects`` and for the Detector's collision status alike (touching within
        round-off counts as intersecting).
    parallel : float, dimensionless
        ``|sin(angle)|`` below which two directions are treated as parallel (segment-segment).
    planarity : float, m
        Largest distance of a polygon vertex from its best-fit plane.
    coplanar_volume : float, m^3
        A point set whose convex hull has less volume than this is flat (not a polyhedron).
    gjk_epsilon : float, m
        GJK stops when the lower and upper bounds on the distance differ by less than this.
    gjk_max_iterations : int
        Upper bound on GJK iterations; hitting it raises rather than returning a guess.
    penetration_witness_offset : float, m
        To find witness points of penetrating shapes, one core is moved out along the
        separating-axis normal by the penetration depth plus this offset and the closest points
        of the (then separated) cores are computed.  Any positive value gives the same answer
        in exact arithmetic; a millimetre keeps the closest-point solve well conditioned.
    feature_distance : float, m
        ``feature_at``: a point within this distance of a face plane (or a shape's surface) is
        on it; a point on two face planes is on their edge, on three or more at a vertex.
    joint_limit : float, rad or m
        A joint value this far outside its [lower, upper] still counts as within limits
        (absorbs round-off of IK and trajectory sampling at a limit).
    ik_position : float, m
        Inverse kinematics succeeds only when the reached position is within this of the target
        (checked by forward kinematics, for plug-in and numerical solvers alike).
    ik_orientation : float, rad
        ... and the reached orientation is within this angle of the target.
    ik_max_iterations : int
        Damped-least-squares iterations per start of the numerical IK solver.
    ik_restarts : int
        Random restarts of the numerical IK solver after the seeded start fails.
    ik_damping : float, m
        Damping lambda of the damped-least-squares step ``J^T (J J^T + lambda^2 I)^-1 e``.
    kinematic_probe : float, dimensionless
        Relative round-off allowance when the trajectory verifier measures a chain's geometry
        from forward kinematics (a joint moving less than this, relative to the robot's size,
        drives nothing); its lever-arm bounds are inflated by this fraction.
    verify_contact : float, m
        Certified verification: a clearance within this of the stopping distance counts as a
        collision (conservative advancement only approaches a contact, never lands on it).
    verify_max_evaluations : int
        Certified verification: the most clearance evaluations for one trajectory; a trajectory
        not resolved within it is reported INCOMPLETE, never safe.  Sampled verification: the
        most samples one request may ask for (``frequency`` x duration, or the joint-space steps
        of ``joint_step``); a request for more is refused before any work.
    edge_max_evaluations : int
        ``Verifier.check_edges``: the most clearance evaluations for one edge (the default of its
        ``max_evaluations``); an edge not resolved within it is INCOMPLETE, never clear.
    max_magnitude : float, in the file's units
        Scene files: the largest magnitude of any number (coordinates, sizes, limits, times...).
        Beyond it, products of coordinates (hull volumes, squared distances) lose all precision
        or overflow to infinity; a file number past it is refused at load, naming its place.
    max_prism_sides : int
        ``Prism.n_sides`` at most this (the hull of ``2 n_sides`` points is built per prism;
        a million sides would take minutes to load).
    covariance_relative : float, dimensionless
        ``armguard.uncertainty``: a covariance ``C`` is accepted as symmetric positive
        semi-definite when ``|C_ij - C_ji|`` is at most this times ``sqrt(C_ii C_jj)`` and the
        correlation matrix ``C_ij / sqrt(C_ii C_jj)`` has no eigenvalue below minus this (each
        entry in its own units: m² and rad² side by side; round-off of products such as
        ``J C J^T``; a negative variance beyond round-off is refused); an eigenvalue below this
        times the largest counts as zero (a direction known exactly).
    merge_conditioning : float, dimensionless
        ``armguard.uncertainty``: merging two estimates needs ``C1 + C2`` invertible; the merge
        raises when its smallest eigenvalue is below this times its largest (both estimates
        claim exact knowledge along a common direction).
    probability_quadrature : float, dimensionless (probability)
        ``armguard.uncertainty``: absolute error target of each 1-D quadrature in
        ``probability_inside`` (one per polygon edge).
    rotation_orthonormality : float, dimensionless
        ``armguard.uncertainty``: a (4, 4) pose is accepted when its rotation block ``R`` has
        ``max|R^T R - I|`` at most this (round-off of chained products) and ``det R > 0``.
    terrain_margin : float, m
        ``armguard.terrain``: each level of the terrain pyramid above the finest is grown by this
        much more than the level below it, so that round-off can never make a parent box miss a
        link that one of its children hits (coarse-to-fine verdicts equal the flat finest-level
        test's; ample for maps within 10 km of W's origin).
    cspace_contact : float, m
        ``armguard.cspace``: a joint-space box of a forbidden-values map is proven free only when
        its certified clearance (clearance at the box centre minus the lever-arm bound of the
        box) exceeds the stopping distance by more than this (absorbs the distance kernels'
        round-off, as ``verify_contact`` does for trajectories).
    cspace_max_depth : int
        ``armguard.cspace``: how many halvings in all (over joints 1, 2, 3 together) a box of one
        map step — one (joint 1, joint 2) cell × one joint-3 quantum — may undergo while its bound
        is inconclusive; a box still unresolved then is marked forbidden (conservative).  Each
        halving costs up to twice the clearance evaluations of that box and shrinks its bound by
        about a factor 2^(1/3); 2 keeps a 1° Hermes map within a minute on two cores.
    clip_plane : float, m
        ``armguard.clip``: a point within this of a clipping plane's inside counts as inside
        (touching counts as intersecting, as for ``intersects``); also the margin by which a
        shell cell must clear the test object to be labelled OUTSIDE, and a vertex may stick
        out of it and still be labelled INSIDE.
    clip_chord : float, m
        ``armguard.clip``: a curved obstacle (Cylinder, Sphere, Capsule) is clipped as a
        circumscribed polytope of short segments and ruled strips (Smith §IV) whose every point
        is within this of the shape: it never misses a contact, and an INTERSECTED answer can be a
        false alarm only where the shape is within this of the guard.  A cylinder of radius ``r``
        gets the fewest sides ``n`` with ``r (sec(π/n) - 1)`` at most this (23 at 0.1 m).
    paper_agreement : float, m
        ``bench/paper_fidelity.py``: two checkers' distances closer than this agree (the paper
        checker's nearest distance is "right"); coal holds meshes in float32 (up to 0.5 µm at
        8 m, docs/models.md), so agreement cannot be asked to be tighter than about a micrometre.
    jacobian_step : float, rad or m
        Distance Jacobians by finite differences (the framework default for a backend without
        witness Jacobians, and the tests' reference): the step along each velocity direction.
    jacobian_kink : float, m/rad or m/m
        ... a pair whose forward and backward differences differ by more than this is not smooth
        there (a smooth distance's differ by ``jacobian_step`` times its second derivative).
    jacobian_face : float, m
        Witness Jacobians: a shape's vertices within this of its support plane form the support
        face that decides whether witness points are unique (``smooth``).
    jacobian_parallel : float, dimensionless
        ... ``|sin(angle)|`` below which two witness edges are parallel, or a normal lies along
        a cylinder's axis (a flat face).
    avoid_still : float, rad/s or m/s
        ``armguard.avoid``: a filtered velocity whose every component is at most this is a stop
        (status STOPPED); one within this of the command is the command (status FREE).
    avoid_feasibility : float, m/s or rad/s
        ``armguard.avoid``: the solver's answer may break a damper constraint or a velocity limit
        by at most this (round-off), else the answer is to stop.
    avoid_row : float, m/rad or m/m
        ``armguard.avoid``: a pair whose Jacobian row is no longer than this is no damper
        constraint: no joint moves its distance (a pair of one rigid body, its row rounding noise,
        -3.8e-9 m/rad on ur5's wrist 2 and tool link) and its constraint only stopped the arm.
    differential_contact_band : float, m
        Differential tests and ``armguard compare``: a verdict (collides or not) may differ
        between two backends (or a backend and ``reference/``) only where the reference distance
        is within this of 0.
    differential_distance : float, m
        ... separated distances agree within this (both backends exact up to round-off).
    differential_hull : float, m
        ... within this where a side is a ``coal.Convex`` hull (coal's GJK on mesh hulls stops
        within it; measured 3.6e-6 m on the Panda's hulls).
    differential_witness : float, m
        ... the analytic backend's witness relation ``| |p_WA - p_WB| - |d| |`` holds within this.
    differential_fcl : float, m
        ... python-fcl's distances were measured up to 5.3e-2 m off the exact ones (its capsule
        and GJK paths); it is held to verdicts outside this band (not on Ranger, where it is off
        by 0.32 m on some pairs).
    differential_unique_min_distance : float, m
        ... witness points are compared between backends only on pairs where they are unique:
        both sides capsules or spheres, the reference distance above this, ...
    differential_parallel : float, dimensionless
        ... and, for two capsules, ``|sin(angle between the axes)|`` above this.
    differential_unique_point : float, m
        ... unique witness points agree within this.
    """

    length: float = 1e-12
    parallel: float = 1e-12
    planarity: float = 1e-9
    coplanar_volume: float = 1e-15
    gjk_epsilon: float = 1e-12
    gjk_max_iterations: int = 128
    penetration_witness_offset: float = 1e-3
    feature_distance: float = 1e-7
    kinematic_probe: float = 1e-9
    verify_contact: float = 1e-6
    verify_max_evaluations: int = 200_000
    edge_max_evaluations: int = 1000
    max_magnitude: float = 1e9
    max_prism_sides: int = 1024
    joint_limit: float = 1e-9
    ik_position: float = 1e-9
    ik_orientation: float = 1e-9
    ik_max_iterations: int = 200
    ik_restarts: int = 16
    ik_damping: float = 1e-4
    terrain_margin: float = 1e-9
    covariance_relative: float = 1e-9
    merge_conditioning: float = 1e-12
    probability_quadrature: float = 1e-10
    clip_plane: float = 1e-9
    clip_chord: float = 1e-3
    rotation_orthonormality: float = 1e-9
    cspace_contact: float = 1e-6
    cspace_max_depth: int = 2
    paper_agreement: float = 1e-6
    jacobian_step: float = 1e-6
    jacobian_kink: float = 1e-2
    jacobian_face: float = 1e-9
    jacobian_parallel: float = 1e-9
    avoid_still: float = 1e-9
    avoid_feasibility: float = 1e-9
    avoid_row: float = 1e-6
    differential_contact_band: float = 1e-6
    differential_distance: float = 1e-6
    differential_hull: float = 1e-5
    differential_witness: float = 1e-9
    differential_fcl: float = 6e-2
    differential_unique_min_distance: float = 1e-3
    differential_parallel: float = 1e-3
    differential_unique_point: float = 1e-6

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.type in ("int", int):
                least = _LEAST_COUNT.get(f.name, 1)
                if isinstance(v, bool) or not hasattr(v, "__index__") or int(v) < least:
                    raise ToleranceError(f"Tolerances.{f.name}: expected an integer >= {least}, got {v!r}")
            else:
                x = float(v) if isinstance(v, numbers.Real) and not isinstance(v, bool) else math.nan
                if not (math.isfinite(x) and x > 0.0):
                    raise ToleranceError(f"Tolerances.{f.name}: expected a finite number > 0, got {v!r}")

    def differential(self) -> dict:
        """The ``differential_*`` tolerances without their prefix (what a comparison report records)."""
        return {f.name.removeprefix("differential_"): getattr(self, f.name) for f in fields(self)
                if f.name.startswith("differential_")}


_LEAST_COUNT = {"edge_max_evaluations": 2, "max_prism_sides": 3, "ik_restarts": 0, "cspace_max_depth": 0}
"""The least value of an integer field (1 where not named): an edge's covering evaluates both ends; a
prism has 3 sides at least; no restart and no halving are counts that make sense."""

DEFAULT_TOLERANCES = Tolerances()
