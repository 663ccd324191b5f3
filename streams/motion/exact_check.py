"""Exact validation of a trajectory of k arms with the world's coal collision checker.

Between consecutive samples the configuration is interpolated linearly in joint space so that
no tool centre point moves more than ``max_tcp_step`` [m] (default 5 mm) between two
checks; every check is a full :meth:`CollisionWorld.in_collision` query (every pair of arms, self,
table, resting objects, held objects). Joint limits are checked on every sample, and, when
times are given, the finite-difference velocity and acceleration limits (with a relative
tolerance).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world.collision import CollisionPair, CollisionWorld, ObjectBox
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext


@dataclass(frozen=True, eq=False)
class HeldObject:
    """An object held rigidly by an arm: its box and its pose in the tool0 frame."""

    name: str
    size: tuple[float, float, float]  # [m]
    T_tool0_obj: FloatArray  # (4, 4)


@dataclass(frozen=True)
class ValidationReport:
    """``ok`` or the first failure: its kind, sample index and the colliding pairs."""

    ok: bool
    reason: str = ""
    index: int = -1
    pairs: tuple[CollisionPair, ...] = ()
    checks: int = 0


def configure_world(
    ctx: WorldContext,
    world: CollisionWorld,
    objects: Mapping[str, ObjectBox],
    held: Mapping[str, HeldObject],
    q: FloatArray,
) -> None:
    """Put ``objects`` on the table and ``held`` objects in the hands at ``q`` ``(dof,)``."""
    for arm in ctx.arm_names:
        if world.held_by(arm) is not None:
            world.detach(arm)
    qs = ctx.split(q)
    placed = dict(objects)
    for arm, h in held.items():
        placed[h.name] = ObjectBox(ctx.kinematics[arm].fk_tool0(qs[arm]) @ h.T_tool0_obj, h.size)
    world.set_objects(placed)
    for arm, h in held.items():
        world.attach(arm, h.name, qs[arm])


def interpolate_by_tcp(ctx: WorldContext, q: FloatArray, max_tcp_step: float) -> FloatArray:
    """Samples ``q`` ``(m, dof)`` refined so no TCP moves more than ``max_tcp_step`` [m]."""
    if len(q) < 2:
        return np.asarray(q, dtype=np.float64)
    steps = []
    for arm in ctx.arm_names:
        p = ctx.fk[arm].tcp_positions(ctx.layout.part(q, arm))
        steps.append(np.linalg.norm(np.diff(p, axis=0), axis=1))
    # joint-space chords bend the TCP path; 1.5x covers the curvature between samples
    n = np.maximum(1, np.ceil(1.5 * np.max(steps, axis=0) / max_tcp_step)).astype(int)
    out = [q[:1]]
    for k in range(len(q) - 1):
        s = (np.arange(1, n[k] + 1) / n[k])[:, None]
        out.append(q[k][None] * (1.0 - s) + q[k + 1][None] * s)
    return np.concatenate(out)


def validate_trajectory(
    ctx: WorldContext,
    world: CollisionWorld,
    q: FloatArray,
    t: FloatArray | None = None,
    max_tcp_step: float = 0.005,
    limit_tolerance: float = 1e-3,
    near: CollisionWorld | None = None,
    fine_steps: int = 32,
) -> ValidationReport:
    """Check samples ``q`` ``(m, dof)`` (at times ``t`` ``(m,)`` [s] if given) against the
    world as configured (see :func:`configure_world`).

    ``near``: the same world with a safety distance (such as ``arm_margin``); where a free
    sample collides in ``near``, the chords to its neighbouring samples are checked at
    ``fine_steps`` points each, so a contact between samples (a wrist passing a finger
    within a millimetre) is found wherever a finer replay would place its samples. Every
    collision of ``world`` is one of ``near`` (it only adds a distance), so a sample free in
    ``near`` is not queried in ``world`` again: one query per sample where the arms are apart.
    ``checks`` counts the samples and chord points checked."""
    q = np.asarray(q, dtype=np.float64)
    lo, hi = ctx.scene.joint_array("lower"), ctx.scene.joint_array("upper")
    bad = np.flatnonzero(np.any((q < lo - 1e-9) | (q > hi + 1e-9), axis=1))
    if len(bad):
        return ValidationReport(False, "joint limits", int(bad[0]))
    if t is not None and len(q) > 2:
        v = ctx.scene.joint_array("velocity_limit")
        a = ctx.scene.joint_array("acceleration_limit")
        dt = np.diff(t)
        vel = np.diff(q, axis=0) / dt[:, None]
        acc = np.diff(vel, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
        if np.any(np.abs(vel) > np.array(v) * (1 + limit_tolerance)):
            return ValidationReport(False, "velocity limit", int(np.argmax(np.abs(vel).max(1))))
        if np.any(np.abs(acc) > np.array(a) * (1 + 0.05 + limit_tolerance)):
            return ValidationReport(False, "acceleration limit", int(np.argmax(np.abs(acc).max(1))))
    dense = interpolate_by_tcp(ctx, q, max_tcp_step)
    checks = 0  # samples and chord points checked
    for i, qi in enumerate(dense):
        checks += 1
        if near is not None and not near.in_collision(qi):
            continue  # free with the safety distance: free without it, and not close
        if world.in_collision(qi):
            return ValidationReport(False, "collision", i, world.report(qi), checks)
        if near is None:
            continue
        for j in (i - 1, i + 1):  # the chords on both sides of a close sample
            if not 0 <= j < len(dense):
                continue
            for s in np.linspace(0.0, 1.0, fine_steps + 2)[1:-1]:
                qs = qi + s * (dense[j] - qi)
                checks += 1
                if world.in_collision(qs):
                    return ValidationReport(False, "collision", i, world.report(qs), checks)
    return ValidationReport(True, checks=checks)
