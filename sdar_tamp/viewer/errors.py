"""Errors of the viewers, and the check for their optional dependencies."""

from __future__ import annotations

import importlib
from types import ModuleType

from sdar_tamp.errors import SdarError


class MissingDependencyError(SdarError):
    """An optional dependency is not installed; the message names the extra that provides it."""


def require(module: str, purpose: str) -> ModuleType:
    """Import ``module`` or raise :class:`MissingDependencyError` naming the ``viz`` extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        package = module.split(".")[0]
        raise MissingDependencyError(
            f"{purpose} needs {package}: pip install 'sdar-tamp[viz]'"
        ) from None
