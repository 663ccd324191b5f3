"""Typed adapter over plotly: typed-array specs for figures given as plain dicts, and the
plotly.js bundle to embed in a page.

plotly ships without type stubs and is an optional dependency (the ``viz`` extra); this module is
the only place that imports it. Arrays are passed as plotly.js typed-array specs (base64 of
float32), which keeps long animations small.
"""

from __future__ import annotations

import base64
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from sdar_tamp.viewer.errors import require

JSON = dict[str, Any]


def typed_array(values: ArrayLike, dtype: str = "f4") -> JSON:
    """A flat numeric array as a plotly.js typed-array spec (``f4`` float32, ``i4`` int32)."""
    kind = {"f4": "<f4", "i4": "<i4", "u1": "u1"}[dtype]  # plotly.js reads little-endian
    data = np.ascontiguousarray(np.asarray(values).reshape(-1), dtype=np.dtype(kind))
    return {"dtype": dtype, "bdata": base64.b64encode(data.tobytes()).decode("ascii")}


def plotly_js() -> str:
    """The source of plotly.js (minified) shipped with the installed plotly package."""
    offline = require("plotly.offline", "the interactive viewer")
    source: str = offline.get_plotlyjs()
    return source
