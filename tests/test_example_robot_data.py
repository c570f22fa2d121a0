"""Every URDF example-robot-data installs loads, or its fault is named: the front door beyond the arms.

The public-robot table (``armguard.model._public``) holds the arms; the package holds 69 URDFs in
all (legged robots, humanoids, hands, flying arms).  Each loads here as ``load_model(path)``, with
the SRDF the search finds beside it, or raises a :class:`~armguard.SceneFileError` whose message
names what is wrong in the files themselves (:data:`FAULTS`, read in the files by hand: an empty
URDF, a mimic of a misspelt joint, limits of 1e16, SRDF states for joints the URDF does not have or
outside its limits).  Four robots that once failed, each for its own reason, are checked against
coal as well:

* centauro: a 566-gon face, which Qhull's triangulation fans out from one vertex: coal's Convex
  holds at most 254 neighbours a vertex (its copy of the hull is triangulated in strips);
* talos_full_v2: ``package:///`` mesh names, and gripper joints that mimic a sibling Pinocchio
  reaches later (renamed in the XML Pinocchio reads, then named back);
* a1: an SRDF home with the floating base's virtual ``root_joint``;
* icub: SRDF chains from the chest (a base the torso moves; legs whose tip is not below it).
"""

from __future__ import annotations

import re
import sysconfig
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard import DEFAULT_TOLERANCES as TOL
from armguard import SceneFileError

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
URDFS = sorted(str(p.relative_to(ROBOTS)) for p in ROBOTS.rglob("*.urdf")) if ROBOTS.is_dir() else []

FAULTS = {
    # the file is xacro's output of nothing: <robot> with a comment only
    "ur_description/urdf/ur3.urdf": "a URDF needs at least one <link>",
    # <mimic joint="index_q1"> where the joint is Left_index_q1
    "alex_description/urdf/alex_psyonic_hands.urdf": "joint='index_q1': no joint of that name",
    # rotor joints limited to +-1e16 rad (meant: continuous)
    "iris_description/robots/iris.urdf": "beyond 1e+09",
    # romeo.srdf's half_sitting names LToePitch, which neither romeo URDF has
    "romeo_description/urdf/romeo.urdf": "names joint 'LToePitch'",
    "romeo_description/urdf/romeo_small.urdf": "names joint 'LToePitch'",
    # solo.srdf is solo12's (its HAA joints): solo.urdf is the 8-joint solo
    "solo_description/robots/solo.urdf": "names joint 'FL_HAA'",
    # half_sitting's hip and knee values lie outside the URDF's limits
    "simple_humanoid_description/urdf/simple_humanoid.urdf": "is outside the limits",
    "simple_humanoid_description/urdf/simple_humanoid_classical.urdf": "is outside the limits",
}

needs_erd = pytest.mark.skipif(not URDFS, reason="example-robot-data is not installed")


@needs_erd
def test_the_fault_list_names_files_the_package_has():
    assert set(FAULTS) <= set(URDFS), sorted(set(FAULTS) - set(URDFS))
    assert len(URDFS) >= 60


@needs_erd
@pytest.mark.parametrize("urdf", URDFS)
def test_every_urdf_loads_or_names_its_fault(urdf):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        if urdf in FAULTS:
            with pytest.raises(SceneFileError, match=re.escape(FAULTS[urdf])) as exc:
                armguard.load_model(ROBOTS / urdf)
            assert exc.value.file.endswith((".urdf", ".srdf"))
            return
        m = armguard.load_model(ROBOTS / urdf)
    # never a smaller model: every <collision> of the file is a geometry of the model
    n_collisions = sum(len(link.findall("collision")) for link in ET.parse(ROBOTS / urdf).getroot().findall("link"))
    assert len(m.collision_model.geometryObjects) == n_collisions
    assert m.pin_model.nq == len(m.neutral())


