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


def test_refining_gives_every_instance_of_the_stream_its_own_placeholder() -> None:
    """A plan that takes the shared placeholder from two of three instances refines the
    stream: the third instance, which the plan did not use, gets its own too (else the next
    plan takes it and one other, and each round refines one more pair)."""
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder

    def slots(item: str):  # type: ignore[no-untyped-def]
        yield (f"{item}-slot",)

    problem = PDDLProblem(
        DOMAIN,
        {},
        STREAMS,
        {"sample-slot": from_gen_fn(slots)},
        [("item", "a"), ("item", "b"), ("item", "c")],
        ("and", ("placed", "a"), ("placed", "b")),
    )
    engine = Engine(problem, {"sample-slot": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    builder = OptimisticBuilder(engine, frozenset())
    world = builder.build(10)
    results = [r for r in {id(r): r for r in world.provenance.values()}.values()]
    assert len(results) == 3 and len({r.outputs for r in results}) == 1  # all share one
    plan = results[:2]
    assert builder.refine(plan) is True
    assert builder.refined == {"sample-slot"}
    refined = builder.build(10)
    outputs = {r.inputs: r.outputs for r in refined.provenance.values()}
    assert len(set(outputs.values())) == 3  # c's too


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


LEVELS_DOMAIN = """(define (domain reach) (:requirements :strips)
  (:predicates (item ?b) (pos ?b ?p) (conf ?q) (path ?q ?t) (done))
  (:action go :parameters (?q ?t) :precondition (path ?q ?t) :effect (done)))"""
LEVELS_STREAMS = """(define (stream reach)
  (:stream sample-pos :inputs (?b) :domain (item ?b) :outputs (?p) :certified (pos ?b ?p))
  (:stream ik :inputs (?b ?p) :domain (pos ?b ?p) :outputs (?q) :certified (conf ?q))
  (:stream plan-path :inputs (?q) :domain (conf ?q) :outputs (?t) :certified (path ?q ?t)))"""


def _levels_problem() -> PDDLProblem:
    def positions(item: str):  # type: ignore[no-untyped-def]
        for k in range(10):
            yield (f"{item}-p{k}",)

    return PDDLProblem(
        LEVELS_DOMAIN,
        {},
        LEVELS_STREAMS,
        {
            "sample-pos": from_gen_fn(positions),
            "ik": from_gen_fn(lambda b, p: iter([(f"q-{p}",)])),
            "plan-path": from_gen_fn(lambda q: iter([(f"t-{q}",)])),
        },
        [("item", "a")],
        ("done",),
    )


def test_a_shared_placeholder_takes_the_lowest_level_of_the_instances_that_make_it() -> None:
    """Real positions from the 1st to the 5th call (levels 1 to 5) all feed one shared ik
    placeholder: it enters at the level the first position gives it (2), not at that of the
    instance met first, and plan-path on it (3) is in the world at limit 3."""
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder, is_placeholder

    engine = Engine(_levels_problem(), {"ik": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    (state,) = engine.instances.values()  # sample-pos on the item
    for _ in range(5):
        assert engine.sample(state)
    levels = engine.store.levels
    positions = {a.args[1]: level for a, level in levels.items() if a.predicate == "pos"}
    assert sorted(positions.values()) == [1, 2, 3, 4, 5]
    world = OptimisticBuilder(engine, frozenset()).build(3)
    confs = {a: level for a, level in world.facts.items() if a.predicate == "conf"}
    assert len(confs) == 1 and all(is_placeholder(a.args[0]) for a in confs)
    assert list(confs.values()) == [2]
    assert [level for a, level in world.facts.items() if a.predicate == "path"] == [3]
    first = next(p for p, level in positions.items() if level == 1)
    assert world.provenance[next(iter(confs))].inputs[1] == first  # made on the first one


def test_real_facts_of_later_samples_do_not_hide_the_plan_on_earlier_ones() -> None:
    """A solve whose sampler has been called many times before a plan is searched for at the
    level that the first samples allow finds that plan there."""
    from solvers.stream_planning.engine import Engine
    from solvers.stream_planning.optimistic import OptimisticBuilder

    engine = Engine(_levels_problem(), {"ik": StreamInfo(opt_gen_fn="shared")})
    engine.start()
    (state,) = engine.instances.values()
    for _ in range(8):
        engine.sample(state)
    for limit in range(3, 9):
        world = OptimisticBuilder(engine, frozenset()).build(limit)
        assert any(a.predicate == "path" for a in world.facts), limit
