"""The shipped robot descriptions written from the makers' published parameters: the Franka
Panda with its hand and the UR10e with the 2F-85-mould gripper.

Their forward kinematics (pinocchio, read from the URDF) is compared with an independent
Denavit-Hartenberg computation from the makers' tables."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot, chain_to, se3_to_array
from sdar_tamp.world.finger_geometry import finger_geometry
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.ur_identify import ur_parameters
from sdar_tamp.world.ur_ik import URParameters
from streams._pin_geometry import arm_primitives

ROBOTS = domain_path("robots")
PANDA = ROBOTS / "panda_hand.urdf"
UR10E = ROBOTS / "ur10e_2f85.urdf"
FINGERS = ("gripper_left_finger", "gripper_right_finger")

#: Franka's table in Craig's convention, per joint: (a_{i-1}, d_i, alpha_{i-1}) [m, m, rad]
PANDA_DH = (
    (0.0, 0.333, 0.0),
    (0.0, 0.0, -np.pi / 2),
    (0.0, 0.316, np.pi / 2),
    (0.0825, 0.0, np.pi / 2),
    (-0.0825, 0.384, -np.pi / 2),
    (0.0, 0.0, np.pi / 2),
    (0.088, 0.0, np.pi / 2),
)
PANDA_FLANGE_D = 0.107
PANDA_TCP = 0.1034
#: The datasheet's position limits [rad] and velocity limits [rad/s]
PANDA_LOWER = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
PANDA_UPPER = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
PANDA_VELOCITY = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
#: UR's table for the UR10e (standard convention), and its alphas
UR10E_DH = URParameters(0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655)
UR_ALPHA = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _t(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def panda_dh_flange(q: np.ndarray) -> np.ndarray:
    """Flange pose by Craig's convention: Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i) Tz(d_i)."""
    T = np.eye(4)
    for (a, d, alpha), qi in zip(PANDA_DH, q, strict=True):
        T = T @ _rx(alpha) @ _t(a, 0, 0) @ _rz(qi) @ _t(0, 0, d)
    return T @ _t(0, 0, PANDA_FLANGE_D)


def ur_dh_flange(p: URParameters, q: np.ndarray) -> np.ndarray:
    """Flange pose in the ROS base frame by the standard convention
    Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i); the DH base is base_link turned by pi about z."""
    a = (0.0, p.a2, p.a3, 0.0, 0.0, 0.0)
    d = (p.d1, 0.0, 0.0, p.d4, p.d5, p.d6)
    T = _rz(np.pi)
    for i in range(6):
        T = T @ _rz(q[i]) @ _t(0, 0, d[i]) @ _t(a[i], 0, 0) @ _rx(UR_ALPHA[i])
    return T


def _configurations(robot: PinRobot, n: int, seed: int) -> np.ndarray:
    lo = np.maximum(robot.model.lowerPositionLimit, -np.pi)
    hi = np.minimum(robot.model.upperPositionLimit, np.pi)
    return np.random.default_rng(seed).uniform(lo, hi, (n, robot.nq))


def test_panda_forward_kinematics_is_franka_dh() -> None:
    robot = PinRobot.load(PANDA)
    assert robot.nq == 7 and len(chain_to(robot, "tcp").joints) == 7
    flange, tool0, tcp = (robot.frame_id(f) for f in ("flange", "tool0", "tcp"))
    hand = _rz(-np.pi / 4)
    for q in _configurations(robot, 50, 1):
        T = panda_dh_flange(q)
        np.testing.assert_allclose(robot.frame_pose(q, flange), T, atol=1e-9)
        np.testing.assert_allclose(robot.frame_pose(q, tool0), T @ hand, atol=1e-9)
        expected_tcp = T @ hand @ _t(0, 0, PANDA_TCP)
        np.testing.assert_allclose(robot.frame_pose(q, tcp), expected_tcp, atol=1e-9)


def test_panda_limits_are_the_datasheets() -> None:
    robot = PinRobot.load(PANDA)
    assert robot.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
    np.testing.assert_array_equal(robot.model.lowerPositionLimit, PANDA_LOWER)
    np.testing.assert_array_equal(robot.model.upperPositionLimit, PANDA_UPPER)
    np.testing.assert_array_equal(robot.model.velocityLimit, PANDA_VELOCITY)


def test_ur10e_forward_kinematics_is_ur_dh() -> None:
    robot = PinRobot.load(UR10E)
    tool0, tcp = robot.frame_id("tool0"), robot.frame_id("tcp")
    for q in _configurations(robot, 50, 2):
        T = ur_dh_flange(UR10E_DH, q)
        np.testing.assert_allclose(robot.frame_pose(q, tool0), T, atol=1e-9)
        np.testing.assert_allclose(robot.frame_pose(q, tcp), T @ _t(0, 0, 0.178), atol=1e-9)


