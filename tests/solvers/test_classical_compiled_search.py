"""The compiled successor generator, the switch to compiled code mid-search, and the type-based
exploration queue of greedy lazy search."""

from __future__ import annotations

import random
import sys

import pytest
from classical_helpers import load
from test_classical_relaxed_engines import _gripper, _states, needs_numba

from sdar_tamp.errors import ParameterError
from solvers.classical import bitset_task as compiled_module
from solvers.classical import ground, heuristics, jit_relaxed, plan
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.heuristics import RelaxedHeuristic
from solvers.classical.open_lists import TypeBuckets


@needs_numba
def test_compiled_successors_list_the_same_operators_in_the_same_order() -> None:
    for task in (_gripper(100), load("logistics", "three-cities"), load("briefcase", "office")):
        python = CompiledTask(ground(task))
        fast = CompiledTask(ground(task))
        fast.use_compiled_successors()
        for state in _states(python, 80, seed=11):
            assert fast.applicable(state) == python.applicable(state)


@needs_numba
def test_compiled_successors_respect_negative_preconditions() -> None:
    task = load("briefcase", "lights-out")
    compiled = CompiledTask(ground(task))
    assert any(op[1] for op in compiled.operators), "the case needs negative preconditions"
    fast = CompiledTask(ground(task))
    fast.use_compiled_successors()
    for state in _states(compiled, 60, seed=5):
        assert fast.applicable(state) == compiled.applicable(state)


