"""`StreamInfo(opt_gen_fn="shared")`: one placeholder per stream output, valid plans."""

from sdar_tamp.language.generators import from_gen_fn
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """(define (domain shelf) (:requirements :strips)
  (:predicates (item ?b) (slot ?b ?p) (at ?b ?p) (placed ?b))
  (:action put :parameters (?b ?p) :precondition (and (item ?b) (slot ?b ?p))
     :effect (and (at ?b ?p) (placed ?b))))"""
STREAMS = """(define (stream shelf)
  (:stream sample-slot :inputs (?b) :domain (item ?b) :outputs (?p) :certified (slot ?b ?p)))"""


def test_two_items_each_get_their_own_value() -> None:
    def slots(item: str):  # type: ignore[no-untyped-def]
        for k in range(3):
            yield (f"{item}-slot{k}",)

    problem = PDDLProblem(
        DOMAIN,
        {},
        STREAMS,
        {"sample-slot": from_gen_fn(slots)},
        [("item", "a"), ("item", "b")],
        ("and", ("placed", "a"), ("placed", "b")),
    )
    for algorithm in ("focused", "binding", "adaptive"):
        solution = solve(
            problem,
            algorithm=algorithm,
            max_time=10,
            stream_info={"sample-slot": StreamInfo(opt_gen_fn="shared")},
        )
        assert solution.status is Status.SOLVED, algorithm
        assert solution.plan is not None
        for action in solution.plan:
            item, slot = action.args
            assert slot.startswith(f"{item}-slot")


def test_a_plan_on_shared_placeholders_refines_its_instances() -> None:
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder

    def slots(item: str):  # type: ignore[no-untyped-def]
        yield (f"{item}-slot",)

    problem = PDDLProblem(
        DOMAIN,
        {},
        STREAMS,
        {"sample-slot": from_gen_fn(slots)},
        [("item", "a"), ("item", "b")],
        ("and", ("placed", "a"), ("placed", "b")),
    )
    engine = Engine(problem, {"sample-slot": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    builder = OptimisticBuilder(engine, frozenset())
    shared = builder.build(10)
    outputs = {r.outputs for r in shared.provenance.values() if r.external == "sample-slot"}
    assert len(outputs) == 1  # one placeholder for both items
    plan = list({id(r): r for r in shared.provenance.values()}.values())
    assert builder.refine(plan) is True
    assert builder.refine(plan) is False  # already refined
    refined = builder.build(10)
    outputs = {r.outputs for r in refined.provenance.values() if r.external == "sample-slot"}
    assert len(outputs) == 2  # each item's instance has its own