def test_ur10e_is_identified_with_its_published_parameters() -> None:
    found = ur_parameters(PinRobot.load(UR10E))
    assert found is not None
    params, T_root_dh = found
    assert params == UR10E_DH
    np.testing.assert_allclose(T_root_dh, _rz(np.pi), atol=1e-15)
    assert ur_parameters(PinRobot.load(PANDA)) is None  # seven joints: not a UR


def test_the_ur10e_has_the_ur5e_structure() -> None:
    """Same joint and frame names as the shipped UR5e, the same gripper and TCP."""
    ur5e, ur10e = PinRobot.load(domain_path("robots/ur5e_2f85.urdf")), PinRobot.load(UR10E)
    assert ur10e.joint_names == ur5e.joint_names
    names = {str(f.name) for f in ur10e.model.frames}
    assert names == {str(f.name) for f in ur5e.model.frames}
    a, b = finger_geometry(ur5e, FINGERS), finger_geometry(ur10e, FINGERS)
    assert (a.depth, a.width, a.opening) == (b.depth, b.width, b.opening)


def test_panda_hand_fingers() -> None:
    """Pre-grasp opening 0.060 m between the pads; fingertips 0.0095 m beyond the TCP."""
    fingers = finger_geometry(PinRobot.load(PANDA), FINGERS)
    assert (fingers.depth, fingers.width, fingers.opening) == (0.0095, 0.022, 0.06)


@pytest.mark.parametrize("urdf", [PANDA, UR10E], ids=["panda", "ur10e"])
def test_primitives_only_and_the_gripper_is_named_so(urdf: Path) -> None:
    """Boxes and cylinders only (the optimiser's sphere model reads them); every shape past
    the flange belongs to a ``gripper_*`` link, and no arm link is so named."""
    robot = PinRobot.load(urdf)
    prims = arm_primitives(urdf)
    assert {p.kind for p in prims} <= {"box", "cylinder"}
    assert len(prims) == len(robot.geometry.geometryObjects)
    flange_joint = chain_to(robot, "tool0").joints[-1]
    last = int(robot.model.getJointId(flange_joint.name))
    gripper = {str(o.name) for o in robot.geometry.geometryObjects if o.name.startswith("gripper")}
    assert gripper and all(p.joint == last for p in prims if p.name in gripper)
    hand_frames = {"gripper_base_link", *FINGERS}
    on_hand = {
        str(o.name)
        for o in robot.geometry.geometryObjects
        if str(robot.model.frames[o.parentFrame].name) in hand_frames
    }
    assert on_hand == gripper


@pytest.mark.parametrize(("urdf", "dof"), [(PANDA, 7), (UR10E, 6)], ids=["panda", "ur10e"])
def test_the_sphere_model_reads_them(urdf: Path, dof: int) -> None:
    """Every moving joint carries spheres, and the coarse model puts the whole gripper in one
    box on the last joint (fewer spheres there than the fine model)."""
    from streams.motion.spheres import arm_spheres

    fine, coarse = arm_spheres(urdf), arm_spheres(urdf, coarse=True)
    for model in (fine, coarse):
        assert sorted(set(model.joint.tolist())) == list(range(1, dof + 1))
    assert (coarse.joint == dof).sum() < (fine.joint == dof).sum()


def test_panda_shapes_envelope_the_makers_meshes() -> None:
    """Every collision-mesh vertex of links 0 to 7 of Franka's own description (as packaged in
    ``example-robot-data``, whose link frames are the same DH frames) lies within 3 mm of our
    shapes. Skipped when that package is not installed."""
    from tests.world.test_maker_urdfs import SHARE

    if SHARE is None:
        pytest.skip("example-robot-data is not installed")
    robots = SHARE / "example-robot-data" / "robots"
    theirs = PinRobot.load(robots / "panda_description" / "urdf" / "panda.urdf", (robots, SHARE))
    ours = PinRobot.load(PANDA)
    for i in range(8):
        link = f"panda_link{i}"
        points = []
        for obj in theirs.geometry.geometryObjects:
            if str(theirs.model.frames[obj.parentFrame].name) != link:
                continue
            T = se3_to_array(obj.placement)  # in the joint frame, as ours are
            v = np.asarray(obj.geometry.vertices(), dtype=np.float64).reshape(-1, 3)
            points.append(v @ T[:3, :3].T + T[:3, 3])
        p = np.concatenate(points)
        covered = np.zeros(len(p), dtype=bool)
        for obj in ours.geometry.geometryObjects:
            if str(ours.model.frames[obj.parentFrame].name) != link:
                continue
            T = se3_to_array(obj.placement)
            local = (p - T[:3, 3]) @ T[:3, :3]
            g = obj.geometry
            if type(g).__name__ == "Box":
                covered |= np.all(np.abs(local) <= np.asarray(g.halfSide) + 0.003, axis=1)
            else:
                radial = np.hypot(local[:, 0], local[:, 1]) <= g.radius + 0.003
                covered |= radial & (np.abs(local[:, 2]) <= g.halfLength + 0.003)
        assert covered.all(), (link, p[~covered][:3])
