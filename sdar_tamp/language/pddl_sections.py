"""The top level of PDDL domain and problem files: the supported requirements, the section
keywords of each, and ``(define (KIND NAME) (:section ...) ...)`` split into its sections.

Supported requirements: ``:strips :typing :negative-preconditions :disjunctive-preconditions
:equality :existential-preconditions :universal-preconditions :quantified-preconditions
:conditional-effects :derived-predicates :action-costs :adl :durative-actions`` (durative
actions run one after the other: :mod:`sdar_tamp.language.durative`). Names are
case-insensitive.
"""

from __future__ import annotations

from collections.abc import Iterable

from sdar_tamp.language.errors import PddlSyntaxError, UnknownKeywordError
from sdar_tamp.language.grammar import expect_head, expect_list, expect_symbol
from sdar_tamp.language.sexpr import SExpr, SList

REQUIREMENTS = frozenset(
    {
        ":strips",
        ":typing",
        ":negative-preconditions",
        ":disjunctive-preconditions",
        ":equality",
        ":existential-preconditions",
        ":universal-preconditions",
        ":quantified-preconditions",
        ":conditional-effects",
        ":derived-predicates",
        ":action-costs",
        ":adl",
        ":durative-actions",
        ":numeric-fluents",
    }
)
DOMAIN_SECTIONS = (
    ":requirements",
    ":types",
    ":constants",
    ":predicates",
    ":functions",
    ":action",
    ":durative-action",
    ":derived",
)
PROBLEM_SECTIONS = (":domain", ":requirements", ":objects", ":init", ":goal", ":metric")


def split_sections(root: SList, kind: str, allowed: Iterable[str]) -> list[tuple[str, SList]]:
    """The ``(keyword, section)`` pairs of ``(define (KIND NAME) ...)``, in order, each
    keyword one of ``allowed``."""
    expect_head(root, "define", f"a {kind} '(define ({kind} NAME) ...)'")
    if len(root.items) < 2:
        raise PddlSyntaxError(f"expected '({kind} NAME)' after 'define'", root.location)
    result: list[tuple[str, SList]] = []
    allowed = tuple(allowed)
    for node in root.items[2:]:
        section = expect_list(node, f"a {kind} section such as ({allowed[0]} ...)")
        keyword = expect_symbol(section.items[0] if section.items else section, "a keyword")
        if keyword.text not in allowed:
            raise UnknownKeywordError(
                f"unknown {kind} section {keyword.text!r}; expected one of {', '.join(allowed)}",
                keyword.location,
            )
        result.append((keyword.text, section))
    return result


def read_requirements(body: Iterable[SExpr]) -> list[str]:
    """The requirements of a ``(:requirements ...)`` section, each one of :data:`REQUIREMENTS`.

    Raises:
        UnknownKeywordError: an unsupported requirement.
    """
    requirements: list[str] = []
    for token in body:
        symbol = expect_symbol(token, "a requirement")
        if symbol.text not in REQUIREMENTS:
            raise UnknownKeywordError(
                f"unsupported requirement {symbol.text!r}; supported: "
                f"{', '.join(sorted(REQUIREMENTS))}",
                symbol.location,
            )
        requirements.append(symbol.text)
    return requirements
