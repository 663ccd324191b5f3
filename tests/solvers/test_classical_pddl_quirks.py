"""Real-world PDDL quirks (the IPC logistics and zenotravel styles) parse, solve and validate;
``sdar plan --strict`` reports each quirk with file:line:col and exits 2.

The real IPC files are not shipped: set ``SDAR_IPC_DIR`` to a folder holding ``logistics00/``
and ``zenotravel/`` (as in aibasel/downward-benchmarks) to also run them.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.leniency import (
    DUPLICATE_PREDICATE,
    GLUED_VARIABLE,
    IMPLICIT_PREDICATE,
    REPEATED_VARIABLE,
)
from solvers.classical import (
    GroundAction,
    GroundingError,
    PlanningTask,
    plan,
    task_from_problem,
    validated_plan_cost,
)

# Untyped STRIPS in upper case, a repeated variable in a declaration, '?' glued to names,
# a predicate declared twice, and predicates that only the problem uses.
DOMAIN = """;; a small logistics
(define (DOMAIN Haul)
  (:REQUIREMENTS :STRIPS)
  (:PREDICATES (OBJ ?obj) (TRUCK ?truck) (LOCATION ?loc)
               (AT ?obj ?loc) (IN ?obj ?obj) (Obj ?o))
  (:ACTION LOAD
    :PARAMETERS (?o ?t ?l)
    :PRECONDITION (AND (OBJ?o) (TRUCK ?t) (AT ?o ?l) (AT?t?l))
    :EFFECT (AND (NOT (AT ?o ?l)) (IN ?o ?t)))
  (:ACTION UNLOAD
    :PARAMETERS (?o ?t ?l)
    :PRECONDITION (AND (IN ?o ?t) (AT ?t ?l))
    :EFFECT (AND (NOT (IN ?o ?t)) (AT ?o ?l)))
  (:ACTION DRIVE
    :PARAMETERS (?t ?from ?to)
    :PRECONDITION (AND (TRUCK ?t) (LOCATION ?from) (LOCATION ?to) (AT ?t ?from))
    :EFFECT (AND (NOT (AT ?t ?from)) (AT ?t ?to))))
"""
PROBLEM = """(define (PROBLEM haul-1) (:DOMAIN HAUL)
  (:OBJECTS P1 P2 T1 A B)
  (:INIT (OBJ P1) (OBJ P2) (TRUCK T1) (LOCATION A) (LOCATION B)
         (AT P1 A) (AT P2 A) (AT T1 A) (FRAGILE P2) (ROAD A B))
  (:GOAL (AND (AT P1 B) (AT P2 B) (ROAD A B))))
