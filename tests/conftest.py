"""Suite-wide settings: how many processes `pytest -n auto` starts."""

from __future__ import annotations

import os

import pytest

#: Most of the suite's time is spent in a few long planning tests; beyond four processes the
#: start-up of each (pinocchio, CasADi, the optimiser build) outweighs what they share out.
MAX_WORKERS = 4


def usable_cpus() -> int:
    """The CPUs this process may run on (the affinity mask where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    return max(1, min(MAX_WORKERS, usable_cpus()))
