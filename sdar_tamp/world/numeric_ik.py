"""Batched numeric inverse kinematics of any serial chain (6 or 7 DoF and others).

Forward kinematics and the geometric Jacobian of a :class:`~sdar_tamp.world._pin.Chain` are
evaluated with numpy for a whole batch at once. The solver is damped least squares
(Levenberg-Marquardt with a fixed damping) on the pose error ``(p_t - p, log(R_t R^T))`` in the
root frame; for a redundant arm the step also moves, in the Jacobian's null space, toward the
reference configuration (the home, or the centre of the limits). Joints are clamped into their
limits after every step. Every target is tried from several seeds (the reference first, then
uniform draws inside the limits), and the targets no seed solved get fresh seeds in up to
``rounds`` rounds; of the seeds that converge, the one closest to the reference is kept.
The descent runs compiled (:mod:`.ik_kernel`, one start after the other) where numba runs, else
(or with ``NumericIKOptions(compiled=False)``) with numpy, the starts side by side.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world import ik_kernel
from sdar_tamp.world._pin import Chain
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.transforms import BoolArray, FloatArray


@dataclass(frozen=True)
class NumericIKOptions:
    """Tolerances [m], [rad] and effort of :func:`numeric_ik`."""

    seeds: int = 8
    iterations: int = 200
    position_tolerance: float = 1e-6  # [m]
    rotation_tolerance: float = 1e-6  # [rad]
    damping: float = 1e-2  # initial; adapted per row (Levenberg-Marquardt)
    max_step: float = 0.5  # [rad] or [m] per joint and iteration
    null_space_gain: float = 0.1
    rounds: int = 6  # fresh seeds for the targets not yet solved
    #: Pose error norm below which the null-space pull fades out in proportion (0: never):
    #: near the pose its steps leave the pose by their second-order terms and slow the last
    #: iterations of the descent.
    null_space_fade: float = 0.0
    #: Descend with the compiled kernel (:mod:`.ik_kernel`, one start after the other) where
    #: numba runs, else (or when False) with numpy, the starts side by side.
    compiled: bool = True


@dataclass(frozen=True)
class NumericIKResult:
    """``q`` ``(n, dof)`` [rad]; ``ok`` ``(n,)`` where a seed converged."""

    q: FloatArray
    ok: BoolArray

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.ok)) if len(self.ok) else 1.0


def _rotations(axis: FloatArray, angle: FloatArray) -> FloatArray:
    """Rotation matrices ``(n, 3, 3)`` about the unit ``axis`` ``(3,)`` by ``angle`` ``(n,)``."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    out: FloatArray = np.eye(3) + s * k + (1.0 - c) * (k @ k)
    return out


