"""The transfer strategies of SDAR-M's ladder (the paper's Alg. 2), each producing the
transfer between the lifted configurations as a list of stages:

* ``plain`` (:class:`PlainStrategy`): one synchronous optimisation, warm-started from the
  straight line, then from a lifted via-point (SDAR-M's stream map, where OMPL is installed,
  tries a sampled collision-free path's warm start in between:
  :func:`streams.motion.sampling.warm_started_strategies`);
* ``untangle`` (:class:`UntangleStrategy`, rules in ``docs/arm_untangling.md``): the arm that
  reaches deepest into the shared middle of the table yields: it moves to a lifted park pose
  above its own side while every other arm goes straight to its goal; then it moves to its
  own goal while the others wait. If that fails, the next deepest arm yields, and so on;
* ``sequential`` (:class:`SequentialStrategy`): the deepest arm retracts to its home pose,
  the other arms move to their goals (together, else one at a time, deepest first), then the
  first arm moves to its goal; if that fails, the next deepest arm retracts first;
* ``one-arm`` (:class:`OneArmStrategy`): the baseline motion planner's transfer.

Every strategy works for any number of arms placed anywhere around the table: "deep" is
:meth:`~streams.motion.transfers.Transfers.depth`, how far an arm's TCP reaches past the
table centre along the direction its base faces. With two arms the orders above are those of
the two-arm planner (the arm reaching deeper into the other's half first).

A strategy gets the call's :class:`~streams.motion.transfers.Transfers` (optimised and direct
transfers, warm starts, park poses) and the :class:`~streams.motion.records.TransferProblem`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sdar_tamp.world.transforms import FloatArray
from streams.motion.records import TransferProblem
from streams.motion.transfers import Transfers


class TransferStrategy(Protocol):
    """Produces the transfer as a list of stages (each a ``(k, dof)`` path) or None."""

    @property
    def name(self) -> str: ...

    def __call__(
        self, transfers: Transfers, problem: TransferProblem
    ) -> list[FloatArray] | None: ...


def _only(i: int, n: int) -> tuple[bool, ...]:
    """Per-arm ``fixed`` flags with every arm but ``i`` waiting."""
    return tuple(k != i for k in range(n))


#: A further attempt at a transfer: the optimised path, or None.
Rescue = Callable[[Transfers, TransferProblem], "FloatArray | None"]


@dataclass(frozen=True)
class PlainStrategy:
    """One synchronous optimisation: straight-line warm start, then ``rescue`` (if any),
    then a lifted via-point.

    ``rescue`` is tried between the two warm starts; SDAR-M's is
    :func:`streams.motion.sampling.sampled_warm_start` (a sampled path warm-starts the optimiser).
    It should succeed with an optimised path or not at all: a failure of this rung is what
    lets SDAR-M try another grounding first."""

    name: str = "plain"
    lifted_warm_start: bool = True
    rescue: Rescue | None = None

    def __call__(self, transfers: Transfers, problem: TransferProblem) -> list[FloatArray] | None:
        path = transfers.optimise(problem, problem.q_from, problem.q_to)
        if path is None and self.rescue is not None:
            path = self.rescue(transfers, problem)
        if path is None and self.lifted_warm_start:
            ws = transfers.lifted_via(problem.q_from, problem.q_to)
            path = transfers.optimise(problem, problem.q_from, problem.q_to, ws)
        return None if path is None else [path]


@dataclass(frozen=True)
class UntangleStrategy:
    """Arm untangling (see the module docstring and ``docs/arm_untangling.md``): one arm
    yields (parks) while the others go to their goals, then it goes to its goal; the
    yielding arm is tried in order of depth, deepest first (ties: layout order)."""

    name: str = "untangle"
    park_height: float = 0.30  # [m]

    def __call__(self, transfers: Transfers, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = transfers.ctx
        order = np.argsort(-transfers.depth(problem.q_from))
        n = len(ctx.layout)
        for y in (int(k) for k in order):
            arm = ctx.arm_names[y]
            sl = ctx.layout.slice(y)
            park = transfers.park(arm, problem.q_to[sl], self.park_height)
            if park is None:
                continue
            q_mid = problem.q_to.copy()
            q_mid[sl] = park
            first = transfers.optimise_or_lift(problem, problem.q_from, q_mid)
            if first is None:
                continue
            second = transfers.optimise(problem, q_mid, problem.q_to, fixed=_only(y, n))
            if second is not None:
                return [first, second]
        return None


@dataclass(frozen=True)
class SequentialStrategy:
    """Retract the first arm to home, move the others, move the first. The first arm is
    tried in order of depth, deepest first (ties: layout order). The others move together
    in one stage; with three arms or more, if that stage fails, one at a time, in the same
    order of depth (with two arms the one stage is the other arm's alone)."""

    name: str = "sequential"

    def __call__(self, transfers: Transfers, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = transfers.ctx
        layout = ctx.layout
        n = len(layout)
        order = [int(k) for k in np.argsort(-transfers.depth(problem.q_from))]
        for f in order:
            first, others = _only(f, n), tuple(k == f for k in range(n))
            q1 = layout.replace(problem.q_from, f, ctx.home(ctx.arm_names[f]))
            q2 = layout.replace(problem.q_to, f, q1[layout.slice(f)])
            head = transfers.optimise_or_lift(problem, problem.q_from, q1, first)
            if head is None:
                continue
            middle = transfers.optimise_or_lift(problem, q1, q2, others)
            middle_stages = [middle] if middle is not None else None
            if middle_stages is None and n > 2:
                middle_stages = _one_at_a_time(transfers, problem, q1, q2, [k for k in order
                                                                           if k != f])  # fmt: skip
            if middle_stages is None:
                continue
            tail = transfers.optimise_or_lift(problem, q2, problem.q_to, first)
            if tail is not None:
                return [head, *middle_stages, tail]
        return None


def _one_at_a_time(
    transfers: Transfers, problem: TransferProblem, q_a: FloatArray, q_b: FloatArray,
    arms: list[int],
) -> list[FloatArray] | None:  # fmt: skip
    """Stages taking the arms ``arms`` (layout positions) from ``q_a`` to ``q_b`` one after
    the other in that order (the others waiting), or None when one fails."""
    layout = transfers.ctx.layout
    n = len(layout)
    stages: list[FloatArray] = []
    q = q_a.copy()
    for i in arms:
        q_next = layout.replace(q, i, layout.part(q_b, i))
        path = transfers.optimise_or_lift(problem, q, q_next, _only(i, n))
        if path is None:
            return None
        stages.append(path)
        q = q_next
    return stages


@dataclass(frozen=True)
class OneArmStrategy:
    """The baseline motion planner's transfer: the arms move one after the other, each
    straight to its goal while the others wait; arms bound for their home poses move first,
    then the others, each group in order of depth, deepest first (ties: layout order)."""

    name: str = "one-arm"

    def __call__(self, transfers: Transfers, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = transfers.ctx
        layout = ctx.layout
        n = len(layout)
        moving = [
            i
            for i in range(n)
            if not np.allclose(layout.part(problem.q_from, i), layout.part(problem.q_to, i))
        ]
        depth = transfers.depth(problem.q_from)
        homeward = {
            i: bool(np.allclose(layout.part(problem.q_to, i), ctx.home(ctx.arm_names[i])))
            for i in moving
        }
        moving.sort(key=lambda i: (not homeward[i], -depth[i]))
        stages: list[FloatArray] = []
        q = problem.q_from.copy()
        for i in moving:
            q_next = layout.replace(q, i, layout.part(problem.q_to, i))
            path = transfers.optimise_or_lift(problem, q, q_next, _only(i, n))
            if path is None:
                return None
            stages.append(path)
            q = q_next
        return stages or [np.stack([problem.q_from, problem.q_to])]
