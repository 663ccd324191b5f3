"""Typed adapter over CasADi: the only module that imports it.

CasADi has no type stubs; everything symbolic is ``Any`` here, and what leaves this module
as a result is a numpy array.
"""

from __future__ import annotations

from typing import Any

import casadi as _ca
import numpy as np

from sdar_tamp.world.transforms import FloatArray

#: The casadi module, typed as ``Any`` for the symbolic code in :mod:`streams.motion.fk_casadi` and
#: :mod:`streams.motion.optimiser`.
ca: Any = _ca


def sx_sym(name: str, rows: int, cols: int = 1) -> Any:
    return ca.SX.sym(name, rows, cols)


def to_array(value: Any) -> FloatArray:
    """A casadi ``DM`` (or anything array-like) as a float64 numpy array."""
    return np.asarray(ca.DM(value).full() if not isinstance(value, np.ndarray) else value,
                      dtype=np.float64)  # fmt: skip


def function(name: str, inputs: list[Any], outputs: list[Any]) -> Any:
    """A casadi ``Function``; with SX inputs it is fully expanded."""
    return ca.Function(name, inputs, outputs)
