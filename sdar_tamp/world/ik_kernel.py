"""The numeric IK's descent compiled by numba, one start at a time.

:func:`descend_rows` does what :func:`.numeric_ik._descend` does with numpy (damped least
squares, Levenberg-Marquardt damping per start, the null-space pull toward a reference that
fades near the pose, joints blocked at a limit solved without, a start stopping when it
converges, stalls or makes no progress in a window), but for one start after the other in
compiled loops: the numpy version spends most of its time in the overhead of small array
operations (some 1 ms per iteration of a batch), the compiled one some microseconds per start
and iteration. The starts of one target run in order; once ``enough`` of them have converged
the others are not run (the numpy version runs them side by side and stops the rest when
``enough`` have converged, so the two may keep different solutions; each is a converged
solution within the limits).

numba is imported only when the kernel is first needed; the machine code is cached beside
this module (the first process compiles it, a few seconds). Where numba cannot load or compile
it, :func:`kernel` returns None (once per process) and the numpy descent is used.
"""

from __future__ import annotations

import importlib.util
import logging
from collections.abc import Callable
from typing import Any

import numpy as np

from sdar_tamp.world._pin import Chain
from sdar_tamp.world.transforms import BoolArray, FloatArray

_log = logging.getLogger(__name__)

#: Packed chain: joint placements ``(dof, 4, 4)``, unit axes ``(dof, 3)``, kinds (1: prismatic,
#: 2: revolute about +z, 0: other revolute) ``(dof,)`` and the end frame's placement ``(4, 4)``.
PackedChain = tuple[FloatArray, FloatArray, Any, FloatArray]


def pack(chain: Chain) -> PackedChain:
    """The arrays of ``chain`` the kernel reads."""
    placements = np.ascontiguousarray(np.stack([j.T_parent_joint for j in chain.joints]))
    axes = np.ascontiguousarray(np.stack([j.axis / np.linalg.norm(j.axis) for j in chain.joints]))
    kinds = np.array(
        [
            1 if j.kind == "prismatic" else 2 if a[0] == 0.0 and a[1] == 0.0 and a[2] > 0.0 else 0
            for j, a in zip(chain.joints, axes, strict=True)
        ],
        dtype=np.int64,
    )
    end = np.ascontiguousarray(chain.T_joint_frame, dtype=np.float64)
    return placements.astype(np.float64), axes.astype(np.float64), kinds, end


def _dot4(A: Any, B: Any, r: int, c: int) -> float:
    """Entry ``(r, c)`` of ``A @ B`` for ``(4, 4)`` matrices."""
    return float(A[r, 0] * B[0, c] + A[r, 1] * B[1, c] + A[r, 2] * B[2, c] + A[r, 3] * B[3, c])


def _fk(chain: Any, q: Any, frames: Any, end: Any) -> None:
    """Joint frames ``(dof, 4, 4)`` and the end frame ``(4, 4)`` of ``q`` into ``frames``, ``end``
    (no arrays allocated: each joint's frame is the previous one times its placement, then
    turned)."""
    placements, axes, kinds, end_T = chain
    for i in range(len(q)):
        P = placements[i]
        F = frames[i]
        if i == 0:
            F[:, :] = P
        else:
            G = frames[i - 1]
            for r in range(4):
                for c in range(4):
                    F[r, c] = _dot4(G, P, r, c)
        a = axes[i]
        if kinds[i] == 1:  # prismatic
            for r in range(3):
                F[r, 3] += (F[r, 0] * a[0] + F[r, 1] * a[1] + F[r, 2] * a[2]) * q[i]
        elif kinds[i] == 2:  # about z: turn x and y
            cq, sq = np.cos(q[i]), np.sin(q[i])
            for r in range(3):
                x, y = F[r, 0], F[r, 1]
                F[r, 0] = cq * x + sq * y
                F[r, 1] = cq * y - sq * x
        else:  # Rodrigues: R = cos I + sin K + (1 - cos) a a^T, K the axis' cross matrix
            cq, sq = np.cos(q[i]), np.sin(q[i])
            v = 1.0 - cq
            R00, R11, R22 = cq + v * a[0] * a[0], cq + v * a[1] * a[1], cq + v * a[2] * a[2]
            R01, R10 = v * a[0] * a[1] - sq * a[2], v * a[0] * a[1] + sq * a[2]
            R02, R20 = v * a[0] * a[2] + sq * a[1], v * a[0] * a[2] - sq * a[1]
            R12, R21 = v * a[1] * a[2] - sq * a[0], v * a[1] * a[2] + sq * a[0]
            for r in range(3):
                x, y, z = F[r, 0], F[r, 1], F[r, 2]
                F[r, 0] = x * R00 + y * R10 + z * R20
                F[r, 1] = x * R01 + y * R11 + z * R21
                F[r, 2] = x * R02 + y * R12 + z * R22
    G = frames[len(q) - 1]
    for r in range(4):
        for c in range(4):
            end[r, c] = _dot4(G, end_T, r, c)


