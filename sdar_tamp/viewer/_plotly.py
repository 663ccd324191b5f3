"""Typed adapter over plotly: a figure given as plain dicts -> one self-contained HTML page.

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


def figure_html(figure: JSON, div_id: str, post_script: str | None = None) -> str:
    """The full HTML page of ``figure`` (``data``, ``layout``, ``frames``) with plotly.js
    embedded, so it works offline. ``post_script`` runs once the plot is drawn."""
    pio = require("plotly.io", "the interactive viewer")
    html: str = pio.to_html(
        figure,
        config={"displaylogo": False, "responsive": True},
        auto_play=False,
        include_plotlyjs=True,
        include_mathjax=False,
        full_html=True,
        post_script=post_script,
        default_width="100%",
        default_height="100vh",
        validate=False,
        div_id=div_id,
    )
    return html