SRDF_FAULTS = [u for u in FAULTS if u.startswith(("romeo", "solo", "simple_humanoid"))]


@needs_erd
@pytest.mark.parametrize("urdf", SRDF_FAULTS, ids=[u.split("/")[-1] for u in SRDF_FAULTS])
def test_an_srdf_that_does_not_fit_says_how_to_load_the_urdf_alone(urdf, tmp_path):
    """An SRDF armguard found that refuses its URDF: the error names the SRDF's element and the way out,
    and that way (a sidecar with ``model.srdf: none``) loads the URDF alone: every <collision> a
    geometry, the same pairs as ``srdf=False``, the command line's check answering (exit 0 or 1; 3 where
    no pair is left to check)."""
    from click.testing import CliRunner

    from armguard.cli import main

    with pytest.raises(SceneFileError, match=re.escape(FAULTS[urdf])) as exc:
        armguard.load_model(ROBOTS / urdf)
    assert exc.value.file.endswith(".srdf") and "`srdf: none`" in exc.value.message and "srdf=False" in exc.value.message
    side = tmp_path / "alone.yaml"
    side.write_text(f"armguard_scene: 1\nname: alone\nmodel: {{urdf: {ROBOTS / urdf}, srdf: none}}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        m, bare = armguard.load_model(side), armguard.load_model(ROBOTS / urdf, srdf=False)
    assert m.srdf is None and np.array_equal(m.pairs.names, bare.pairs.names)
    n_collisions = sum(len(link.findall("collision")) for link in ET.parse(ROBOTS / urdf).getroot().findall("link"))
    assert len(m.collision_model.geometryObjects) == n_collisions
    res = CliRunner().invoke(main, ["check", str(side)])
    if len(m.pairs):
        assert res.exit_code in (0, 1), res.output
    else:  # simple_humanoid's links with geometry are all adjacent: no verdict, and check says why
        assert res.exit_code == 3 and "no pair to check" in res.output, res.output


@needs_erd
def test_a_scene_files_urdf_robot_takes_the_srdf_the_file_names(tmp_path):
    """A scene file's URDF robot: ``srdf: none`` loads romeo without the romeo.srdf that refuses it, and
    an SRDF the file names is the robot's own (not only its disabled pairs: romeo.srdf is no longer read)."""
    urdf = ROBOTS / "romeo_description/urdf/romeo.urdf"
    cell = tmp_path / "cell.yaml"
    cell.write_text(f"armguard_scene: 1\nname: cell\nrobots:\n  - name: romeo\n    urdf: {urdf}\n    srdf: none\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        alone = armguard.load_model(cell)
        pairs = {tuple(sorted((p.a, p.b))) for p in alone.scene.allowed_pairs()}
        assert ("romeo/LWristRollLink", "romeo/l_wrist") in pairs
        mine = tmp_path / "mine.srdf"
        mine.write_text('<robot name="romeo"><disable_collisions link1="LWristRollLink" link2="l_wrist" '
                        'reason="Never"/></robot>')
        cell.write_text(cell.read_text().replace("srdf: none", f"srdf: {mine}"))
        named = armguard.load_model(cell)
    assert ("romeo/LWristRollLink", "romeo/l_wrist") not in {tuple(sorted((p.a, p.b))) for p in named.scene.allowed_pairs()}
    assert len(named.pairs) < len(alone.pairs)
    from armguard.scene import save_scene

    cell.write_text(cell.read_text().replace(f"srdf: {mine}", f"srdf: {ROBOTS / 'romeo_description/srdf/romeo.srdf'}"))
    with pytest.raises(SceneFileError) as exc:  # named, romeo.srdf's misfit is the scene file's, at its srdf key
        armguard.load_model(cell)
    assert exc.value.where.startswith("robots[0].srdf") and "LToePitch" in exc.value.message
    for m in (alone, named):  # saved, each loads back with its own SRDF (or none), not the one beside the URDF
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", armguard.ArmguardWarning)
            back = armguard.load_scene(save_scene(m.scene, tmp_path / "saved.yaml"))
        assert back.allowed_pairs() == m.scene.allowed_pairs()


@needs_erd
def test_a_scene_files_urdf_robot_takes_its_srdfs_home_unless_the_file_gives_one(tmp_path):
    """A scene file's URDF robot without ``home:`` starts where ``load_model`` of its URDF does: at the
    SRDF's home state (panda.srdf's ``default``, not zero); a ``home:`` in the file still wins."""
    urdf = ROBOTS / "panda_description/urdf/panda.urdf"
    srdf_home = armguard.load_model(urdf).scene.home("panda")
    assert np.abs(srdf_home).max() > 1.0  # the SRDF's state, not the zero default
    cell = tmp_path / "cell.yaml"
    cell.write_text(f"armguard_scene: 1\nname: cell\nrobots:\n  - name: panda\n    urdf: {urdf}\n")
    assert np.array_equal(armguard.load_scene(cell).home("panda"), srdf_home)
    cell.write_text(cell.read_text() + "    srdf: none\n")  # no SRDF: zero, clipped to the limits
    alone = armguard.load_scene(cell).home("panda")
    assert not np.array_equal(alone, srdf_home) and np.abs(alone).max() < 0.1
    cell.write_text(cell.read_text().replace("    srdf: none\n", "    home: [0, 0, 0, -1, 0, 1, 0, 0]\n"))
    assert np.allclose(armguard.load_scene(cell).home("panda"), [0, 0, 0, -1, 0, 1, 0, 0])


AGAINST_COAL = ["centauro_description/urdf/centauro.urdf", "talos_data/robots/talos_full_v2.urdf",
                "a1_description/urdf/a1.urdf", "icub_description/robots/icub.urdf"]


@needs_erd
@pytest.mark.parametrize("urdf", AGAINST_COAL, ids=[u.split("/")[-1] for u in AGAINST_COAL])
def test_once_failing_robots_match_coal(urdf):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        m = armguard.load_model(ROBOTS / urdf)
    a, c = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
    for q in m.random_q(3, 5):
        ra, rc = a.pair_distances(q), c.pair_distances(q)
        assert np.array_equal(ra.pairs, rc.pairs)
        sep = (ra.distance > TOL.differential_contact_band) & (rc.distance > TOL.differential_contact_band)
        assert np.all(np.abs(ra.distance - rc.distance)[sep] <= TOL.differential_hull)
        assert (ra.distance.min() <= 0) == (rc.distance.min() <= 0) or abs(rc.distance.min()) <= TOL.differential_contact_band


@needs_erd
def test_talos_full_keeps_its_names_and_couplings():
    """The joints Pinocchio read under new names have their URDF names back, and each gripper joint
    follows the joint it mimics (the mimic joints are not in q)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        m = armguard.load_model(ROBOTS / "talos_data/robots/talos_full_v2.urdf")
    names = list(m.pin_model.names)
    assert "gripper_left_joint" in names and "gripper_left_inner_double_joint" in names
    assert not any("~" in n for n in names) and not any("~" in f.name for f in m.pin_model.frames)
    assert m.pin_model.nq == 32  # 44 joint values, less the 12 mimic joints


MIMIC_URDF = """<robot name="grip">
  <link name="world"/><link name="palm"><collision><geometry><box size="0.1 0.1 0.02"/></geometry></collision></link>
  <link name="left"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.01 0.02 0.1"/></geometry></collision></link>
  <link name="right"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.01 0.02 0.1"/></geometry></collision></link>
  <link name="tip"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
  <joint name="fix" type="fixed"><parent link="world"/><child link="palm"/></joint>
  <joint name="b_drive" type="revolute"><parent link="palm"/><child link="right"/><origin xyz="0.03 0 0.01"/>
    <axis xyz="0 1 0"/><limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="a_follow" type="revolute"><parent link="palm"/><child link="left"/><origin xyz="-0.03 0 0.01"/>
    <axis xyz="0 1 0"/><limit lower="-0.5" upper="0.5" effort="1" velocity="1"/>
    <mimic joint="b_drive" multiplier="-1" offset="0.1"/></joint>
  <joint name="a_tip" type="fixed"><parent link="left"/><child link="tip"/><origin xyz="0 0 0.1"/></joint>
</robot>"""


def test_a_mimic_of_a_sibling_pinocchio_reaches_later_loads_as_the_urdf_says(tmp_path):
    """``a_follow`` mimics its sibling ``b_drive``, which Pinocchio's name order reaches second (it
    refuses the file as it is): the model loads, and every frame is where the URDF puts it, against
    Pinocchio's model of the same file without mimics at the coupled joint values."""
    import pinocchio as pin

    f = tmp_path / "grip.urdf"
    f.write_text(MIMIC_URDF)
    with pytest.raises((RuntimeError, ValueError), match="mimic"):
        pin.buildModelFromUrdf(str(f), mimic=True)
    m = armguard.load_model(f)
    pm, free = m.pin_model, pin.buildModelFromUrdf(str(f))
    assert pm.nq == 1 and list(pm.names)[1:] == ["b_drive", "a_follow"]
    dm, df = pm.createData(), free.createData()
    for x in np.linspace(-0.5, 0.5, 7):
        qf = np.zeros(free.nq)
        qf[free.joints[free.getJointId("b_drive")].idx_q] = x
        qf[free.joints[free.getJointId("a_follow")].idx_q] = -x + 0.1
        pin.framesForwardKinematics(pm, dm, np.array([x]))
        pin.framesForwardKinematics(free, df, qf)
        for k, fr in enumerate(free.frames):
            got = dm.oMf[pm.getFrameId(fr.name, fr.type)]
            np.testing.assert_allclose(got.homogeneous, df.oMf[k].homogeneous, atol=1e-12)
    d = armguard.checker(m, "analytic").pair_distances(np.array([0.2]))
    assert np.allclose(d.distance, armguard.checker(m, "coal").pair_distances(np.array([0.2])).distance, atol=1e-9)


DEPTHS = [  # (URDF, pair, configuration index in random_q(20, 11)): coal's EPA deeper than the reference
    ("romeo_description/urdf/romeo_laas_small.urdf", ("RShoulderYawCollision_shape_0", "TorsoCollision_shape_0"), 2),
]


@needs_erd
@pytest.mark.parametrize("urdf, pair, i", DEPTHS, ids=[d[0].split("/")[-1] for d in DEPTHS])
def test_a_cylinder_depth_where_coal_differs_is_the_references(urdf, pair, i):
    """``bench sweep``'s *depths off*: two overlapping cylinders of romeo_laas_small whose depths
    differ by 0.43 m between the backends.  The slow support-function reference
    (``armguard.geometry._support_reference``) gives armguard's to 1e-9 m: coal's EPA is
    the one off, as on panda_collision's cylinders (``bench robots``)."""
    from armguard.geometry._support_reference import reference_signed_distance
    from armguard.model._shapes import placed_shapes

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", armguard.ArmguardWarning)
        m = armguard.load_model(ROBOTS / urdf)
    q = m.random_q(20, 11)[i]
    k = [j for j, p in enumerate(m.pairs.names) if tuple(p) == pair][0]
    d = armguard.checker(m, "analytic").pair_distances(q).distance[k]
    d_coal = armguard.checker(m, "coal").pair_distances(q).distance[k]
    a, b = placed_shapes(m, q, pair)
    assert type(a).__name__ == type(b).__name__ == "Cylinder"
    ref = reference_signed_distance(a, b)
    assert ref < 0 and abs(d - ref) <= 1e-9 and d_coal < ref - 0.1
