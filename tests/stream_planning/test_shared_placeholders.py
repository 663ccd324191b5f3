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


def _one_item_problem() -> PDDLProblem:
    def slots(item: str):  # type: ignore[no-untyped-def]
        yield (f"{item}-slot",)

    return PDDLProblem(
        DOMAIN, {}, STREAMS, {"sample-slot": from_gen_fn(slots)}, [("item", "a")], ("placed", "a")
    )


def test_a_shared_placeholder_one_result_makes_is_bound_without_a_new_search() -> None:
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder

    engine = Engine(_one_item_problem(), {"sample-slot": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    builder = OptimisticBuilder(engine, frozenset())
    world = builder.build(10)
    plan = list({id(r): r for r in world.provenance.values()}.values())
    assert [r.external for r in plan if r.kind == "stream"] == ["sample-slot"]
    assert builder.refine(plan) is False  # one producer: the placeholder means its output
    assert builder.refined == set()


def test_shared_and_unique_placeholders_need_as_many_searches_when_unambiguous() -> None:
    counts = {}
    for mode in ("shared", "unique"):
        solution = solve(
            _one_item_problem(),
            algorithm="adaptive",
            max_time=10,
            stream_info={"sample-slot": StreamInfo(opt_gen_fn=mode)},
        )
        assert solution.status is Status.SOLVED and solution.plan is not None
        assert solution.plan[0].args == ("a", "a-slot")
        counts[mode] = solution.statistics["iterations"]
    assert counts["shared"] == counts["unique"]


CHAIN_DOMAIN = """(define (domain chain) (:requirements :strips)
  (:predicates (num ?x) (big ?x) (done))
  (:action finish :parameters (?x) :precondition (big ?x) :effect (done)))"""
CHAIN_STREAMS = """(define (stream chain)
  (:stream next :inputs (?x) :domain (num ?x) :outputs (?y) :certified (num ?y))
  (:stream test-big :inputs (?x) :domain (num ?x) :certified (big ?x)))"""


def test_a_shared_placeholder_fed_back_to_its_own_stream_is_refined() -> None:
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder, OptResult

    problem = PDDLProblem(
        CHAIN_DOMAIN,
        {},
        CHAIN_STREAMS,
        {
            "next": from_gen_fn(lambda x: iter([(x + 1,)])),
            "test-big": from_gen_fn(lambda x: iter([()] if x >= 2 else [])),
        },
        [("num", 0)],
        ("done",),
    )
    engine = Engine(problem, {"next": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    builder = OptimisticBuilder(engine, frozenset())
    world = builder.build(10)
    loop = [
        r for r in {id(r): r for r in world.provenance.values()}.values() if r.external == "next"
    ]
    assert len(loop) == 1  # next(0) -> #o; next(#o) adds nothing new
    (first,) = loop
    again = OptResult("next", first.outputs, first.outputs, (), (), first.level + 1, "stream")
    assert builder.refine([again]) is True  # takes its own output: ambiguous
    solution = solve(problem, algorithm="adaptive", max_time=10, stream_info={
        "next": StreamInfo(opt_gen_fn="shared")})  # fmt: skip
    assert solution.status is Status.SOLVED and solution.plan is not None
    assert solution.plan[0].args == (2,)
