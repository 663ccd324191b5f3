"""The export formats and their defaults (no imports: the command line reads them at start)."""

from __future__ import annotations

FORMATS = ("joint-trajectory", "csv", "urscript")
CSV_RATE = 50.0  #: rows per second of the CSV table [1/s]
