"""A probabilistic roadmap whose edges are certified, beside the same roadmap with sampled edges.

A planar 3-link arm with 5 mm links works among four 2 mm plates.  The roadmap's nodes are random
collision-free configurations (``Checker.collides``); each node is joined to its nearest neighbours
(SciPy's k-d tree).  Every edge is checked twice:

* **sampled**, every 0.05 rad of the joint that moves most (the step Drake and MoveIt suggest), with
  the same exact yes/no check at each sample: fast, but a plate thinner than a sample's travel can
  lie between two samples;
* **certified**, by ``Verifier.check_edges``: every configuration of the edge is proven clear, or a
  configuration in contact is found (the lever-arm bound of each pair over the joints between its
  two links, Schwarzer, Saha & Latombe's covering).

The roadmap with sampled edges then holds edges that pass through a plate; the certified one does
not.  A shortest path through the certified roadmap (SciPy's Dijkstra) is verified once more as a
trajectory (``Verifier.verify``): SAFE.  ``--plot FILE.png`` draws the arm at a configuration of a
sampled "free" edge where it is inside a plate, with the samples on either side.

Run: ``python examples/prm_edges.py [--nodes 150] [--seed 0] [--plot prm_edges.png]``
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

import armguard
from armguard.geometry import Box, Capsule
from armguard.kinematics import DHRow, Robot, Trajectory
from armguard.model import model_of
from armguard.scene import Scene
from armguard.verify import EdgeStatus, Verifier

LINKS = (0.5, 0.4, 0.3)  # m
LINK_RADIUS = 0.0025  # m: 5 mm links
PLATE = 0.001  # m: half of a 2 mm plate's thickness
STEP = 0.05  # rad: the sampled check's step
NEIGHBOURS = 6


def build_scene() -> Scene:
    robot = Robot.from_dh(
        "arm", [DHRow(a, 0.0, 0.0) for a in LINKS], lower=[-3.0] * 3, upper=[3.0] * 3, max_velocity=[1.0] * 3,
        max_acceleration=[2.0] * 3, link_shapes={f"link{i + 1}": (Capsule([-a, 0, 0], [0, 0, 0], LINK_RADIUS),) for i, a in enumerate(LINKS)},
    )
    scene = Scene("prm-plates")
    scene.add_robot(robot, self_pairs=[])  # a planar arm folds onto itself: obstacles only
    for k, (x, y, turn) in enumerate(((0.7, 0.3, 0.3), (-0.5, 0.6, -0.4), (0.2, -0.8, 1.2), (-0.75, -0.35, 2.0))):
        c, s = np.cos(turn), np.sin(turn)
        scene.add_body(f"plate{k}", [Box([x, y, 0.0], [PLATE, 0.12, 0.1], [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])])
    return scene


def roadmap(model, n_nodes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``(nodes (N, 3), edges (E, 2))``: collision-free nodes, each joined to its nearest neighbours."""
    checker = armguard.checker(model)
    nodes = []
    while len(nodes) < n_nodes:
        Q = rng.uniform(-3.0, 3.0, (4 * n_nodes, 3))
        nodes.extend(Q[~checker.collides(model.pin_q(Q))])
    nodes = np.array(nodes[:n_nodes])
    _, near = cKDTree(nodes).query(nodes, k=NEIGHBOURS + 1)
    edges = {tuple(sorted((i, int(j)))) for i, row in enumerate(near) for j in row[1:]}
    return nodes, np.array(sorted(edges))


def sampled_free(model, Q0: np.ndarray, Q1: np.ndarray) -> np.ndarray:
    """``(E,) bool``: no sample in contact, every ``STEP`` rad of the joint that moves most."""
    checker = armguard.checker(model)
    free = np.empty(len(Q0), dtype=bool)
    for i, (a, b) in enumerate(zip(Q0, Q1)):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / STEP)))
        S = a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)
        free[i] = not checker.collides(model.pin_q(S)).any()
    return free


