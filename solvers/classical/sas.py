"""A ground task in Fast Downward's SAS+ input format (version 3).

Every fluent or derived fact becomes a binary variable, value 0 for true and 1 for false, so
negative preconditions, goals and axiom bodies are ordinary facts. Derived variables start at
their default value (false) and get an axiom layer from their stratum. Operators are named
``o<index>`` after their position in :attr:`GroundTask.operators`. Costs must be integers:
they are multiplied by the smallest power of ten (up to :data:`MAX_SCALE`) that makes them
integral, else rounded at that scale.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from solvers.classical.task import GroundOperator, GroundTask

TRUE, FALSE = 0, 1
#: The largest cost multiplier; costs finer than 1 / MAX_SCALE are rounded.
MAX_SCALE = 1000
_MAX_INT = 2**31 - 1


@dataclass(frozen=True)
class SasTask:
    """The SAS+ text of a ground task; ``scale`` multiplied every action cost."""

    text: str
    scale: int

    def scaled_bound(self, bound: float) -> int | None:
        """The integer Fast Downward bound (plans of scaled cost below it) for a cost bound,
        or None when there is none (infinite, or beyond Fast Downward's integers)."""
        if not math.isfinite(bound):
            return None
        scaled = math.ceil(bound * self.scale - 1e-9)
        return scaled if scaled < _MAX_INT else None


def cost_scale(costs: Iterable[float]) -> int:
    """The smallest power of ten up to :data:`MAX_SCALE` making every cost an integer (else
    :data:`MAX_SCALE`)."""
    values = list(costs)
    scale = 1
    while scale < MAX_SCALE:
        if all(abs(c * scale - round(c * scale)) <= 1e-9 * max(1.0, c * scale) for c in values):
            return scale
        scale *= 10
    return scale


def sas_task(task: GroundTask) -> SasTask:
    """The SAS+ text of ``task`` (which must have a relaxed-reachable goal)."""
    scale = cost_scale(op.cost for op in task.operators)
    layers = {axiom.head: axiom.stratum for axiom in task.axioms}
    lines = ["begin_version", "3", "end_version", "begin_metric", "1", "end_metric"]
    lines.append(str(len(task.facts)))
    for fact, atom in enumerate(task.facts):
        layer = layers.get(fact, 0) if fact in task.derived else -1
        lines += ["begin_variable", f"var{fact}", str(layer), "2"]
        lines += [f"Atom {atom}", f"NegatedAtom {atom}", "end_variable"]
    lines.append("0")  # mutex groups
    lines.append("begin_state")
    lines += [str(TRUE if fact in task.init else FALSE) for fact in range(len(task.facts))]
    lines.append("end_state")
    goal = dict.fromkeys(task.negative_goal, FALSE) | dict.fromkeys(task.goal, TRUE)
    lines += ["begin_goal", str(len(goal))]
    lines += [f"{fact} {value}" for fact, value in sorted(goal.items())]
    lines.append("end_goal")
    operators = [_operator(index, op, scale) for index, op in enumerate(task.operators)]
    kept = [text for text in operators if text is not None]
    lines.append(str(len(kept)))
    lines += kept
    lines.append(str(len(task.axioms)))
    for axiom in task.axioms:
        body = [(f, TRUE) for f in axiom.body] + [(f, FALSE) for f in axiom.negative_body]
        lines += ["begin_rule", str(len(body))]
        lines += [f"{fact} {value}" for fact, value in sorted(body)]
        lines += [f"{axiom.head} {FALSE} {TRUE}", "end_rule"]
    lines.append("")
    return SasTask("\n".join(lines), scale)


def _operator(index: int, op: GroundOperator, scale: int) -> str | None:
    """One ``begin_operator`` block, or None for an operator without any effect."""
    pre = dict.fromkeys(op.negative_precondition, FALSE) | dict.fromkeys(op.precondition, TRUE)
    # (variable, value, condition): all deletes before all adds, so that when both fire in one
    # state the add, applied last, wins (PDDL's rule)
    Effect = tuple[int, int, tuple[tuple[int, int], ...]]
    deletes: list[Effect] = [(fact, FALSE, ()) for fact in op.deletes]
    adds: list[Effect] = []
    for conditional in op.conditional:
        condition: dict[int, int] = {}
        consistent = True
        for fact, value in [(f, TRUE) for f in conditional.condition] + [
            (f, FALSE) for f in conditional.negative_condition
        ]:
            if fact in pre:  # decided by the precondition: drop the literal or the effect
                consistent = consistent and pre[fact] == value
            elif condition.setdefault(fact, value) != value:
                consistent = False
        if consistent:
            cond = tuple(sorted(condition.items()))
            deletes += [(fact, FALSE, cond) for fact in conditional.deletes]
            adds += [(fact, TRUE, cond) for fact in conditional.adds]
    effects = deletes + adds + [(fact, TRUE, ()) for fact in op.adds]
    if not effects:
        return None
    changed = {fact for fact, _, _ in effects}
    prevail = sorted((f, v) for f, v in pre.items() if f not in changed)
    lines = ["begin_operator", f"o{index}", str(len(prevail))]
    lines += [f"{fact} {value}" for fact, value in prevail]
    lines.append(str(len(effects)))
    for fact, value, cond in effects:
        head = " ".join(f"{f} {v}" for f, v in cond)
        lines.append(f"{len(cond)} {head + ' ' if head else ''}{fact} {pre.get(fact, -1)} {value}")
    lines += [str(round(op.cost * scale)), "end_operator"]
    return "\n".join(lines)
