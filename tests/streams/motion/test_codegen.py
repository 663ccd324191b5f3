"""Compiled CasADi derivatives (``streams.motion.codegen``): the cache, the background compile, the
lock, every way it can fail (the caller then keeps CasADi's own evaluation), and the
optimiser giving the same paths with its derivatives compiled."""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path

import numpy as np
import pytest

from streams.context import WorldContext
from streams.motion import codegen
from streams.motion._casadi import ca, to_array
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.sphere_pairs import HeldSpheres

FAST = ("-O0", "-shared", "-fPIC")  # the tests' flags: the same code, compiled sooner
needs_cc = pytest.mark.skipif(codegen.compiler() is None, reason="no C compiler (cc)")


RECIPE = "sin(x0) x1^2 + exp(x2), and its gradient"


def _function(scale: float = 1.0) -> ca.Function:
    x = ca.SX.sym("x", 3)
    y = scale * ca.sin(x[0]) * x[1] ** 2 + ca.exp(x[2])
    return ca.Function("small", [x], [y, ca.jacobian(y, x)], ["x"], ["y", "dy"])


def _wait(path: Path, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.is_file() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert path.is_file(), f"{path} did not appear within {timeout} s"


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv(codegen.ENV_CACHE, str(folder))
    monkeypatch.delenv(codegen.ENV_SWITCH, raising=False)
    return folder


def test_switch_and_cache_folder(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    for off in ("0", "false", "No", " off "):
        monkeypatch.setenv(codegen.ENV_SWITCH, off)
        assert not codegen.enabled()
    monkeypatch.setenv(codegen.ENV_SWITCH, "1")
    assert codegen.enabled()
    monkeypatch.setenv(codegen.ENV_CACHE, str(tmp_path / "a"))
    assert codegen.cache_dir() == tmp_path / "a"
    monkeypatch.delenv(codegen.ENV_CACHE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert codegen.cache_dir() == tmp_path / "xdg" / "sdar-tamp"


def test_switched_off_compiles_nothing(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(codegen.ENV_SWITCH, "0")
    assert codegen.request([_function()], "small", RECIPE, FAST) is None
    assert not cache.exists()


def test_without_a_compiler_nothing_is_compiled(
    cache: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setenv("CC", "no-such-compiler-here")
    with caplog.at_level(logging.INFO, logger=codegen._log.name):
        assert codegen.request([_function()], "small", RECIPE, FAST) is None
    assert "no C compiler (no-such-compiler-here)" in caplog.text
    assert not cache.exists()


@needs_cc
def test_compiled_in_the_background_then_taken_from_the_cache(cache: Path) -> None:
    fn = _function()
    target = codegen.request([fn], "small", RECIPE, FAST)
    assert target is not None and target.parent == cache
    _wait(target)
    lock = target.with_name(target.name + ".lock")
    deadline = time.monotonic() + 30
    while lock.exists() and time.monotonic() < deadline:  # the compile's shell cleans up
        time.sleep(0.05)
    assert sorted(p.name for p in cache.iterdir()) == [target.name]  # no lock, no staging
    (twin,) = codegen.load([fn], target)
    assert twin.name_out() == fn.name_out()
    for x in ([0.3, -1.2, 0.5], [2.0, 0.1, -3.0]):
        for a, b in zip(twin(x), fn(x), strict=True):
            assert np.array_equal(to_array(a), to_array(b))
    assert codegen.request([fn], "small", RECIPE, FAST) == target  # found at once
    assert codegen.library_path(RECIPE, cache, FAST) == target
    assert codegen.library_path(RECIPE, cache) != target  # other flags, another library
    assert codegen.library_path("another recipe", cache, FAST) != target
    assert codegen.same_values([fn], [twin])
    assert not codegen.same_values([fn], [_function(scale=2.0)])


@needs_cc
def test_a_fresh_lock_is_respected_and_a_stale_one_taken_over(cache: Path) -> None:
    code = codegen.source([_function()], "small")
    target = codegen.library_path(RECIPE, cache, FAST)
    cache.mkdir(parents=True)
    lock = target.with_name(target.name + ".lock")
    lock.touch()
    cc = codegen.compiler()
    assert cc is not None
    assert not codegen.start_compile(code, target, cc, FAST)  # another process compiles
    old = time.time() - codegen.STALE_LOCK - 1
    os.utime(lock, (old, old))
    assert codegen.start_compile(code, target, cc, FAST)  # that one died: taken over
    _wait(target)


@needs_cc
def test_a_failing_compiler_leaves_no_library(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CC", "false")  # exits 1, like a compiler that rejects the code
    target = codegen.request([_function()], "small", RECIPE, FAST)
    assert target == codegen.library_path(RECIPE, cache, FAST)
    lock = target.with_name(target.name + ".lock")
    deadline = time.monotonic() + 30
    while lock.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not lock.exists() and not target.exists()
    assert list(cache.iterdir()) == []


def _query(ctx: WorldContext) -> TransferQuery:
    """A transfer whose straight line runs through an obstacle: IPOPT has work to do."""
    home = np.concatenate([np.array(a.home) for a in ctx.scene.arms])
    q_a, q_b = home.copy(), home.copy()
    q_a[0] += 0.6
    q_b[0] -= 0.6
    arm = ctx.arm_names[0]
    middle = ctx.kinematics[arm].fk_tcp(ctx.layout.part(0.5 * (q_a + q_b), arm))[:3, 3]
    held = tuple(HeldSpheres.empty() for _ in ctx.scene.arms)
    obstacles = (middle[None, :], np.array([0.06]))  # a ball where the tool passes
    return TransferQuery(q_a, q_b, held, obstacles, 3.0)


@needs_cc
def test_the_optimiser_gives_the_same_paths_compiled(
    ctx: WorldContext, cache: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # few slots: far less code to compile (1 s instead of 8 s), the same kind of NLP
    options = TrajOptOptions(
        knots=5, arm_arm_slots=4, obstacle_slots=2, table_slots=2, compiled=False
    )
    plain = TrajectoryOptimiser(ctx, options)
    fast = TrajectoryOptimiser(ctx, options)
    fast.request_compiled(FAST)
    assert fast._library is not None
    _wait(fast._library, timeout=300)
    query = _query(ctx)
    with caplog.at_level(logging.INFO, logger="sdar_tamp.streams.motion.optimiser"):
        b = fast.solve(query)
    assert fast.compiled and "compiled derivatives in use" in caplog.text
    a = plain.solve(query)
    assert not plain.compiled
    assert a.rounds >= 1 and a.iterations > 0  # IPOPT ran
    assert (a.success, a.status, a.iterations, a.rounds) == (
        b.success,
        b.status,
        b.iterations,
        b.rounds,
    )
    assert np.array_equal(a.path, b.path)


def test_a_broken_library_keeps_the_optimiser_uncompiled(
    ctx: WorldContext, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    opt = TrajectoryOptimiser(ctx, TrajOptOptions(compiled=False))
    broken = tmp_path / "casadi-broken.so"
    broken.write_bytes(b"not a shared library")
    opt._library = broken
    with caplog.at_level(logging.INFO, logger="sdar_tamp.streams.motion.optimiser"):
        result = opt.solve(_query(ctx))
    assert not opt.compiled and opt._library is None and not broken.exists()
    assert "could not be loaded, kept uncompiled" in caplog.text
    assert result.iterations >= 0  # solved with CasADi's own evaluation


def test_a_build_asks_for_its_derivatives_compiled(
    ctx: WorldContext, cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CC", "false")  # a compiler that fails at once: no library appears
    build = OptimiserBuild(ctx, TrajOptOptions(knots=6), background=False)
    opt = build.get()
    assert opt._library is not None and opt._library.parent == cache
    assert not opt.compiled  # nothing to load yet (and here never)
    off = OptimiserBuild(ctx, TrajOptOptions(knots=6, compiled=False), background=False)
    assert off.get()._library is None


def test_a_failure_to_ask_does_not_break_the_build(
    ctx: WorldContext,
    cache: Path,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    def refuse(*args: object, **kwargs: object) -> None:
        raise RuntimeError("code generation failed")

    monkeypatch.setattr(codegen, "request", refuse)
    with caplog.at_level(logging.INFO, logger="sdar_tamp.streams.motion.optimiser_build"):
        build = OptimiserBuild(ctx, TrajOptOptions(knots=6), background=False)
        opt = build.get()
    assert isinstance(opt, TrajectoryOptimiser) and opt._library is None
    assert (
        "compiled derivatives unavailable, kept uncompiled: code generation failed" in caplog.text
    )


@needs_cc
def test_a_library_with_other_values_is_not_used_and_removed(
    ctx: WorldContext, cache: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A library found under the optimiser's recipe that is something else (a stale cache):
    refused, deleted (the next process compiles it again), the optimiser stays uncompiled."""
    opt = TrajectoryOptimiser(ctx, TrajOptOptions(knots=5, compiled=False))
    impostor = codegen.library_path(opt.recipe(), cache)
    code = codegen.source([_function()], "small")
    cc = codegen.compiler()
    assert cc is not None and codegen.start_compile(code, impostor, cc, FAST)
    _wait(impostor)
    opt._library = impostor
    with caplog.at_level(logging.INFO, logger="sdar_tamp.streams.motion.optimiser"):
        opt.solve(_query(ctx))
    assert not opt.compiled and opt._library is None and not impostor.exists()
    assert "could not be loaded" in caplog.text or "gives other values" in caplog.text


def test_a_broken_library_in_a_read_only_cache_is_only_refused(
    ctx: WorldContext,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    opt = TrajectoryOptimiser(ctx, TrajOptOptions(knots=5, compiled=False))
    broken = tmp_path / "casadi-broken.so"
    broken.write_bytes(b"not a shared library")

    def refuse(self: Path, missing_ok: bool = False) -> None:
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "unlink", refuse)
    opt._library = broken
    with caplog.at_level(logging.INFO, logger="sdar_tamp.streams.motion.optimiser"):
        opt.solve(_query(ctx))
    assert not opt.compiled and opt._library is None and broken.exists()
    assert f"could not remove {broken}" in caplog.text