def _error(target: Any, end: Any, err: Any) -> float:
    """The pose error ``(6,)`` (position, then rotation vector of ``R_t R^T``) into ``err``;
    returns its squared norm."""
    R = np.zeros((3, 3))
    for r in range(3):
        err[r] = target[r, 3] - end[r, 3]
        for c in range(3):
            R[r, c] = target[r, 0] * end[c, 0] + target[r, 1] * end[c, 1] + target[r, 2] * end[c, 2]
    cos = min(1.0, max(-1.0, (R[0, 0] + R[1, 1] + R[2, 2] - 1.0) / 2.0))
    angle = np.arccos(cos)
    sin = np.sin(angle)
    vx, vy, vz = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    if sin >= 1e-9:
        scale = angle / (2.0 * sin)
        err[3], err[4], err[5] = vx * scale, vy * scale, vz * scale
    elif cos >= 0.0:
        err[3], err[4], err[5] = vx * 0.5, vy * 0.5, vz * 0.5
    else:  # angle pi: the axis is the column of R + I of largest norm
        best, norm = 0, -1.0
        for col in range(3):
            R[col, col] += 1.0
        for col in range(3):
            n = np.sqrt(R[0, col] ** 2 + R[1, col] ** 2 + R[2, col] ** 2)
            if n > norm:
                best, norm = col, n
        for r in range(3):
            err[3 + r] = np.pi * R[r, best] / norm
    total = 0.0
    for r in range(6):
        total += err[r] * err[r]
    return total


def _jacobian(chain: Any, frames: Any, end: Any, J: Any) -> None:
    """The geometric Jacobian ``(6, dof)`` of the end frame into ``J``."""
    _, axes, kinds, _ = chain
    for i in range(len(kinds)):
        a, F = axes[i], frames[i]
        z0 = F[0, 0] * a[0] + F[0, 1] * a[1] + F[0, 2] * a[2]
        z1 = F[1, 0] * a[0] + F[1, 1] * a[1] + F[1, 2] * a[2]
        z2 = F[2, 0] * a[0] + F[2, 1] * a[1] + F[2, 2] * a[2]
        if kinds[i] == 1:
            J[0, i], J[1, i], J[2, i] = z0, z1, z2
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0
        else:
            d0, d1, d2 = end[0, 3] - F[0, 3], end[1, 3] - F[1, 3], end[2, 3] - F[2, 3]
            J[0, i] = z1 * d2 - z2 * d1
            J[1, i] = z2 * d0 - z0 * d2
            J[2, i] = z0 * d1 - z1 * d0
            J[3, i], J[4, i], J[5, i] = z0, z1, z2


