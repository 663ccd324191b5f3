"""PDDLProblem: values become objects, and every bad argument is named."""

import numpy as np
import pytest

from sdar_tamp.language import (
    ArityError,
    ProblemDefinitionError,
    StreamMapError,
    UndeclaredError,
)
from sdar_tamp.language.formula_model import And as AndF
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.formula_model import Exists as ExistsF
from sdar_tamp.language.formulas import And, Equal, Exists, Not
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem

DOMAIN = """(define (domain pick) (:requirements :strips :typing :equality)
  (:types block - thing thing)
  (:constants table - thing)
  (:predicates (on ?b ?s) (pose ?b ?p) (atpose ?b ?p) (holding ?b))
  (:functions (total-cost) (dist ?a ?b))
  (:action pick :parameters (?b - block ?p) :precondition (atpose ?b ?p)
     :effect (and (holding ?b) (not (atpose ?b ?p)))))"""
STREAM = """(define (stream s)
  (:stream sample :inputs (?b) :domain (block ?b) :outputs (?p) :certified (pose ?b ?p))
  (:stream free :inputs (?p) :domain (Grasp ?p))
  (:stream grasp :inputs (?b) :domain (block ?b) :outputs (?g)
  :certified (Grasp ?g)))"""
TABLE = object()


def make(**changes: object) -> PDDLProblem:
    args: dict[str, object] = {
        "domain_pddl": DOMAIN,
        "constant_map": {"TABLE": TABLE},
        "stream_pddl": STREAM,
        "stream_map": {
            "sample": from_gen_fn(lambda b: iter([(0.0,)])),
            "free": from_test(lambda p: True),
            "GRASP": from_gen_fn(lambda b: iter([("g",)])),
        },
        "init": [
            ("Block", "a"),
            ("AtPose", "a", (1.0, 2.0)),
            ("on", "a", TABLE),
            Equal(("total-cost",), 0),
        ],
        "goal": And(("Holding", "a"), Not(("on", "a", TABLE))),
    }
    args.update(changes)
    return PDDLProblem(*args.values())  # type: ignore[arg-type]


def test_values_become_named_objects_and_come_back() -> None:
    problem = make()
    facts = problem.facts
    a = problem.objects.name("a")
    pose = problem.objects.name((1.0, 2.0))
    assert Atom("atpose", (a, pose)) in facts.init
    assert Atom("on", (a, "table")) in facts.init
    assert problem.objects.value("table") is TABLE
    assert problem.objects.value(pose) == (1.0, 2.0)
    assert facts.numeric == {("total-cost", ()): 0.0}
    assert isinstance(facts.goal, AndF)


def test_type_facts_give_the_most_specific_type_and_its_ancestors() -> None:
    facts = make().facts
    a = make().objects.name("a")
    assert facts.objects[a] == "block"
    assert Atom("thing", (a,)) in facts.init
    assert Atom("thing", ("table",)) in facts.init


def test_hashable_values_by_value_unhashable_by_identity() -> None:
    array = np.zeros(3)
    other = np.zeros(3)
    problem = make(
        init=[
            ("pose", "a", array),
            ("pose", "a", other),
            ("pose", "a", (1, 2)),
            ("pose", "a", (1, 2)),
        ]
    )
    names = {atom.args[1] for atom in problem.facts.init if atom.predicate == "pose"}
    assert len(names) == 3
    assert problem.objects.value(problem.objects.name(array)) is array


def test_quantified_goal_with_variables() -> None:
    problem = make(goal=Exists(["?b"], ("holding", "?b")))
    assert isinstance(problem.facts.goal, ExistsF)
    assert problem.facts.goal.body == Atom("holding", ("?b",))


def test_unpacks_like_a_tuple() -> None:
    domain_pddl, constant_map, stream_pddl, stream_map, init, goal = make()
    assert domain_pddl == DOMAIN and "TABLE" in constant_map and stream_pddl == STREAM
    assert set(stream_map) == {"sample", "free", "grasp"}  # type: ignore[arg-type]
    assert len(list(init)) == 4 and goal[0] == "and"


def test_constant_map_missing_a_constant() -> None:
    with pytest.raises(ProblemDefinitionError, match=r"constant_map.*missing: \['table'\]"):
        make(constant_map={})


def test_constant_map_with_an_extra_constant() -> None:
    with pytest.raises(ProblemDefinitionError, match=r"not constants of the domain: \['floor'\]"):
        make(constant_map={"table": TABLE, "floor": 1})


def test_stream_map_missing_a_stream() -> None:
    with pytest.raises(StreamMapError, match="no callable for: free, grasp"):
        make(stream_map={"sample": from_gen_fn(lambda b: iter([]))})


def test_stream_map_naming_an_unknown_stream() -> None:
    stream_map = {name: from_test(bool) for name in ("sample", "free", "grasp", "smaple")}
    with pytest.raises(StreamMapError, match="do not declare: smaple"):
        make(stream_map=stream_map)


def test_stream_map_value_not_callable() -> None:
    with pytest.raises(StreamMapError, match=r"stream_map\['sample'\] must be callable"):
        make(stream_map={"sample": 3, "free": bool, "grasp": bool})


def test_stream_map_debug_and_bad_string() -> None:
    assert make(stream_map="debug").stream_map == "debug"
    with pytest.raises(StreamMapError, match="'debug'"):
        make(stream_map="debgu")


def test_init_with_undeclared_predicate_declares_it() -> None:
    problem = make(init=[("block", "a"), ("InHand", "a")])
    # (the fixture's stream file also earns cross-check warnings: tests/language/test_cross_check)
    (leniency,) = (item for item in problem.leniencies if item.kind == "implicit-predicate")
    assert str(leniency.location).startswith("init[1]") and "'inhand'" in leniency.message


def test_init_with_wrong_arity() -> None:
    with pytest.raises(ArityError, match=r"init\[0\].*'on' takes 2"):
        make(init=[("on", "a")])


def test_init_with_unrelated_types() -> None:
    domain = DOMAIN.replace("thing thing)", "thing thing ball)")
    with pytest.raises(ProblemDefinitionError, match="unrelated type"):
        make(domain_pddl=domain, init=[("block", "a"), ("ball", "a")])


def test_goal_with_unbound_variable() -> None:
    with pytest.raises(ProblemDefinitionError, match=r"goal.*variable \?b is not bound"):
        make(goal=("holding", "?b"))


def test_goal_that_is_not_a_formula() -> None:
    with pytest.raises(ProblemDefinitionError, match="expected a formula tuple"):
        make(goal="holding a")


def test_bad_numeric_value() -> None:
    with pytest.raises(ProblemDefinitionError, match="expected a finite number"):
        make(init=[Equal(("total-cost",), "zero")])


def test_undeclared_function_in_init() -> None:
    with pytest.raises(UndeclaredError, match="undeclared function 'length'"):
        make(init=[Equal(("length", "a"), 3)])


def test_domain_errors_name_the_domain_file() -> None:
    with pytest.raises(UndeclaredError, match=r"domain\.pddl:1:"):
        make(domain_pddl="(define (domain d) (:action a :precondition (p)))")
