"""ADL features: conditional and universal effects, derived predicates, quantified formulas."""

from __future__ import annotations

import dataclasses

from classical_helpers import load, load_text

from sdar_tamp.language.domain_model import Axiom
from sdar_tamp.language.formula_model import And, Atom, Exists, ForAll, Imply, Not, Or, Parameter
from solvers.classical import PlanStatus, ground, plan, validated_plan_cost
from solvers.classical.bitset_task import CompiledTask, mask


def test_moving_the_case_moves_its_contents() -> None:
    task = ground(load("briefcase", "office"))
    move = next(op for op in task.operators if str(op.action) == "(move home hall)")
    # one conditional effect per item: (when (in ?i) (and (at ?i hall) (not (at ?i home))))
    assert len(move.conditional) == 3
    compiled = CompiledTask(task)
    facts = task.facts
    state = compiled.init
    put_in = next(
        i for i, op in enumerate(task.operators) if str(op.action) == "(put-in letter home)"
    )
    index = task.operators.index(move)
    carried = compiled.successor(compiled.successor(state, put_in), index)
    empty = compiled.successor(state, index)
    at_hall = facts.index(Atom("at", ("letter", "hall")))
    assert carried >> at_hall & 1
    assert not empty >> at_hall & 1


def test_briefcase_plans_use_the_lamp_and_switches() -> None:
    result = plan(load("briefcase", "lights-out"), search="astar", heuristic="max")
    assert result.status is PlanStatus.SOLVED and result.plan is not None
    steps = [str(a) for a in result.plan]
    assert len(steps) == 8
    assert "(put-in torch kitchen)" in steps and "(toggle hall hall)" in steps
    task = load("briefcase", "lights-out")
    assert validated_plan_cost(task, result.plan) == 8.0  # optimal, whichever tie A* takes


def test_negated_derived_precondition_limits_the_case() -> None:
    task = ground(load("briefcase", "office"))
    compiled = CompiledTask(task)
    ops = {str(op.action): i for i, op in enumerate(task.operators)}
    state = compiled.successor(compiled.init, ops["(move home hall)"])
    state = compiled.successor(state, ops["(put-in torch hall)"])
    state = compiled.successor(state, ops["(move hall home)"])
    assert ops["(put-in letter home)"] in compiled.applicable(state)
    full = compiled.successor(state, ops["(put-in letter home)"])
    assert full >> task.facts.index(Atom("full")) & 1
    # (not (full)): a third item does not fit; taking one out makes room again
    assert not any(task.operators[i].name == "put-in" for i in compiled.applicable(full))
    emptier = compiled.successor(full, ops["(take-out torch home)"])
    assert not emptier >> task.facts.index(Atom("full")) & 1


def test_toggle_conditional_effects_flip_the_light() -> None:
    task = ground(load("briefcase", "lights-out"))
    compiled = CompiledTask(task)
    toggle = next(
        i for i, op in enumerate(task.operators) if str(op.action) == "(toggle hall hall)"
    )
    light = mask([task.facts.index(Atom("light-on", ("hall",)))])
    dark = mask([task.facts.index(Atom("dark", ("hall",)))])
    off = compiled.successor(compiled.init, toggle)
    on = compiled.successor(off, toggle)
    assert compiled.init & light and not compiled.init & dark
    assert not off & light and off & dark  # the derived (dark hall) follows
    assert on == compiled.init


def test_recursive_derived_goal_changes_the_plan() -> None:
    # (above ?x ?y): transitive closure of on. Goal: a above c, by any tower.
    task = load("blocksworld", "sussman", use_costs=False)
    above = Axiom(
        "above",
        (Parameter("?x"), Parameter("?y")),
        Or(
            (
                Atom("on", ("?x", "?y")),
                Exists(
                    (Parameter("?z"),), And((Atom("on", ("?x", "?z")), Atom("above", ("?z", "?y"))))
                ),
            )
        ),
    )
    domain = dataclasses.replace(task.domain, axioms=(above,))
    derived = dataclasses.replace(task, domain=domain, goal=Atom("above", ("a", "c")))
    result = plan(derived, search="astar", heuristic="max")
    assert result.plan is not None
    # unstack c, put it down, then a on c: 4 steps (a direct (on a c) goal needs the same 4)
    assert len(result.plan) == 4
    # with c already on a's tower, b on c then a on b also satisfies above: both found valid
    tall = dataclasses.replace(
        derived, goal=And((Atom("above", ("a", "c")), Atom("on", ("a", "b"))))
    )
    result = plan(tall, search="astar", heuristic="blind")
    assert result.plan is not None and len(result.plan) == 6
    assert [str(a) for a in result.plan][-1] == "(stack a b)"


def test_universal_imply_goal_and_negated_quantifiers() -> None:
    task = load("blocksworld", "sussman", use_costs=False)
    # every block on the table is clear (so: no towers), and no block is held
    flat = ForAll((Parameter("?x"),), Imply(Atom("on-table", ("?x",)), Atom("clear", ("?x",))))
    empty_hand = Not(Exists((Parameter("?x"),), Atom("holding", ("?x",))))
    result = plan(dataclasses.replace(task, goal=And((flat, empty_hand))), search="astar")
    assert result.plan is not None
    assert [str(a) for a in result.plan] == ["(unstack c a)", "(put-down c)"]
    # no tower can stand when every block on the table must be clear
    tower = And((flat, Atom("on", ("b", "a"))))
    assert plan(dataclasses.replace(task, goal=tower)).status is PlanStatus.UNSOLVABLE


def test_disjunctive_goal_takes_the_cheaper_branch() -> None:
    text = """(define (problem either) (:domain delivery-costs)
      (:objects a b c - place van - vehicle box - package)
      (:init (at van a) (parcel-at box a) (road a b) (road a c)
             (= (length a b) 9) (= (length a c) 2) (= (total-cost) 0))
      (:goal (or (at van b) (at van c)))
      (:metric minimize (total-cost)))"""
    result = plan(load_text("delivery_costs", text), search="astar", heuristic="max")
    assert result.plan is not None and [str(a) for a in result.plan] == ["(drive van a c)"]
    assert result.cost == 2.0