def _step(
    J: Any,
    err: Any,
    damping: float,
    to_ref: Any,
    gain: float,
    max_step: float,
    work: Any,
    step: Any,
) -> None:
    """The damped least-squares step ``(dof,)`` into ``step``, plus the null-space pull for a
    redundant chain, clipped to ``max_step``: ``J^T (J J^T + d^2 I)^-1 [err, J]`` by Cholesky
    (``work`` ``(6, 7 + dof)``: the factor, then the right-hand sides)."""
    dof = J.shape[1]
    L = work[:, :6]
    Y = work[:, 6:]
    for i in range(6):  # the Cholesky factor of J J^T + d^2 I
        for j in range(i + 1):
            s = damping * damping if i == j else 0.0
            for k in range(dof):
                s += J[i, k] * J[j, k]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = np.sqrt(s) if i == j else s / L[j, j]
    m = 1 + dof if dof > 6 else 1
    for c in range(m):
        for i in range(6):
            v = err[i] if c == 0 else J[i, c - 1]
            for k in range(i):
                v -= L[i, k] * Y[k, c]
            Y[i, c] = v / L[i, i]
        for i in range(5, -1, -1):
            v = Y[i, c]
            for k in range(i + 1, 6):
                v -= L[k, i] * Y[k, c]
            Y[i, c] = v / L[i, i]
    for i in range(dof):  # J^T Y: J^+ err (column 0) and J^+ J (the others)
        v = 0.0
        for k in range(6):
            v += J[k, i] * Y[k, 0]
        step[i] = v
    if dof > 6:
        for i in range(dof):
            pulled = to_ref[i]
            for j in range(dof):
                p = 0.0
                for k in range(6):
                    p += J[k, i] * Y[k, 1 + j]
                pulled -= p * to_ref[j]
            step[i] += gain * pulled
    for i in range(dof):
        step[i] = min(max(step[i], -max_step), max_step)


def _descend_one(
    chain: Any, target: Any, q: Any, ref: Any, lo: Any, hi: Any, settings: Any, iterations: int
) -> bool:
    """One start's descent, ``q`` ``(dof,)`` updated in place; True when it converged."""
    position_tol, rotation_tol, damping, max_step, gain, fade = settings
    dof = len(q)
    frames, end = np.empty((dof, 4, 4)), np.empty((4, 4))
    t_frames, t_end = np.empty((dof, 4, 4)), np.empty((4, 4))
    err, t_err, J, Jb = np.empty(6), np.empty(6), np.empty((6, dof)), np.empty((6, dof))
    to_ref, step, trial = np.empty(dof), np.empty(dof), np.empty(dof)
    blocked = np.zeros(dof, dtype=np.bool_)
    work = np.empty((6, 7 + dof))
    _fk(chain, q, frames, end)
    cost = _error(target, end, err)
    checkpoint = cost
    for it in range(iterations):
        if _converged(err, position_tol, rotation_tol):
            return True
        if it and it % 10 == 0:  # no real progress in a window: a local minimum
            if not cost < 0.5 * checkpoint:
                return False
            checkpoint = cost
        _jacobian(chain, frames, end, J)
        pull = 1.0 if fade <= 0.0 else min(1.0, np.sqrt(cost) / fade)
        for j in range(dof):
            to_ref[j] = (ref[j] - q[j]) * pull
        _step(J, err, damping, to_ref, gain, max_step, work, step)
        # a joint at a limit that the step pushes outward is frozen: solve without it
        any_blocked = False
        for j in range(dof):
            blocked[j] = (q[j] <= lo[j] and step[j] < 0.0) or (q[j] >= hi[j] and step[j] > 0.0)
            any_blocked = any_blocked or blocked[j]
        if any_blocked:
            for j in range(dof):
                for r in range(6):
                    Jb[r, j] = 0.0 if blocked[j] else J[r, j]
            _step(Jb, err, damping, to_ref, gain, max_step, work, step)
            for j in range(dof):
                if blocked[j]:
                    step[j] = 0.0
        for j in range(dof):
            trial[j] = min(max(q[j] + step[j], lo[j]), hi[j])
        _fk(chain, trial, t_frames, t_end)
        t_cost = _error(target, t_end, t_err)
        if t_cost < cost:  # Levenberg-Marquardt: accept and trust the model more
            damping = max(damping / 3.0, 1e-6)
            q[:] = trial
            frames[:], end[:], err[:] = t_frames, t_end, t_err
            cost = t_cost
        elif damping >= 1e2:  # refused at the largest damping: stalled
            return False
        else:  # refused: damp more
            damping = min(damping * 4.0, 1e2)
    return _converged(err, position_tol, rotation_tol)