def chain_fk(chain: Chain, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Joint frames ``(n, dof, 4, 4)`` and end-frame poses ``(n, 4, 4)`` in the root frame
    for configurations ``q`` ``(n, dof)``."""
    q = np.atleast_2d(np.asarray(q, dtype=np.float64))
    n = len(q)
    frames = np.empty((n, chain.dof, 4, 4))
    T = np.broadcast_to(np.eye(4), (n, 4, 4))
    for i, joint in enumerate(chain.joints):
        T = T @ joint.T_parent_joint  # the joint frame at q = 0, then its motion
        axis = joint.axis / np.linalg.norm(joint.axis)
        if joint.kind == "prismatic":
            T[:, :3, 3] += (T[:, :3, :3] @ axis) * q[:, i, None]
        elif axis[0] == 0.0 and axis[1] == 0.0 and axis[2] > 0.0:  # about z: turn x and y
            c, s = np.cos(q[:, i])[:, None], np.sin(q[:, i])[:, None]
            x, y = T[:, :3, 0].copy(), T[:, :3, 1].copy()
            T[:, :3, 0] = c * x + s * y
            T[:, :3, 1] = c * y - s * x
        else:
            T[:, :3, :3] = T[:, :3, :3] @ _rotations(axis, q[:, i])
        frames[:, i] = T
    end: FloatArray = T @ chain.T_joint_frame
    return frames, end


def chain_jacobian(chain: Chain, frames: FloatArray, end: FloatArray) -> FloatArray:
    """Geometric Jacobians ``(n, 6, dof)`` (linear rows first) of the end frame, root frame."""
    axes = np.stack([j.axis / np.linalg.norm(j.axis) for j in chain.joints])  # (dof, 3)
    z = np.einsum("nijk,ik->nij", frames[:, :, :3, :3], axes)  # joint axes, root frame
    prismatic = np.array([j.kind == "prismatic" for j in chain.joints])[None, :, None]
    linear = np.where(prismatic, z, np.cross(z, end[:, None, :3, 3] - frames[:, :, :3, 3]))
    J: FloatArray = np.concatenate(
        [np.transpose(linear, (0, 2, 1)), np.transpose(np.where(prismatic, 0.0, z), (0, 2, 1))],
        axis=1,
    )
    return J


def rotation_log(R: FloatArray) -> FloatArray:
    """Rotation vectors ``(n, 3)`` (axis times angle [rad]) of rotation matrices ``(n, 3, 3)``."""
    cos = np.clip((np.trace(R, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    vee = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    sin = np.sin(angle)
    small = sin < 1e-9
    scale = np.where(small, 0.5, angle / (2.0 * np.where(small, 1.0, sin)))
    out: FloatArray = vee * scale[:, None]
    near_pi = small & (cos < 0.0)
    if near_pi.any():  # angle pi: the axis is the column of R + I of largest norm
        B = R[near_pi] + np.eye(3)
        col = np.argmax(np.linalg.norm(B, axis=1), axis=1)
        axis = B[np.arange(len(B)), :, col]
        out[near_pi] = np.pi * axis / np.linalg.norm(axis, axis=1, keepdims=True)
    return out


def pose_error(T_target: FloatArray, T: FloatArray) -> FloatArray:
    """``(n, 6)``: position error [m] then rotation error [rad] (root frame)."""
    dp = T_target[:, :3, 3] - T[:, :3, 3]
    dr = rotation_log(T_target[:, :3, :3] @ np.transpose(T[:, :3, :3], (0, 2, 1)))
    return np.concatenate([dp, dr], axis=1)


def _step(
    J: FloatArray, err: FloatArray, damping: FloatArray, to_ref: FloatArray, opts: NumericIKOptions
) -> FloatArray:
    """Damped least-squares steps ``(m, dof)``, plus the null-space pull ``to_ref`` for a
    redundant chain, clipped to ``max_step``."""
    Jt = np.transpose(J, (0, 2, 1))
    JJt = J @ Jt + (damping**2)[:, None, None] * np.eye(6)
    if J.shape[2] <= 6:
        step = (Jt @ np.linalg.solve(JJt, err[:, :, None]))[:, :, 0]
    else:  # one solve for the step and the null-space projection: (JJt)^-1 [err, J]
        rhs = np.concatenate([err[:, :, None], J], axis=2)
        sol = Jt @ np.linalg.solve(JJt, rhs)  # (m, dof, 1 + dof): J^+ err, J^+ J
        step = sol[:, :, 0] + opts.null_space_gain * (
            to_ref - (sol[:, :, 1:] @ to_ref[:, :, None])[:, :, 0]
        )
    out: FloatArray = np.clip(step, -opts.max_step, opts.max_step)
    return out


#: Damping at which a row that still cannot improve has stalled (it stops descending).
_MAX_DAMPING = 1e2
#: A row whose squared pose error has not dropped below this share of its value
#: :data:`_PROGRESS_WINDOW` iterations before is in a local minimum (it stops descending).
_PROGRESS_RATIO = 0.5
_PROGRESS_WINDOW = 10


def _converged(err: FloatArray, opts: NumericIKOptions) -> BoolArray:
    position = np.linalg.norm(err[:, :3], axis=1) < opts.position_tolerance
    rotation = np.linalg.norm(err[:, 3:], axis=1) < opts.rotation_tolerance
    return np.asarray(position & rotation, dtype=np.bool_)


def numeric_ik(
    chain: Chain,
    T_root_target: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    q_ref: FloatArray | None = None,
    options: NumericIKOptions | None = None,
    seed: int = 0,
) -> NumericIKResult:
    """IK of ``chain``'s end frame for targets ``(n, 4, 4)`` in the root frame, joints within
    ``[lower, upper]`` ``(dof,)``; redundancy resolved toward ``q_ref`` ``(dof,)`` (default:
    the centre of the limits). Deterministic in ``seed``.

    Raises:
        KinematicsError: shapes that do not match the chain, or ``lower > upper``.
    """
    opts = NumericIKOptions() if options is None else options
    T_t = np.asarray(T_root_target, dtype=np.float64).reshape(-1, 4, 4)
    lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    ref = (lo + hi) / 2.0 if q_ref is None else np.asarray(q_ref, dtype=np.float64)
    if lo.shape != (chain.dof,) or hi.shape != lo.shape or ref.shape != lo.shape:
        raise KinematicsError(f"expected limits and reference of shape ({chain.dof},)")
    if np.any(lo > hi):
        raise KinematicsError("lower limits above upper limits")
    n, dof = len(T_t), chain.dof
    rng = np.random.default_rng(seed)
    q_out = np.repeat(ref[None], n, axis=0)
    ok = np.zeros(n, dtype=bool)
    for round_ in range(max(1, opts.rounds)):
        todo = np.flatnonzero(~ok)
        if len(todo) == 0:
            break
        s = max(1, opts.seeds)
        draws = rng.uniform(lo, hi, (len(todo), s, dof))
        if round_ == 0:
            draws[:, 0] = ref  # the reference is the first seed of every target
        q, done = _descend(chain, T_t[todo], draws, lo, hi, ref, opts)
        distance = np.where(done, np.linalg.norm(q - ref, axis=2), np.inf)
        best = np.argmin(distance, axis=1)
        q_out[todo] = q[np.arange(len(todo)), best]
        ok[todo] = np.isfinite(distance[np.arange(len(todo)), best])
    return NumericIKResult(q_out, np.asarray(ok, dtype=np.bool_))


def _descend(
    chain: Chain,
    T_t: FloatArray,
    starts: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    ref: FloatArray,
    opts: NumericIKOptions,
    enough: int | None = None,
) -> tuple[FloatArray, BoolArray]:
    """Damped least squares from ``starts`` ``(n, s, dof)`` toward targets ``(n, 4, 4)``, the
    null space pulled toward ``ref`` ``(dof,)`` or one per start ``(n, s, dof)``: final ``q``
    ``(n, s, dof)`` and which converged ``(n, s)``. A start stops when it converges, when its
    squared error has not fallen by :data:`_PROGRESS_RATIO` in :data:`_PROGRESS_WINDOW`
    iterations, or (``enough``) when ``enough`` starts of its target have converged."""
    n, s, dof = starts.shape
    compiled = ik_kernel.kernel() if opts.compiled else None
    if compiled is not None:
        settings = (
            opts.position_tolerance,
            opts.rotation_tolerance,
            opts.damping,
            opts.max_step,
            opts.null_space_gain,
            opts.null_space_fade,
        )
        refs_all = np.empty(starts.shape)  # writable: the kernel's one signature
        refs_all[...] = ref
        return compiled(
            ik_kernel.pack(chain),
            np.array(T_t, dtype=np.float64, order="C"),
            np.array(starts, dtype=np.float64, order="C"),
            refs_all,
            np.array(lo, dtype=np.float64, order="C"),
            np.array(hi, dtype=np.float64, order="C"),
            settings,
            int(opts.iterations),
            0 if enough is None else int(enough),
        )
    q = starts.reshape(n * s, dof).copy()
    targets = np.repeat(T_t, s, axis=0)
    refs = np.broadcast_to(ref, starts.shape).reshape(n * s, dof)
    damping = np.full(n * s, opts.damping)
    frames, end = chain_fk(chain, q)
    err = pose_error(targets, end)
    cost = np.einsum("ij,ij->i", err, err)
    done = _converged(err, opts)
    live = ~done  # rows still descending: neither converged nor stalled
    checkpoint = cost.copy()
    for it in range(opts.iterations):
        if it and it % _PROGRESS_WINDOW == 0:  # no real progress in a window: a local minimum
            live &= cost < _PROGRESS_RATIO * checkpoint
            checkpoint = cost.copy()
        if enough is not None:  # targets with enough converged starts stop the others
            solved = done.reshape(n, s).sum(axis=1) >= enough
            live &= ~np.repeat(solved, s)
        rows = np.flatnonzero(live)
        if len(rows) == 0:
            break
        qa, ea, da, fa, enda = q[rows], err[rows], damping[rows], frames[rows], end[rows]
        J = chain_jacobian(chain, fa, enda)
        to_ref = refs[rows] - qa
        if opts.null_space_fade > 0.0:
            size = np.sqrt(np.einsum("ij,ij->i", ea, ea))
            to_ref = to_ref * np.minimum(1.0, size / opts.null_space_fade)[:, None]
        step = _step(J, ea, da, to_ref, opts)
        # a joint at a limit that the step pushes outward is frozen: solve without it
        blocked = ((qa <= lo) & (step < 0.0)) | ((qa >= hi) & (step > 0.0))
        some = np.flatnonzero(blocked.any(axis=1))
        if len(some):  # those rows again, without their frozen joints
            Jb = np.where(blocked[some, None, :], 0.0, J[some])
            again = _step(Jb, ea[some], da[some], to_ref[some], opts)
            step[some] = np.where(blocked[some], 0.0, again)
        trial = np.clip(qa + step, lo, hi)
        t_frames, t_end = chain_fk(chain, trial)
        t_err = pose_error(targets[rows], t_end)
        t_cost = np.einsum("ij,ij->i", t_err, t_err)
        better = t_cost < cost[rows]
        # Levenberg-Marquardt: accept and trust the model more, or refuse and damp more
        stalled = ~better & (da >= _MAX_DAMPING)
        damping[rows] = np.where(
            better, np.maximum(da / 3.0, 1e-6), np.minimum(da * 4, _MAX_DAMPING)
        )
        won = rows[better]
        q[won], frames[won], end[won] = trial[better], t_frames[better], t_end[better]
        err[won], cost[won] = t_err[better], t_cost[better]
        done[rows] = _converged(err[rows], opts)
        live[rows] = ~done[rows] & ~stalled
    return q.reshape(n, s, dof), done.reshape(n, s)


def _checked(
    chain: Chain, T_root_target: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    T_t = np.asarray(T_root_target, dtype=np.float64).reshape(-1, 4, 4)
    lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    if lo.shape != (chain.dof,) or hi.shape != lo.shape:
        raise KinematicsError(f"expected limits of shape ({chain.dof},), got {lo.shape}")
    if np.any(lo > hi):
        raise KinematicsError("lower limits above upper limits")
    return T_t, lo, hi


def target_draws(T_targets: FloatArray, seed: int, shape: tuple[int, ...]) -> FloatArray:
    """Uniform draws in ``[0, 1)`` of ``shape`` for each target ``(n, 4, 4)``: ``(n, *shape)``,
    each target's drawn from a generator keyed by ``seed`` and the target's own bytes, so a
    target gets the same starts whatever batch it is solved in (and in whatever order)."""
    out = np.empty((len(T_targets), *shape))
    for i, T in enumerate(T_targets):
        key = int.from_bytes(hashlib.blake2b(T.tobytes(), digest_size=8).digest(), "little")
        out[i] = np.random.default_rng([seed, key]).random(shape)
    return out


def numeric_ik_branches(
    chain: Chain,
    T_root_target: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    q_ref: FloatArray,
    branches: int,
    options: NumericIKOptions | None = None,
    seed: int = 0,
    distinct: float = 1e-3,
) -> tuple[FloatArray, BoolArray]:
    """Up to ``branches`` distinct solutions per target (``(n, 4, 4)`` in the root frame):
    ``q`` ``(n, branches, dof)`` and ``valid`` ``(n, branches)``. Every target is solved from
    ``options.seeds`` starts (``q_ref`` first, then uniform draws inside the limits); targets
    no start solved get fresh starts for up to ``options.rounds`` rounds. A target's draws
    depend only on ``seed`` and the target (:func:`target_draws`), and every step of the
    descent is row by row, so its solutions do not depend on the batch it is solved in.
    Solutions closer than ``distinct`` [rad] on every joint count once; they are ordered by
    their distance from ``q_ref`` (nearest first). Invalid rows hold ``q_ref``.
    Deterministic in ``seed``.

    Raises:
        KinematicsError: shapes that do not match the chain, ``lower > upper`` or
            ``branches < 1``.
    """
    opts = NumericIKOptions() if options is None else options
    T_t, lo, hi = _checked(chain, T_root_target, lower, upper)
    ref = np.asarray(q_ref, dtype=np.float64)
    if ref.shape != lo.shape:
        raise KinematicsError(f"expected a reference of shape ({chain.dof},), got {ref.shape}")
    if branches < 1:
        raise KinematicsError(f"branches must be >= 1, got {branches}")
    n, s = len(T_t), max(1, opts.seeds)
    rounds = max(1, opts.rounds)
    unit = target_draws(T_t, seed, (rounds, s, chain.dof))  # (n, rounds, s, dof) in [0, 1)
    q_out = np.repeat(np.repeat(ref[None, None], n, axis=0), branches, axis=1)
    valid = np.zeros((n, branches), dtype=bool)
    for round_ in range(rounds):
        todo = np.flatnonzero(~valid.any(axis=1))
        if len(todo) == 0:
            break
        draws = lo + (hi - lo) * unit[todo, round_]
        if round_ == 0:
            draws[:, 0] = ref
        q, done = _descend(chain, T_t[todo], draws, lo, hi, ref, opts, enough=branches)
        order = np.argsort(np.where(done, np.linalg.norm(q - ref, axis=2), np.inf), axis=1)
        for row, t in enumerate(todo):
            kept: list[FloatArray] = []
            for k in order[row]:
                if not done[row, k] or len(kept) == branches:
                    break
                if all(np.abs(q[row, k] - other).max() >= distinct for other in kept):
                    kept.append(q[row, k])
            if kept:
                q_out[t, : len(kept)] = kept
                valid[t, : len(kept)] = True
    return q_out, np.asarray(valid, dtype=np.bool_)


def numeric_ik_from(
    chain: Chain,
    T_root_target: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    starts: FloatArray,
    options: NumericIKOptions | None = None,
) -> tuple[FloatArray, BoolArray]:
    """Continue solutions: each target ``(n, 4, 4)`` solved from its own starts ``starts``
    ``(n, b, dof)`` only, the null space pulled toward the start (the nearest solution of
    the start's branch): ``q`` ``(n, b, dof)`` and which converged ``(n, b)``.

    Raises:
        KinematicsError: shapes that do not match the chain or ``lower > upper``.
    """
    opts = NumericIKOptions() if options is None else options
    T_t, lo, hi = _checked(chain, T_root_target, lower, upper)
    q0 = np.asarray(starts, dtype=np.float64)
    if q0.ndim != 3 or q0.shape[0] != len(T_t) or q0.shape[2] != chain.dof:
        raise KinematicsError(
            f"expected starts of shape ({len(T_t)}, b, {chain.dof}), got {q0.shape}"
        )
    q0 = np.clip(q0, lo, hi)
    return _descend(chain, T_t, q0, lo, hi, q0, opts)
