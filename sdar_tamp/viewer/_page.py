"""The HTML around the 3-D page: layout, controls, the page script and plotly.js, in one file.

plotly.js (about 4.8 MB) is embedded gzip-compressed and base64-encoded (about 2 MB) and unpacked
by the browser (``DecompressionStream``: Chrome 80, Firefox 113, Safari 16.4 or later); the page
needs no network. The page's own script and style sheet are ``page.js`` and ``page.css`` beside
this module.
"""

from __future__ import annotations

import base64
import gzip
import html
import json
from importlib.resources import files
from typing import Any

from sdar_tamp.viewer._plotly import plotly_js

#: Element ids read by the page script (and by tests).
DATA_ID = "sdar-data"
PLOTLY_ID = "sdar-plotly"


def _resource(name: str) -> str:
    return (files("sdar_tamp.viewer") / name).read_text(encoding="utf-8")


def packed_plotly_js() -> str:
    """plotly.js gzip-compressed (reproducibly: no time stamp) and base64-encoded."""
    raw = plotly_js().encode("utf-8")
    return base64.b64encode(gzip.compress(raw, compresslevel=9, mtime=0)).decode("ascii")


def script_json(value: Any) -> str:
    """``value`` as JSON safe inside a ``<script>`` element (no ``</`` sequence)."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def page_html(title: str, data: Any) -> str:
    """The whole page: ``data`` (see :func:`sdar_tamp.viewer.html.page_data`) drawn by
    ``page.js`` with the embedded plotly.js."""
    return _TEMPLATE.format(
        title=html.escape(title),
        style=_resource("page.css"),
        data_id=DATA_ID,
        data=script_json(data),
        plotly_id=PLOTLY_ID,
        plotly=packed_plotly_js(),
        script=_resource("page.js"),
    )


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
{style}
</style>
</head>
<body>
<div id="sdar-banner" hidden></div>
<header id="sdar-header"><span id="sdar-title">{title}</span>
  <span id="sdar-verdict"></span></header>
<main id="sdar-main">
  <section id="sdar-view"><div id="sdar-viewer"></div>
    <div id="sdar-hud"><div id="sdar-hud-time"></div><div id="sdar-hud-step"></div>
      <div id="sdar-hud-arms"></div></div>
  </section>
  <section id="sdar-joints-pane"><div id="sdar-joints"></div></section>
</main>
<footer id="sdar-controls" hidden>
  <div id="sdar-buttons">
    <button id="sdar-prev" type="button" title="previous step (left arrow)">&#x25C2; step</button>
    <button id="sdar-play" type="button" title="play / pause (space)">&#x25B6; play</button>
    <button id="sdar-next" type="button" title="next step (right arrow)">step &#x25B8;</button>
    <label for="sdar-speed">speed</label>
    <select id="sdar-speed" title="playback speed">
      <option value="0.25">0.25&#xD7;</option><option value="0.5">0.5&#xD7;</option>
      <option value="1" selected>1&#xD7;</option><option value="2">2&#xD7;</option>
      <option value="4">4&#xD7;</option><option value="8">8&#xD7;</option>
    </select>
    <span id="sdar-clock"></span>
  </div>
  <div id="sdar-timeline">
    <div id="sdar-events"></div>
    <input id="sdar-slider" type="range" min="0" max="1" step="any" value="0"
      aria-label="time">
    <div id="sdar-steps"></div>
  </div>
</footer>
<script type="application/json" id="{data_id}">{data}</script>
<script type="application/gzip-base64" id="{plotly_id}">{plotly}</script>
<script>
{script}
</script>
</body>
</html>
"""
