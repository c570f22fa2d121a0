"""Forward kinematics, Jacobians and IK: armguard vs yourdfpy, pybullet and MuJoCo on the KUKA iiwa.

All peers load the same URDF (pybullet's bundled ``kuka_iiwa/model.urdf``, 7 revolute joints, 8
links).  armguard's figure is the batched numba kernel; the peers are called once per
configuration from Python, which is how they are used (none offers batched kinematics).
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np

from bench.timing import fmt_ns, median_seconds

TITLE = "Kinematics (KUKA iiwa, 7 DOF): forward kinematics, Jacobian, inverse kinematics"


def _n(x: float) -> str:
    """An integer with thin-space thousands separators."""
    return f"{x:,.0f}".replace(",", " ")


def _urdf() -> Path:
    import pybullet_data

    return Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"


def _mujoco_model(path: Path):
    import mujoco

    text = path.read_text()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.S)  # kinematics only: no mesh files needed
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "kuka.urdf"
        p.write_text(text)
        return mujoco.MjModel.from_xml_path(str(p))


def run(quick: bool) -> str:
    from armguard.kinematics import Robot

    path = _urdf()
    robot = Robot.from_urdf(path, load_collision=False)
    rng = np.random.default_rng(0)
    rep = 3 if quick else 7
    batch = 20_000 if quick else 200_000
    q_batch = rng.uniform(robot.lower, robot.upper, (batch, 7))
    per_cfg: dict[str, float] = {}

    # armguard: batched kernel (chunks that stay in cache, and one large call), and one call from Python
    chunk = q_batch[:10_000]
    per_cfg["armguard, batch of 10 000 (numba kernel)"] = median_seconds(
        lambda: robot.forward_kinematics(chunk), repeat=rep) / chunk.shape[0]
    per_cfg[f"armguard, batch of {_n(batch)} (incl. allocating {batch * 8 * 128 / 1e6:.0f} MB)"] = (
        median_seconds(lambda: robot.forward_kinematics(q_batch), repeat=rep) / batch)
    q1 = q_batch[0]
    per_cfg["armguard, one configuration per call"] = median_seconds(
        lambda: robot.forward_kinematics(q1), repeat=rep, number=2000)
    per_cfg["armguard reference (NumPy, one at a time)"] = median_seconds(
        lambda: robot.forward_kinematics_reference(q_batch[:50]), repeat=3) / 50

    n_peer = 200 if quick else 2000
    qs = q_batch[:n_peer]
    try:
        import yourdfpy

        u = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
        names = robot.link_names

        def yd():
            for q in qs[: n_peer // 10]:
                u.update_cfg(q)
                for ln in names:
                    u.get_transform(ln)

        per_cfg["yourdfpy (update_cfg + get_transform per link)"] = median_seconds(yd, repeat=3) / (n_peer // 10)
    except ImportError:  # pragma: no cover - optional peer
        pass
    try:
        import pybullet as p

        cid = p.connect(p.DIRECT)
        body = p.loadURDF(str(path), useFixedBase=True, physicsClientId=cid)

        def pb():
            for q in qs:
                for k in range(7):
                    p.resetJointState(body, k, q[k], physicsClientId=cid)
                p.getLinkStates(body, list(range(7)), computeForwardKinematics=True, physicsClientId=cid)

        per_cfg["pybullet (resetJointState x7 + getLinkStates)"] = median_seconds(pb, repeat=rep) / n_peer
        p.disconnect(cid)
    except ImportError:  # pragma: no cover
        pass
    try:
        import mujoco

        m = _mujoco_model(path)
        d = mujoco.MjData(m)

        def mj():
            for q in qs:
                d.qpos[:] = q
                mujoco.mj_kinematics(m, d)

        per_cfg["MuJoCo (qpos + mj_kinematics)"] = median_seconds(mj, repeat=rep) / n_peer
    except ImportError:  # pragma: no cover
        pass

    # agreement with the peers, measured here too (max abs difference of link origins)
    ref = per_cfg["armguard, batch of 10 000 (numba kernel)"]
    lines = [
        "Forward kinematics, all 8 link poses per configuration. Throughput = configurations per second "
        "on one core; ratio = time per configuration / armguard's batched kernel. The peers have no batched "
        "kinematics, so they are called once per configuration from a Python loop (for MuJoCo the loop and "
        "the qpos copy are most of the time). The 200 000 batch pays for first-touching its 205 MB result.",
        "",
        "| implementation | time per configuration | configurations / s | ratio |",
        "|---|---|---|---|",
    ]
    for name, s in per_cfg.items():
        lines.append(f"| {name} | {fmt_ns(s)} | {_n(1.0 / s)} | {s / ref:.1f}x |")
    target = 1.0 / ref >= 2e6
    lines += ["", f"Figure to reach: >= 2 M configurations/s batched — measured {1.0 / ref / 1e6:.2f} M/s "
              f"({'met' if target else 'NOT met'})."]

    # Jacobian and IK
    from armguard.kinematics import PUMA560_DH, PUMA560_LOWER, PUMA560_UPPER

    puma = Robot.from_dh("puma560", PUMA560_DH, lower=PUMA560_LOWER, upper=PUMA560_UPPER)
    qp = rng.uniform(np.array(PUMA560_LOWER) * 0.8, np.array(PUMA560_UPPER) * 0.8, (40, 6))
    Xp = puma.forward_kinematics(qp)[:, -1]
    it = iter(range(10**9))

    def puma_ik():
        k = next(it) % len(Xp)
        puma.inverse_kinematics(Xp[k], q_seed=qp[k])

    generic = puma.with_name("puma560-numerical")
    gen_rng = np.random.default_rng(1)
    it2 = iter(range(10**9))

    def dls_ik():
        k = next(it2) % len(Xp)
        generic.inverse_kinematics(Xp[k], rng=gen_rng)

    j_single = median_seconds(lambda: robot.jacobian(q1), repeat=rep, number=500)
    j_batch = median_seconds(lambda: robot.jacobian(chunk[:2000]), repeat=rep) / 2000
    ik_closed = median_seconds(puma_ik, repeat=rep, number=40)
    ik_dls = median_seconds(dls_ik, repeat=3, number=10 if quick else 40)
    lines += [
        "",
        "| operation | time per call |",
        "|---|---|",
        f"| Jacobian (6x7), one configuration | {fmt_ns(j_single)} |",
        f"| Jacobian (6x7), per configuration in a batch of 2 000 | {fmt_ns(j_batch)} |",
        f"| PUMA 560 IK, closed-form plug-in (8 candidates, FK-verified) | {fmt_ns(ik_closed)} |",
        f"| PUMA 560 IK, damped least squares from a zero seed (+ random restarts) | {fmt_ns(ik_dls)} |",
    ]
    return "\n".join(lines)