"""


def _write(tmp_path: Path) -> tuple[Path, Path]:
    domain, problem = tmp_path / "domain.pddl", tmp_path / "problem.pddl"
    domain.write_text(DOMAIN)
    problem.write_text(PROBLEM)
    return domain, problem


def _solve_and_validate(domain_text: str, problem_text: str) -> tuple[GroundAction, ...]:
    domain = parse_domain(domain_text, "domain.pddl")
    task = task_from_problem(domain, parse_problem(problem_text, domain, "problem.pddl"))
    result = plan(task)
    assert result.solved and result.plan is not None
    assert validated_plan_cost(task, result.plan) == len(result.plan)
    return result.plan


def test_quirky_domain_parses_with_noted_leniencies() -> None:
    domain = parse_domain(DOMAIN, "domain.pddl")
    assert domain.name == "haul" and domain.predicates["in"].arity == 2
    assert [(i.kind, str(i.location)) for i in domain.leniencies] == [
        (REPEATED_VARIABLE, "domain.pddl:5:40"),
        (DUPLICATE_PREDICATE, "domain.pddl:5:46"),
        (GLUED_VARIABLE, "domain.pddl:8:28"),
        (GLUED_VARIABLE, "domain.pddl:8:57"),
        (GLUED_VARIABLE, "domain.pddl:8:59"),
    ]
    problem = parse_problem(PROBLEM, domain, "problem.pddl")
    assert [(i.kind, str(i.location)) for i in problem.leniencies] == [
        (IMPLICIT_PREDICATE, "problem.pddl:4:41"),
        (IMPLICIT_PREDICATE, "problem.pddl:4:54"),
    ]


def test_quirky_domain_solves_and_the_plan_validates() -> None:
    steps = _solve_and_validate(DOMAIN, PROBLEM)
    assert [s.name for s in steps].count("drive") == 1
    assert {s.args[0] for s in steps if s.name == "unload"} == {"p1", "p2"}


def test_plan_command_solves_the_quirky_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = _write(tmp_path)
    assert main(["plan", str(domain), str(problem)]) == 0
    assert "status: solved" in capsys.readouterr().out


def test_plan_strict_prints_located_warnings_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = _write(tmp_path)
    assert main(["plan", "--strict", str(domain), str(problem)]) == 2
    captured = capsys.readouterr()
    warnings = [line for line in captured.err.splitlines() if line.startswith("sdar: warning:")]
    assert len(warnings) == 5
    assert f"sdar: warning: {domain}:5:40: variable ?obj appears twice" in warnings[0]
    assert f"{domain}:8:28: '?o' is glued" in warnings[2]
    assert "sdar: error: --strict: 5 warning(s)" in captured.err
    assert "status:" not in captured.out


def test_plan_strict_checks_the_problem_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = _write(tmp_path)
    clean = (
        DOMAIN.replace("(IN ?obj ?obj) (Obj ?o)", "(IN ?obj ?t)")
        .replace("(OBJ?o)", "(OBJ ?o)")
        .replace("(AT?t?l)", "(AT ?t ?l)")
    )
    domain.write_text(clean)
    assert main(["plan", "--strict", str(domain), str(problem)]) == 2
    err = capsys.readouterr().err
    assert f"sdar: warning: {problem}:4:41: predicate 'fragile' is not declared" in err
    problem.write_text(PROBLEM.replace(" (FRAGILE P2) (ROAD A B)", "").replace(" (ROAD A B)", ""))
    assert main(["plan", "--strict", str(domain), str(problem)]) == 0
    assert "status: solved" in capsys.readouterr().out


# --- the real IPC files, when present ---------------------------------------------------------

IPC_DIR = os.environ.get("SDAR_IPC_DIR")
IPC_PROBLEMS = [
    ("logistics00", "probLOGISTICS-4-0.pddl"),
    ("logistics00", "probLOGISTICS-6-1.pddl"),
    ("zenotravel", "p01.pddl"),
    ("zenotravel", "p05.pddl"),
]


@pytest.mark.skipif(IPC_DIR is None, reason="set SDAR_IPC_DIR to a folder of IPC domains")
@pytest.mark.parametrize(("folder", "problem"), IPC_PROBLEMS)
def test_real_ipc_problem_parses_solves_and_validates(folder: str, problem: str) -> None:
    base = Path(str(IPC_DIR)) / folder
    if not (base / problem).is_file():
        pytest.skip(f"{base / problem} is missing")
    steps = _solve_and_validate((base / "domain.pddl").read_text(), (base / problem).read_text())
    assert steps


@pytest.mark.parametrize("value", [float("nan"), float("inf")])
def test_non_finite_cost_value_in_a_task_is_a_grounding_error(value: float) -> None:
    domain = parse_domain(
        "(define (domain c) (:requirements :action-costs) (:predicates (done))"
        " (:functions (price)) (:action a :effect (and (done) (increase (total-cost) (price)))))"
    )
    task = PlanningTask(domain, {}, frozenset(), Atom("done"), numeric_init={("price", ()): value})
    with pytest.raises(GroundingError, match="finite and non-negative"):
        plan(task)


FREE_VARIABLES = """(define (domain f) (:requirements :strips :derived-predicates)
 (:predicates (on ?x ?y) (clear ?x) (covered ?x) (p ?x))
 (:derived (covered ?x) (and (clear ?x) (on ?y ?x)))
 (:action a :parameters (?x) :precondition (and (clear ?x) (on ?x ?z) (p ?z) (covered ?x))
  :effect (and (not (clear ?x)) (p ?x))))
"""


@pytest.mark.parametrize(
    ("init", "solvable"),
    [("(clear b) (on b c) (p c) (on a b)", True), ("(clear b) (on b c) (on a b)", False)],
)
def test_free_variables_are_read_as_existential(init: str, solvable: bool) -> None:
    # (covered b) needs some ?y on b; action a needs some ?z under ?x with (p ?z)
    problem = f"(define (problem q) (:domain f) (:objects a b c) (:init {init}) (:goal (p b)))"
    if solvable:
        assert [s.name for s in _solve_and_validate(FREE_VARIABLES, problem)] == ["a"]
    else:
        domain = parse_domain(FREE_VARIABLES, "domain.pddl")
        result = plan(task_from_problem(domain, parse_problem(problem, domain, "problem.pddl")))
        assert not result.solved
