"""The replay's walk along a plan's timeline: collisions, gripper events and the end state.

The rules and tolerances are those of :mod:`sdar_tamp.replay` (``POS_TOL`` [m] and
``ANGLE_TOL`` [rad] for poses; the contact rule of :func:`contact_allowed`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanEvent, PlanFile, PlanObservation
from sdar_tamp.plan_rules import STILL_TOL, Violation
from sdar_tamp.replay_sampling import tcp_subdivisions
from sdar_tamp.world.collision import CollisionPair, CollisionWorld, ObjectBox
from sdar_tamp.world.footprint import corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw

POS_TOL = 1e-3  #: [m]
ANGLE_TOL = math.radians(1.0)  #: [rad]
#: Rotations mapping a cuboid onto itself (pi about x, y or z).
_SYMMETRY = [np.diag(d) for d in ((1.0, 1, 1), (1.0, -1, -1), (-1.0, 1, -1), (-1.0, -1, 1))]


def _pose_error(T_a: FloatArray, T_b: FloatArray) -> tuple[float, float]:
    """Distance [m] and rotation angle [rad] between two cuboid poses, modulo symmetry."""
    R = T_a[:3, :3].T @ T_b[:3, :3]
    trace = max(float(np.trace(R @ S)) for S in _SYMMETRY)
    angle = math.acos(min(1.0, max(-1.0, (trace - 1.0) / 2.0)))
    return float(np.linalg.norm(T_a[:3, 3] - T_b[:3, 3])), angle


def _planar_error(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float]:
    """Distance [m] and yaw difference modulo pi [rad] of two ``(x, y, yaw)`` poses."""
    d = (a[2] - b[2]) % math.pi
    return math.hypot(a[0] - b[0], a[1] - b[1]), min(d, math.pi - d)


def contact_allowed(pair: CollisionPair, exempt: Mapping[str, tuple[str, FloatArray]]) -> bool:
    """The contact rule: ``pair`` is the gripper of an arm touching the object of its grasp or
    release while that arm stands at its event configuration (``exempt``: arm -> (object,
    configuration))."""
    for arm, (obj, _) in exempt.items():
        target = f"object:{obj}"
        other = pair.second if pair.first == target else pair.first if pair.second == target else ""
        if other.startswith(f"{arm}_gripper"):
            return True
    return False


def describe_contacts(pairs: list[CollisionPair], world: CollisionWorld, limit: int = 3) -> str:
    """The colliding ``pairs`` as a message: the first ``limit`` pairs of shapes, led by the
    arms in contact when a pair joins two arms (``arms south and north in contact: ...``;
    a held object counts as its arm's)."""
    arms: list[str] = []
    for p in pairs:
        a, b = world.owner(p.first), world.owner(p.second)
        if a is not None and b is not None and a != b:
            both = " and ".join(sorted((a, b), key=world.layout.names.index))
            if both not in arms:
                arms.append(both)
    text = ", ".join(f"{p.first} with {p.second}" for p in pairs[:limit])
    text += " ..." if len(pairs) > limit else ""
    return f"arms {'; '.join(arms)} in contact: {text}" if arms else text


class ReplayWalk:
    """The state of the world along the timeline (resting and held objects), walked once in
    time order by :meth:`walk`, which returns the first violation of the replay rules.
    Without a ``plan``, the timeline comes in stretches to :meth:`walk_samples` (a plan being
    planned) and :meth:`final` checks nothing about ``final_poses``."""

    def __init__(
        self,
        instance: Instance,
        plan: PlanFile | None,
        scene: Scene,
        step: float,
        kins: dict[str, ArmKinematics],
        world: CollisionWorld,
    ) -> None:
        self.instance, self.plan, self.scene, self.step = instance, plan, scene, step
        self.kins = kins
        self.layout = scene.layout
        self.sizes = {o.name: o.size for o in instance.objects}
        for seen in () if plan is None else plan.observations:
            self.sizes.update(seen.added)
        self.rest = {o.name: o.start.as_tuple() for o in instance.objects}
        self.held: dict[str, tuple[str, FloatArray]] = {}  # arm -> (object, T_tcp_object)
        self.exempt: dict[str, tuple[str, FloatArray]] = {}  # arm -> (object, q_arm)
        self.world = world
        self.world.set_objects({n: self.box(n, p) for n, p in self.rest.items()})
        self.checks = 0
        self.free: FloatArray | None = None  # the last configuration found free

    def box(self, name: str, pose: tuple[float, ...]) -> ObjectBox:
        size = self.sizes[name]
        return ObjectBox(pose_xyz_yaw(pose[0], pose[1], size[2] / 2.0, pose[2]), size)

    def arm_q(self, arm: str, q: FloatArray) -> FloatArray:
        return self.layout.part(q, arm)

    def tcp(self, arm: str, q: FloatArray) -> FloatArray:
        return self.kins[arm].fk_tcp(self.arm_q(arm, q))

    # -- collisions -----------------------------------------------------------------------------
    def collide(self, q: FloatArray, t: float) -> Violation | None:
        if self.free is not None and np.array_equal(q, self.free):
            return None  # standing still in an unchanged world
        self.checks += 1
        for arm, (_, q_event) in list(self.exempt.items()):
            if np.abs(self.arm_q(arm, q) - q_event).max() > STILL_TOL:
                del self.exempt[arm]  # the arm has moved: contact counts again
        if not self.world.in_collision(q):
            self.free = q.copy()
            return None
        pairs = [p for p in self.world.report(q) if not self.allowed(p)]
        if not pairs:
            return None
        return Violation(t, "collision", describe_contacts(pairs, self.world))

    def allowed(self, p: CollisionPair) -> bool:
        return contact_allowed(p, self.exempt)

    def subdivisions(self, q: FloatArray) -> NDArray[np.int_]:
        """See :func:`tcp_subdivisions`."""
        return tcp_subdivisions(q, self.kins, self.layout, self.step)

    # -- the walk -------------------------------------------------------------------------------
    def start_from(
        self, resting: Mapping[str, tuple[float, float, float]], held: Mapping[str, str],
        q: FloatArray, T_tcp_object: Mapping[str, FloatArray],
    ) -> None:  # fmt: skip
        """Begin a walk later than ``t = 0`` (:meth:`walk` with ``t_from``) from a known state:
        the ``resting`` objects, arm -> ``held`` object (held at ``T_tcp_object[arm]``) at the
        configuration ``q`` ``(dof,)`` of that time."""
        self.rest = {n: (float(p[0]), float(p[1]), float(p[2])) for n, p in resting.items()}
        self.world.set_objects({n: self.box(n, p) for n, p in self.rest.items()})
        for arm, obj in held.items():
            T_obj = self.tcp(arm, q) @ T_tcp_object[arm]
            self.world.set_object(obj, ObjectBox(T_obj, self.sizes[obj]))
            self.world.attach(arm, obj, self.arm_q(arm, q))
            self.held[arm] = (obj, np.asarray(T_tcp_object[arm]))
        self.free = None

    def walk(self, t_stop: float, t_from: float = 0.0) -> Violation | None:
        """Replay from ``t_from`` (see :meth:`start_from`) until ``t_stop`` [s] (exclusive);
        the first violation, or None."""
        plan = self.plan
        if plan is None:
            raise ParameterError("the walk has no plan: walk its samples with walk_samples")
        events = [e for e in plan.events if e.t >= t_from]
        seen = [o for o in plan.observations if o.t >= t_from]
        found = self.walk_samples(plan.t, plan.q, events, t_stop, t_from, seen)
        moments = [e.t for e in plan.events] + [o.t for o in plan.observations]
        end = max(float(plan.t[-1]), max(moments, default=0.0))
        if found is not None or t_stop <= end:
            return found
        return self.final(end)

    def walk_samples(
        self,
        t: FloatArray,
        q: FloatArray,
        events: Sequence[PlanEvent],
        t_stop: float = math.inf,
        t_from: float = -math.inf,
        observations: Sequence[PlanObservation] = (),
    ) -> Violation | None:
        """Replay samples ``q`` ``(n, dof)`` at ``t`` ``(n,)`` [s], ``events`` and
        ``observations`` (each sorted by time, within ``t``) from ``t_from`` until ``t_stop``
        [s] (exclusive), from the state the walk is in; the first violation, or None. Walking
        a timeline in consecutive stretches (each starting with the last sample of the one
        before) checks what one walk checks."""
        knot_t = np.union1d(t, [e.t for e in events] + [o.t for o in observations])
        knot_t = knot_t[: int(np.searchsorted(knot_t, t_stop)) + 1]  # the last one: to t_stop
        knot_t = knot_t[int(np.searchsorted(knot_t, t_from)) :]
        columns = range(self.layout.dof)
        knot_q = np.stack([np.interp(knot_t, t, q[:, j]) for j in columns], axis=1)
        counts = self.subdivisions(knot_q) if len(knot_t) > 1 else np.zeros(0, dtype=int)
        pending = list(events)
        seen = list(observations)
        for k, tk in enumerate(knot_t):
            if tk >= t_stop:
                return None
            while seen and seen[0].t <= tk:
                found = self.observe(seen.pop(0))
                if found is not None:
                    return found
            group = [e for e in pending if e.t <= tk]
            pending = pending[len(group) :]
            for e in group:
                self.exempt[e.arm] = (e.object, self.arm_q(e.arm, knot_q[k]).copy())
            found = self.collide(knot_q[k], float(tk))
            for e in group:
                found = found or self.apply(e, knot_q[k], float(tk))
            if group and found is None:
                found = self.collide(knot_q[k], float(tk))
            if found is not None:
                return found
            if k + 1 < len(knot_t):
                n = int(counts[k])
                for s in range(1, n):
                    t_s = float(tk + (knot_t[k + 1] - tk) * s / n)
                    if t_s >= t_stop:
                        return None
                    q_s = knot_q[k] + (knot_q[k + 1] - knot_q[k]) * (s / n)
                    found = self.collide(q_s, t_s)
                    if found is not None:
                        return found
        return None

    def observe(self, seen: PlanObservation) -> Violation | None:
        """The observed arrangement replaces the planned one: footprints inside the workspace
        and clear of each other, no held object among them (the arms are checked against it
        by the collision check of the same instant)."""
        t = seen.t
        held = {o: a for a, (o, _) in self.held.items()}
        for name in seen.resting:
            if name in held:
                return Violation(
                    t, "observation", f"{name} is seen resting but {held[name]} holds it"
                )
            if name not in self.sizes:
                return Violation(t, "observation", f"{name} is neither the instance's nor added")
        names = sorted(seen.resting)
        if names:
            rect = corners(
                np.array([seen.resting[n] for n in names]),
                np.array([self.sizes[n][:2] for n in names]),
            )
            ws = self.instance.workspace
            out = ~inside_rectangle(rect, (ws.x[0] - POS_TOL, ws.x[1] + POS_TOL),
                                    (ws.y[0] - POS_TOL, ws.y[1] + POS_TOL))  # fmt: skip
            if out.any():
                name = names[int(np.flatnonzero(out)[0])]
                return Violation(t, "observation", f"{name} is seen outside the workspace")
            shrunk = corners(
                np.array([seen.resting[n] for n in names]),
                np.array([self.sizes[n][:2] for n in names]) - 2.0 * POS_TOL,
            )
            over = np.triu(overlap_matrix(shrunk, rect), k=1)
            if over.any():
                i, j = np.argwhere(over)[0]
                return Violation(t, "observation", f"{names[i]} is seen overlapping {names[j]}")
        self.free = None
        self.rest = {n: (float(p[0]), float(p[1]), float(p[2])) for n, p in seen.resting.items()}
        self.world.set_objects({n: self.box(n, p) for n, p in self.rest.items()})
        return None

    def apply(self, e: PlanEvent, q: FloatArray, t: float) -> Violation | None:
        """Check and perform one gripper event at configuration ``q`` ``(dof,)``."""
        self.free = None  # the world changes
        T_world_tcp = self.tcp(e.arm, q)
        if e.type == "grasp":
            if e.arm in self.held:
                return Violation(
                    t, "grasp", f"{e.arm} grasps {e.object} while holding {self.held[e.arm][0]}"
                )
            if e.object not in self.rest:
                return Violation(t, "grasp", f"{e.arm} grasps {e.object}, which is not resting")
            T_obj = self.box(e.object, self.rest[e.object]).T_world_obj
            d, a = _pose_error(T_world_tcp @ e.T_tcp_object, T_obj)
            if d > POS_TOL or a > ANGLE_TOL:
                return Violation(
                    t,
                    "grasp",
                    f"{e.arm} grasps {e.object} with the tool "
                    f"{d * 1e3:.1f} mm / {math.degrees(a):.1f} deg away from it "
                    "(tolerance 1 mm / 1 deg)",
                )
            del self.rest[e.object]
            self.held[e.arm] = (e.object, inverse(T_world_tcp) @ T_obj)
            self.world.attach(e.arm, e.object, self.arm_q(e.arm, q))
            return None
        holding = self.held.get(e.arm)
        if holding is None or holding[0] != e.object:
            what = holding[0] if holding else "nothing"
            return Violation(t, "release", f"{e.arm} releases {e.object} but holds {what}")
        d, a = _pose_error(holding[1], e.T_tcp_object)
        if d > POS_TOL or a > ANGLE_TOL:
            return Violation(
                t,
                "release",
                f"{e.arm} releases {e.object} with T_tcp_object "
                f"{d * 1e3:.1f} mm / {math.degrees(a):.1f} deg off the grasp",
            )
        T = T_world_tcp @ holding[1]
        lz = self.sizes[e.object][2]
        tilt = math.acos(min(1.0, abs(float(T[2, 2]))))
        if abs(T[2, 3] - lz / 2.0) > POS_TOL or tilt > ANGLE_TOL:
            return Violation(
                t,
                "release",
                f"{e.object} released at z = {T[2, 3]:.4f} m tilted "
                f"{math.degrees(tilt):.1f} deg; it must rest flat on the table "
                f"(z = {lz / 2:.4f} m)",
            )
        pose = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))
        size = np.array(self.sizes[e.object][:2])
        ws = self.instance.workspace
        rect = corners(np.array([pose]), size)
        if not inside_rectangle(
            rect, (ws.x[0] - POS_TOL, ws.x[1] + POS_TOL), (ws.y[0] - POS_TOL, ws.y[1] + POS_TOL)
        )[0]:
            return Violation(
                t,
                "release",
                f"{e.object} released at ({pose[0]:.3f}, {pose[1]:.3f}) m leaves the workspace",
            )
        shrunk = corners(np.array([pose]), size - 2.0 * POS_TOL)
        for other, p in self.rest.items():
            rect_o = corners(np.array([p]), np.array(self.sizes[other][:2]))
            if overlap_matrix(shrunk, rect_o)[0, 0]:
                return Violation(t, "release", f"{e.object} released onto {other}")
        del self.held[e.arm]
        self.world.detach(e.arm, self.arm_q(e.arm, q))
        self.world.set_object(e.object, self.box(e.object, pose))
        self.rest[e.object] = pose
        return None

    def final(self, t: float) -> Violation | None:
        if self.held:
            what = ", ".join(f"{a} holds {o}" for a, (o, _) in self.held.items())
            return Violation(t, "held", f"the plan ends with {what}")
        goals = {o.name: o.goal.as_tuple() for o in self.instance.objects}
        names = list(goals)
        plan = self.plan
        if plan is not None and plan.observations:  # objects gone or come: those on the table
            names = [n for n in goals if n in self.rest] + sorted(set(self.rest) - set(goals))
            differ = sorted(set(self.rest) ^ set(plan.final_poses))
            if differ:
                return Violation(
                    t, "final poses", f"final_poses and the objects on the table differ: {differ}"
                )
        for name in names:
            checks = [] if plan is None else [("final poses", plan.final_poses[name])]
            if name in goals:
                checks.insert(0, ("goal", goals[name]))
            for kind, ref in checks:
                d, a = _planar_error(self.rest[name], ref)
                if d > POS_TOL or a > ANGLE_TOL:
                    x, y, yaw = self.rest[name]
                    return Violation(
                        t,
                        kind,
                        f"{name} ends at ({x:.4f}, {y:.4f}, {yaw:.4f}), "
                        f"{d * 1e3:.1f} mm / {math.degrees(a):.1f} deg from "
                        f"{kind} {tuple(round(v, 4) for v in ref)}",
                    )
        return None
