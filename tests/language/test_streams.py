"""Stream files: streams, tests, functions, predicates and rules."""

from sdar_tamp.language import parse_domain, parse_stream_file
from sdar_tamp.language.formula_model import Atom, FunctionTerm

DOMAIN = parse_domain(
    """(define (domain pick) (:requirements :strips :typing) (:types block region)
       (:predicates (block-at ?b ?p) (pose ?b ?p) (contained ?b ?p ?r) (cfree ?p ?q)
                    (atpose ?b ?p)))""",
    "domain.pddl",
)

STREAMS = """
(define (stream pick-streams)
  (:stream sample-pose
    :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r) (Stable ?p)))
  (:stream test-cfree :inputs (?p ?q) :domain (and (Stable ?p) (Stable ?q))
    :certified (cfree ?p ?q))
  (:stream plan-motion :inputs (?p) :domain (Stable ?p) :fluents (atpose)
    :outputs (?t) :certified (Traj ?p ?t))
  (:function (Distance ?p ?q) (and (Stable ?p) (Stable ?q)))
  (:predicate (Collides ?p ?q) (and (Stable ?p) (Stable ?q)))
  (:rule :parameters (?b ?p) :domain (pose ?b ?p) :certified (Stable ?p)))
"""


def test_stream_file_contents() -> None:
    streams = parse_stream_file(STREAMS, DOMAIN, "stream.pddl")
    assert streams.name == "pick-streams"
    sample, test, motion = streams.streams
    assert sample.name == "sample-pose" and sample.inputs == ("?b", "?r")
    assert sample.outputs == ("?p",) and not sample.is_test
    assert Atom("stable", ("?p",)) in sample.certified
    assert Atom("block", ("?b",)) in sample.domain  # type names are unary predicates
    assert test.is_test and test.certified == (Atom("cfree", ("?p", "?q")),)
    assert motion.fluents == ("atpose",)
    (function,) = streams.functions
    assert function.head == FunctionTerm("distance", ("?p", "?q"))
    (predicate,) = streams.predicates
    assert predicate.name == "collides" and predicate.inputs == ("?p", "?q")
    (rule,) = streams.rules
    assert rule.parameters == ("?b", "?p") and rule.certified == (Atom("stable", ("?p",)),)
    assert sample.location is not None and sample.location.line == 3