@needs_numba
def test_large_tasks_switch_to_compiled_successors_after_enough_calls(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(compiled_module, "JIT_AFTER_CALLS", 5)
    compiled = CompiledTask(ground(_gripper(100)))
    reference = CompiledTask(ground(_gripper(100)))
    reference._jit_pending = False
    states = _states(reference, 12, seed=2)
    lists = [compiled.applicable(state) for state in states]
    assert compiled._jit is not None
    assert lists == [reference.applicable(state) for state in states]
    small = CompiledTask(ground(load("blocksworld", "sussman")))
    for state in _states(small, 12, seed=2):
        small.applicable(state)
    assert small._jit is None


@needs_numba
def test_large_tasks_switch_to_the_compiled_heuristic_after_its_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(heuristics, "JIT_AFTER_SECONDS", 0.0)
    # a process that has not loaded the compiled code yet (an earlier test of this worker may
    # have: a later task then uses it at once, tested in test_classical_relaxed_engines.py)
    monkeypatch.setattr(jit_relaxed, "kernel_loaded", lambda: False)
    compiled = CompiledTask(ground(_gripper(100)))
    auto = RelaxedHeuristic(compiled, "ff", compiled.costs)
    python = RelaxedHeuristic(compiled, "ff", compiled.costs, engine="python")
    python.canonical, python.heap_order = False, True  # as "auto" on a large task with numba
    assert auto.jit is None and auto.jit_pending
    states = _states(compiled, 10, seed=4)
    assert auto(states[0], True) == python(states[0], True)  # by the queue, then switches
    assert auto.jit is not None and not auto.jit_pending
    for state in states[1:]:
        assert auto(state, True) == python(state, True)


def test_type_buckets_pop_every_successor_once() -> None:
    buckets = TypeBuckets(seed=1)
    pushed = set()
    rng = random.Random(0)
    for origin in range(30):
        operators = list(range(rng.randint(1, 6)))
        buckets.push((float(origin % 4), float(origin % 3)), origin, 0.0, operators)
        pushed |= {(origin, op) for op in operators}
    popped = []
    while buckets:
        origin, op, g = buckets.pop()
        assert g == 0.0
        popped.append((origin, op))
    assert len(popped) == len(pushed) and set(popped) == pushed
    assert not buckets.keys and not buckets.buckets


@pytest.mark.parametrize(
    ("domain", "problem"), [("logistics", "three-cities"), ("briefcase", "office")]
)
def test_exploration_is_repeatable_and_valid(domain: str, problem: str) -> None:
    task = load(domain, problem)
    first = plan(task, search="lazy-gbfs", heuristic="ff-lmcount")
    again = plan(task, search="lazy-gbfs", heuristic="ff-lmcount")
    assert first.plan is not None  # plan() validates every plan it returns
    assert first.plan == again.plan
    assert first.statistics.expanded == again.statistics.expanded
    without = plan(task, search="lazy-gbfs", heuristic="ff-lmcount", exploration=False)
    assert without.plan is not None
    lazy_gbfs = plan(task, search="gbfs", lazy=True, exploration=True)
    assert lazy_gbfs.plan is not None


@pytest.mark.parametrize(("search", "lazy"), [("astar", False), ("wastar", True), ("gbfs", False)])
def test_exploration_needs_greedy_lazy_search(search: str, lazy: bool) -> None:
    task = load("blocksworld", "sussman")
    with pytest.raises(ParameterError, match="exploration needs greedy lazy search"):
        plan(task, search=search, lazy=lazy, exploration=True)


@needs_numba
def test_a_broken_numba_leaves_the_search_on_the_python_engines(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Compiled code that fails to load mid-search: a warning, then the same search in Python."""
    from solvers.classical import jit, jit_relaxed, jit_successors

    task = _gripper(100)
    reference = plan(task, search="lazy-gbfs", heuristic="ff-lmcount")

    def broken(*_args: object) -> object:
        raise OSError("llvmlite: cannot load the shared library")

    monkeypatch.setattr(jit_relaxed, "_kernel", lambda: broken)
    monkeypatch.setattr(jit_successors, "_applicable_kernel", lambda: broken)
    monkeypatch.setattr(jit, "_broken", [])
    monkeypatch.setattr(heuristics, "JIT_AFTER_SECONDS", 0.0)
    monkeypatch.setattr(compiled_module, "JIT_AFTER_CALLS", 3)
    with caplog.at_level("WARNING"):
        again = plan(task, search="lazy-gbfs", heuristic="ff-lmcount")
    assert again.plan == reference.plan
    assert again.statistics.expanded == reference.statistics.expanded
    assert "numba cannot run the heuristic: llvmlite: cannot load" in caplog.text
    assert "the search goes on without compiled code" in caplog.text
    # the failure is remembered: later tasks do not try again, an explicit request is refused
    assert not jit.available()
    compiled = CompiledTask(ground(task))
    assert RelaxedHeuristic(compiled, "ff", compiled.costs).jit_pending is False
    with pytest.raises(
        ParameterError,
        match=r"engine 'numba' is unavailable: numba failed in this process "
        r"\(the heuristic: llvmlite",
    ):
        RelaxedHeuristic(compiled, "ff", compiled.costs, engine="numba")


def test_numba_that_cannot_be_imported_is_remembered(monkeypatch: pytest.MonkeyPatch) -> None:
    from solvers.classical import jit, jit_relaxed

    monkeypatch.setattr(jit, "_broken", [])
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba -> ImportError
    with pytest.raises(jit.CompiledCodeUnavailable, match="numba cannot run _evaluate"):
        jit.compile_kernel(jit_relaxed._evaluate)
    assert not jit.available()
    assert "numba failed in this process (_evaluate:" in jit.why_unavailable()


@needs_numba
def test_a_later_task_walks_its_trie_compiled_at_once() -> None:
    """Once the process loaded the compiled trie walk, a new large task uses it from its first
    successor list (the rounds of a stream planning solve ground one task each)."""
    from solvers.classical import jit_successors

    compiled = CompiledTask(ground(_gripper(100)))
    compiled.use_compiled_successors()
    assert jit_successors.kernel_loaded()
    later = CompiledTask(ground(_gripper(100)))
    first = later.applicable(later.init)
    assert later._jit is not None  # compiled from the first call
    assert first == compiled.applicable(compiled.init)
