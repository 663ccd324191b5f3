"""The rules of a plan that need no replay: format, scene, instance, limits and dwells.

Every check returns the earliest :class:`Violation` it finds (or None); the replay
(:mod:`sdar_tamp.replay`) combines them with the geometric rules. The rules and their
tolerances are listed in the README (section "What `sdar validate` checks").

Limits are checked on the plan's own samples, which are the trajectory (the executor streams
them; between samples the motion is linear in joint space):

* velocity of interval ``i``: ``(q[i+1] - q[i]) / (t[i+1] - t[i])``;
* acceleration at sample ``i``: the second divided difference on the non-uniform grid,
  ``(v[i] - v[i-1]) / ((t[i+1] - t[i-1]) / 2)``, with the robot at rest before ``t = 0`` and
  after the last sample (``v[-1] = v[n-1] = 0``, the virtual neighbour one spacing away).

Both are mean values of the derivative of any smooth motion through the samples (mean value
theorem for divided differences), so they never exceed its true peak: a plan whose samples
break a limit cannot be followed within it. Hence only a numerical tolerance (relative 1e-6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sdar_tamp.plan_file import EVENT_TYPES, GRIPPER_DWELL, MAX_DT, PlanFile, plan_joint_names
from sdar_tamp.world.errors import ArmLayoutError
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, translation

LIMIT_RTOL = 1e-6  #: relative tolerance of the velocity and acceleration limits
JOINT_TOL = 1e-9  #: [rad] tolerance of the joint limits
STILL_TOL = 1e-9  #: [rad] "still": no joint moves more than this
TIME_TOL = 1e-9  #: [s] tolerance of time comparisons (dwell length, event times)
FRAME_TOL = 1e-6  #: tolerance of the arms' frames and home against the scene


@dataclass(frozen=True)
class Violation:
    """The first broken rule: time [s], kind (see the README) and a message."""

    t: float
    kind: str
    message: str


def _finite(a: FloatArray) -> bool:
    return bool(np.all(np.isfinite(a)))


def _rigid(T: FloatArray) -> bool:
    if T.shape != (4, 4) or not _finite(T):
        return False
    R = T[:3, :3]
    bottom = np.allclose(T[3], [0.0, 0.0, 0.0, 1.0])
    return bottom and np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0.0


def check_format(plan: PlanFile) -> Violation | None:
    """What :func:`~sdar_tamp.plan_reading.load_plan` guarantees, for plans built in memory:
    times from 0, increasing, at most ``MAX_DT`` apart; finite values; events sorted, within
    the trajectory, of a known arm and type, with rigid transforms."""
    t, q = plan.t, plan.q

    def bad(key: str, detail: str) -> Violation:
        return Violation(0.0, "format", f"{key}: {detail}")

    if t.ndim != 1 or len(t) == 0:
        return bad("trajectory.t", f"expected a non-empty list of times, got shape {t.shape}")
    try:
        dof = plan.layout.dof
    except ArmLayoutError as err:
        return bad("arms", str(err))
    if q.shape != (len(t), dof):
        return bad("trajectory.q", f"expected shape ({len(t)}, {dof}), got {q.shape}")
    for name, values in (("trajectory.t", t[:, None]), ("trajectory.q", q)):
        if not _finite(values):
            i = int(np.argwhere(~np.isfinite(values))[0, 0])
            return bad(f"{name}[{i}]", "expected finite numbers")
    if t[0] != 0.0:
        return bad("trajectory.t[0]", f"expected 0, got {t[0]!r}")
    h = np.diff(t)
    if np.any(h <= 0.0):
        i = int(np.argmax(h <= 0.0)) + 1
        return bad(f"trajectory.t[{i}]", f"expected a time > {t[i - 1]!r}, got {t[i]!r}")
    if np.any(h > MAX_DT + TIME_TOL):
        i = int(np.argmax(h > MAX_DT + TIME_TOL)) + 1
        return bad(f"trajectory.t[{i}]", f"expected at most {MAX_DT} s after t[{i - 1}]")
    for i, e in enumerate(plan.events):
        key = f"events[{i}]"
        if not (math.isfinite(e.t) and 0.0 <= e.t <= t[-1]):
            return bad(f"{key}.t", f"expected a time within [0, {t[-1]}] s, got {e.t!r}")
        if i and e.t < plan.events[i - 1].t:
            return bad(f"{key}.t", "expected events sorted by time")
        if e.arm not in plan.arm_names or e.type not in EVENT_TYPES:
            return bad(
                key,
                f"expected an arm of {list(plan.arm_names)} and a type of "
                f"{list(EVENT_TYPES)}, got {e.arm!r}, {e.type!r}",
            )
        if not _rigid(e.T_tcp_object):
            return bad(f"{key}.T_tcp_object", "expected a finite rigid transform")
    for name, pose in plan.final_poses.items():
        if not all(math.isfinite(v) for v in pose):
            return bad(f"final_poses.{name}", "expected finite numbers")
    return None


def check_scene(plan: PlanFile, scene: Scene) -> Violation | None:
    """Arm names and order, joint names (each arm's robot joints, in order, as
    ``ArmSpec.joint_names``), base poses, tool frames and
    home configurations equal the scene's."""
    if plan.arm_names != scene.arm_names:
        return Violation(
            0.0,
            "scene",
            f"arms {list(plan.arm_names)} differ from the "
            f"scene's {list(scene.arm_names)} (names and order)",
        )
    for i, (info, spec) in enumerate(zip(plan.arms, scene.arms, strict=True)):
        expected = plan_joint_names(spec.name, spec.joint_names)
        if info.joints != expected:
            if len(info.joints) != len(expected):
                return Violation(
                    0.0,
                    "scene",
                    f"arms[{i}].joints: the scene's arm {spec.name!r} has {len(expected)} "
                    f"joints {list(expected)}, the plan's {len(info.joints)}",
                )
            k = next(
                k for k, (a, b) in enumerate(zip(info.joints, expected, strict=True)) if a != b
            )
            return Violation(
                0.0,
                "scene",
                f"arms[{i}].joints[{k}]: expected {expected[k]!r}, got {info.joints[k]!r} (the "
                f"joints of the scene's robot, in order: {list(expected)})",
            )
        tcp = translation(0.0, 0.0, spec.gripper.tcp_offset)
        for label, T, ref in (
            ("T_world_base", info.T_world_base, spec.T_world_base),
            ("T_tool0_tcp", info.T_tool0_tcp, tcp),
            ("home", info.home, np.array(spec.home)),
        ):
            if T.shape != ref.shape or not np.allclose(T, ref, atol=FRAME_TOL):
                return Violation(
                    0.0, "scene", f"arms[{i}].{label} of {spec.name} differs from the scene"
                )
    return None


