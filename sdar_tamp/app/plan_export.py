"""How a solution becomes a plan file: the plan's motions and gripper events, in order.

Actions are read through the domain and :class:`~solvers.sdar.vocabulary.SdarVocabulary`,
not by argument position: a gripper action's events are its ``holding`` effects (added by a
pick, deleted by a place: arm, object and grasp by parameter name, one event per effect, so an
action may work any number of grippers); a move's trajectory is the output of the
vocabulary's motion stream, found through the fact that stream certifies and the move
requires. The domain must have the vocabulary's move, pick and place; its two-gripper
actions (``pick-both``, ``place-both``) are read when it has them.

Simultaneous gripper actions: the events of one action, and those of consecutive gripper
actions with no move between them (several ``pick`` or ``place`` actions at one
configuration, as a task planner for k arms may emit them), are consecutive items of the
timeline, which :func:`~sdar_tamp.plan_building.build_plan_file` puts at one instant with one
dwell (a second action of the same arm waits for the first's dwell).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from sdar_tamp.app.problem import Rearrangement
from sdar_tamp.app.records import TaskRecord, task_records
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import ActionSchema, Domain
from sdar_tamp.language.stream_model import StreamFile
from sdar_tamp.language.traversal import iter_atoms, iter_effect_literals
from sdar_tamp.plan_building import GripperEvent, MotionSegment, PlanBuilder, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.transforms import inverse
from solvers.sdar.vocabulary import SdarVocabulary
from solvers.solution import Action, Solution
from streams.grasps import Grasp
from streams.motion.records import MotionResult


@dataclass(frozen=True)
class GripperAction:
    """One gripper's part of a pick or place: arm, object and grasp."""

    arm: str
    obj: str
    grasp: Grasp


class ActionDecoder:
    """Reads the plan actions of a rearrangement domain by the names of its vocabulary.

    Raises:
        ParameterError: the domain lacks the vocabulary's move, pick or place, a gripper
            action has no ``holding`` effect, or no move precondition is certified by the
            motion stream.
    """

    def __init__(
        self, domain: Domain, streams: StreamFile, vocabulary: SdarVocabulary | None = None
    ) -> None:
        self.vocabulary = voc = vocabulary or SdarVocabulary()
        actions = {a.name: a for a in domain.actions}
        missing = [n for n in (voc.move, voc.pick, voc.place) if n not in actions]
        if missing:
            raise ParameterError(f"the domain has no action(s) {', '.join(missing)}")
        self._grippers: dict[str, tuple[bool, tuple[tuple[int, int, int], ...]]] = {}
        for name, pick in (
            (voc.pick, True),
            (voc.place, False),
            (voc.pick_both, True),
            (voc.place_both, False),
        ):
            if name not in actions:  # a domain without two-gripper actions (say, for k arms)
                continue
            action = actions[name]
            index = {p.name: i for i, p in enumerate(action.parameters)}
            parts = tuple(
                (index[lit.atom.args[0]], index[lit.atom.args[1]], index[lit.atom.args[2]])
                for lit in iter_effect_literals(action.effect)
                if lit.atom.predicate == voc.holding and lit.negated != pick
            )
            if not parts:
                raise ParameterError(f"action {name!r} has no {voc.holding!r} effect")
            self._grippers[name] = (pick, parts)
        self._trajectory = self._trajectory_index(actions[voc.move], streams)

    def _trajectory_index(self, move: ActionSchema, streams: StreamFile) -> int:
        voc = self.vocabulary
        stream = next((s for s in streams.streams if s.name == voc.motion), None)
        if stream is None or not stream.outputs:
            raise ParameterError(f"the stream file has no motion stream {voc.motion!r}")
        output = stream.outputs[0]
        index = {p.name: i for i, p in enumerate(move.parameters)}
        for certified in stream.certified:
            if output not in certified.args:
                continue
            position = certified.args.index(output)
            for atom in iter_atoms(move.precondition):
                if atom.predicate == certified.predicate and atom.args[position] in index:
                    return index[atom.args[position]]
        raise ParameterError(
            f"action {voc.move!r} requires no fact that stream {voc.motion!r} certifies"
        )

    def is_move(self, action: Action) -> bool:
        return action.name == self.vocabulary.move

    def trajectory(self, action: Action) -> MotionResult:
        """The motion of a move action."""
        result = action.args[self._trajectory]
        if not isinstance(result, MotionResult) or result.trajectory is None:
            raise ParameterError(f"{action.name}: no trajectory in its arguments")
        return result

    def gripper(self, action: Action) -> tuple[bool, tuple[GripperAction, ...]]:
        """``(is_pick, parts)`` of a pick or place action (one part per gripper)."""
        if action.name not in self._grippers:
            raise ParameterError(f"{action.name!r} is neither a move nor a gripper action")
        pick, parts = self._grippers[action.name]
        args = action.args
        return pick, tuple(GripperAction(args[a], args[o], args[g]) for a, o, g in parts)


