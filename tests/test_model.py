"""The Model of record: armguard's own FK and shapes follow Pinocchio's model of every URDF."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armguard
from armguard.model import WORKSPACE

from test_backends import ROBOTS

URDF_MODELS = {
    "ranger": lambda: armguard.load_model("ranger"),
    "hermes": lambda: armguard.load_model("hermes"),
    "puma560": lambda: armguard.load_model("puma560"),
    "gmf_s480": lambda: armguard.load_model("gmf_s480"),
    "rover": lambda: armguard.load_model("rover"),
    "panda": lambda: armguard.load_model(ROBOTS / "panda_description/urdf/panda.urdf",
                                         srdf=ROBOTS / "panda_description/srdf/panda.srdf"),
    "ur5": lambda: armguard.load_model(ROBOTS / "ur_description/urdf/ur5_robot.urdf"),
}


def _urdf_link(model, robot: str, link: str) -> str:
    """The URDF name of a scene link: ``R_link`` for an SRDF arm group, the link itself otherwise."""
    names = {f.name for f in model.pin_model.frames}
    return f"{robot}_{link}" if f"{robot}_{link}" in names else link


@pytest.mark.parametrize("name", list(URDF_MODELS), ids=list(URDF_MODELS))
def test_fk_and_shapes_follow_pinocchio(name):
    model = URDF_MODELS[name]()
    data = model.pin_model.createData()
    gdata = pin.GeometryData(model.collision_model)
    for q in model.random_q(50, 5):
        pin.framesForwardKinematics(model.pin_model, data, q)
        pin.updateGeometryPlacements(model.pin_model, data, model.collision_model, gdata, q)
        flat = model.scene_q(q)
        k = 0
        for rname, robot in model.scene.robots.items():
            X = robot.forward_kinematics(flat[k:k + robot.n_joints])
            k += robot.n_joints
            for i, ln in enumerate(robot.link_names):
                fid = model.pin_model.getFrameId(_urdf_link(model, rname, ln), pin.FrameType.BODY)
                np.testing.assert_allclose(X[i], data.oMf[fid].homogeneous, atol=1e-12, err_msg=f"{name}: {rname}/{ln}")
        # each scene shape sits where Pinocchio places its GeometryObject (capsules: end points)
        seen: dict = {}
        for item in model.scene.shapes_at(flat):
            i = seen.get(item.owner, 0)
            seen[item.owner] = i + 1
            go_i = model.geometry_index(model.geometry_name(item.owner, i))
            go = model.collision_model.geometryObjects[go_i]
            if type(go.geometry).__name__ == "Capsule":
                M = gdata.oMg[go_i]
                h = go.geometry.halfLength * M.rotation[:, 2]
                a0, a1 = M.translation - h, M.translation + h
                p0, p1 = item.shape.p0, item.shape.p1
                err = min(max(np.abs(p0 - a0).max(), np.abs(p1 - a1).max()), max(np.abs(p0 - a1).max(), np.abs(p1 - a0).max()))
                assert err <= 1e-12, (name, item.owner, err)


@pytest.mark.parametrize("name", list(URDF_MODELS), ids=list(URDF_MODELS))
def test_q_round_trip_and_pairs_name_geometry_objects(name):
    model = URDF_MODELS[name]()
    q = model.random_q(10, 1)
    np.testing.assert_allclose(model.pin_q(model.scene_q(q)), q, atol=1e-15)
    names = {go.name for go in model.collision_model.geometryObjects}
    assert len(model.pairs) > 0
    assert set(model.pairs.a) <= names and set(model.pairs.b) <= names | {WORKSPACE}
    assert all(a != b for a, b in zip(model.pairs.a, model.pairs.b))


def test_continuous_joints_take_pinocchio_cos_sin(tmp_path):
    urdf = tmp_path / "spin.urdf"
    urdf.write_text("""<robot name="spin"><link name="base"/><link name="arm">
      <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.1"/></geometry></collision></link>
      <link name="post"><collision><origin xyz="0.5 0.5 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
      <joint name="fix" type="fixed"><parent link="base"/><child link="post"/></joint>
      <joint name="j" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint></robot>""")
    model = armguard.load_model(urdf)
    assert model.nq == 2  # pinocchio's (cos, sin)
    for angle in np.linspace(-3.0, 3.0, 7):
        q = np.array([np.cos(angle), np.sin(angle)])
        assert model.scene_q(q)[0] == pytest.approx(angle)
        a = armguard.checker(model, "analytic").pair_distances(q)
        c = armguard.checker(model, "coal").pair_distances(q)
        np.testing.assert_allclose(a.distance, c.distance, atol=1e-9)
