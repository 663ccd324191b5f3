"""The stream file checked against its domain: a certified predicate nothing reads and a
predicate the domain reads that nothing makes true are located warnings, recorded in
``PDDLProblem.leniencies`` and printed by ``sdar check`` (errors with ``--strict``)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.language.cross_check import cross_check
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.leniency import UNACHIEVABLE_PREDICATE, UNUSED_CERTIFIED
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.language.streams import parse_stream_file

DOMAIN = """(define (domain line) (:requirements :strips)
  (:predicates (block ?b) (pose ?b ?p) (safe ?p) (at ?b ?p) (done ?b))
  (:action place :parameters (?b ?p)
     :precondition (and (block ?b) (pose ?b ?p) (safe ?p))
     :effect (and (at ?b ?p) (done ?b))))"""

STREAMS = """(define (stream line)
  (:stream sample-pose :inputs (?b) :domain (block ?b) :outputs (?p)
     :certified (pose ?b ?p))
  (:stream test-safe :inputs (?b ?p) :domain (pose ?b ?p)
     :certified (SAFE-POSE ?p)))"""  # a typo: the domain reads (safe ?p)


def _problem(streams: str = STREAMS, init: tuple[tuple[object, ...], ...] = ()) -> PDDLProblem:
    return PDDLProblem(
        DOMAIN,
        {},
        streams,
        {
            "sample-pose": from_gen_fn(lambda b: iter([(1.0,)])),
            "test-safe": from_test(lambda b, p: True),
        },
        [("block", "a"), *init],
        ("done", "a"),
    )


def test_a_certified_typo_is_two_located_warnings(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, "sdar_tamp.language"):
        problem = _problem()
    found = {item.kind: item for item in problem.leniencies}
    unused = found[UNUSED_CERTIFIED]
    assert "stream 'test-safe' certifies 'safe-pose'" in unused.message
    assert str(unused.location) == "stream.pddl:4:3"
    unachievable = found[UNACHIEVABLE_PREDICATE]
    assert unachievable.message.startswith("'safe' is read but no action adds it")
    assert str(unachievable.location) == "domain.pddl:3:3"  # the action that reads it
    assert unachievable.level == logging.WARNING
    # an unread certified fact is often a type-like fact of PDDLStream's idiom: logged at INFO
    assert unused.level == logging.INFO
    levels = {r.getMessage().rsplit("[", 1)[1]: r.levelno for r in caplog.records}
    assert levels == {"unused-certified]": logging.INFO, "unachievable-predicate]": logging.WARNING}


def test_an_initial_fact_makes_a_predicate_achievable() -> None:
    problem = _problem(init=(("safe", 1.0),))
    kinds = [item.kind for item in problem.leniencies]
    assert UNACHIEVABLE_PREDICATE not in kinds and UNUSED_CERTIFIED in kinds


def test_a_consistent_stream_file_has_no_warnings() -> None:
    problem = _problem(STREAMS.replace("SAFE-POSE", "safe"))
    assert problem.leniencies == ()


def test_a_predicate_only_the_goal_reads_is_used() -> None:
    domain = parse_domain(DOMAIN)
    streams = parse_stream_file(
        STREAMS.replace("SAFE-POSE", "safe").replace("(pose ?b ?p))", "(and (pose ?b ?p) (x ?p)))"),
        domain,
    )
    assert [i.kind for i in cross_check(domain, streams)] == [UNUSED_CERTIFIED]
    assert cross_check(domain, streams, goal=Atom("x", ("1",))) == ()


def test_without_the_initial_facts_reads_are_not_checked() -> None:
    domain = parse_domain(DOMAIN)
    streams = parse_stream_file(STREAMS, domain)
    assert [i.kind for i in cross_check(domain, streams)] == [UNUSED_CERTIFIED]


def _files(tmp_path: Path, streams: str) -> tuple[Path, Path, Path]:
    domain, stream, problem = (tmp_path / n for n in ("d.pddl", "s.pddl", "p.pddl"))
    domain.write_text(DOMAIN)
    stream.write_text(streams)
    problem.write_text("(define (problem p) (:domain line) (:objects a) (:init (block a))"
                       " (:goal (done a)))")  # fmt: skip
    return domain, stream, problem


def test_sdar_check_prints_the_warnings(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    domain, stream, problem = _files(tmp_path, STREAMS)
    assert main(["check", str(domain), str(problem), "--streams", str(stream)]) == 0
    err = capsys.readouterr().err
    assert f"sdar: warning: {stream}:4:3: stream 'test-safe' certifies 'safe-pose'" in err
    assert f"sdar: warning: {domain}:3:3: 'safe' is read but" in err
    assert main(["check", str(domain), str(problem), "--streams", str(stream), "--strict"]) == 2
    assert "--strict: 2 warning(s)" in capsys.readouterr().err


def test_sdar_check_of_a_consistent_file_is_quiet(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, stream, problem = _files(tmp_path, STREAMS.replace("SAFE-POSE", "safe"))
    argv = ["check", str(domain), str(problem), "--streams", str(stream), "--strict"]
    assert main(argv) == 0
    assert "warning" not in capsys.readouterr().err