def _converged(err: Any, position_tol: float, rotation_tol: float) -> bool:
    position = np.sqrt(err[0] ** 2 + err[1] ** 2 + err[2] ** 2)
    rotation = np.sqrt(err[3] ** 2 + err[4] ** 2 + err[5] ** 2)
    return bool(position < position_tol and rotation < rotation_tol)


def descend_rows(
    chain: Any,
    targets: Any,
    starts: Any,
    refs: Any,
    lo: Any,
    hi: Any,
    settings: Any,
    iterations: int,
    enough: int,
) -> tuple[Any, Any]:
    """Every target's ``(n, 4, 4)`` starts ``(n, s, dof)`` in order, each pulled toward its
    reference ``refs`` ``(n, s, dof)``; a target's remaining starts are skipped once
    ``enough`` (> 0) of them converged. Final ``q`` ``(n, s, dof)`` and which converged
    ``(n, s)``. ``settings``: position and rotation tolerance, initial damping, largest step,
    null-space gain, fade."""
    n, s, _ = starts.shape
    q = starts.copy()
    done = np.zeros((n, s), dtype=np.bool_)
    for t in range(n):
        found = 0
        for k in range(s):
            if enough > 0 and found >= enough:
                break
            if _descend_one(chain, targets[t], q[t, k], refs[t, k], lo, hi, settings, iterations):
                done[t, k] = True
                found += 1
    return q, done


_loaded: list[Callable[..., tuple[FloatArray, BoolArray]] | None] = []


def kernel() -> Callable[..., tuple[FloatArray, BoolArray]] | None:
    """:func:`descend_rows` compiled (loaded or compiled once per process), or None where numba
    cannot run it (then the caller descends with numpy)."""
    if not _loaded:
        _loaded.append(_compile())
    return _loaded[0]


def _compile() -> Callable[..., tuple[FloatArray, BoolArray]] | None:
    if importlib.util.find_spec("numba") is None:
        _log.info("numba is not installed: the numeric IK descends with numpy")
        return None
    try:
        import numba

        jit = numba.njit(cache=True, nogil=True)
        glob = globals()
        for name in ("_dot4", "_fk", "_error", "_jacobian", "_step", "_converged"):
            glob[name] = jit(glob[name])
        glob["_descend_one"] = jit(_descend_one)
        compiled = jit(descend_rows)
        _probe(compiled)
        return compiled
    except Exception as error:  # a broken numba or llvmlite, an unsupported platform
        _log.warning("numba cannot run the numeric IK (%s): it descends with numpy", error)
        return None


def _probe(compiled: Callable[..., tuple[FloatArray, BoolArray]]) -> None:
    """Compile (or load) the kernel now, on a one-joint chain."""
    placements, axes = np.eye(4)[None], np.array([[0.0, 0.0, 1.0]])
    chain = (placements, axes, np.array([2], dtype=np.int64), np.eye(4))
    z = np.zeros((1, 1, 1))
    compiled(chain, np.eye(4)[None], z, z, z[0, 0], z[0, 0] + 1.0, _settings_of(), 1, 0)


def _settings_of(
    position: float = 1e-6,
    rotation: float = 1e-6,
    damping: float = 1e-2,
    max_step: float = 0.5,
    gain: float = 0.1,
    fade: float = 0.0,
) -> tuple[float, float, float, float, float, float]:
    return (position, rotation, damping, max_step, gain, fade)
