"""Small scenes for the verifier tests: arms among thin plates and rods (closed-form geometry)."""

from __future__ import annotations

import numpy as np

from armguard.geometry import Box, Capsule, Sphere
from armguard.kinematics import Coupling, DHRow, Robot
from armguard.scene import Scene

LINKS = (0.5, 0.4, 0.3)


def planar_arm(name: str = "arm", radius: float = 0.02) -> Robot:
    """A 3-link planar arm (standard DH, links along x of each frame), capsule links."""
    rows = [DHRow(a, 0.0, 0.0) for a in LINKS]
    shapes = {f"link{i + 1}": (Capsule([-a, 0, 0], [0, 0, 0], radius),) for i, a in enumerate(LINKS)}
    return Robot.from_dh(name, rows, lower=[-3.0] * 3, upper=[3.0] * 3, max_velocity=[1.0] * 3,
                         max_acceleration=[2.0] * 3, link_shapes=shapes)


def spatial_arm(convention: str = "standard") -> Robot:
    """A 6-DOF spatial arm with offsets, twists, a prismatic joint and a coupled joint (for the lever-arm bound)."""
    rows = [
        DHRow(0.1, np.pi / 2, 0.3),
        DHRow(0.4, 0.0, 0.05),
        DHRow(0.05, np.pi / 2, 0.0),
        DHRow(0.0, -np.pi / 2, 0.35, joint_type="prismatic"),
        DHRow(0.0, np.pi / 2, 0.0),
        DHRow(0.02, 0.0, 0.1),
    ]
    names = [f"link{i}" for i in range(7)]
    shapes = {
        "link1": (Capsule([0, 0, 0], [0, 0, -0.2], 0.05),),
        "link2": (Capsule([-0.4, 0, 0], [0, 0, 0], 0.04),),
        "link3": (Box([0.0, 0.0, 0.05], [0.05, 0.04, 0.1]),),
        "link4": (Capsule([0, 0, -0.2], [0, 0, 0], 0.03),),
        "link5": (Sphere([0, 0, 0], 0.04),),
        "link6": (Capsule([0, 0, 0], [0.1, 0.05, 0.08], 0.02),),
    }
    return Robot.from_dh(
        "spatial", rows, convention=convention, link_names=names,
        joint_names=["j1", "j2", "j3", "j4", "j5", "j6"],
        lower=[-3, -2, -2, 0.0, -3], upper=[3, 2, 2, 0.3, 3],
        couplings=[Coupling("j5", {"j3": -1.0, "j2": 0.5}, 0.1)],
        link_shapes=shapes,
    )


def thin_scene(rng: np.random.Generator, n_obstacles: int = 3, thickness: float = 0.002) -> Scene:
    """The planar arm among thin plates (boxes ``thickness`` thick) and rods (capsules of radius ``thickness``)."""
    sc = Scene("thin")
    sc.add_robot(planar_arm(radius=0.005), self_pairs=[])  # a planar arm folds onto itself: check obstacles only
    for k in range(n_obstacles):
        ang = rng.uniform(-np.pi, np.pi)
        r = rng.uniform(0.55, 1.1)
        c = np.array([r * np.cos(ang), r * np.sin(ang), 0.0])
        if k % 2 == 0:
            t = ang + np.pi / 2 + rng.uniform(-0.5, 0.5)  # thin across the arm's sweep, long radially
            R = np.array([[np.cos(t), -np.sin(t), 0.0], [np.sin(t), np.cos(t), 0.0], [0.0, 0.0, 1.0]])
            sc.add_body(f"plate{k}", [Box(c, [thickness, rng.uniform(0.03, 0.12), 0.1], R @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))])
        else:
            sc.add_body(f"rod{k}", [Capsule(c + [0, 0, -0.1], c + [0, 0, 0.1], thickness)])
    return sc


def thin_suite(rng: np.random.Generator, n: int, *, n_obstacles: int = 3, max_step: float = 1.5):
    """``n`` (scene, trajectory) cases: the planar arm among thin obstacles, both ends of every
    trajectory at least 1 cm clear (so collisions happen between the knots)."""
    from armguard.kinematics import Trajectory
    from armguard.verify import ClearanceModel

    cases = []
    while len(cases) < n:
        sc = thin_scene(rng, n_obstacles=n_obstacles)
        model = ClearanceModel(sc, source="reference")
        for _ in range(20):
            q0 = rng.uniform(-2.5, 2.5, 3)
            q1 = np.clip(q0 + rng.uniform(-max_step, max_step, 3), -2.9, 2.9)
            if model.reference_distances(q0)[0].min() > 0.01 and model.reference_distances(q1)[0].min() > 0.01:
                cases.append((sc, Trajectory.joint_interpolated(sc.robots["arm"], [q0, q1], profile="linear")))
                break
    return cases
