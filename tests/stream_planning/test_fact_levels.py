"""The optimistic world gives each fact the lowest level any stream result gives it.

A stream without options shares its optimistic outputs between its instances (PDDLStream's
default, kept by the compatibility layer), so one fact on a shared placeholder is certified by
many instances; with a sampler that never runs dry, new samples (of ever higher levels) keep
arriving. The fact must keep the level of its cheapest derivation, and the instances on it be
made at that level: here the plan needs nothing but the initial pose, and is found at level 2
after a handful of samples (taking facts in the order found, the placeholder's fact took the
level of the newest sample and the plan was never found)."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

from sdar_tamp.compat.pddlstream import PDDLProblem, from_fn, from_gen_fn, solve

DOMAIN = """
(define (domain levels) (:requirements :strips)
  (:predicates (obj ?o) (pos ?o ?p) (conf ?q) (kin ?o ?p ?q) (motion ?q ?t) (at ?q) (done ?o))
  (:action go :parameters (?q1 ?q2 ?t)
    :precondition (and (at ?q1) (motion ?q2 ?t) (conf ?q2))
    :effect (and (at ?q2) (not (at ?q1))))
  (:action grab :parameters (?o ?p ?q)
    :precondition (and (kin ?o ?p ?q) (at ?q))
    :effect (done ?o)))
"""
STREAMS = """
(define (stream levels)
  (:stream sample :inputs (?o) :domain (obj ?o) :outputs (?p) :certified (pos ?o ?p))
  (:stream ik :inputs (?o ?p) :domain (pos ?o ?p) :outputs (?q)
    :certified (and (conf ?q) (kin ?o ?p ?q)))
  (:stream motion :inputs (?q) :domain (conf ?q) :outputs (?t) :certified (motion ?q ?t)))
"""


def test_a_shared_placeholder_keeps_its_lowest_level() -> None:
    counter = itertools.count()

    def sample(_obj: str) -> Iterator[tuple[str]]:
        while True:  # never runs dry
            yield (f"p{next(counter)}",)

    streams = {
        "sample": from_gen_fn(sample),
        "ik": from_fn(lambda o, p: (("q", o, p),)),
        "motion": from_fn(lambda q: (("t", q),)),
    }
    init = [("obj", "a"), ("obj", "b"), ("obj", "c"), ("at", "q0"), ("conf", "q0")]
    init.append(("pos", "a", "pa"))
    problem = PDDLProblem(DOMAIN, {}, STREAMS, streams, init, ("done", "a"))
    solution = solve(problem, algorithm="adaptive", max_time=60, verbose=False)
    assert solution.plan is not None
    assert [a.name for a in solution.plan] == ["go", "grab"]
    assert solution.plan[1].args[:2] == ("a", "pa")
    assert solution.streams["sample"].calls <= 12
    assert solution.statistics["complexity"] <= 3


def test_a_copied_fact_store_joins_as_the_original_and_stays_apart() -> None:
    """The optimistic world starts from a copy of the real facts: the same levels, the same
    join results in the same order, and what the copy learns stays out of the original."""
    from sdar_tamp.language.formula_model import Atom
    from solvers.stream_planning.facts import FactStore

    store = FactStore()
    store.add(Atom("pos", ("a", "p1")), 2)
    store.add(Atom("pos", ("b", "p2")), 0)
    store.add(Atom("pos", ("a", "p1")), 1)  # a lower level for a known atom
    copy = store.copy()
    query = (Atom("pos", ("?o", "?p")),)
    assert list(copy.join(query, {})) == list(store.join(query, {}))
    assert copy.levels == {Atom("pos", ("a", "p1")): 1, Atom("pos", ("b", "p2")): 0}
    assert copy.add(Atom("pos", ("c", "p3")), 3)
    assert Atom("pos", ("c", "p3")) not in store
    assert [b["?o"] for b, _ in store.join((Atom("pos", ("?o", "p3")),), {})] == []
    assert [b["?o"] for b, _ in copy.join((Atom("pos", ("?o", "p3")),), {})] == ["c"]
