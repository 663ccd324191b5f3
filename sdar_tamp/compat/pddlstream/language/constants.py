"""``pddlstream.language.constants``: formula builders, plan values, ``PDDLProblem``,
``print_solution`` and the readers of a program's PDDL files."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from typing import Any, NamedTuple

from sdar_tamp.compat.pddlstream.language.problem import PDDLProblem as PDDLProblem
from sdar_tamp.compat.pddlstream.unsupported import not_provided
from sdar_tamp.compat.pddlstream.utils import INF, read, str_from_object
from sdar_tamp.language.formula_model import TOTAL_COST as TOTAL_COST
from solvers.solution import Action as Action
from solvers.solution import Certificate as Certificate
from solvers.solution import DurativeAction as DurativeAction
from solvers.solution import Solution as Solution

__all__ = [
    "AND",
    "CONNECTIVES",
    "DOMAIN_FILE",
    "EQ",
    "EXISTS",
    "FAILED",
    "FORALL",
    "IMPLY",
    "INCREASE",
    "INFEASIBLE",
    "MAXIMIZE",
    "MINIMIZE",
    "NOT",
    "NOT_PLAN",
    "OBJECT",
    "OBJECTIVES",
    "OPERATORS",
    "OR",
    "PARAMETER",
    "PDDLSTREAM_FILES",
    "PDDL_FILES",
    "PROBLEM_FILE",
    "QUANTIFIERS",
    "STREAM_FILE",
    "SUCCEEDED",
    "TOTAL_COST",
    "TOTAL_TIME",
    "TYPE",
    "WHEN",
    "Action",
    "And",
    "Assignment",
    "Certificate",
    "DurativeAction",
    "Equal",
    "Evaluation",
    "Exists",
    "Fact",
    "ForAll",
    "FunctionAction",
    "Head",
    "Imply",
    "Minimize",
    "Not",
    "OptPlan",
    "Or",
    "Output",
    "PDDLProblem",
    "Solution",
    "StreamAction",
    "Type",
    "concatenate",
    "get_args",
    "get_constraints",
    "get_costs",
    "get_length",
    "get_parameter_name",
    "get_prefix",
    "is_cost",
    "is_head",
    "is_parameter",
    "is_plan",
    "partition_facts",
    "print_plan",
    "print_solution",
    "read_pddl_pair",
    "read_pddlstream_pair",
    "read_relative",
    "read_relative_dir",
    "str_from_action",
    "str_from_plan",
]

EQ = "="
AND = "and"
OR = "or"
NOT = "not"
EXISTS = "exists"
FORALL = "forall"
WHEN = "when"
IMPLY = "imply"
MINIMIZE = "minimize"
MAXIMIZE = "maximize"
INCREASE = "increase"
PARAMETER = "?"
TYPE = "-"
OBJECT = "object"
TOTAL_TIME = "total-time"
CONNECTIVES = (AND, OR, NOT, IMPLY)
QUANTIFIERS = (FORALL, EXISTS)
OBJECTIVES = (MINIMIZE, MAXIMIZE, INCREASE)
OPERATORS = (*CONNECTIVES, *QUANTIFIERS, WHEN)

SUCCEEDED = True
FAILED = None
INFEASIBLE = False
NOT_PLAN = (FAILED, INFEASIBLE)

DOMAIN_FILE = "domain.pddl"
PROBLEM_FILE = "problem.pddl"
STREAM_FILE = "stream.pddl"
PDDL_FILES = (DOMAIN_FILE, PROBLEM_FILE)
PDDLSTREAM_FILES = (DOMAIN_FILE, STREAM_FILE)


class OptPlan(NamedTuple):
    action_plan: Any
    preimage_facts: Any


class Assignment(NamedTuple):
    args: Any


class StreamAction(NamedTuple):
    name: str
    inputs: tuple[Any, ...]
    outputs: tuple[Any, ...]


class FunctionAction(NamedTuple):
    name: str
    inputs: tuple[Any, ...]


class Head(NamedTuple):
    function: str
    args: tuple[Any, ...]


class Evaluation(NamedTuple):
    head: Head
    value: Any


def Output(*args: Any) -> tuple[Any, ...]:
    """One stream output tuple."""
    return tuple(args)


def And(*expressions: Any) -> Any:
    """A conjunction (one expression is returned as it is)."""
    return expressions[0] if len(expressions) == 1 else (AND, *expressions)


def Or(*expressions: Any) -> Any:
    """A disjunction (one expression is returned as it is)."""
    return expressions[0] if len(expressions) == 1 else (OR, *expressions)


def Not(expression: Any) -> tuple[Any, ...]:
    return (NOT, expression)


def Imply(expression1: Any, expression2: Any) -> tuple[Any, ...]:
    return (IMPLY, expression1, expression2)


def Equal(expression1: Any, expression2: Any) -> tuple[Any, ...]:
    return (EQ, expression1, expression2)


def Minimize(expression: Any) -> tuple[Any, ...]:
    return (MINIMIZE, expression)


def Type(param: str, ty: str) -> tuple[Any, ...]:
    return (param, TYPE, ty)


def Exists(args: Sequence[str], expression: Any) -> tuple[Any, ...]:
    return (EXISTS, args, expression)


def ForAll(args: Sequence[str], expression: Any) -> tuple[Any, ...]:
    return (FORALL, args, expression)


def get_prefix(expression: Sequence[Any]) -> Any:
    return expression[0]


def get_args(head: Sequence[Any]) -> tuple[Any, ...]:
    return tuple(head[1:])


def concatenate(*args: Iterable[Any]) -> tuple[Any, ...]:
    return tuple(item for arg in args for item in arg)


def Fact(predicate: str, args: Iterable[Any]) -> tuple[Any, ...]:
    """The fact ``(predicate, *args)``."""
    return (predicate, *args)


def is_parameter(expression: Any) -> bool:
    return isinstance(expression, str) and expression.startswith(PARAMETER)


def get_parameter_name(expression: Any) -> Any:
    return expression[len(PARAMETER) :] if is_parameter(expression) else expression


def is_head(expression: Sequence[Any]) -> bool:
    return bool(get_prefix(expression) not in OPERATORS)


def is_plan(plan: Any) -> bool:
    """True unless ``plan`` is ``None`` (failed) or ``False`` (infeasible)."""
    return not any(plan is status for status in NOT_PLAN)


def get_length(plan: Any) -> float:
    return len(plan) if is_plan(plan) else INF


def str_from_action(action: Sequence[Any]) -> str:
    name, args = action[:2]
    return f"{name}{str_from_object(tuple(args))}"


def str_from_plan(plan: Any) -> str:
    if not is_plan(plan):
        return str(plan)
    return str_from_object([str_from_action(action) for action in plan])


def print_plan(plan: Any) -> None:
    """One line per step: ``n) name arg ...`` (timed steps as ``start - end) name ...``)."""
    if not is_plan(plan):
        return
    step = 1
    for action in plan:
        if isinstance(action, DurativeAction):
            args = " ".join(map(str_from_object, action.args))
            end = action.start + action.duration
            print(f"{action.start:.2f} - {end:.2f}) {action.name} {args}")
        elif isinstance(action, StreamAction | FunctionAction):
            print(f"    {action.name}({', '.join(map(str_from_object, action.inputs))})")
        else:
            name, args = action[:2]
            print(f"{step:2}) {name} {' '.join(map(str_from_object, args))}")
            step += 1


def print_solution(solution: Any) -> None:
    """PDDLStream's summary of ``plan, cost, certificate``: solved, cost, length, plan."""
    plan, cost, certificate = solution
    deferred = 0
    if is_plan(plan) and plan is not None:
        deferred = sum(isinstance(a, StreamAction | FunctionAction) for a in plan)
    print()
    print(f"Solved: {is_plan(plan)}")
    print(f"Cost: {cost:.3f}")
    length = get_length(plan)
    print(f"Length: {length - deferred if math.isfinite(length) else length}")
    print(f"Deferred: {deferred}")
    print(f"Evaluations: {len(certificate)}")
    print_plan(plan)


