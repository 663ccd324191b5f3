"""Logger names: every logger of the distribution sits under ``sdar_tamp``.

The packages ``solvers`` and ``streams`` are importable on their own, so their module names do
not start with the prefix; :func:`get_logger` adds it. An application configures all of them
with ``logging.getLogger("sdar_tamp")``. The library only creates loggers: levels and handlers
are the application's.
"""

from __future__ import annotations

import logging

PREFIX = "sdar_tamp"


def logger_name(module: str) -> str:
    """``module`` (a ``__name__``) under :data:`PREFIX`: ``solvers.solve`` ->
    ``sdar_tamp.solvers.solve``; names already under it are kept."""
    if module == PREFIX or module.startswith(PREFIX + "."):
        return module
    return f"{PREFIX}.{module}"


def get_logger(module: str) -> logging.Logger:
    """The logger of ``module`` (pass ``__name__``), named by :func:`logger_name`."""
    return logging.getLogger(logger_name(module))
