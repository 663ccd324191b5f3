"""Suite-wide settings (how many processes `pytest -n auto` starts) and the expensive shared
fixtures: the world context, the optimisers and the motion planner."""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

from streams.context import WorldContext
from streams.motion import codegen, sphere_cache
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.planner import MotionPlanner

# The suite plans with CasADi's own evaluation of the optimiser's derivatives (the same
# values as compiled, tests/streams/motion/test_codegen.py): a fresh machine would otherwise
# spend about 20 s of CPU compiling them beside the tests. Subprocesses inherit the switch.
os.environ[codegen.ENV_SWITCH] = "0"
# Fitted sphere models are not kept in the user's cache folder by the suite (the tests of the
# disk cache switch it on in a folder of their own).
os.environ[sphere_cache.ENV_SWITCH] = "0"

#: Most of the suite's time is spent in a few long planning tests; beyond four processes the
#: start-up of each (pinocchio, CasADi, the optimiser build) outweighs what they share out.
MAX_WORKERS = 4


def usable_cpus() -> int:
    """The CPUs this process may run on (the affinity mask where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    return max(1, min(MAX_WORKERS, usable_cpus()))


@pytest.fixture(scope="session")
def ctx() -> WorldContext:
    """The shipped scene's world context (kinematics, collision, sphere models)."""
    return WorldContext.load()


@pytest.fixture(scope="session")
def optimisers() -> OptimiserCache:
    """The trajectory optimisers of the test process: a planner made with this cache shares
    the optimiser of every other planner of the same scene and options (built once)."""
    return OptimiserCache()


@pytest.fixture(scope="session")
def planner(ctx: WorldContext, optimisers: OptimiserCache) -> MotionPlanner:
    """The motion planner of ``ctx``: built once per test process (the optimiser with it)."""
    return MotionPlanner(ctx, optimisers=optimisers)


@pytest.fixture(scope="session")
def benchmark_script() -> Callable[[str], ModuleType]:
    """Loads ``benchmarks/<name>.py`` as the module ``name`` (the benchmarks are scripts, not
    a package), once per session, with their folder importable as when a script runs (their
    shared ``_*.py`` modules)."""
    folder = Path(__file__).resolve().parents[1] / "benchmarks"
    if str(folder) not in sys.path:
        sys.path.append(str(folder))

    def load(name: str) -> ModuleType:
        if name in sys.modules:
            return sys.modules[name]
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        return module

    return load