def check_instance(plan: PlanFile, instance: Instance) -> Violation | None:
    """The plan's instance name and the objects it names are the instance's."""
    if plan.instance != instance.name:
        return Violation(0.0, "instance", f"plan for {plan.instance!r}, not {instance.name!r}")
    named = set(plan.final_poses) | {e.object for e in plan.events}
    if plan.observations:  # objects may come (added) or go (the replay checks the end)
        added: set[str] = set().union(*(o.added for o in plan.observations))
        known = set(instance.names) | added
        clash = sorted(set(instance.names) & added)
        for i, seen in enumerate(plan.observations):
            if i and seen.t < plan.observations[i - 1].t:
                return Violation(seen.t, "format", f"observations[{i}].t: expected sorted times")
        if clash or not named <= known:
            what = clash or sorted(named - known)
            return Violation(
                0.0, "instance", f"objects {what} are neither the instance's nor added once"
            )
        return None
    if named != set(instance.names):
        return Violation(
            0.0,
            "instance",
            f"the plan's objects {sorted(named)} differ from the "
            f"instance's {sorted(instance.names)}",
        )
    return None


def check_timeline(
    plan: PlanFile,
    scene: Scene,
    dwell: float = GRIPPER_DWELL,
    v_tol: float = LIMIT_RTOL,
    a_tol: float = LIMIT_RTOL,
) -> Violation | None:
    """The earliest joint-limit, velocity, acceleration or dwell violation (that order on
    ties); see the module docstring for the measures."""
    found = [
        v
        for v in (
            _joint_limits(plan.t, plan.q, scene),
            _velocity(plan.t, plan.q, scene, v_tol),
            _acceleration(plan, scene, a_tol),
            _dwell(plan, scene, dwell),
        )
        if v is not None
    ]
    return min(found, key=lambda v: v.t) if found else None  # min keeps the first on ties


def joint_label(name: str) -> str:
    """A robot joint's name as messages show it (a trailing ``_joint`` dropped)."""
    return name[: -len("_joint")] if name.endswith("_joint") and name != "_joint" else name


def _joint(scene: Scene, j: int) -> str:
    """``arm joint`` of entry ``j`` of the scene's configuration vector."""
    arm, k = scene.layout.locate(j)
    return f"{arm} {joint_label(scene.arm(arm).joint_names[k])}"


def check_samples(
    t: FloatArray, q: FloatArray, scene: Scene, v_tol: float = LIMIT_RTOL
) -> Violation | None:
    """The earliest joint-limit or velocity violation of samples ``q`` ``(n, dof)`` [rad] at
    ``t`` ``(n,)`` [s] (any stretch of a timeline: both rules are per sample and per
    interval)."""
    found = [v for v in (_joint_limits(t, q, scene), _velocity(t, q, scene, v_tol)) if v]
    return min(found, key=lambda v: v.t) if found else None


def _joint_limits(t: FloatArray, q: FloatArray, scene: Scene) -> Violation | None:
    lo, hi = scene.joint_array("lower"), scene.joint_array("upper")
    bad = (q < lo - JOINT_TOL) | (q > hi + JOINT_TOL)
    if not bad.any():
        return None
    i, j = np.argwhere(bad)[0]
    msg = f"{_joint(scene, j)} = {q[i, j]:.6f} rad outside [{lo[j]:.6f}, {hi[j]:.6f}]"
    return Violation(float(t[i]), "joint limit", msg)


