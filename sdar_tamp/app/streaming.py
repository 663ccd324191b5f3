"""Plan while the arms move: each step of ``sdar solve`` emitted as soon as it is planned and
checked (``sdar solve --stream``).

:func:`solve_stream` prepares the instance as :func:`~sdar_tamp.app.pipeline.solve_instance`
does and returns a :class:`PlanStream`: its :attr:`~PlanStream.header` says what a consumer
needs (arms, joint names, start poses); iterating it runs the same solver
(:func:`~sdar_tamp.app.solving.rearrangement_steps`) and yields one :class:`StreamStep` per
executed decision, as the plan file's motion segments and gripper events with absolute times
(:mod:`sdar_tamp.app.stream_records`). Before a step is yielded its stretch of the timeline is
replayed by :class:`~sdar_tamp.replay_steps.StepValidator` against the world as it is then
(joint limits, velocities, collisions along its motions, its gripper events); a rejected
stretch stops the stream with :class:`StepRejected`. When the iteration ends,
:attr:`PlanStream.outcome` holds what ``solve_instance`` returns: the whole plan file,
replayed by the independent validator.

The first step is the one a robot waits for: the trajectory optimiser's background build
(a few tenths of a second of CPU, holding the interpreter much of the time) is deferred until
that step is out, unless the step needs the optimiser, which then starts the build and waits
for it (:class:`~streams.motion.optimiser_build.OptimiserBuild`).

Timing: a stream carries the synchronous execution (``execution="sync"``), the only timing
that is fixed when a step is planned: the asynchronous modes re-time every step against the
whole plan once it is complete. The concatenation of the steps is then the plan that
``solve_instance(..., execution="sync")`` (``sdar solve --execution sync``) writes with the
same seed and options; planning is the same run, step for step.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.pipeline import PreparedSolve, describe, finish_solve, prepare_solve
from sdar_tamp.app.plan_export import decoder_of, plan_builder, timeline
from sdar_tamp.app.records import SolveOutcome, TaskRecord
from sdar_tamp.app.solving import rearrangement_steps
from sdar_tamp.app.stream_records import StreamHeader, StreamStep
from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.plan_building import PlanPart, plan_arms
from sdar_tamp.plan_rules import Violation
from sdar_tamp.replay_steps import StepValidator


class StepRejected(SdarError):
    """The replay rejected a planned step before it was emitted; ``index`` is the step's and
    ``violation`` the replay's first finding."""

    def __init__(self, index: int, violation: Violation) -> None:
        self.index, self.violation = index, violation
        super().__init__(f"step {index} rejected by the replay: {describe(violation)}")


class PlanStream:
    """One streamed solve (see the module docstring); iterate it once."""

    def __init__(
        self,
        prepared: PreparedSolve,
        progress: Callable[[int, int], None] | None = None,
        started: float | None = None,
    ) -> None:
        self.prepared = prepared
        self.progress = progress
        self.started = time.perf_counter() if started is None else started
        r = prepared.rearrangement
        arms = plan_arms(r.ctx.scene)
        instance = prepared.instance
        self.header = StreamHeader(
            instance.name,
            arms,
            {o.name: o.start.as_tuple() for o in instance.objects},
            r.config.gripper_time,
        )
        self.outcome: SolveOutcome | None = None
        self.last_part: PlanPart | None = None  # the end's part: the last dwell
        self._iterated = False

    def __iter__(self) -> Iterator[StreamStep]:
        if self._iterated:
            raise ParameterError("a PlanStream is iterated once")
        self._iterated = True
        prepared = self.prepared
        r = prepared.rearrangement
        builder = plan_builder(r)
        decoder = decoder_of(r)
        checker = StepValidator(prepared.instance, r.ctx.scene)
        steps = rearrangement_steps(r, progress=self.progress)
        while True:
            try:
                planned = next(steps)
            except StopIteration as end:
                solution = end.value
                break
            task = TaskRecord.from_trace(planned.task)
            for item in timeline(planned.actions, (task,), decoder):
                builder.add(item)
            part = builder.take()
            violation = checker.check(part.t, part.q, part.events)
            if violation is not None:
                steps.close()
                raise StepRejected(planned.index, violation)
            # the optimiser's build, deferred, starts once the first step is out (a step that
            # needs the optimiser starts it itself and waits for it)
            prepared.world.planner.start_build()
            yield StreamStep(
                planned.index,
                task.kind,
                task.objects,
                task.arms,
                task.to_buffer,
                time.perf_counter() - self.started,
                part,
            )
        self.outcome = finish_solve(prepared, solution, None, builder)
        if self.outcome.plan is not None:  # the builder finished the plan: its last part
            self.last_part = builder.parts[-1]


def solve_stream(
    instance_path: Path,
    config: PlannerConfig | None = None,
    *,
    time_limit: float | None = None,
    seed: int | None = None,
    task_planner: str | None = None,
    motion_planner: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    cache: PlannerCache | None = None,
    scene: Path | None = None,
) -> PlanStream:
    """:func:`~sdar_tamp.app.pipeline.solve_instance` as a stream of steps (arguments alike;
    the execution is ``"sync"`` whatever ``config`` says, see the module docstring).
    ``planned_at`` of each step counts from this call.

    Raises:
        ParameterError: a value out of range or an unknown planner name.
    """
    started = time.perf_counter()
    prepared = prepare_solve(
        instance_path,
        config,
        time_limit=time_limit,
        seed=seed,
        task_planner=task_planner,
        motion_planner=motion_planner,
        execution="sync",
        cache=cache,
        scene=scene,
        defer_build=True,
    )
    return PlanStream(prepared, progress, started)
