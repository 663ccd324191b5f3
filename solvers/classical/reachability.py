"""Relaxed reachability: the facts and action instances reachable when deletes are ignored.

The normalised task becomes a positive logic program: an action rule derives ``~action:<name>``
instances from the positive preconditions, effect rules derive added facts from an action
instance plus the effect condition, and axiom rules derive derived facts. Negated literals over
fixed (static) predicates and equalities prune bindings; other negations are relaxed away. The
program is evaluated semi-naively (each round joins only against the facts new in the previous
round), so no parameter combination that is not supported by reachable facts is ever formed.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass

from sdar_tamp.language.formula_model import EQUALITY
from solvers.classical.join import (
    Fact,
    FactBase,
    GroundingTimeout,
    JoinPlan,
    compile_join,
    run_join,
)
from solvers.classical.normalize import Lit, NormTask

__all__ = [
    "GroundingTimeout",
    "action_predicate",
    "fixed_predicates",
    "reachable_facts",
    "split_condition",
]


def action_predicate(name: str) -> str:
    return f"~action:{name}"


def split_condition(lits: tuple[Lit, ...], fixed: frozenset[str]) -> tuple[list[Lit], list[Lit]]:
    """(positive atoms to join, filters): equalities and negations of fixed predicates."""
    atoms: list[Lit] = []
    filters: list[Lit] = []
    for lit in lits:
        if lit.predicate == EQUALITY or (not lit.positive and lit.predicate in fixed):
            filters.append(lit)
        elif lit.positive:
            atoms.append(lit)
    return atoms, filters


@dataclass(frozen=True)
class _Rule:
    atoms: tuple[Lit, ...]
    head: Lit
    full: JoinPlan
    filters: tuple[Lit, ...]
    # unconditional effects of an action rule, added directly: (predicate, head argument spec)
    direct: tuple[tuple[str, tuple[int | str, ...]], ...] = ()


def _rule(
    atoms: list[Lit],
    filters: list[Lit],
    head: Lit,
    direct: tuple[tuple[str, tuple[int | str, ...]], ...] = (),
    sizes: Mapping[str, int] | None = None,
) -> _Rule:
    plan = compile_join(atoms, filters, sizes=sizes)
    return _Rule(tuple(atoms), head, plan, tuple(filters), direct)


def _rules(
    norm: NormTask, fixed: frozenset[str], sizes: Mapping[str, int] | None = None
) -> list[_Rule]:
    rules: list[_Rule] = []
    for action in norm.actions:
        atoms, filters = split_condition(action.precondition, fixed)
        head = Lit(action_predicate(action.name), action.parameters)
        direct: list[tuple[str, tuple[int | str, ...]]] = []
        for effect in action.effects:
            lit = effect.literal
            if not lit.positive:
                continue
            if not effect.parameters and not effect.condition:
                spec = tuple(
                    action.parameters.index(a) if a.startswith("?") else a for a in lit.args
                )
                direct.append((lit.predicate, spec))
                continue
            cond_atoms, cond_filters = split_condition(effect.condition, fixed)
            rules.append(_rule([head, *cond_atoms], cond_filters, lit, sizes=sizes))
        rules.append(_rule(atoms, filters, head, tuple(direct), sizes))
    for axiom in norm.axioms:
        atoms, filters = split_condition(axiom.body, fixed)
        rules.append(_rule(atoms, filters, Lit(axiom.predicate, axiom.head), sizes=sizes))
    return rules


def _sizes(base: FactBase) -> dict[str, int]:
    return {predicate: len(facts) for predicate, facts in base.relations.items()}


def fixed_predicates(norm: NormTask) -> frozenset[str]:
    """Predicates whose facts never change: neither touched by an effect nor derived."""
    predicates = {p for p, _ in norm.facts}
    for action in norm.actions:
        predicates.update(lit.predicate for lit in action.precondition)
        for effect in action.effects:
            predicates.update(lit.predicate for lit in effect.condition)
    for axiom in norm.axioms:
        predicates.update(lit.predicate for lit in axiom.body)
    predicates.update(lit.predicate for lit in norm.goal)
    return frozenset(predicates - norm.fluent - norm.derived - {EQUALITY})


def reachable_facts(norm: NormTask, deadline: float | None = None) -> FactBase:
    """The least fixpoint of the relaxed program: init facts, reachable facts, action instances."""
    fixed = fixed_predicates(norm)
    base = FactBase(norm.facts)
    rules = _rules(norm, fixed, _sizes(base))
    seeded: dict[tuple[int, int], JoinPlan] = {}  # (rule, atom): plan with that atom first

    def seeded_plan(r: int, i: int) -> JoinPlan:
        plan = seeded.get((r, i))
        if plan is None:
            rule = rules[r]
            plan = seeded[(r, i)] = compile_join(
                list(rule.atoms), list(rule.filters), first=i, sizes=_sizes(base)
            )
        return plan

    delta: dict[str, set[Fact]] | None = None  # None: first round, everything is new
    while True:
        new: dict[str, set[Fact]] = {}
        for r, rule in enumerate(rules):
            if deadline is not None and time.perf_counter() > deadline:
                raise GroundingTimeout
            plans: list[tuple[JoinPlan, set[Fact] | None]]
            if delta is None:
                plans = [(rule.full, None)]
            else:
                plans = [
                    (seeded_plan(r, i), delta[atom.predicate])
                    for i, atom in enumerate(rule.atoms)
                    if atom.predicate in delta
                ]
            head = rule.head
            for plan, seed in plans:
                for binding in run_join(plan, base, None, seed, deadline):
                    args = tuple(binding[a] if a.startswith("?") else a for a in head.args)
                    if base.contains(head.predicate, args):
                        continue
                    new.setdefault(head.predicate, set()).add(args)
                    for predicate, spec in rule.direct:
                        fact = tuple(args[s] if isinstance(s, int) else s for s in spec)
                        if not base.contains(predicate, fact):
                            new.setdefault(predicate, set()).add(fact)
        if not new:
            return base
        for predicate, tuples in new.items():
            for args in tuples:
                base.add(predicate, args)
        delta = new
