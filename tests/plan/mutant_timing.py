"""Mutants that break the timeline rules: joint, velocity and acceleration limits, dwells,
event times, jumps, time stamps, non-finite values."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterator

import numpy as np

from sdar_tamp.world.transforms import FloatArray
from tests.plan.mutant_base import (
    JOINTS,
    Base,
    Mutant,
    acceleration,
    index,
    instants,
    moving_mask,
    remove,
    retime,
    scene_arms,
    smooth_bump,
    velocity,
    with_events,
    with_q,
)


# -- mutant families ---------------------------------------------------------------------------
def _joint_limits(b: Base) -> Iterator[Mutant]:
    scene, q = b.ctx.scene, b.plan.q
    for j, name in enumerate(JOINTS):
        for delta in (1e-7,):
            hi, lo = float(q[:, j].max()), float(q[:, j].min())
            for field, value in (("upper", hi - delta), ("lower", lo + delta)):
                yield Mutant(
                    "joint limit",
                    f"scene {name} {field} {delta}",
                    b.plan,
                    frozenset({"joint limit"}),
                    scene=scene_arms(scene, j, field, value),
                    mention=name,
                )
        limits = scene.arms[j // 6]
        for sign in (1.0, -1.0):
            edge = limits.upper[j % 6] if sign > 0 else limits.lower[j % 6]
            far = float(q[:, j].max() if sign > 0 else q[:, j].min())
            if abs(edge) > 3.0:  # +-pi joints: the offset would be a large rotation
                continue
            moved = np.array(q)
            moved[:, j] += edge - far + sign * 1e-3
            yield Mutant(
                "joint limit",
                f"plan {name} {sign:+.0f}",
                with_q(b.plan, moved),
                frozenset({"joint limit", "grasp", "collision"}),
                fine=True,
            )


def _velocity_limits(b: Base) -> Iterator[Mutant]:
    scene, v = b.ctx.scene, np.abs(velocity(b.plan))
    for j, name in enumerate(JOINTS):
        peak = float(v[:, j].max())
        if peak < 0.1:
            continue
        for eps in (1e-4,):
            yield Mutant(
                "velocity",
                f"scene {name} {eps}",
                b.plan,
                frozenset({"velocity"}),
                scene=scene_arms(scene, j, "velocity_limit", peak / (1.0 + eps)),
                mention=name,
            )
        v_max = scene.arms[j // 6].velocity_limit[j % 6]
        i = int(np.argmax(v[:, j]))
        for eps in (0.01, 0.03, 0.05):
            h = np.diff(b.plan.t)
            h[i] *= peak / (v_max * (1.0 + eps))  # this one interval is run faster
            yield Mutant(
                "velocity", f"plan {name} {eps}", retime(b.plan, h), frozenset({"velocity"})
            )


def _acceleration_limits(b: Base) -> Iterator[Mutant]:
    scene, plan = b.ctx.scene, b.plan
    acc = np.abs(acceleration(plan))
    a_max = np.concatenate([a.acceleration_limit for a in scene.arms])
    v_max = np.concatenate([a.velocity_limit for a in scene.arms])
    a_ratio = float((acc / a_max).max())
    v_ratio = float((np.abs(velocity(plan)) / v_max).max())
    for eps in (1e-5, 1e-3, 0.01, 0.02, 0.03, 0.05, 0.24):
        s = math.sqrt(a_ratio / (1.0 + eps))  # motion (not the dwells) runs 1/s times faster
        expect = {"acceleration"} | ({"velocity"} if v_ratio / s > 1.0 else set())
        h = np.diff(plan.t)
        h = np.where(moving_mask(plan), h * s, h)
        yield Mutant("acceleration", f"faster motion {eps}", retime(plan, h), frozenset(expect))
    for j, name in enumerate(JOINTS):
        peak = float(acc[:, j].max())
        if peak < 0.5:
            continue
        for eps in (1e-4,):
            yield Mutant(
                "acceleration",
                f"scene {name} {eps}",
                plan,
                frozenset({"acceleration"}),
                scene=scene_arms(scene, j, "acceleration_limit", peak / (1.0 + eps)),
                mention=name,
            )
    # the plan ends, or starts, in full motion
    moving = moving_mask(plan)
    last = index(plan, instants(plan)[-1]) + 26
    for k in (last + 10, last + 20, last + 30):
        assert moving[k - 1]
        cut = dataclasses.replace(plan, t=plan.t[: k + 1], q=plan.q[: k + 1])
        yield Mutant(
            "acceleration",
            f"ends moving at {k}",
            cut,
            frozenset({"acceleration"}),
            mention="when the plan ends",
        )
    first = int(np.argmax(moving))
    for k in (2, 3, 5):
        late = remove(plan, first + 1, k)  # the first k motion samples gone: starts fast
        late = dataclasses.replace(late, t=late.t[first:] - late.t[first], q=late.q[first:])
        events = tuple(dataclasses.replace(e, t=e.t - plan.t[first]) for e in late.events)
        yield Mutant(
            "acceleration",
            f"starts moving {k}",
            dataclasses.replace(late, events=events),
            frozenset({"acceleration"}),
            mention="when it starts",
        )


def _dwells(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    for t_e in instants(plan):
        k = index(plan, t_e)
        for n in (1, 2, 3, 5, 8, 12, 17, 21, 24, 25):  # 0.02 .. 0.5 s of the dwell removed
            yield Mutant(
                "dwell", f"t={t_e:.2f} minus {n}", remove(plan, k + 1, n), frozenset({"dwell"})
            )
        for factor in (0.99, 0.999, 0.9999):
            h = np.diff(plan.t)
            h[k : k + 25] *= factor
            yield Mutant("dwell", f"t={t_e:.2f} x{factor}", retime(plan, h), frozenset({"dwell"}))
        for j, name in enumerate(JOINTS):  # either arm moves a little during the dwell
            q = np.array(plan.q)
            q[k : k + 26, j] += 1e-4 * smooth_bump(26)
            yield Mutant(
                "dwell",
                f"t={t_e:.2f} {name} moves",
                with_q(plan, q),
                frozenset({"dwell"}),
                mention=name,
            )
    # a second action of one gripper within the dwell
    grasp = plan.events[0]
    for dt in (0.0, 0.1, 0.3):
        again = dataclasses.replace(grasp, t=grasp.t + dt, type="release")
        yield Mutant(
            "dwell",
            f"release {dt} s after grasp",
            with_events(plan, [*plan.events, again]),
            frozenset({"dwell"}),
        )
    # the plan ends before a dwell is over
    t_r = instants(plan)[-1]
    k = index(plan, t_r)
    for n in (0, 5, 24):
        cut = dataclasses.replace(plan, t=plan.t[: k + n + 1], q=plan.q[: k + n + 1])
        yield Mutant("dwell", f"ends {n} samples after release", cut, frozenset({"dwell"}))


def _moved_events(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    shifts = (-0.5, -0.1, -0.02, -0.001, 0.001, 0.02, 0.1, 0.49, 1.0)
    expect = frozenset({"dwell", "grasp", "release"})
    for i, e in enumerate(plan.events):
        for dt in shifts:
            events = list(plan.events)
            events[i] = dataclasses.replace(e, t=e.t + dt)
            yield Mutant(
                "event moved", f"{e.arm} {e.type} {dt:+}", with_events(plan, events), expect
            )
    for t_e in instants(plan):
        for dt in shifts:
            events = [dataclasses.replace(e, t=e.t + dt) if e.t == t_e else e for e in plan.events]
            yield Mutant("event moved", f"t={t_e:.2f} {dt:+}", with_events(plan, events), expect)


def _jumps(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    moving = moving_mask(plan)
    inside_motion = int(np.flatnonzero(moving)[40])
    inside_dwell = index(plan, instants(plan)[0]) + 10
    expect = frozenset({"velocity", "acceleration", "dwell", "joint limit"})
    for j, name in enumerate(JOINTS):
        for k, size, kind in itertools.product(
            (inside_motion, inside_dwell), (0.01, -0.1), ("spike", "step")
        ):
            q = np.array(plan.q)
            if kind == "spike":
                q[k, j] += size
            else:
                q[k:, j] += size
            yield Mutant("jump", f"{kind} {name} {size} at {k}", with_q(plan, q), expect)


def _time_stamps(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    n = len(plan.t)
    expect = frozenset({"format"})
    for k in (1, n // 3, n // 2, n - 1):
        edits: dict[str, Callable[[FloatArray], None]] = {
            "repeated": lambda t, k=k: t.__setitem__(k, t[k - 1]),
            "backwards": lambda t, k=k: t.__setitem__(k, t[k - 1] - 0.001),
            "gap": lambda t, k=k: t.__setitem__(slice(k, None), t[k:] + 0.021),
        }
        for name, edit in edits.items():
            t = np.array(plan.t)
            edit(t)
            events = tuple(
                e if e.t <= t[-1] else dataclasses.replace(e, t=float(t[-1])) for e in plan.events
            )
            yield Mutant(
                "time",
                f"{name} at {k}",
                dataclasses.replace(plan, t=t, events=events),
                expect,
                mention=f"trajectory.t[{k}]",
            )
    t = np.array(plan.t)
    t[[n // 2, n // 2 + 1]] = t[[n // 2 + 1, n // 2]]
    yield Mutant("time", "swapped", dataclasses.replace(plan, t=t), expect)
    yield Mutant("time", "late start", dataclasses.replace(plan, t=plan.t + 0.01), expect)
    for t_bad in (-0.1, plan.duration + 0.01):
        events = list(plan.events)
        events[-1] = dataclasses.replace(events[-1], t=t_bad)
        yield Mutant(
            "time", f"event at {t_bad:.2f}", dataclasses.replace(plan, events=tuple(events)), expect
        )
    unsorted = (plan.events[2], *plan.events[:2], *plan.events[3:])
    yield Mutant("time", "events unsorted", dataclasses.replace(plan, events=unsorted), expect)


def _non_finite(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    n = len(plan.t)
    expect = frozenset({"format"})
    for value in (math.nan, math.inf, -math.inf):
        for k, j in ((0, 0), (n // 2, 7), (n - 1, 11)):
            q = np.array(plan.q)
            q[k, j] = value
            yield Mutant(
                "non-finite",
                f"q[{k},{j}]={value}",
                with_q(plan, q),
                expect,
                mention=f"trajectory.q[{k}]",
            )
        t = np.array(plan.t)
        t[n // 2] = value
        yield Mutant("non-finite", f"t={value}", dataclasses.replace(plan, t=t), expect)
        e = plan.events[1]
        T = np.array(e.T_tcp_object)
        T[0, 3] = value
        events = (plan.events[0], dataclasses.replace(e, T_tcp_object=T), *plan.events[2:])
        yield Mutant(
            "non-finite", f"T_tcp_object {value}", dataclasses.replace(plan, events=events), expect
        )
        events = (plan.events[0], dataclasses.replace(e, t=value), *plan.events[2:])
        yield Mutant(
            "non-finite", f"event t {value}", dataclasses.replace(plan, events=events), expect
        )
        final = dict(plan.final_poses)
        final["o1"] = (value, 0.0, 0.0)
        yield Mutant(
            "non-finite",
            f"final pose {value}",
            dataclasses.replace(plan, final_poses=final),
            expect,
        )
        for i, key in itertools.product((0, 1), ("T_world_base", "home")):
            value_array = np.array(getattr(plan.arms[i], key))
            value_array.flat[3] = value
            arms = list(plan.arms)
            arms[i] = dataclasses.replace(arms[i], **{key: value_array})
            yield Mutant(
                "non-finite",
                f"arms[{i}].{key} {value}",
                dataclasses.replace(plan, arms=(arms[0], arms[1])),
                frozenset({"scene"}),
                mention=f"arms[{i}].{key}",
            )


TIMING_FAMILIES: tuple[Callable[[Base], Iterator[Mutant]], ...] = (
    _joint_limits,
    _velocity_limits,
    _acceleration_limits,
    _dwells,
    _moved_events,
    _jumps,
    _time_stamps,
    _non_finite,
)