def partition_facts(facts: Iterable[Sequence[Any]]) -> tuple[list[Any], list[Any], list[Any]]:
    """``(functions, negated, atoms)`` of a list of facts."""
    functions, negated, atoms = [], [], []
    for fact in facts:
        prefix = get_prefix(fact)
        if prefix in (EQ, MINIMIZE):
            functions.append(fact[1])
        elif prefix == NOT:
            negated.append(fact[1])
        else:
            atoms.append(fact)
    return functions, negated, atoms


def is_cost(expression: Sequence[Any]) -> bool:
    return bool(get_prefix(expression) == MINIMIZE)


def get_costs(objectives: Iterable[Sequence[Any]]) -> list[Any]:
    return [o for o in objectives if is_cost(o)]


def get_constraints(objectives: Iterable[Sequence[Any]]) -> list[Any]:
    return [o for o in objectives if not is_cost(o)]


def read_relative(file: str, relative_path: str) -> str:
    """The text of ``relative_path`` next to ``file`` (a module's ``__file__``)."""
    return read(os.path.join(os.path.dirname(os.path.abspath(file)), relative_path))


def read_relative_dir(
    file: str, relative_dir: str = "./", filenames: Sequence[str] = ()
) -> list[str]:
    return [read_relative(file, os.path.join(relative_dir, name)) for name in filenames]


def read_pddl_pair(file: str, **kwargs: Any) -> list[str]:
    """``[domain.pddl, problem.pddl]`` texts from the folder of ``file``."""
    return read_relative_dir(file, filenames=PDDL_FILES, **kwargs)


def read_pddlstream_pair(file: str, **kwargs: Any) -> list[str]:
    """``[domain.pddl, stream.pddl]`` texts from the folder of ``file``."""
    return read_relative_dir(file, filenames=PDDLSTREAM_FILES, **kwargs)


__getattr__ = not_provided(
    __name__, "PDDLStream's internal expression helpers over its own objects"
)
