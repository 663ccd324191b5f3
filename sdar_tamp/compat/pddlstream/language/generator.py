"""``pddlstream.language.generator``: adapters from plain Python samplers to streams.

The core adapters (:mod:`sdar_tamp.language.generators`) already have PDDLStream's meaning;
this module adds the remaining names (``from_gen``, ``universe_test``, ``empty_test``, ...).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from sdar_tamp.language.generators import (
    ListGenFn,
    fn_from_constant,
    from_constant,
    from_fn,
    from_gen_fn,
    from_list_fn,
    from_list_gen_fn,
    from_sampler,
    from_test,
    negate_test,
)

__all__ = [
    "accelerate_list_gen_fn",
    "empty_gen",
    "empty_test",
    "fn_from_constant",
    "from_constant",
    "from_fn",
    "from_gen",
    "from_gen_fn",
    "from_list_fn",
    "from_list_gen_fn",
    "from_sampler",
    "from_test",
    "get_next",
    "negate_test",
    "outputs_from_boolean",
    "universe_test",
]


def universe_test(*_args: Any, **_kwargs: Any) -> bool:
    """A test that always passes."""
    return True


def empty_test(*_args: Any, **_kwargs: Any) -> bool:
    """A test that always fails."""
    return False


def outputs_from_boolean(boolean: Any) -> tuple[()] | None:
    """``()`` (one empty output: the test passed) when true, else ``None`` (no output)."""
    return () if boolean else None


def from_gen(generator: Iterable[Any]) -> ListGenFn:
    """A stream whose outputs come from one generator shared by all its instances."""
    iterator = iter(generator)
    return from_gen_fn(lambda *_args, **_kwargs: iterator)


def empty_gen() -> ListGenFn:
    """A stream that never produces."""
    return from_gen(())


def get_next(generator: Iterator[Any], default: Any = None) -> Any:
    """The next item of ``generator`` (``default``, an empty list if None, once exhausted)."""
    try:
        return next(generator)
    except StopIteration:
        return [] if default is None else default


def accelerate_list_gen_fn(
    list_gen_fn: Callable[..., Iterable[Any]],
    num_elements: int = 1,
    max_attempts: int = 1,
    max_time: float = float("inf"),
) -> ListGenFn:
    """Each call gathers up to ``num_elements`` outputs over at most ``max_attempts`` calls
    of ``list_gen_fn``'s generator and ``max_time`` seconds."""

    def gen(*inputs: Any, **kwargs: Any) -> Iterator[list[Any]]:
        generator = iter(list_gen_fn(*inputs, **kwargs))
        done = False
        while not done:
            start = time.time()
            batch: list[Any] = []
            for _ in range(max_attempts):
                if len(batch) >= num_elements or time.time() - start >= max_time:
                    break
                try:
                    batch.extend(next(generator) or [])
                except StopIteration:
                    done = True
                    break
            yield batch

    return from_list_gen_fn(gen)
