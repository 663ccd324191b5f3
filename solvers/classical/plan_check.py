"""Plan validation by independent simulation.

Actions are executed from the *lifted* schemas with :func:`sdar_tamp.language.plan_run.run_plan`:
each step's precondition formula is evaluated on a set of atoms (quantifiers range over the
typed objects, derived predicates are evaluated from the domain's axioms), effects (conditional
and universal) are evaluated in the state before the step, deletes are applied before adds, and
costs are looked up from the task's numeric values. Finally the goal formula is evaluated.
Nothing here shares code with the search's grounding and bitset machinery.
"""

from __future__ import annotations

from collections.abc import Sequence

from sdar_tamp.language.formula_model import FunctionTerm
from sdar_tamp.language.plan_run import run_plan
from sdar_tamp.language.state_index import TypedObjects
from solvers.classical.errors import PlanValidationError
from solvers.classical.problem import GroundAction, PlanningTask


def validated_plan_cost(task: PlanningTask, plan: Sequence[GroundAction]) -> float:
    """The cost of ``plan`` if it solves ``task``; otherwise :class:`PlanValidationError`.

    With ``task.use_costs`` false every step costs 1.
    """

    def cost_of(term: FunctionTerm) -> float:
        key = (term.name, term.args)
        if key not in task.numeric_init:
            raise PlanValidationError(f"no value for cost term {key}")
        return float(task.numeric_init[key])

    run = run_plan(
        task.domain,
        TypedObjects(task.domain, task.objects),
        task.init,
        [(action.name, action.args) for action in plan],
        task.goal,
        cost_of,
    )
    if run.failed_step == -1:
        raise PlanValidationError(run.reason)
    if run.failed_step is not None:
        raise PlanValidationError(f"step {run.failed_step + 1}: {run.reason}")
    return run.cost if task.use_costs else float(len(plan))
