"""What the compatibility tree does not provide, said clearly where a program reaches for it.

PDDLStream's internals (its Fast Downward translator, temporal planners, skeleton queues,
optimizer compilation, statistics files) have no counterpart here. A module of the tree whose
names are only partly provided ends with ``__getattr__ = not_provided(__name__, WHY)``: any other
public name of it raises :class:`NotProvidedError` naming the module, the name and why, instead
of Python's bare "cannot import name". A name a program calls only at run time (so that its
import must succeed) is an :func:`unsupported_function`: importing it works, calling it raises.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable
from typing import Any, NoReturn

from sdar_tamp.errors import SdarError

__all__ = [
    "FAST_DOWNWARD_INTERNALS",
    "SCHEDULING_INTERNALS",
    "SKELETON_INTERNALS",
    "NotProvidedError",
    "not_provided",
    "unsupported_function",
]

#: Why the modules of ``pddlstream.algorithms.scheduling`` provide nothing.
SCHEDULING_INTERNALS = (
    "PDDLStream's stream-plan scheduling internals (it recovers stream plans from Fast "
    "Downward's output); the solvers here schedule streams themselves "
    "(solvers.stream_planning)"
)

#: Why the modules of PDDLStream's skeleton queue provide nothing.
SKELETON_INTERNALS = (
    "PDDLStream's skeleton queue and stream-plan internals; the adaptive algorithm here "
    "keeps its own (solvers.stream_planning)"
)
#: Why the modules of PDDLStream's Fast Downward interface provide nothing.
FAST_DOWNWARD_INTERNALS = (
    "Fast Downward's translator and search internals; planning here is the core classical"
    " planner (solvers.classical)"
)

_PREFIX = "sdar_tamp.compat."
_DOCS = "docs/pddlstream.md"


class NotProvidedError(SdarError, ImportError, NotImplementedError):
    """A PDDLStream name whose functionality this compatibility tree does not have."""


def _public(module: str) -> str:
    return module[len(_PREFIX) :] if module.startswith(_PREFIX) else module


def not_provided(module: str, why: str) -> Callable[[str], Any]:
    """A module ``__getattr__``: underscore names are missing as usual, a submodule of a
    package is imported (``from pkg import submodule`` asks the package first), every other
    name raises :class:`NotProvidedError` saying ``why``."""

    def __getattr__(name: str) -> Any:  # noqa: N807 (the module protocol's name)
        if name.startswith("_"):
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        package = sys.modules.get(module)
        is_package = package is not None and hasattr(package, "__path__")
        if is_package and importlib.util.find_spec(f"{module}.{name}") is not None:
            return importlib.import_module(f"{module}.{name}")
        raise NotProvidedError(
            f"{_public(module)}.{name} is not provided by sdar_tamp.compat.pddlstream: {why} "
            f"(see {_DOCS})"
        )

    return __getattr__


def unsupported_function(module: str, name: str, why: str) -> Callable[..., NoReturn]:
    """A function that can be imported and raises :class:`NotProvidedError` when called."""

    def function(*_args: Any, **_kwargs: Any) -> NoReturn:
        raise NotProvidedError(
            f"{_public(module)}.{name}() is not supported by sdar_tamp.compat.pddlstream: "
            f"{why} (see {_DOCS})"
        )

    function.__name__ = function.__qualname__ = name
    function.__module__ = module
    function.__doc__ = f"Not supported here: {why}. Calling it raises NotProvidedError."
    return function