def decoder_of(rearrangement: Rearrangement) -> ActionDecoder:
    problem = rearrangement.problem
    return ActionDecoder(problem.domain, problem.streams)


def timeline(
    plan: Sequence[Action], tasks: Sequence[TaskRecord], decoder: ActionDecoder
) -> list[MotionSegment | GripperEvent]:
    """The plan's motions and gripper events in order (every event of an action of several
    grippers; consecutive gripper actions stay consecutive, hence simultaneous).
    ``tasks`` label the motions (kind and objects of the task each belongs to)."""
    labels = [(t.kind, t.objects) for t in tasks for _ in range(t.motions)]
    items: list[MotionSegment | GripperEvent] = []
    motions = 0
    for action in plan:
        if decoder.is_move(action):
            result = decoder.trajectory(action)
            traj = result.trajectory
            assert traj is not None
            kind, objects = labels[motions] if motions < len(labels) else ("", ())
            items.append(MotionSegment(traj.t, traj.q, result.level or "", objects, kind))
            motions += 1
            continue
        pick, parts = decoder.gripper(action)
        for part in parts:
            event = "grasp" if pick else "release"
            T_tcp_object = inverse(part.grasp.T_object_tcp)
            items.append(GripperEvent(part.arm, event, part.obj, T_tcp_object))
    return items


def motion_levels(plan: Sequence[Action], decoder: ActionDecoder) -> dict[str, int]:
    """Motion level (how the motion stream found each motion) -> number of motions."""
    levels: dict[str, int] = {}
    for action in plan:
        if decoder.is_move(action):
            level = str(decoder.trajectory(action).level)
            levels[level] = levels.get(level, 0) + 1
    return dict(sorted(levels.items()))


def plan_file_from_solution(
    rearrangement: Rearrangement,
    solution: Solution,
    metrics: Mapping[str, float | int | str] | None = None,
    gripper_time: float | None = None,
) -> PlanFile:
    """The timed plan file of a solved rearrangement (planning figures in ``metrics``;
    ``gripper_time`` [s] defaults to the configuration's)."""
    if solution.plan is None:
        raise ParameterError("solution has no plan (status: " + solution.status.value + ")")
    instance = rearrangement.instance
    items = timeline(solution.plan, task_records(solution), decoder_of(rearrangement))
    return build_plan_file(
        rearrangement.ctx.scene,
        instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        items,
        plan_metrics(solution, metrics),
        gripper_time=rearrangement.config.gripper_time if gripper_time is None else gripper_time,
        q_start=rearrangement.start_conf.q,
    )


def plan_builder(rearrangement: Rearrangement, gripper_time: float | None = None) -> PlanBuilder:
    """The :class:`~sdar_tamp.plan_building.PlanBuilder` that :func:`plan_file_from_solution`
    builds its plan file with (``gripper_time`` [s] defaults to the configuration's), for a
    caller that adds the items of each step as it is planned."""
    instance = rearrangement.instance
    return PlanBuilder(
        rearrangement.ctx.scene,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        rearrangement.home.q,
        rearrangement.config.gripper_time if gripper_time is None else gripper_time,
    )


def plan_metrics(
    solution: Solution, metrics: Mapping[str, float | int | str] | None = None
) -> dict[str, float | int | str]:
    """The plan file's planning figures of ``solution``, with ``metrics`` added."""
    stats = solution.statistics
    figures: dict[str, float | int | str] = {
        "planning_time": float(stats.get("planning_time", 0.0)),
        "planning_time_selection": float(stats.get("selection_time", 0.0)),
        "planning_time_motion": float(stats.get("motion_time", 0.0)),
    }
    figures.update(metrics or {})
    return figures