def main(n_nodes: int = 150, seed: int = 0, plot: str | None = None) -> dict:
    scene = build_scene()
    model = model_of(scene)
    verifier = Verifier(scene)
    rng = np.random.default_rng(seed)
    nodes, edges = roadmap(model, n_nodes, rng)
    Q0, Q1 = nodes[edges[:, 0]], nodes[edges[:, 1]]

    sampled = sampled_free(model, Q0, Q1)
    certified = verifier.check_edges(Q0, Q1)
    through = np.flatnonzero(sampled & (certified.code == EdgeStatus.COLLISION))  # sampled "free", through a plate
    print(f"{len(nodes)} nodes, {len(edges)} edges")
    print(f"sampled every {STEP} rad: {int(sampled.sum())} free")
    print(f"certified:               {certified.summary()}")
    print(f"edges the sampled roadmap holds that pass through a plate: {len(through)}")
    for i in through[:3]:
        print(f"  edge {tuple(int(k) for k in edges[i])}: at s = {certified.s[i]:.3f} {certified.pair[i][0]} meets "
              f"{certified.pair[i][1]} ({certified.distance[i] * 1e3:.2f} mm)")

    # a shortest path through the certified roadmap, from node 0 to the farthest node it reaches
    ok = certified.clear
    length = np.linalg.norm(Q1[ok] - Q0[ok], axis=1)
    graph = csr_matrix((length, (edges[ok, 0], edges[ok, 1])), shape=(len(nodes), len(nodes)))
    dist, pred = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    goal = int(np.argmax(np.where(np.isfinite(dist), dist, -1.0)))
    path = [goal]
    while path[-1] != 0:
        path.append(int(pred[path[-1]]))
    path = nodes[path[::-1]]
    report = verifier.verify(Trajectory.joint_interpolated(scene.robots["arm"], path, profile="linear"))
    print(f"path of {len(path)} nodes ({dist[goal]:.2f} rad): {report.status.name}, "
          f"minimum clearance {report.min_clearance * 1e3:.1f} mm")
    if plot and len(through):
        i = through[int(np.argmin(certified.distance[through]))]  # the deepest: the clearest picture
        draw(scene, model, Q0[i], Q1[i], float(certified.s[i]), plot)
    return {"nodes": nodes, "edges": edges, "sampled": sampled, "certified": certified, "through": through,
            "path": path, "report": report}


def draw(scene, model, q0, q1, s_hit: float, path: str) -> None:
    """The arm at a sampled edge's two samples around the contact, and at the contact, among the plates."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from armguard._io import save_figure

    fig, ax = plt.subplots(figsize=(6, 6))
    n = max(1, int(np.ceil(np.max(np.abs(q1 - q0)) / STEP)))
    k = min(int(s_hit * n), n - 1)
    zoom = ax.inset_axes([0.58, 0.04, 0.4, 0.4])
    for a in (ax, zoom):
        for body in scene.bodies.values():
            for box in body.shapes:
                corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]) * box.half_extents[:2]
                xy = corners @ box.rotation[:2, :2].T + box.center[:2]
                a.fill(xy[:, 0], xy[:, 1], color="#555555")
        for s, colour, style, label in ((k / n, "#1f77b4", "-o", "sample before (free)"),
                                        ((k + 1) / n, "#2ca02c", "-o", "sample after (free)"),
                                        (s_hit, "#d62728", "--", "between them: in contact (certified)")):
            pts = model.link_poses(q0 + s * (q1 - q0))["arm"][:, :2, 3]  # each link frame's origin: base, link tips
            a.plot(pts[:, 0], pts[:, 1], style, color=colour, label=f"{label}, s = {s:.3f}", lw=1.5, ms=3)
    tip = model.link_poses(q0 + s_hit * (q1 - q0))["arm"][-1, :2, 3]
    zoom.set_xlim(tip[0] - 0.03, tip[0] + 0.03)
    zoom.set_ylim(tip[1] - 0.03, tip[1] + 0.03)
    zoom.set_aspect("equal")
    zoom.set_xticks([])
    zoom.set_yticks([])
    ax.indicate_inset_zoom(zoom, edgecolor="black")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"a sampled 'free' edge through a 2 mm plate ({STEP} rad steps)\n"
                 f"(links drawn as their axes: {2 * LINK_RADIUS * 1e3:g} mm capsules)", fontsize=10)
    ax.legend(loc="upper center", fontsize=8)
    save_figure(fig, path)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nodes", type=int, default=150)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plot", default=None, help="a PNG of the arm in a plate on a sampled 'free' edge")
    a = ap.parse_args()
    main(a.nodes, a.seed, a.plot)
