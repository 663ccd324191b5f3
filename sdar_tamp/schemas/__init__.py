"""JSON Schemas (draft 2020-12) of the project's files, shipped with the package.

``instance`` (rearrangement instance YAML), ``scene`` (scene YAML), ``plan`` (plan file
JSON) and ``observed`` (observed state YAML, ``sdar replan``); :func:`schema` returns one
as a dict, :func:`schema_path` its file. YAML files are checked on their parsed value (for
example ``yaml.safe_load``). The schemas describe the shape (keys, types, lengths, signs);
the loaders check more (finite numbers, ``lower < upper``, the rules listed in each schema's
``description``), so a document a schema accepts
may still be refused by its loader.
"""

from __future__ import annotations

import json
from importlib.resources import files
from pathlib import Path
from typing import Any

from sdar_tamp.errors import ParameterError

SCHEMAS = ("instance", "scene", "plan", "observed")


def schema_path(name: str) -> Path:
    """The shipped file of schema ``name`` (one of :data:`SCHEMAS`)."""
    if name not in SCHEMAS:
        raise ParameterError(f"name must be one of {', '.join(SCHEMAS)}; got {name!r}")
    return Path(str(files(__name__) / f"{name}.schema.json"))


def schema(name: str) -> dict[str, Any]:
    """Schema ``name`` as a JSON value."""
    value: dict[str, Any] = json.loads(schema_path(name).read_text(encoding="utf-8"))
    return value
