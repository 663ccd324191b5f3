from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.errors import GenerationError, SuiteError
from sdar_tamp.world.footprint import corners, inflate, overlap_matrix
from sdar_tamp.world.generators import GeneratorOptions, generate_instance, max_objects
from sdar_tamp.world.instance import Instance, load_instance, validate_instance
from sdar_tamp.world.instance_files import generate, generate_suite, show_instance
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.suites import build_suite, load_suite, suite_members


def test_same_seed_same_instance() -> None:
    assert generate_instance("M", 12, 5) == generate_instance("M", 12, 5)
    assert generate_instance("R", 8, 5) != generate_instance("R", 8, 6)


@pytest.mark.parametrize("n", [4, 7, 12])
def test_single_cycle(n: int) -> None:
    for seed in range(3):
        g = instance_dependency_graph(generate_instance("S", n, seed))
        cycles = g.cycle_components()
        assert len(cycles) == 1 and g.is_simple_cycle(cycles[0])


@pytest.mark.parametrize("n", [4, 9, 12])
def test_double_cycle(n: int) -> None:
    for seed in range(3):
        g = instance_dependency_graph(generate_instance("D", n, seed))
        cycles = g.cycle_components()
        assert len(cycles) == 2 and all(g.is_simple_cycle(c) for c in cycles)


def test_mixed_has_all_three_kinds() -> None:
    for seed in range(4):
        inst = generate_instance("M", 12, seed)
        s = instance_dependency_graph(inst).structure()
        assert len(inst.objects) == 12 and s.independent and s.chains and s.cycles


def test_random_is_feasible_and_uses_default_cuboid() -> None:
    inst = generate_instance("R", 12, 0)
    validate_instance(inst)
    assert {o.size for o in inst.objects} == {(0.08, 0.04, 0.05)}


def test_bad_arguments_and_impossible_requests() -> None:
    with pytest.raises(ParameterError, match="family"):
        generate_instance("Q", 5, 0)
    with pytest.raises(ParameterError, match="at least 4"):
        generate_instance("D", 3, 0)
    tiny = GeneratorOptions(workspace=Workspace((0.0, 0.2), (0.0, 0.2)), attempts=3, samples=200)
    with pytest.raises(GenerationError, match=r"after 3 attempts \(in 3 of them no room"):
        generate_instance("S", 6, 0, tiny)
    with pytest.raises(ParameterError, match=r"at most 7 objects .* got 20"):
        generate_instance("S", 20, 0, tiny)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("R", 4, -5), "seed must be an integer >= 0, got -5"),
        (("R", 2.5, 0), "objects must be an integer >= 1, got 2.5"),
        (("R", True, 0), "objects must be an integer >= 1"),
        (("R", 4, 1.0), "seed must be an integer >= 0"),
    ],
)
def test_numeric_arguments_are_checked(args: tuple[str, int, int], message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        generate_instance(*args)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"gap": -0.01}, "gap"),
        ({"gap": float("nan")}, "gap"),
        ({"attempts": 0}, "attempts"),
        ({"samples": 0}, "samples"),
        ({"crowded_attempts": 0}, "crowded_attempts"),
        ({"size": (0.08, 0.0, 0.05)}, r"size\[1\]"),
    ],
)
def test_generator_options_are_checked(kwargs: dict[str, object], name: str) -> None:
    with pytest.raises(ParameterError, match=name):
        GeneratorOptions(**kwargs)  # type: ignore[arg-type]


def test_area_bound_refuses_what_cannot_fit_and_accepts_the_suites() -> None:
    # grown footprints (0.08 + 0.026) x (0.04 + 0.026) in the grown 0.526 x 0.626 workspace
    assert max_objects() == int(0.526 * 0.626 / (0.106 * 0.066)) == 47
    assert max_objects(GeneratorOptions(gap=0.01)) == 69
    assert max(m.n_objects for m in suite_members("paper")) <= max_objects()
    stress = suite_members("stress")
    assert all(m.gap is not None and m.n_objects <= max_objects(GeneratorOptions(gap=m.gap))
               for m in stress)  # fmt: skip
    with pytest.raises(ParameterError, match=r"objects: at most 47 objects .* got 48"):
        generate_instance("R", 48, 0)
    with pytest.raises(ParameterError, match="got 200"):
        generate_instance("M", 200, 0)


