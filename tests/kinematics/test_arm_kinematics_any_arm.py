"""ArmKinematics of any arm: the numeric IK of a 7-DoF arm (round trips, branches, continued
solutions), the closed form of the UR5e against the numeric IK, and the errors."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.kinematics import (
    NUMERIC_BRANCHES,
    NUMERIC_DISTINCT,
    ArmKinematics,
    IKSolutions,
)
from sdar_tamp.world.numeric_ik import numeric_ik_branches, pose_error
from sdar_tamp.world.scene import Scene, load_scene
from tests.kinematics.conftest import ARM7_URDF


@pytest.fixture(scope="module")
def kin7(scene7: Scene) -> ArmKinematics:
    return ArmKinematics.from_scene(scene7, "left")


def _reachable(kin: ArmKinematics, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    q = np.random.default_rng(seed).uniform(kin.spec.lower_array, kin.spec.upper_array, (n, 7))
    return q, kin.fk_batch(q)


def test_from_model_needs_no_scene(scene7: Scene, kin7: ArmKinematics) -> None:
    spec = scene7.arm("left")
    built = ArmKinematics.from_model(spec, ARM7_URDF, tcp_offset=0.1034)
    assert not built.closed_form and built.dof == 7 and built.branches == NUMERIC_BRANCHES
    assert built.tool_frame == "tool0" and built.params is None
    q = np.array(spec.home)
    np.testing.assert_allclose(built.fk_tcp(q), kin7.fk_tcp(q), atol=1e-15)


def test_fk_batch_is_pinocchio_fk(kin7: ArmKinematics) -> None:
    q, T = _reachable(kin7, 30, 0)
    for qi, Ti in zip(q, T, strict=True):
        np.testing.assert_allclose(kin7.fk_tool0(qi), Ti, atol=1e-12)
        np.testing.assert_allclose(kin7.fk_tcp(qi), Ti @ kin7.T_tool0_tcp, atol=1e-12)


def test_numeric_ik_round_trips_on_reachable_poses(kin7: ArmKinematics) -> None:
    q_true, targets = _reachable(kin7, 300, 1)
    sol = kin7.ik_tool0(targets)
    assert sol.q.shape == (300, NUMERIC_BRANCHES, 7) and sol.valid.shape == (300, 4)
    assert sol.valid.any(axis=1).mean() > 0.99
    lo, hi = kin7.spec.lower_array, kin7.spec.upper_array
    rows, branches = np.nonzero(sol.valid)
    q = sol.q[rows, branches]
    assert np.all(q >= lo) and np.all(q <= hi)
    err = np.abs(pose_error(targets[rows], kin7.fk_batch(q))).max()
    assert err < 1e-5
    for i in range(0, 300, 10):  # branches are distinct, nearest the home first
        qs = sol.q[i][sol.valid[i]]
        d = np.linalg.norm(qs - np.array(kin7.spec.home), axis=1)
        assert np.all(np.diff(d) >= 0.0)
        for a in range(len(qs)):
            for b in range(a):
                assert np.abs(qs[a] - qs[b]).max() >= NUMERIC_DISTINCT
    best, ok = sol.closest(q_true[0])
    assert best.shape == (300, 7) and ok.mean() > 0.99


def test_unreachable_poses_have_no_valid_branch(kin7: ArmKinematics) -> None:
    far = np.eye(4)
    far[:3, 3] = [2.0, 0.0, 0.5]
    sol = kin7.ik_tcp(far)
    assert sol.q.shape == (1, NUMERIC_BRANCHES, 7) and not sol.valid.any()


def test_continued_solutions_stay_on_their_branch(kin7: ArmKinematics) -> None:
    rng = np.random.default_rng(2)
    home = np.array(kin7.spec.home)
    q = np.clip(home + rng.normal(0.0, 0.3, (40, 7)), kin7.spec.lower_array, kin7.spec.upper_array)
    targets = kin7.fk_batch(q)
    T_tcp = targets @ kin7.T_tool0_tcp
    lifted = T_tcp.copy()
    lifted[:, :3, 3] -= 0.05 * T_tcp[:, :3, 2]
    first, second = kin7.ik_tcp_pair(T_tcp, lifted)
    both = first.valid & second.valid
    assert both.any(axis=1).all()
    assert np.abs(first.q - second.q).max(axis=-1)[both].max() < 1.0
    rows, b = np.nonzero(both)
    q2 = second.q[rows, b]
    np.testing.assert_allclose(kin7.fk_batch(q2) @ kin7.T_tool0_tcp, lifted[rows], atol=1e-5)
    with pytest.raises(KinematicsError, match="starts of shape"):
        kin7.ik_tcp_from(T_tcp, np.zeros((40, 7)))
    with pytest.raises(KinematicsError, match="as many first as second"):
        kin7.ik_tcp_pair(T_tcp, lifted[:3])


def test_numeric_pairs_are_solved_once(scene7: Scene, monkeypatch: pytest.MonkeyPatch) -> None:
    kin = ArmKinematics.from_scene(scene7, "left")  # its own table of solved pairs
    q = np.array(kin.spec.home) + np.linspace(-0.2, 0.2, 7)
    T = kin.fk_batch(np.stack([q, q + 0.05])) @ kin.T_tool0_tcp
    lifted = T.copy()
    lifted[:, :3, 3] -= 0.05 * T[:, :3, 2]
    first, second = kin.ik_tcp_pair(T, lifted)
    assert first.valid.any(axis=1).all() and second.valid.any(axis=1).all()
    calls: list[int] = []
    solve = ArmKinematics.ik_tcp

    def counted(self: ArmKinematics, T_world_tcp: np.ndarray) -> IKSolutions:
        calls.append(len(T_world_tcp))
        return solve(self, T_world_tcp)

    monkeypatch.setattr(ArmKinematics, "ik_tcp", counted)
    again = kin.ik_tcp_pair(T[::-1], lifted[::-1])  # met before: read, not solved
    assert calls == []
    np.testing.assert_array_equal(again[0].q, first.q[::-1])
    np.testing.assert_array_equal(again[1].valid, second.valid[::-1])
    one_new = np.concatenate([T[:1], T[:1] @ kin.T_tool0_tcp])
    kin.ik_tcp_pair(one_new, np.concatenate([lifted[:1], lifted[:1]]))
    assert calls == [1]  # only the pair not met before, once
    empty = kin.ik_tcp_pair(np.zeros((0, 4, 4)), np.zeros((0, 4, 4)))
    assert empty[0].q.shape == (0, NUMERIC_BRANCHES, 7) and empty[1].valid.shape == (0, 4)


def test_closed_form_continued_solutions_pick_the_nearest_branch(ctx_ur: ArmKinematics) -> None:
    kin = ctx_ur
    home = np.array(kin.spec.home)
    T = kin.fk_tcp(home)[None]
    near = kin.ik_tcp_from(T, home[None, None] + 0.01)
    assert near.q.shape == (1, 1, 6) and near.valid[0, 0]
    np.testing.assert_allclose(near.q[0, 0], home, atol=1e-9)


@pytest.fixture(scope="module")
def ctx_ur() -> ArmKinematics:
    return ArmKinematics.from_scene(load_scene(), "left")


def test_ur_closed_form_agrees_with_the_numeric_ik(ctx_ur: ArmKinematics) -> None:
    kin = ctx_ur
    assert kin.closed_form and kin.branches == 8
    rng = np.random.default_rng(4)
    lo, hi = kin.spec.lower_array, kin.spec.upper_array
    q_true = rng.uniform(lo, hi, (100, 6))
    targets = kin.fk_batch(q_true)
    closed = kin.ik_tool0(targets)
    T_root = np.linalg.inv(kin.T_world_base) @ targets
    q_num, ok = numeric_ik_branches(kin.chain, T_root, lo, hi, np.array(kin.spec.home), 4)
    assert ok.any(axis=1).mean() > 0.99
    rows, b = np.nonzero(ok)
    reached = kin.fk_batch(q_num[rows, b])
    assert np.abs(pose_error(targets[rows], reached)).max() < 1e-5  # both reach the pose
    # every numeric solution is one of the closed form's valid branches
    d = np.abs(closed.q[rows] - q_num[rows, b][:, None]).max(axis=-1)
    d = np.where(closed.valid[rows], d, np.inf).min(axis=1)
    assert np.all(d < 1e-3)  # (near-singular poses leave the joints less exact than the pose)


def test_bad_arms_and_shapes_raise(scene7: Scene, kin7: ArmKinematics, tmp_path: Path) -> None:
    spec = scene7.arm("left")
    with pytest.raises(KinematicsError, match="not \\['a'"):
        ArmKinematics.from_model(spec, ARM7_URDF, tcp_offset=0.1, joint_names=("a",) * 7)
    six = replace(
        spec, joint_names=spec.joint_names[:6], lower=spec.lower[:6], upper=spec.upper[:6],
        velocity_limit=spec.velocity_limit[:6], acceleration_limit=spec.acceleration_limit[:6],
        home=spec.home[:6],
    )  # fmt: skip
    with pytest.raises(KinematicsError, match="has 7 joints; arm 'left' has 6"):
        ArmKinematics.from_model(six, ARM7_URDF, tcp_offset=0.1)
    with pytest.raises(KinematicsError, match="unknown frame 'nose'"):
        ArmKinematics.from_model(spec, ARM7_URDF, tcp_offset=0.1, tool_frame="nose")
    named = ArmKinematics.from_model(
        spec, ARM7_URDF, tcp_offset=0.1, joint_names=tuple(f"joint{i}" for i in range(1, 8))
    )
    assert named.dof == 7
    with pytest.raises(KinematicsError, match=r"shape \(7,\)"):
        kin7.fk_tool0(np.zeros(6))
    with pytest.raises(KinematicsError, match="poses of shape"):
        kin7.ik_tool0(np.zeros((3, 3)))
    with pytest.raises(KinematicsError, match="branches must be >= 1"):
        numeric_ik_branches(kin7.chain, np.eye(4), spec.lower_array, spec.upper_array,
                            np.array(spec.home), 0)  # fmt: skip
    with pytest.raises(KinematicsError, match="reference of shape"):
        numeric_ik_branches(kin7.chain, np.eye(4), spec.lower_array, spec.upper_array,
                            np.zeros(6), 2)  # fmt: skip


def test_a_description_with_more_joints_than_the_arm(scene7: Scene, tmp_path: Path) -> None:
    """A finger joint outside the chain: FK fills it with 0; damped least squares refuses."""
    text = ARM7_URDF.read_text(encoding="utf-8").replace(
        '<joint name="gripper_left_finger_joint" type="fixed">',
        '<joint name="gripper_left_finger_joint" type="prismatic">\n'
        '    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>',
    )
    path = tmp_path / "fingers.urdf"
    path.write_text(text, encoding="utf-8")
    spec = scene7.arm("left")
    kin = ArmKinematics.from_model(spec, path, tcp_offset=0.1034)
    assert kin.robot.nq == 8 and kin.dof == 7
    q = np.array(spec.home)
    np.testing.assert_allclose(kin.fk_tool0(q), kin.fk_batch(q[None])[0], atol=1e-12)
    with pytest.raises(KinematicsError, match="has 8 joints, the arm 7"):
        kin.ik_dls(kin.fk_tool0(q), q)


def test_damped_least_squares_on_the_seven_dof_arm(kin7: ArmKinematics) -> None:
    home = np.array(kin7.spec.home)
    target = kin7.fk_tcp(np.clip(home + 0.2, kin7.spec.lower_array, kin7.spec.upper_array))
    res = kin7.ik_dls(target, home, frame="tcp")
    assert res.success
    np.testing.assert_allclose(kin7.fk_tcp(res.q), target, atol=1e-9)


def test_numeric_branch_functions_check_their_input(kin7: ArmKinematics) -> None:
    from sdar_tamp.world.numeric_ik import numeric_ik_from

    lo, hi = kin7.spec.lower_array, kin7.spec.upper_array
    home = np.array(kin7.spec.home)
    with pytest.raises(KinematicsError, match=r"limits of shape \(7,\)"):
        numeric_ik_branches(kin7.chain, np.eye(4), lo[:6], hi[:6], home, 2)
    with pytest.raises(KinematicsError, match="lower limits above upper"):
        numeric_ik_branches(kin7.chain, np.eye(4), hi, lo, home, 2)
    with pytest.raises(KinematicsError, match=r"starts of shape \(1, b, 7\)"):
        numeric_ik_from(kin7.chain, np.eye(4), lo, hi, np.zeros((2, 1, 7)))
    # a start outside the limits is clamped into them first
    target = kin7.fk_batch(home[None])[0]
    q, _ = numeric_ik_from(kin7.chain, target, lo, hi, (home + 10.0)[None, None])
    assert q.shape == (1, 1, 7) and np.all(q >= lo) and np.all(q <= hi)


def test_numeric_ik_of_a_pose_does_not_depend_on_its_batch(
    scene7: Scene, kin7: ArmKinematics
) -> None:
    """A pose's solutions are the same alone, in a batch and in a shuffled batch (bit for
    bit), so the solved-pair table cannot make a plan depend on which batch met a pose first."""
    _, targets = _reachable(kin7, 24, 5)
    together = kin7.ik_tool0(targets)
    order = np.random.default_rng(6).permutation(24)
    shuffled = kin7.ik_tool0(targets[order])
    np.testing.assert_array_equal(shuffled.q, together.q[order])
    np.testing.assert_array_equal(shuffled.valid, together.valid[order])
    for i in (0, 7, 23):
        alone = kin7.ik_tool0(targets[i])
        np.testing.assert_array_equal(alone.q[0], together.q[i])
        np.testing.assert_array_equal(alone.valid[0], together.valid[i])
    fresh = ArmKinematics.from_scene(scene7, "left")  # a cold table of pairs
    lifted = targets @ kin7.T_tool0_tcp
    lifted[:, :3, 3] -= 0.05 * lifted[:, :3, 2]
    a = kin7.ik_tcp_pair(targets[:12] @ kin7.T_tool0_tcp, lifted[:12])
    fresh.ik_tcp_pair(targets[5:] @ kin7.T_tool0_tcp, lifted[5:])  # met first in another batch
    b = fresh.ik_tcp_pair(targets[:12] @ kin7.T_tool0_tcp, lifted[:12])
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.q, y.q)
        np.testing.assert_array_equal(x.valid, y.valid)
