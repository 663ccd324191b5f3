"""PDDL 2.1 durative actions: the model (:class:`DurativeActionSchema`) and its reader
(:func:`read_durative_action`).

A ``(:durative-action NAME :parameters (...) :duration (= ?duration D) :condition C :effect E)``
has a fixed duration ``D`` (an expression: a number, function terms, ``+ - * /``, evaluated at
its start), conditions each tagged ``(at start ...)``, ``(over all ...)`` or ``(at end ...)``
and effects each tagged ``(at start ...)`` or ``(at end ...)``; both may be numeric
(:mod:`sdar_tamp.language.numeric`) and use ``?duration``. Plans run durative actions one after
the other (:mod:`sdar_tamp.language.sequential` compiles each into one instantaneous action
whose cost is its duration). Refused with a located
:class:`~sdar_tamp.language.errors.UnsupportedFeatureError`: duration inequalities
(``(<= ?duration ...)``) and continuous effects (``#t``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TypeAlias

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import PddlSyntaxError, UnsupportedFeatureError
from sdar_tamp.language.formula_model import (
    TRUE,
    And,
    AndEffect,
    Effect,
    Formula,
    Parameter,
)
from sdar_tamp.language.formula_reader import FormulaReader
from sdar_tamp.language.grammar import expect_list, expect_symbol, parse_options
from sdar_tamp.language.numeric import (
    DURATION,
    Comparison,
    Expression,
    NumericEffect,
    NumericReader,
    is_comparison,
    is_numeric_effect,
    split_conjuncts,
)
from sdar_tamp.language.sexpr import SExpr, SList, Symbol

START, OVER_ALL, END = "at start", "over all", "at end"
_COMPARISONS = frozenset({"<", "<=", ">", ">="})

NO_EFFECT: Effect = AndEffect(())

ConditionReader: TypeAlias = Callable[[FormulaReader, SExpr, Mapping[str, str], str], Formula]
"""Reads one condition: ``(reader, node, scope, what) -> formula``."""


@dataclass(frozen=True)
class DurativeActionSchema:
    """A domain's ``(:durative-action ...)``: conditions at its start, over its whole
    duration and at its end, effects at its start and at its end, and its ``duration``."""

    name: str
    parameters: tuple[Parameter, ...]
    duration: Expression
    at_start: Formula = TRUE
    over_all: Formula = TRUE
    at_end: Formula = TRUE
    start_effect: Effect = NO_EFFECT
    end_effect: Effect = NO_EFFECT
    location: SourceLocation | None = field(default=None, compare=False)
    numeric_conditions: Mapping[str, tuple[Comparison, ...]] = field(default_factory=dict)
    """The numeric conditions by tag (``"at start"``, ``"over all"``, ``"at end"``)."""
    numeric_effects: Mapping[str, tuple[NumericEffect, ...]] = field(default_factory=dict)
    """The numeric effects by tag (``"at start"``, ``"at end"``)."""


def read_durative_action(
    section: SList, reader: FormulaReader, read_condition: ConditionReader
) -> DurativeActionSchema:
    """The durative action of ``(:durative-action ...)``; ``read_condition(reader, node,
    scope, what)`` reads one condition (the domain reader's, which closes free variables).

    Raises:
        PddlSyntaxError: a malformed action (no ``:duration``, an untimed condition...).
        UnsupportedFeatureError: a construct of temporal PDDL outside the supported part.
    """
    if len(section.items) < 2:
        raise PddlSyntaxError("expected an action name after ':durative-action'", section.location)
    name = expect_symbol(section.items[1], "an action name").text
    what = f"durative action {name!r}"
    options = parse_options(section, (":parameters", ":duration", ":condition", ":effect"), what, 2)
    params = (
        reader.parameters(options[":parameters"], f"the parameters of {what}")
        if ":parameters" in options
        else ()
    )
    if any(p.name == DURATION for p in params):
        raise PddlSyntaxError(f"{what}: '?duration' cannot be a parameter", section.location)
    if ":duration" not in options:
        raise PddlSyntaxError(f"{what} has no ':duration'", section.location)
    scope = {p.name: p.type for p in params}
    numeric = NumericReader(reader.term, reader.function_arity, duration=True)
    duration = _duration(options[":duration"], numeric, scope, what)
    conditions: dict[str, list[Formula]] = {START: [], OVER_ALL: [], END: []}
    numeric_conditions: dict[str, list[Comparison]] = {START: [], OVER_ALL: [], END: []}
    for tag, node in _timed_parts(options.get(":condition"), (START, OVER_ALL, END), what):
        _refuse_continuous(node)
        rest, parts = split_conjuncts(node, is_comparison)
        numeric_conditions[tag].extend(numeric.comparison(part, scope) for part in parts)
        if rest is not None and not (isinstance(rest, SList) and not rest.items):
            _refuse_duration_variable(rest, what)
            conditions[tag].append(read_condition(reader, rest, scope, f"a condition of {what}"))
    effects: dict[str, list[Effect]] = {START: [], END: []}
    numeric_effects: dict[str, list[NumericEffect]] = {START: [], END: []}
    for tag, node in _timed_parts(options.get(":effect"), (START, END), what):
        _refuse_continuous(node)
        rest, parts = split_conjuncts(node, is_numeric_effect)
        numeric_effects[tag].extend(numeric.effect(part, scope) for part in parts)
        if rest is not None:
            _refuse_duration_variable(rest, what)
            effects[tag].append(reader.effect(rest, scope))
    return DurativeActionSchema(
        name,
        params,
        duration,
        _conjunction(conditions[START]),
        _conjunction(conditions[OVER_ALL]),
        _conjunction(conditions[END]),
        AndEffect(tuple(effects[START])),
        AndEffect(tuple(effects[END])),
        section.location,
        {tag: tuple(parts) for tag, parts in numeric_conditions.items() if parts},
        {tag: tuple(parts) for tag, parts in numeric_effects.items() if parts},
    )


def _conjunction(parts: list[Formula]) -> Formula:
    return parts[0] if len(parts) == 1 else And(tuple(parts))


def _duration(
    node: SExpr, numeric: NumericReader, scope: Mapping[str, str], what: str
) -> Expression:
    constraint = expect_list(node, f"the duration of {what}, '(= ?duration VALUE)'")
    items = constraint.items
    head = items[0] if items else constraint
    if isinstance(head, Symbol) and head.text == "and":
        raise UnsupportedFeatureError(
            f"{what}: duration inequalities are not supported; give '(= ?duration VALUE)'",
            constraint.location,
        )
    if isinstance(head, Symbol) and head.text in _COMPARISONS:
        raise UnsupportedFeatureError(
            f"{what}: duration inequalities ('{head.text}') are not supported; give "
            "'(= ?duration VALUE)'",
            constraint.location,
        )
    if not (isinstance(head, Symbol) and head.text == "=") or len(items) != 3:
        raise PddlSyntaxError(
            f"{what}: expected the duration as '(= ?duration VALUE)'", constraint.location
        )
    variable = items[1]
    if not (isinstance(variable, Symbol) and variable.text == DURATION):
        raise PddlSyntaxError(f"{what}: expected '?duration' after '='", variable.location)
    value = items[2]
    _refuse_duration_variable(value, what)
    duration = numeric.expression(value, scope)
    if isinstance(duration, float) and duration < 0:
        raise PddlSyntaxError(
            f"{what}: durations must be non-negative, got {duration:g}", value.location
        )
    return duration


def _timed_parts(
    node: SExpr | None, tags: tuple[str, ...], what: str
) -> Iterator[tuple[str, SExpr]]:
    """The ``(tag, body)`` of each ``(at start body)``... of a conjunction of timed parts."""
    if node is None:
        return
    lst = expect_list(node, f"the conditions or effects of {what}")
    if not lst.items:
        return
    head = lst.items[0]
    if isinstance(head, Symbol) and head.text == "and":
        for part in lst.items[1:]:
            yield from _timed_parts(part, tags, what)
        return
    shown = ", ".join(f"({t} ...)" for t in tags)
    if isinstance(head, Symbol) and head.text in ("at", "over") and len(lst.items) == 3:
        when = lst.items[1]
        tag = f"{head.text} {when.text}" if isinstance(when, Symbol) else ""
        if tag in tags:
            yield tag, lst.items[2]
            return
        if tag == OVER_ALL:
            raise PddlSyntaxError(
                f"{what}: an effect cannot be '(over all ...)'; expected {shown}", lst.location
            )
    if isinstance(head, Symbol) and head.text in ("forall", "when"):
        raise UnsupportedFeatureError(
            f"{what}: a '{head.text}' around timed parts is not supported; put it inside {shown}",
            lst.location,
        )
    raise PddlSyntaxError(f"{what}: expected a timed part, one of {shown}", lst.location)


def _refuse_continuous(node: SExpr) -> None:
    for lst in _lists(node):
        for item in lst.items:
            if isinstance(item, Symbol) and item.text == "#t":
                raise UnsupportedFeatureError(
                    "continuous effects ('#t') are not supported", item.location
                )


def _refuse_duration_variable(node: SExpr, what: str) -> None:
    for lst in _lists(node):
        for item in lst.items:
            if isinstance(item, Symbol) and item.text in (DURATION, "#t"):
                raise UnsupportedFeatureError(
                    f"{what}: '{item.text}' may only appear in ':duration', numeric conditions "
                    "and numeric effects",
                    item.location,
                )


def _lists(node: SExpr) -> Iterator[SList]:
    if isinstance(node, SList):
        yield node
        for item in node.items:
            yield from _lists(item)
