import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.motion.exact_check import (
    HeldObject,
    configure_world,
    interpolate_by_tcp,
    validate_trajectory,
)


def test_interpolation_keeps_tcp_steps_below_a_centimetre(ctx: WorldContext) -> None:
    q0 = _home12(ctx)
    q1 = q0 + 0.6
    dense = interpolate_by_tcp(ctx, np.stack([q0, q1]), 0.01)
    for i, arm in enumerate(ctx.arm_names):
        p = ctx.fk[arm].tcp_positions(dense[:, 6 * i : 6 * i + 6])
        assert np.linalg.norm(np.diff(p, axis=0), axis=1).max() <= 0.01


def test_a_pass_through_an_object_is_caught(ctx: WorldContext) -> None:
    world = ctx.new_world()
    kin = ctx.kinematics["left"]
    home = _home12(ctx)
    T = kin.fk_tcp(home[:6])
    # a tall box right where the left tool passes half-way
    q_mid = home.copy()
    q_mid[1] += 0.5
    p = kin.fk_tcp(q_mid[:6])[:3, 3]
    box = ObjectBox(pose_xyz_yaw(p[0], p[1], p[2], 0.0), (0.06, 0.06, 0.06))
    configure_world(ctx, world, {"o": box}, {}, home)
    q_end = home.copy()
    q_end[1] += 1.0
    traj = np.stack([home, q_end])  # the coarse samples themselves are free
    assert not world.in_collision(home) and T.shape == (4, 4)
    report = validate_trajectory(ctx, world, traj)
    assert not report.ok and report.reason == "collision"
    assert any("object:o" in (c.first, c.second) for c in report.pairs)


def test_held_object_is_checked_and_limits_too(ctx: WorldContext) -> None:
    world = ctx.new_world()
    home = _home12(ctx)
    held = {"left": HeldObject("h", (0.05, 0.05, 0.05), np.eye(4) @ _tz(0.2))}
    configure_world(ctx, world, {}, held, home)
    assert world.held_by("left") == "h"
    bad = home.copy()
    bad[0] = 3.0  # beyond the shoulder_pan limit
    assert validate_trajectory(ctx, world, np.stack([home, bad])).reason == "joint limits"
    t = np.array([0.0, 0.01])
    fast = home.copy()
    fast[3] -= 0.5
    assert validate_trajectory(ctx, world, np.stack([home, fast]), t).ok  # 2 samples: no FD
    t3 = np.array([0.0, 0.01, 0.02])
    q3 = np.stack([home, fast, fast])
    assert validate_trajectory(ctx, world, q3, t3).reason == "velocity limit"


def _tz(z: float) -> np.ndarray:
    T = np.eye(4)
    T[2, 3] = z
    return T


def _home12(ctx: WorldContext) -> np.ndarray:
    return np.concatenate([ctx.home(a) for a in ctx.arm_names])


class _Band:
    """A stand-in world: colliding while the first joint is inside ``(lo, hi)``."""

    def __init__(self, lo: float, hi: float) -> None:
        self.lo, self.hi, self.queries = lo, hi, 0

    def in_collision(self, q: np.ndarray) -> bool:
        self.queries += 1
        return bool(self.lo < q[0] < self.hi)

    def report(self, q: np.ndarray) -> tuple[()]:
        return ()


def test_chords_beside_a_close_sample_are_checked_finely(ctx: WorldContext) -> None:
    """Both samples are free, the chord between them is not (a graze between samples): found
    only when ``near`` (the world with a safety distance) marks a sample as close."""
    q0 = _home12(ctx)
    q0[0] = 0.0
    q1 = q0.copy()
    q1[0] = 1.0
    traj = np.stack([q0, q1])
    world = _Band(0.45, 0.55)  # the contact: between the samples
    plain = validate_trajectory(ctx, world, traj, max_tcp_step=10.0)  # type: ignore[arg-type]
    assert plain.ok and plain.checks == 2
    close = _Band(-0.1, 0.05)  # q0 is within the safety distance, q1 is not
    report = validate_trajectory(ctx, world, traj, max_tcp_step=10.0, near=close)  # type: ignore[arg-type]
    assert not report.ok and report.reason == "collision" and report.index == 0
    far = _Band(5.0, 6.0)  # no sample close: no fine check, the graze stays unseen
    assert validate_trajectory(ctx, world, traj, max_tcp_step=10.0, near=far).ok  # type: ignore[arg-type]


def test_samples_free_with_the_safety_distance_are_not_queried_again(ctx: WorldContext) -> None:
    """``near`` holds every collision of ``world`` (it adds a distance): a sample free there
    costs one query; a sample close in ``near`` is decided by ``world``."""
    q0 = _home12(ctx)
    q0[0] = 0.0
    q1 = q0.copy()
    q1[0] = 1.0
    traj = np.stack([q0, q1])
    world, far = _Band(0.45, 0.55), _Band(5.0, 6.0)
    report = validate_trajectory(ctx, world, traj, max_tcp_step=10.0, near=far)  # type: ignore[arg-type]
    assert report.ok and report.checks == 2
    assert world.queries == 0 and far.queries == 2
    hit, around = _Band(0.9, 1.1), _Band(0.8, 1.2)  # q1 collides in both worlds
    report = validate_trajectory(ctx, hit, traj, max_tcp_step=10.0, near=around)  # type: ignore[arg-type]
    assert not report.ok and report.reason == "collision" and report.index == 1
    assert hit.queries == 1 and around.queries == 2
