"""Grounding: from a lifted :class:`PlanningTask` to an integer :class:`GroundTask`.

Only instances supported by relaxed reachability are created (see :mod:`.reachability`).
Static (fixed) literals are checked here and dropped; negated fluent literals over facts that
are never reachable are trivially true and dropped too.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from operator import itemgetter

from sdar_tamp.language.formula_model import EQUALITY, Atom, FunctionTerm, NumericExpr
from solvers.classical.errors import GroundingError
from solvers.classical.join import (
    DEADLINE_STRIDE,
    FactBase,
    GroundingTimeout,
    compile_join,
    run_join,
)
from solvers.classical.normalize import Lit, NormAction, NormTask, normalize
from solvers.classical.problem import PlanningTask
from solvers.classical.reachability import (
    action_predicate,
    fixed_predicates,
    reachable_facts,
    split_condition,
)
from solvers.classical.task import ConditionalEffect, GroundAxiom, GroundOperator, GroundTask

_EQUALITY, _VARIABLE, _FIXED = 0, 1, 2
# (kind, predicate, positive, arguments from an action's argument tuple)
_Template = tuple[int, str, bool, Callable[[tuple[str, ...]], tuple[str, ...]]]


def _ground_args(lit: Lit, binding: Mapping[str, str]) -> tuple[str, ...]:
    return tuple(binding[a] if a.startswith("?") else a for a in lit.args)


def _positional(
    lit: Lit, parameters: tuple[str, ...]
) -> Callable[[tuple[str, ...]], tuple[str, ...]]:
    """A function from an action's argument tuple to ``lit``'s ground arguments."""
    spec: list[int | str] = [parameters.index(a) if a.startswith("?") else a for a in lit.args]
    if all(isinstance(s, int) for s in spec):
        if not spec:
            return lambda args: ()
        if len(spec) == 1:
            index = spec[0]
            assert isinstance(index, int)
            return lambda args: (args[index],)
        return itemgetter(*spec)
    return lambda args: tuple(args[s] if isinstance(s, int) else s for s in spec)


class _Instantiator:
    def __init__(
        self, task: PlanningTask, norm: NormTask, base: FactBase, deadline: float | None = None
    ) -> None:
        self.deadline = deadline
        self.task = task
        self.norm = norm
        self.base = base
        self.sizes = {predicate: len(facts) for predicate, facts in base.relations.items()}
        self.fixed = fixed_predicates(norm)
        self.variable = norm.fluent | norm.derived
        atoms = sorted(
            (predicate, args)
            for predicate in self.variable
            for args in base.relations.get(predicate, ())
        )
        self.facts = tuple(Atom(p, a) for p, a in atoms)
        self.ids = {atom: i for i, atom in enumerate(atoms)}

    def literals(
        self, lits: tuple[Lit, ...], binding: Mapping[str, str]
    ) -> tuple[list[int], list[int]] | None:
        """(positive ids, negative ids) of the variable literals; ``None`` when never true."""
        positive: list[int] = []
        negative: list[int] = []
        for lit in lits:
            args = _ground_args(lit, binding)
            if lit.predicate == EQUALITY:
                if (len(set(args)) <= 1) != lit.positive:
                    return None
            elif lit.predicate in self.variable:
                fact = self.ids.get((lit.predicate, args))
                if lit.positive:
                    if fact is None:
                        return None
                    positive.append(fact)
                elif fact is not None:
                    negative.append(fact)
            elif self.base.contains(lit.predicate, args) != lit.positive:
                return None
        return sorted(set(positive)), sorted(set(negative))

    def extra(self, name: str, args: tuple[str, ...]) -> float:
        """The task's ``extra_cost`` of a ground action (0 without one)."""
        extra = self.task.extra_cost
        if extra is None:
            return 0.0
        value = float(extra(name, args))
        if not math.isfinite(value) or value < 0:
            raise GroundingError(f"extra costs must be finite and non-negative, got {value}")
        return value

    def cost(self, action: NormAction, binding: Mapping[str, str]) -> float:
        if not self.task.use_costs:
            return 1.0
        return sum((self.amount(expr, binding) for expr in action.costs), 0.0)

    def amount(self, expr: NumericExpr, binding: Mapping[str, str]) -> float:
        if not isinstance(expr, FunctionTerm):
            value = float(expr)
        else:
            args = tuple(binding.get(a, a) for a in expr.args)
            key = (expr.name, args)
            if key not in self.task.numeric_init:
                term = "(" + " ".join((expr.name, *args)) + ")"
                raise GroundingError(f"cost term {term} has no value in the numeric init")
            value = float(self.task.numeric_init[key])
        if not math.isfinite(value) or value < 0:
            raise GroundingError(f"action costs must be finite and non-negative, got {value}")
        return value

    def templates(self, lits: tuple[Lit, ...], parameters: tuple[str, ...]) -> list[_Template]:
        """Literals compiled against an action's argument tuple."""
        result = []
        for lit in lits:
            if lit.predicate == EQUALITY:
                kind = _EQUALITY
            elif lit.predicate in self.variable:
                kind = _VARIABLE
            else:
                kind = _FIXED
            result.append((kind, lit.predicate, lit.positive, _positional(lit, parameters)))
        return result

    def evaluate(
        self, templates: list[_Template], args: tuple[str, ...]
    ) -> tuple[list[int], list[int]] | None:
        """Like :meth:`literals`, for compiled templates and an action's arguments."""
        positive: list[int] = []
        negative: list[int] = []
        ids = self.ids
        for kind, predicate, is_positive, get in templates:
            ground = get(args)
            if kind == _VARIABLE:
                fact = ids.get((predicate, ground))
                if is_positive:
                    if fact is None:
                        return None
                    positive.append(fact)
                elif fact is not None:
                    negative.append(fact)
            elif kind == _EQUALITY:
                if (len(set(ground)) <= 1) != is_positive:
                    return None
            elif self.base.contains(predicate, ground) != is_positive:
                return None
        return positive, negative

    def check_deadline(self) -> None:
        if self.deadline is not None and time.perf_counter() > self.deadline:
            raise GroundingTimeout

    def operators(self, action: NormAction) -> list[GroundOperator]:
        instances = sorted(self.base.relations.get(action_predicate(action.name), ()))
        params = action.parameters
        # the join that produced the instances enforced every literal but the variable ones
        pre_templates = [
            t for t in self.templates(action.precondition, params) if t[0] == _VARIABLE
        ]
        simple = []  # effects without universal parameters: compiled against the arguments
        general = []  # universal effects: joined over the reachable facts
        for effect in action.effects:
            lit = effect.literal
            if not effect.parameters:
                cond = self.templates(effect.condition, params)
                simple.append((cond, lit.predicate, lit.positive, _positional(lit, params)))
            else:
                atoms, filters = split_condition(effect.condition, self.fixed)
                general.append(
                    (effect, compile_join(atoms, filters, prebound=params, sizes=self.sizes))
                )
        needs_binding = bool(general) or any(isinstance(c, FunctionTerm) for c in action.costs)
        fixed_cost = None if needs_binding else self.cost(action, {})
        ids = self.ids
        result = []
        for count, args in enumerate(instances):
            if count % DEADLINE_STRIDE == 0:
                self.check_deadline()
            pre = self.evaluate(pre_templates, args)
            if pre is None:  # pragma: no cover - reachability already checked this
                continue
            adds: set[int] = set()
            deletes: set[int] = set()
            groups: dict[tuple[tuple[int, ...], tuple[int, ...]], tuple[set[int], set[int]]]
            groups = {}
            found: list[tuple[tuple[list[int], list[int]], int, bool]] = []
            for cond, predicate, positive, get in simple:
                condition = self.evaluate(cond, args) if cond else ([], [])
                fact = ids.get((predicate, get(args)))
                if condition is not None and fact is not None:
                    found.append((condition, fact, positive))
            binding = dict(zip(params, args, strict=True)) if needs_binding else {}
            for effect, plan in general:
                for full in run_join(plan, self.base, binding, deadline=self.deadline):
                    condition = self.literals(effect.condition, full)
                    lit = effect.literal
                    fact = ids.get((lit.predicate, _ground_args(lit, full)))
                    if condition is not None and fact is not None:
                        found.append((condition, fact, lit.positive))
            for (cond_pos, cond_neg), fact, positive in found:
                if not cond_pos and not cond_neg:
                    (adds if positive else deletes).add(fact)
                else:
                    key = (tuple(sorted(set(cond_pos))), tuple(sorted(set(cond_neg))))
                    group = groups.setdefault(key, (set(), set()))
                    group[0 if positive else 1].add(fact)
            result.append(
                GroundOperator(
                    name=action.name,
                    args=args,
                    precondition=tuple(sorted(set(pre[0]))),
                    negative_precondition=tuple(sorted(set(pre[1]))),
                    adds=tuple(sorted(adds)),
                    deletes=tuple(sorted(deletes - adds)),
                    conditional=tuple(
                        ConditionalEffect(pos, neg, tuple(sorted(a)), tuple(sorted(d)))
                        for (pos, neg), (a, d) in sorted(groups.items())
                    ),
                    cost=(self.cost(action, binding) if fixed_cost is None else fixed_cost)
                    + self.extra(action.name, args),
                )
            )
        return result

    def axioms(self) -> list[GroundAxiom]:
        result: set[GroundAxiom] = set()
        for axiom in self.norm.axioms:
            atoms, filters = split_condition(axiom.body, self.fixed)
            head = Lit(axiom.predicate, axiom.head)
            stratum = self.norm.strata[axiom.predicate]
            plan = compile_join(atoms, filters, sizes=self.sizes)
            for binding in run_join(plan, self.base, deadline=self.deadline):
                body = self.literals(axiom.body, binding)
                head_id = self.ids.get((axiom.predicate, _ground_args(head, binding)))
                if body is None or head_id is None:  # pragma: no cover - reachable by construction
                    continue
                if head_id in body[0]:
                    continue  # p :- p, ... never adds anything
                result.add(GroundAxiom(head_id, tuple(body[0]), tuple(body[1]), stratum))
        return sorted(result, key=lambda a: (a.stratum, a.head, a.body, a.negative_body))


