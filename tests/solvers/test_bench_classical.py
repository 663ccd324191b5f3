"""benchmarks/bench_classical.py: finding IPC domain files, and who validates a plan."""

from __future__ import annotations

import stat
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOMAINS = ROOT / "domains"


@pytest.fixture(scope="module")
def bench(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    return benchmark_script("bench_classical")


def _touch(folder: Path, *names: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        (folder / name).write_text("(define)")


def test_domain_files_of_the_ipc_layouts(bench: ModuleType, tmp_path: Path) -> None:
    _touch(tmp_path / "shared", "domain.pddl", "p01.pddl", "p02.pddl")
    _touch(tmp_path / "under", "domain_p01.pddl", "p01.pddl", "domain_p2_1.pddl", "p2_1.pddl")
    _touch(tmp_path / "dash", "domain-p01.pddl", "p01.pddl")
    _touch(tmp_path / "airport", "p01-domain.pddl", "p01-airport1-p1.pddl")
    _touch(tmp_path / "orphan", "p01.pddl")  # no domain file: left out
    cases = bench.suite_problems(tmp_path)
    found = {(d, p): dom.name for d, p, dom, _ in cases}
    assert found == {
        ("airport", "p01-airport1-p1"): "p01-domain.pddl",
        ("dash", "p01"): "domain-p01.pddl",
        ("shared", "p01"): "domain.pddl",
        ("shared", "p02"): "domain.pddl",
        ("under", "p01"): "domain_p01.pddl",
        ("under", "p2_1"): "domain_p2_1.pddl",
    }
    selected = bench.suite_problems(tmp_path, {"shared": ("p02",)})
    assert [(d, p) for d, p, _, _ in selected] == [("shared", "p02")]
    first = bench.first_per_domain(cases, 1)
    assert [(d, p) for d, p, _, _ in first] == [
        ("airport", "p01-airport1-p1"), ("dash", "p01"), ("shared", "p01"), ("under", "p01"),
    ]  # fmt: skip


def test_per_domain_must_be_positive(bench: ModuleType, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        bench.main(["--per-domain", "0"])
    assert info.value.code == 2
    assert "--per-domain: expected an integer >= 1, got 0" in capsys.readouterr().err


def _fake_val(folder: Path, output: str, status: int, stream: str = "") -> Path:
    script = folder / "Validate"
    script.write_text(f"#!/bin/sh\necho '{output}' {stream}\nexit {status}\n")
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    return script


@pytest.fixture
def blocks(tmp_path: Path) -> tuple[Path, Path, Path, Path]:
    domain = DOMAINS / "blocksworld" / "domain.pddl"
    problem = DOMAINS / "blocksworld" / "problems" / "reverse4.pddl"
    good = tmp_path / "good.plan"
    good.write_text(
        "(unstack d c)\n(put-down d)\n(unstack c b)\n(stack c d)\n"
        "(unstack b a)\n(stack b c)\n(pick-up a)\n(stack a b)\n"
    )
    bad = tmp_path / "bad.plan"
    bad.write_text("(pick-up a)\n")
    return domain, problem, good, bad


def test_val_verdict_is_taken_when_val_reads_the_files(
    bench: ModuleType, blocks: tuple[Path, Path, Path, Path], tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    domain, problem, good, bad = blocks
    monkeypatch.setattr(bench, "_val_binary", lambda: _fake_val(tmp_path, "Plan invalid", 1))
    assert bench.validate(domain, problem, good) == (False, "VAL")
    monkeypatch.setattr(bench, "_val_binary", lambda: _fake_val(tmp_path, "Plan valid", 0))
    assert bench.validate(domain, problem, bad) == (True, "VAL")


def test_own_validator_decides_where_val_cannot_read_the_domain(
    bench: ModuleType, blocks: tuple[Path, Path, Path, Path], tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    domain, problem, good, bad = blocks
    unreadable = _fake_val(tmp_path, "Problem in domain definition!", 255, ">&2")
    monkeypatch.setattr(bench, "_val_binary", lambda: unreadable)
    assert bench.validate(domain, problem, good) == (True, "own")
    assert bench.validate(domain, problem, bad) == (False, "own")
    monkeypatch.setattr(bench, "_val_binary", lambda: None)  # VAL not installed
    assert bench.validate(domain, problem, good) == (True, "own")


def test_the_own_validator_reads_plans_in_vals_temporal_format(
    bench: ModuleType, tmp_path: Path
) -> None:
    domain, problem, plan = tmp_path / "d.pddl", tmp_path / "p.pddl", tmp_path / "plan"
    domain.write_text(
        "(define (domain lights) (:requirements :durative-actions) (:predicates (on ?l) (warm ?l))"
        " (:durative-action heat :parameters (?l) :duration (= ?duration 2)"
        " :condition (over all (on ?l))"
        " :effect (and (at start (on ?l)) (at end (warm ?l)) (at end (not (on ?l))))))"
    )
    problem.write_text(
        "(define (problem p) (:domain lights) (:objects a) (:init) (:goal (warm a)))"
    )
    plan.write_text("0.000: (heat a) [2.000]\n; makespan 2\n")
    assert bench.own_validation(domain, problem, plan)
    plan.write_text("; nothing\n")
    assert not bench.own_validation(domain, problem, plan)