def _velocity(t: FloatArray, q: FloatArray, scene: Scene, tol: float) -> Violation | None:
    v_max = scene.joint_array("velocity_limit")
    if len(t) < 2:
        return None
    vel = np.diff(q, axis=0) / np.diff(t)[:, None]
    bad = np.abs(vel) > v_max * (1.0 + tol)
    if not bad.any():
        return None
    i, j = np.argwhere(bad)[0]
    msg = (
        f"{_joint(scene, j)} moves at {abs(vel[i, j]):.6g} rad/s from t = {t[i]:.3f} to "
        f"{t[i + 1]:.3f} s, {abs(vel[i, j]) / v_max[j] - 1.0:.3%} over the limit "
        f"{v_max[j]:.6g} rad/s"
    )
    return Violation(float(t[i]), "velocity", msg)


def _acceleration(plan: PlanFile, scene: Scene, tol: float) -> Violation | None:
    a_max = scene.joint_array("acceleration_limit")
    t = plan.t
    if len(t) < 2:
        return None
    h = np.diff(t)
    vel = np.diff(plan.q, axis=0) / h[:, None]
    rest = np.zeros((1, vel.shape[1]))
    v_ext = np.concatenate([rest, vel, rest])  # at rest before the start and after the end
    h_ext = np.concatenate([h[:1], h, h[-1:]])  # the virtual neighbours: one spacing away
    acc = np.diff(v_ext, axis=0) / (0.5 * (h_ext[1:] + h_ext[:-1]))[:, None]  # at every t[i]
    bad = np.abs(acc) > a_max * (1.0 + tol)
    if not bad.any():
        return None
    i, j = np.argwhere(bad)[0]
    where = (
        "when it starts, the robot being at rest before t = 0"
        if i == 0
        else "when the plan ends, the robot having to stop"
        if i == len(t) - 1
        else f"at t = {t[i]:.3f} s"
    )
    msg = (
        f"{_joint(scene, j)} accelerates at {abs(acc[i, j]):.6g} rad/s^2 {where}, "
        f"{abs(acc[i, j]) / a_max[j] - 1.0:.3%} over the limit {a_max[j]:.6g} rad/s^2"
    )
    return Violation(float(t[i]), "acceleration", msg)


def _at(plan: PlanFile, t: float) -> FloatArray:
    """Configuration ``(dof,)`` at time ``t`` [s] (linear between samples)."""
    return np.array([np.interp(t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])


def _dwell(plan: PlanFile, scene: Scene, dwell: float) -> Violation | None:
    """After its gripper event an arm stands still for ``dwell`` [s] (the gripper closes or
    opens; the other arms may move); an arm's gripper acts at most once per dwell, and the
    events of several arms at one instant (any subset of the arms) are one group whose arms
    all stand still."""
    last: dict[str, tuple[float, str]] = {}
    for e in plan.events:
        prev = last.get(e.arm)
        if prev is not None and e.t - prev[0] < dwell - TIME_TOL:
            return Violation(
                e.t,
                "dwell",
                f"the {e.arm} gripper's {e.type} of {e.object} comes {e.t - prev[0]:.3f} s "
                f"after its {prev[1]} at t = {prev[0]:.3f} s; a gripper action takes {dwell} s",
            )
        last[e.arm] = (e.t, e.type)
    t, q = plan.t, plan.q
    for t_e in sorted({e.t for e in plan.events}):
        group = [e for e in plan.events if e.t == t_e]
        what = ", ".join(f"{e.arm} {e.type} of {e.object}" for e in group)
        end = max(t_e, t_e + dwell - TIME_TOL)
        if end > t[-1]:
            return Violation(
                t_e,
                "dwell",
                f"the plan ends {t[-1] - t_e:.3f} s after the {what}; the arm must stand "
                f"still for {dwell} s after a gripper event",
            )
        arms = [i for i, name in enumerate(plan.arm_names) if any(e.arm == name for e in group)]
        cols = np.concatenate([np.arange(plan.layout.dof)[plan.layout.slice(i)] for i in arms])
        q_e = _at(plan, t_e)[cols]
        inside = (t > t_e) & (t < end)
        times = np.concatenate([t[inside], [end]])
        moved = np.abs(np.concatenate([q[inside][:, cols], _at(plan, end)[None, cols]]) - q_e)
        if moved.max() > STILL_TOL:
            k, j = np.argwhere(moved > STILL_TOL)[0]
            return Violation(
                t_e,
                "dwell",
                f"after the {what} at t = {t_e:.3f} s the arm must stand still for "
                f"{dwell} s; {_joint(scene, int(cols[j]))} has moved {moved[k, j]:.3g} rad at "
                f"t = {times[k]:.3f} s",
            )
    return None