def ground_normalized(
    task: PlanningTask, norm: NormTask, deadline: float | None = None
) -> GroundTask:
    base = reachable_facts(norm, deadline)
    inst = _Instantiator(task, norm, base, deadline)
    operators = [op for action in norm.actions for op in inst.operators(action)]
    goal = inst.literals(norm.goal, {})
    init = frozenset(
        inst.ids[(p, a)] for p, a in norm.facts if p in norm.fluent and (p, a) in inst.ids
    )
    derived = frozenset(i for i, atom in enumerate(inst.facts) if atom.predicate in norm.derived)
    static = {p: base.relations.get(p, set()) for p in sorted(inst.fixed) if not p.startswith("~")}
    return GroundTask(
        facts=inst.facts,
        derived=derived,
        init=init,
        goal=tuple(goal[0]) if goal else (),
        negative_goal=tuple(goal[1]) if goal else (),
        goal_reachable=goal is not None,
        operators=tuple(operators),
        axioms=tuple(inst.axioms()),
        static_relations=static,
        source=task,
    )


def ground(task: PlanningTask, *, deadline: float | None = None) -> GroundTask:
    """Ground ``task`` by relaxed reachability. ``deadline`` is a ``time.perf_counter()`` value."""
    return ground_normalized(task, normalize(task), deadline)
