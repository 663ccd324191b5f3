"""An action parameter of a declared type that only a stream's untyped output could fill: a
located ``untyped-output`` warning, and the first reason of the diagnosis when no plan exists."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.compat.pddlstream import PDDLProblem, from_gen_fn, solve
from sdar_tamp.language.cross_check import cross_check
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.leniency import UNTYPED_OUTPUT
from sdar_tamp.language.streams import parse_stream_file
from solvers.solution import Status


def _domain(parameters: str) -> str:
    return f"""(define (domain rooms) (:requirements :strips :typing)
  (:types room item)
  (:predicates (done ?i - item ?r - room) (region ?r - room ?p) (holding ?i - item))
  (:action put :parameters {parameters}
     :precondition (and (holding ?i) (region ?r ?p))
     :effect (and (done ?i ?r) (not (holding ?i)))))"""


# PDDL's typed-list rule: "?p ?r - room" gives ?p the type room too
WRONG = _domain("(?i - item ?p ?r - room)")
RIGHT = _domain("(?i - item ?r - room ?p)")
STREAMS = """(define (stream rooms)
  (:stream sample :inputs (?r) :domain (room ?r) :outputs (?p) :certified (region ?r ?p)))"""
TYPED_STREAMS = STREAMS.replace("(region ?r ?p)", "(and (room ?p) (region ?r ?p))")


def _warnings(domain_text: str, streams_text: str) -> list[str]:
    domain = parse_domain(domain_text, "domain.pddl")
    streams = parse_stream_file(streams_text, domain, "stream.pddl")
    return [str(w) for w in cross_check(domain, streams) if w.kind == UNTYPED_OUTPUT]


def test_a_typed_parameter_where_only_an_untyped_output_fits_is_a_located_warning() -> None:
    (warning,) = _warnings(WRONG, STREAMS)
    assert warning.startswith("domain.pddl:4:3: action 'put': parameter ?p has type 'room'")
    assert "argument 2 of 'region' is stream 'sample''s output ?p" in warning
    assert "certify (room ?p) in the stream" in warning


def test_no_warning_when_the_parameter_is_untyped_or_the_stream_certifies_the_type() -> None:
    assert _warnings(RIGHT, STREAMS) == []
    assert _warnings(WRONG, TYPED_STREAMS) == []


def _problem(domain: str, streams: str) -> PDDLProblem:
    return PDDLProblem(
        domain,
        {},
        streams,
        {"sample": from_gen_fn(lambda room: iter([(1.0,)]))},
        [("item", "mug"), ("room", "office"), ("holding", "mug")],
        ("done", "mug", "office"),
    )


def test_the_warning_is_logged_and_leads_the_diagnosis(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, "sdar_tamp.language"):
        problem = _problem(WRONG, STREAMS)
    assert any("[untyped-output]" in r.getMessage() for r in caplog.records)
    solution = solve(problem, algorithm="adaptive", max_time=10, verbose=False)
    assert solution.status is Status.INFEASIBLE
    assert solution.diagnosis[0].startswith("the problem has a warning: domain.pddl:4:3:")
    assert "[untyped-output]" in solution.diagnosis[0]


@pytest.mark.parametrize("streams", [STREAMS, TYPED_STREAMS])
def test_the_mended_domain_or_a_typed_output_solves(streams: str) -> None:
    domain = RIGHT if streams == STREAMS else WRONG
    solution = solve(_problem(domain, streams), algorithm="adaptive", max_time=10, verbose=False)
    assert solution.status is Status.SOLVED
    assert [a.name for a in solution.plan or ()] == ["put"]


def test_sdar_check_prints_it_and_strict_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, stream = tmp_path / "domain.pddl", tmp_path / "stream.pddl"
    domain.write_text(WRONG)
    stream.write_text(STREAMS)
    assert main(["check", str(domain), "--streams", str(stream)]) == 0
    assert f"sdar: warning: {domain}:4:3: action 'put': parameter ?p" in capsys.readouterr().err
    assert main(["check", str(domain), "--streams", str(stream), "--strict"]) == 2
    assert "--strict: 1 warning(s)" in capsys.readouterr().err