def test_area_bound_is_not_below_a_packing_that_exists() -> None:
    # a grid of 35 turned objects that keeps the clearance: the bound must allow it
    opts = GeneratorOptions()
    ws, (length, width, _), gap = opts.workspace, opts.size, opts.gap
    xs = ws.x[0] + width / 2 + np.arange(7) * (width + gap)
    ys = ws.y[0] + length / 2 + np.arange(5) * (length + gap)
    poses = np.array([(x, y, np.pi / 2) for x in xs for y in ys])
    sizes = np.tile([length, width], (len(poses), 1))
    assert (xs + width / 2 <= ws.x[1]).all() and (ys + length / 2 <= ws.y[1]).all()
    grown = corners(poses, inflate(sizes, gap / 2 - 1e-9))
    over = overlap_matrix(grown, grown)
    np.fill_diagonal(over, False)
    assert not over.any()
    assert len(poses) == 35 <= max_objects(opts)


def test_the_largest_accepted_count_fails_after_a_few_crowded_attempts(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import sdar_tamp.world.generators as generators

    calls: list[object] = []
    attempt = generators._attempt

    def counted(*args: object) -> object:
        calls.append(result := attempt(*args))  # type: ignore[arg-type]
        return result

    monkeypatch.setattr(generators, "_attempt", counted)
    with pytest.raises(GenerationError, match=r"table is too full: .* at most \d+ of them"):
        generate_instance("R", max_objects(), 0)
    assert len(calls) == GeneratorOptions().crowded_attempts
    assert all(isinstance(c, int) and c < max_objects() for c in calls)


def test_suite_members() -> None:
    paper = suite_members("paper")
    assert [m.name for m in paper][:3] == ["R4", "R5", "R6"]
    assert len(paper) == 37 and paper[-1].name == "M10"
    assert {m.n_objects for m in suite_members("stress")} == {16, 20, 24}
    with pytest.raises(SuiteError, match="unknown suite"):
        suite_members("huge")


def test_shipped_paper_suite_is_current() -> None:
    shipped = load_suite("paper")
    assert len(shipped) == 37
    members = suite_members("paper")
    for k in (0, 13, 30):
        m = members[k]
        assert shipped[k] == generate_instance(m.family, m.n_objects, m.seed, name=m.name)


def test_shipped_stress_suite_loads_and_is_current() -> None:
    stress = load_suite("stress")
    assert [len(i.objects) for i in stress[:3]] == [16, 20, 24]
    m = suite_members("stress")[0]
    assert m.gap == 0.01
    assert stress[0] == generate_instance(
        m.family, m.n_objects, m.seed, GeneratorOptions(gap=m.gap), name=m.name
    )


def test_paper_suite_leaves_room_for_the_fingers() -> None:
    gap = GeneratorOptions().gap
    for inst in load_suite("paper"):
        for which in ("start", "goal"):
            poses = np.array([getattr(o, which).as_tuple() for o in inst.objects])
            sizes = inflate(np.array([o.size[:2] for o in inst.objects]), gap / 2 - 1e-6)
            over = overlap_matrix(corners(poses, sizes), corners(poses, sizes))
            np.fill_diagonal(over, False)
            assert not over.any(), (inst.name, which)


def test_commands(tmp_path: Path) -> None:
    out = generate("D", 6, 3, tmp_path / "d6.yaml")
    inst = load_instance(out)
    assert inst.name == "D6" and inst.family == "D" and inst.seed == 3
    png = show_instance(out, tmp_path / "d6.png")
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(SuiteError, match="missing instance files"):
        load_suite("paper", tmp_path)


def test_generate_suite_writes_loadable_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.world.suites as suites

    few = suite_members("paper")[:2]
    monkeypatch.setattr(suites, "suite_members", lambda name: few)
    paths = generate_suite("paper", tmp_path)
    assert [p.name for p in paths] == ["R4.yaml", "R5.yaml"]
    assert load_suite("paper", tmp_path) == build_suite("paper")


def test_refused_samples_are_replaced_by_later_ones() -> None:
    seen: list[Instance] = []

    def refuse_two(inst: Instance) -> str | None:
        seen.append(inst)
        return "refused" if len(seen) <= 2 else None

    plain = generate_instance("S", 6, 11)
    accepted = generate_instance("S", 6, 11, accept=refuse_two)
    assert seen[0] == plain and len(seen) == 3 and accepted == seen[2] != plain


def test_an_acceptance_test_refusing_everything_ends_with_its_reason() -> None:
    with pytest.raises(GenerationError, match=r"3 refused by the acceptance test, the last "
                       r"one: o0 is boxed in"):  # fmt: skip
        generate_instance(
            "R", 4, 5, GeneratorOptions(attempts=3), accept=lambda inst: "o0 is boxed in"
        )
