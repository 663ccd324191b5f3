"""Benchmark: synchronous dual-arm pick and place segments (SDAR-M) in a 12-object scene.

Each segment (seeded): both arms start at grasp configurations of their previous action
(retreat first), then each either picks a resting object or places the object it holds at its
goal pose (or a sampled buffer when the goal is occupied), ending with a straight approach.
Grasp IK is ranked for 2 arms x 2 objects x 6 grasps x 8 branches per step and timed.
Every returned trajectory is re-checked with a fresh coal world at 5 mm resolution.

Every segment is planned twice: without fallbacks (``fallbacks=False``, the paper's "plain"
planner) and with the full ladder (plain, untangle, sequential). Optimisation time is the time
spent in the trajectory optimiser for the segment (all attempts of the ladder).

    python benchmarks/bench_motion.py [--segments 200] [--instance M1] [--seed 0]
    python benchmarks/bench_motion.py --hard 12     # needs OMPL (pip install sdar-tamp[ompl])
    python benchmarks/bench_motion.py --quick            # 3 segments: seconds
    python benchmarks/bench_motion.py --quick --hard 1   # 1 hard transfer of each kind

Prints a line per 20 segments, then one JSON object on the last line.

``--quick`` changes only the default of ``--segments`` (3); without OMPL, ``--quick --hard N``
prints ``{"skipped": "<why>", ...}`` as its last line and exits 0. The JSON keys are the same,
plus ``"quick": true``.

``--hard N``: instead, N transfers whose straight joint-space line collides, for one arm
(the other waits at home) and for both arms (N each): each arm goes from a grasp of one
resting object to a grasp of another (retreat and approach included). Four motion planners
side by side on the same requests: the optimiser alone (no direct paths, no fallbacks), the
OMPL stream alone (RRTConnect, shortcut), the ladder with a sampled first rung (direct paths,
sampled path refined by the optimiser, untangling, one arm at a time) and SDAR-M's own ladder
(direct paths, the optimiser from the straight line, from a sampled path, from a lifted via
point, untangling, one arm at a time). Times are CPU seconds of the planning call (the
machine may be shared); execution times are compared on the transfers the planner and OMPL
both solved.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time

import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw
from streams.buffers import sample_buffers
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKCandidate, IKRequest, compatible_pairs, solve_ik_candidates
from streams.motion.exact_check import HeldObject, configure_world, validate_trajectory
from streams.motion.ladder import plan_dual_motion
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest


def _box(x: float, y: float, yaw: float, size: tuple[float, float, float]) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(x, y, size[2] / 2, yaw), size)


def _footprint(box: ObjectBox) -> np.ndarray:
    T = box.T_world_obj
    pose = np.array([[T[0, 3], T[1, 3], np.arctan2(T[1, 0], T[0, 0])]])
    return corners(pose, np.array([box.size[:2]]))


def hard_set(instance: str, seed: int, count: int, quick: bool = False) -> None:
    """See the module docstring (``--hard``)."""
    from streams.motion.sampling import SampledStrategy, sampled_strategies, warm_started_strategies
    from streams.motion.strategies import PlainStrategy

    ctx = WorldContext.load()
    inst = load_instance(domain_path(f"suites/paper/{instance}.yaml"))
    objects = {o.name: _box(o.start.x, o.start.y, o.start.yaw, o.size) for o in inst.objects}
    names = list(objects)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    world = ctx.new_world()
    optimisers = OptimiserCache()  # one optimiser for both planners
    ladder = MotionPlanner(ctx, optimisers=optimisers)
    alone = MotionPlanner(ctx, direct=False, optimisers=optimisers)
    planners = {
        "optimiser": (alone, (PlainStrategy(lifted_warm_start=False),)),
        "ompl": (ladder, (SampledStrategy(),)),
        "ladder": (ladder, sampled_strategies()),
        "sdar-m": (ladder, warm_started_strategies()),
    }
    alone.trajopt  # noqa: B018  (wait for the build: not part of any planning time)
    grasps = {n: sample_grasps(objects[n].size, ctx.scene.grasp_limits) for n in names}
    cands = {
        (a, n): solve_ik_candidates(
            ctx, world, objects, [IKRequest(a, n, objects[n], grasps[n])], home
        )[:2]
        for a in ctx.arm_names
        for n in names
    }
    rng = np.random.default_rng(seed)
    requests: dict[str, list[MotionRequest]] = {"one_arm": [], "both_arms": []}
    tries = 0
    while min(len(r) for r in requests.values()) < count and tries < 5000:
        tries += 1
        kind = "one_arm" if len(requests["one_arm"]) < count else "both_arms"
        pick = [str(x) for x in rng.choice(names, 4, replace=False)]
        qs = []
        for i, arm in enumerate(ctx.arm_names):
            if kind == "one_arm" and i == 1:
                qs.append((home[arm], home[arm]))
                continue
            a, b = cands[(arm, pick[2 * i])], cands[(arm, pick[2 * i + 1])]
            if not a or not b:
                break
            qs.append((a[int(rng.integers(len(a)))].q, b[int(rng.integers(len(b)))].q))
        if len(qs) < 2:
            continue
        q0 = np.concatenate([qs[0][0], qs[1][0]])
        q1 = np.concatenate([qs[0][1], qs[1][1]])
        if world.in_collision(q0) or world.in_collision(q1):
            continue
        moving = (True, kind == "both_arms")
        request = MotionRequest(q0, q1, objects, retreat=moving, approach=moving)
        configure_world(ctx, ladder.world, objects, {}, q0)
        phases = ladder.phases(request)
        if phases is None:
            continue
        q_from, q_to = phases[0][0][-1], phases[1][0][0]
        line = np.linspace(0.0, 1.0, 40)[:, None] * (q_to - q_from)[None] + q_from[None]
        if validate_trajectory(ctx, ladder.world, line).ok:
            continue  # the straight line is clear: not a hard transfer
        requests[kind].append(request)
    out: dict[str, object] = {"benchmark": "bench_motion_hard", "instance": instance, "seed": seed}
    check = ctx.new_world()
    for kind, reqs in requests.items():
        rows: dict[str, list[tuple[bool, float, float]]] = {}
        for name, (planner, strategies) in planners.items():
            rows[name] = []
            for request in reqs:
                t = time.process_time()
                result = plan_dual_motion(planner, request, strategies=strategies)
                cpu = time.process_time() - t
                ok = result.success and result.trajectory is not None
                if ok and result.trajectory is not None:
                    configure_world(ctx, check, request.objects, request.held, request.q_start)
                    assert validate_trajectory(ctx, check, result.trajectory.q).ok
                duration = result.trajectory.duration if result.trajectory else float("nan")
                rows[name].append((ok, cpu, duration))
        summary: dict[str, object] = {"transfers": len(reqs)}
        for name, r in rows.items():
            solved = [x for x in r if x[0]]
            # execution on the transfers this planner and OMPL both solved
            common = [x[2] for x, o in zip(r, rows["ompl"], strict=True) if x[0] and o[0]]
            summary[name] = {
                "solved": len(solved),
                "time_median_s": float(np.median([x[1] for x in r])) if r else None,
                "time_median_solved_s": float(np.median([x[1] for x in solved]))
                if solved
                else None,
                "execution_median_common_s": float(np.median(common)) if common else None,
            }
            print(f"{kind:>9} {name:>9}: solved {len(solved)}/{len(r)}, median CPU "
                  f"{summary[name]['time_median_s']:.3f} s, execution (common) "  # type: ignore[str-format]
                  f"{summary[name]['execution_median_common_s']}", flush=True)  # fmt: skip
        out[kind] = summary
    out["quick"] = quick
    print(json.dumps(out))


#: ``--quick``'s defaults
QUICK = {"segments": 3}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--segments", type=int, default=200)
    ap.add_argument("--instance", default="M1")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--verbose", action="store_true", help="print every non-plain segment")
    ap.add_argument("--hard", type=int, default=0, help="the hard set instead (see above)")
    ap.add_argument("--quick", action="store_true", help="3 segments: seconds")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        ap.set_defaults(**QUICK)
        args = ap.parse_args(argv)
    if args.hard:
        if args.quick and importlib.util.find_spec("ompl") is None:
            why = "OMPL is not installed (pip install sdar-tamp[ompl])"
            print(f"skipped: {why}")
            print(json.dumps({"benchmark": "bench_motion_hard", "skipped": why, "quick": True}))
            return
        hard_set(args.instance, args.seed, args.hard, args.quick)
        return

    ctx = WorldContext.load()
    t_build = time.perf_counter()
    planner = MotionPlanner(ctx)
    build_time = time.perf_counter() - t_build
    inst = load_instance(domain_path(f"suites/paper/{args.instance}.yaml"))
    start = {o.name: _box(o.start.x, o.start.y, o.start.yaw, o.size) for o in inst.objects}
    goal = {o.name: _box(o.goal.x, o.goal.y, o.goal.yaw, o.size) for o in inst.objects}
    names = list(start)
    rng = np.random.default_rng(args.seed)
    world = ctx.new_world()
    check_world = ctx.new_world()
    grasps = {n: sample_grasps(start[n].size, ctx.scene.grasp_limits) for n in names}
    home = {a: ctx.home(a) for a in ctx.arm_names}
    left, right = ctx.arm_names

    ik_times: list[float] = []
    opt_times: list[float] = []
    plain_opt_times: list[float] = []
    plain_ok = 0
    no_ipopt = 0
    plan_times: list[float] = []
    levels = {"plain": 0, "untangle": 0, "sequential": 0}
    done = failed = skipped = bad_success = 0
    exec_times: list[float] = []
    t_all = time.perf_counter()
    while done + failed < args.segments:
        if skipped > 20 * args.segments:
            break
        pick = [bool(rng.random() < 0.5) for _ in range(2)]
        chosen = [str(n) for n in rng.choice(names, 4, replace=False)]
        prev, target = chosen[:2], chosen[2:]
        resting = dict(start)
        held: dict[str, HeldObject] = {}
        # start: the arm just placed `prev` (pick segments) or just picked `target` (place)
        start_objs = [prev[i] if pick[i] else target[i] for i in range(2)]
        req0 = [
            IKRequest(a, o, start[o], grasps[o])
            for a, o in zip(ctx.arm_names, start_objs, strict=True)
        ]
        c0 = [solve_ik_candidates(ctx, world, resting, [r], home) for r in req0]
        p0 = compatible_pairs(ctx, world, resting, c0[0], c0[1])
        if not p0:
            skipped += 1
            continue
        cand0: tuple[IKCandidate, IKCandidate] = p0[0]
        for i, arm in enumerate(ctx.arm_names):
            if not pick[i]:  # holding target[i], grasped with cand0[i]
                o = target[i]
                T_tool0_obj = (
                    inverse(ctx.kinematics[arm].fk_tool0(cand0[i].q)) @ start[o].T_world_obj
                )
                held[arm] = HeldObject(o, start[o].size, T_tool0_obj)
                del resting[o]
        # targets: pick -> the object at its start; place -> its goal, or a buffer if taken
        boxes: list[ObjectBox] = []
        for i, arm in enumerate(ctx.arm_names):
            o = target[i]
            if pick[i]:
                boxes.append(start[o])
                continue
            taken = [_footprint(b) for b in resting.values()] + [_footprint(b) for b in boxes]
            occupied = np.concatenate(taken) if taken else np.zeros((0, 4, 2))
            if not overlap_matrix(_footprint(goal[o]), occupied).any():
                boxes.append(goal[o])
            else:
                buf = sample_buffers(
                    ctx, arm, start[o].size, occupied, 1, int(rng.integers(1 << 30))
                )
                if not buf:
                    break
                boxes.append(_box(buf[0].x, buf[0].y, buf[0].yaw, start[o].size))
        if len(boxes) < 2:
            skipped += 1
            continue
        # IK ranking step: 2 arms x 2 objects x 6 grasps (x 8 branches)
        q_now = {arm: (cand0[i].q) for i, arm in enumerate(ctx.arm_names)}
        reqs = [
            IKRequest(a, target[j], boxes[j], grasps[target[j]])
            for a in ctx.arm_names
            for j in range(2)
        ]
        t = time.perf_counter()
        cands = solve_ik_candidates(ctx, world, resting, reqs, q_now)
        ik_times.append(time.perf_counter() - t)
        # a place keeps the grasp the object was picked with
        ok_grasp = [None if pick[i] else cand0[i].grasp for i in range(2)]
        c_left = [c for c in cands if c.arm == left and c.obj == target[0]
                  and ok_grasp[0] in (None, c.grasp)]  # fmt: skip
        c_right = [c for c in cands if c.arm == right and c.obj == target[1]
                   and ok_grasp[1] in (None, c.grasp)]  # fmt: skip
        p1 = compatible_pairs(ctx, world, resting, c_left, c_right)
        if not p1:
            skipped += 1
            continue
        q_start = np.concatenate([cand0[0].q, cand0[1].q])
        q_goal = np.concatenate([p1[0][0].q, p1[0][1].q])
        request = MotionRequest(q_start, q_goal, resting, held, (True, True), (True, True))
        plain = plan_dual_motion(planner, request, fallbacks=False)
        plain_ok += int(plain.success)
        no_ipopt += int(plain.success and plain.ipopt_solves == 0)
        plain_opt_times.append(plain.optimisation_time)
        result = plan_dual_motion(planner, request)
        if args.verbose and result.level != "plain":
            pairs = result.validation.pairs[:2] if result.validation else ()
            print(f"segment {done + failed}: pick {pick} -> {result.attempts} {pairs}", flush=True)
        opt_times.append(result.optimisation_time)
        plan_times.append(result.planning_time)
        if result.success and result.trajectory is not None and result.level is not None:
            done += 1
            levels[result.level] += 1
            exec_times.append(result.trajectory.duration)
            configure_world(ctx, check_world, resting, held, q_start)
            if not validate_trajectory(
                ctx, check_world, result.trajectory.q, max_tcp_step=0.005
            ).ok:
                bad_success += 1
        else:
            failed += 1
        n = done + failed
        if n % 20 == 0:
            print(f"{n} segments: {done} ok, levels {levels}, median opt "
                  f"{1e3 * float(np.median(opt_times)):.1f} ms", flush=True)  # fmt: skip
    n = done + failed
    out = {
        "benchmark": "bench_motion",
        "instance": args.instance,
        "segments": n,
        "seed": args.seed,
        "success_rate_with_fallbacks": done / n if n else 0.0,
        "success_rate_without_fallbacks": plain_ok / n if n else 0.0,
        "levels": levels,
        "failures": failed,
        "plain_without_ipopt_straight_line_feasible": no_ipopt,
        "validation_failures_returned_as_success": bad_success,
        "opt_time_median_s": float(np.median(opt_times)) if opt_times else None,
        "opt_time_p90_s": float(np.percentile(opt_times, 90)) if opt_times else None,
        "opt_time_median_without_fallbacks_s": (
            float(np.median(plain_opt_times)) if plain_opt_times else None
        ),
        "planning_time_median_s": float(np.median(plan_times)) if plan_times else None,
        "ik_ranking_median_s": float(np.median(ik_times)) if ik_times else None,
        "ik_ranking_p90_s": float(np.percentile(ik_times, 90)) if ik_times else None,
        "execution_time_median_s": float(np.median(exec_times)) if exec_times else None,
        "skipped_unsampleable": skipped,
        "nlp_build_time_s": build_time,
        "wall_time_s": time.perf_counter() - t_all,
        "quick": args.quick,
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
