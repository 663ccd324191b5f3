"""The retreat and approach of a synchronous segment: the lift of each grasp, the straight tool
moves up from the start and down to the goal (synchronised, or one arm after the other), and
the transfer problem between the two lifted configurations."""

from __future__ import annotations

import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.cartesian import straight_tool_move
from streams.motion.records import MotionRequest, TransferProblem, flag
from streams.motion.shape import ShapeOptions, clearance_lift
from streams.motion.sphere_pairs import HeldSpheres
from streams.motion.spheres import object_spheres
from streams.motion.waypoints import chain_arms, sync_arms

#: Spheres per resting object in the optimiser's obstacle model (8: one per octant, tight
#: enough that a pre-grasp beside a neighbour does not start inside its sphere).
OBSTACLE_SPHERES = 8


def grasp_lifts(
    ctx: WorldContext, shape: ShapeOptions, request: MotionRequest, fixed: float | None = None
) -> tuple[list[float], list[float]]:
    """Per arm, the lift [m] of its retreat and of its approach: ``fixed`` (default the
    request's ``lift``) for every grasp, or, when both are None, from the clearance of
    each grasp's neighbours (the shape's default lift where that is unusable)."""
    lift = fixed if fixed is not None else request.lift
    n = len(ctx.layout)
    if lift is not None:
        return [lift] * n, [lift] * n
    out: tuple[list[float], list[float]] = ([], [])
    for arm in ctx.arm_names:
        kin = ctx.kinematics[arm]
        sl = ctx.layout.slice(arm)
        h = request.held.get(arm)
        ends = (request.q_start[sl], request.q_goal[sl])
        xy = [kin.fk_tcp(q)[:2, 3] for q in ends]
        for side, q in enumerate(ends):
            held = None
            if h is not None:
                held = ObjectBox(kin.fk_tool0(q) @ h.T_tool0_obj, h.size)
            envelope = ctx.scene.arm(arm).gripper.envelope
            found = clearance_lift(
                kin.fk_tcp(q), envelope, request.objects, held, shape, xy[1 - side]
            )
            out[side].append(found if found is not None else shape.default_lift)
    return out


def retreat_and_approach(
    ctx: WorldContext,
    shape: ShapeOptions,
    request: MotionRequest,
    one_at_a_time: bool = False,
    lift: float | None = None,
    last_first: bool = False,
) -> tuple[list[FloatArray], list[FloatArray]] | None:
    """Retreat and approach as lists of paths ``(n, dof)``: one synchronised (padded) path
    each, or, with ``one_at_a_time``, one arm's after the other's (layout order; with
    ``last_first`` the retreat in the reverse order, the mirror of an approach made one arm
    at a time: the arm that came down last goes up first); None if a straight tool move is
    unreachable. ``lift`` [m]: fixed for every grasp (default: :func:`grasp_lifts`)."""
    ret, app = [], []
    up, down = grasp_lifts(ctx, shape, request, lift)
    step = shape.step
    for i, arm in enumerate(ctx.arm_names):
        kin = ctx.kinematics[arm]
        sl = ctx.layout.slice(arm)
        q0, q1 = request.q_start[sl], request.q_goal[sl]
        r = straight_tool_move(kin, q0, -up[i], step) if flag(request.retreat, i) else q0[None]
        a = straight_tool_move(kin, q1, -down[i], step) if flag(request.approach, i) else q1[None]
        if r is None or a is None:
            return None
        ret.append(r)
        app.append(a[::-1])
    if one_at_a_time:
        order = range(len(ret) - 1, -1, -1) if last_first else None
        return chain_arms(ret, order), chain_arms(app)
    return [sync_arms(ret)], [sync_arms(app)]


def transfer_problem(
    ctx: WorldContext, held_slots: int, request: MotionRequest, q_from: FloatArray, q_to: FloatArray
) -> TransferProblem:
    """The transfer from ``q_from`` to ``q_to``: the held objects as ``held_slots`` spheres
    each (tool0 frame), the resting ones as :data:`OBSTACLE_SPHERES` each."""
    held = []
    for arm in ctx.arm_names:
        h = request.held.get(arm)
        if h is None:
            held.append(HeldSpheres.empty())
        else:
            c, r = object_spheres(h.size, h.T_tool0_obj, held_slots)
            held.append(HeldSpheres(c, r))
    cs, rs = [], []
    for box in request.objects.values():
        c, r = object_spheres(box.size, box.T_world_obj, OBSTACLE_SPHERES)
        cs.append(c)
        rs.append(r)
    obstacles = (np.concatenate(cs), np.concatenate(rs)) if cs else (np.zeros((0, 3)), np.zeros(0))
    return TransferProblem(q_from, q_to, tuple(held), obstacles)
