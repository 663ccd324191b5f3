import numpy as np
import pytest

from sdar_tamp.world.kinematics import ArmKinematics
from streams.context import WorldContext
from streams.motion._casadi import ca, function, sx_sym, to_array
from streams.motion.fk_casadi import joint_frames
from streams.motion.spheres import arm_spheres, box_spheres, cylinder_spheres

LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
         "wrist_3_link")  # fmt: skip


@pytest.mark.parametrize("arm", ["left", "right"])
def test_casadi_fk_equals_pinocchio(ctx: WorldContext, arm: str) -> None:
    fk = ctx.fk[arm]
    kin: ArmKinematics = ctx.kinematics[arm]
    rng = np.random.default_rng(1)
    for q in rng.uniform(-np.pi, np.pi, (20, 6)):
        np.testing.assert_allclose(fk.tcp(q), kin.fk_tcp(q), atol=1e-9)
        np.testing.assert_allclose(fk.tool0(q), kin.fk_tool0(q), atol=1e-9)


@pytest.mark.parametrize("arm", ["left", "right"])
def test_joint_frames_are_the_urdf_link_frames(ctx: WorldContext, arm: str) -> None:
    kin = ctx.kinematics[arm]
    q = sx_sym("q", 6)
    f = function("frames", [q], joint_frames(q, kin.T_world_base, kin.params, kin.T_base_dh))
    rng = np.random.default_rng(2)
    for qv in rng.uniform(-np.pi, np.pi, (5, 6)):
        frames = f(qv)
        for link, T in zip(LINKS, frames, strict=True):
            np.testing.assert_allclose(to_array(T), kin.fk(qv, link), atol=1e-9)


def test_casadi_batched_tcp_positions(ctx: WorldContext) -> None:
    fk = ctx.fk["left"]
    q = np.random.default_rng(3).uniform(-2, 2, (7, 6))
    p = fk.tcp_positions(q)
    for qi, pi in zip(q, p, strict=True):
        np.testing.assert_allclose(pi, ctx.kinematics["left"].fk_tcp(qi)[:3, 3], atol=1e-12)
    assert ca.SX.sym("x").shape == (1, 1)


def _covered(points: np.ndarray, c: np.ndarray, r: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(points[:, None] - c[None], axis=-1)
    return np.any(d <= r[None] + 1e-12, axis=1)


def test_cylinder_spheres_cover_the_cylinder() -> None:
    rng = np.random.default_rng(4)
    r, h = 0.05, 0.2
    c, rad = cylinder_spheres(r, h)
    ang, rho = rng.uniform(0, 2 * np.pi, 5000), r * np.sqrt(rng.uniform(0, 1, 5000))
    pts = np.stack([rho * np.cos(ang), rho * np.sin(ang), rng.uniform(-h, h, 5000)], 1)
    assert _covered(pts, c, rad).all()


def test_box_spheres_cover_the_box() -> None:
    half = np.array([0.03, 0.055, 0.0575])
    c, r = box_spheres(half)
    pts = np.random.default_rng(5).uniform(-1, 1, (5000, 3)) * half
    corners = np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T * half
    assert _covered(np.concatenate([pts, corners]), c, r).all()


def test_arm_sphere_model_has_every_moving_link(ctx: WorldContext) -> None:
    s = arm_spheres(ctx.scene.robot_urdf)
    assert set(s.joint.tolist()) == {1, 2, 3, 4, 5, 6}
    assert np.all(s.radius > 0)
