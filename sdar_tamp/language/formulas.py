"""Formula helpers for writing ``init`` and ``goal`` as Python tuples (PDDLStream's spelling).

``And(a, b)`` is ``("and", a, b)``; atoms are tuples ``("On", block, region)`` whose arguments
are arbitrary Python values; a string starting with ``?`` is a variable.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from sdar_tamp.language.formula_model import TOTAL_COST as TOTAL_COST
from sdar_tamp.textfile import read_text

INF = math.inf

Fact = tuple[Any, ...]


def And(*formulas: Any) -> Fact:
    return ("and", *formulas)


def Or(*formulas: Any) -> Fact:
    return ("or", *formulas)


def Not(formula: Any) -> Fact:
    return ("not", formula)


def Imply(antecedent: Any, consequent: Any) -> Fact:
    return ("imply", antecedent, consequent)


def Exists(parameters: Any, formula: Any) -> Fact:
    return ("exists", tuple(parameters), formula)


def ForAll(parameters: Any, formula: Any) -> Fact:
    return ("forall", tuple(parameters), formula)


def Equal(left: Any, right: Any) -> Fact:
    return ("=", left, right)


def read(path: str | Path) -> str:
    """The text of a domain or stream file.

    Raises:
        TextFileError: the file cannot be read or is not UTF-8 (naming the file and the place).
    """
    return read_text(path)
