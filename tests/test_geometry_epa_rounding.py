"""EPA on dense hulls where rounding stops it: the face it kept, not hours of exhaustive SAT.

Source of the cases: so101 (example-robot-data; link hulls of 798-4,262 vertices) at two
configurations drawn by ``model.random_q`` (seeds 1 and 7) where the analytic backend's
``pair_distances`` did not return for minutes.  There shoulder_link's largest hull penetrates
gripper_link's (11.2 mm) and lower_arm_link's (25.2 and 25.9 mm).  On 2-6 % of rigid rotations
of such a pair EPA met a new face whose plane did not hold the origin (rounding, with its bracket
on the depth already 1.4e-10 to 6.9e-9 m wide) and fell back to the exhaustive SAT, whose edge
axes cost E_A E_B (V_A + V_B) ~ 1e11 projections.  Now the face kept once the bracket closed to
``EPA_BRACKET`` is the answer.  The depth is invariant under rotating both hulls, so every rotation
must settle and give the same depth; and the whole model's distances must come back and agree
with coal's.
"""

from __future__ import annotations

import subprocess
import sys
import sysconfig
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
pytestmark = pytest.mark.skipif(not (ROBOTS / "so_arm_description").is_dir(),
                                reason="example-robot-data is not installed")

Q_HANG = {  # so101 configurations (rad) where pair_distances did not return
    "gripper": [-1.3906845558194825, 0.9088746493810893, 1.6661671425702882, -1.1673135401271422,
                1.236486411343845, 1.4099748592702361],
    "lower_arm": [1.6337836456683656, 1.6277678832684979, 1.368690570747054, -0.9986612307335683,
                  1.9094380068514045, 0.4739138595061872],
}


@pytest.fixture(scope="module")
def so101():
    import armguard

    return armguard.load_model("so101")


def _shapes(model, q, link):
    items = model.scene.shapes_at(model.scene_q(np.asarray(q)[None])[0])
    return [it.shape for it in items if it.owner.endswith("/" + link)]


@pytest.mark.parametrize("case, other", [("gripper", "gripper_link"), ("lower_arm", "lower_arm_link")])
def test_epa_settles_every_rotation_of_a_dense_penetrating_pair(so101, case, other):
    from armguard._tolerance import DEFAULT_TOLERANCES as T
    from armguard.geometry._dispatch import _climb_graph
    from armguard.geometry._pair_epa import EPA_BRACKET, EPA_WORK_SIZE, epa_depth
    from armguard.geometry._pair_gjk import centroid_difference, gjk_dir_adj2

    a = max(_shapes(so101, Q_HANG[case], "shoulder_link"), key=lambda s: len(s._sat[0]))
    checked = 0
    for b in _shapes(so101, Q_HANG[case], other):
        pa0, pb0, ga, gb = a._sat[0], b._sat[0], _climb_graph(a), _climb_graph(b)
        depths = []
        for t in range(60):
            R = Rotation.random(random_state=t).as_matrix() if t else np.eye(3)
            pa, pb = np.ascontiguousarray(pa0 @ R.T), np.ascontiguousarray(pb0 @ R.T)
            work = np.zeros(EPA_WORK_SIZE)
            dx, dy, dz = centroid_difference(pa, pb)
            gjk_dir_adj2(pa, ga, pb, gb, 0.0, 0.0, 0.0, dx, dy, dz, T.length, T.gjk_epsilon, T.gjk_max_iterations,
                         work[0:9], np.inf)
            if work[0] != 1.0:  # the cores do not overlap: no EPA
                break
            ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz = epa_depth(pa, ga, pb, gb, work, T.gjk_epsilon)
            assert ok, f"rotation {t}: EPA did not settle {len(pa0)} against {len(pb0)} vertices"
            n = np.array([nx, ny, nz])
            assert np.allclose(np.array([ax, ay, az]) - np.array([bx, by, bz]), depth * n, atol=1e-9)
            depths.append(depth)
        if depths:
            checked += 1
            assert max(depths) - min(depths) <= EPA_BRACKET, depths
    assert checked >= 1  # the stored configuration does put a pair in penetration


def test_dense_robot_distances_return_and_agree_with_coal():
    """In a child process with a time limit: before, this did not return."""
    code = textwrap.dedent(f"""
        import numpy as np, armguard
        m = armguard.load_model("so101")
        an, co = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
        worst = 0.0
        for q in {list(Q_HANG.values())!r}:
            a, c = an.pair_distances(np.array(q)), co.pair_distances(np.array(q))
            assert (a.distance < 0).sum() >= 3 and np.array_equal(a.distance < 0, c.distance < 0)
            worst = max(worst, float(np.abs(a.distance - c.distance).max()))
        print(worst)
    """)
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    assert float(run.stdout.split()[-1]) <= 1e-6
