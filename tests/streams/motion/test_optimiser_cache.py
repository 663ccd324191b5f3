"""The optimiser cache: one background build per scene and options, shared by the planners
given the cache; a failed build re-raises its error."""

import pytest

from sdar_tamp.errors import ParameterError
from streams.context import WorldContext
from streams.motion import optimiser_build
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.planner import MotionPlanner


def test_optimisers_are_built_once_per_scene_and_options(
    ctx: WorldContext, monkeypatch: pytest.MonkeyPatch
) -> None:
    built: list[TrajOptOptions] = []

    class Fake:
        def __init__(self, ctx: WorldContext, options: TrajOptOptions) -> None:
            built.append(options)
            if options.knots == 3:
                raise ParameterError("no NLP with 3 knots")

    monkeypatch.setattr(optimiser_build, "TrajectoryOptimiser", Fake)
    cache = OptimiserCache()
    six = TrajOptOptions(knots=6, compiled=False)
    a = cache.get(ctx, six)
    b = cache.get(ctx, six)
    c = cache.get(ctx, TrajOptOptions(knots=7, compiled=False), background=False)
    assert a is b and c is not a and len(cache) == 2
    assert a.get() is b.get() and a.ready and a.build_time >= 0.0
    assert [o.knots for o in sorted(built, key=lambda o: o.knots)] == [6, 7]
    planner = MotionPlanner(ctx, six, optimisers=cache)
    assert planner.trajopt is a.get() and len(built) == 2  # no second build
    broken = cache.get(ctx, TrajOptOptions(knots=3, compiled=False))
    with pytest.raises(ParameterError, match="no NLP with 3 knots"):
        broken.get()


def test_a_deferred_build_starts_when_asked_or_first_needed(
    ctx: WorldContext, monkeypatch: pytest.MonkeyPatch
) -> None:
    built: list[int] = []

    class Fake:
        def __init__(self, ctx: WorldContext, options: TrajOptOptions) -> None:
            built.append(options.knots)

    monkeypatch.setattr(optimiser_build, "TrajectoryOptimiser", Fake)
    cache = OptimiserCache()
    planner = MotionPlanner(ctx, TrajOptOptions(knots=6, compiled=False), optimisers=cache,
                            defer_build=True)  # fmt: skip
    assert not planner.build.started and not planner.build.ready and built == []
    planner.start_build()
    assert planner.build.started and planner.trajopt is planner.build.get()
    planner.start_build()  # once started, nothing more
    assert built == [6]
    later = cache.get(ctx, TrajOptOptions(knots=7, compiled=False), start=False)
    assert not later.started and built == [6]
    assert isinstance(later.get(), Fake) and later.started and built == [6, 7]  # get() starts it
