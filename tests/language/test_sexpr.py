"""The s-expression reader: exact locations, nesting without recursion limits, error order."""

from __future__ import annotations

import gc
import re

import pytest

from sdar_tamp.language import parse_domain, parse_problem, parse_stream_file
from sdar_tamp.language.errors import PddlSyntaxError
from sdar_tamp.language.formula_reader import MAX_FORMULA_DEPTH
from sdar_tamp.language.sexpr import SExpr, SList, Symbol, read_sexpr
from sdar_tamp.resources import domain_file


def _nodes(root: SList) -> list[SExpr]:
    out: list[SExpr] = []
    stack: list[SExpr] = [root]
    while stack:
        node = stack.pop()
        out.append(node)
        if isinstance(node, SList):
            stack.extend(node.items)
    return out


def _reference(text: str, offset: int) -> tuple[int, int]:
    """Line and column of ``offset`` counted the slow, obvious way."""
    line, column = 1, 1
    for char in text[:offset]:
        line, column = (line + 1, 1) if char == "\n" else (line, column + 1)
    return line, column


@pytest.mark.parametrize(
    "text",
    [
        "(define\n\t(domain D) ; a comment (with parens)\n  (:predicates (P ?x)))\n",
        "(a\r\n  (b c)\r\n\t\t(d\f e)\v(f))",
        "; only a comment\n\n   (x (y (z)) ;; ) (\n w)",
        "(d\u00e9fine (\u00dcn\u00ef \u0130x) (\u03a3\u03a3 tail) \u2028 (q))",  # not ASCII
    ],
)
def test_locations_are_exact(text: str) -> None:
    root = read_sexpr(text, "t.pddl")
    nodes = _nodes(root)
    assert sum(isinstance(n, Symbol) for n in nodes) >= 4
    for node in nodes:
        location = node.location
        assert location.file == "t.pddl"
        assert (location.line, location.column) == _reference(text, node.offset)
        if isinstance(node, Symbol):
            word = re.match(r"[^ \t\r\n\f\v();]+", text[node.offset :])
            assert word is not None and node.text == word.group().lower()
        else:
            assert text[node.offset] == "("


def test_known_positions() -> None:
    root = read_sexpr("(define\n\t(domain D) ; c\n  (x))", "d.pddl")
    header = root.items[1]
    assert isinstance(header, SList)
    assert str(header.location) == "d.pddl:2:2"
    assert str(header.items[1].location) == "d.pddl:2:10"
    assert header.items[1].text == "d"  # type: ignore[union-attr]
    assert str(root.items[2].location) == "d.pddl:3:3"
    assert str(root) == "(define (domain d) (x))"


def test_deep_nesting_is_read_without_recursion() -> None:
    depth = 100_000
    root = read_sexpr("(" * depth + "x" + ")" * depth)
    level, node = 1, root
    while node.items and isinstance(node.items[0], SList):
        level, node = level + 1, node.items[0]
    assert level == depth
    assert str(root) == "(" * depth + "x" + ")" * depth
    assert repr(root).startswith("SList(((((") and len(repr(root)) < 100


BLOCKS = domain_file("blocksworld").read_text(encoding="utf-8")
PICK_PRE = ":precondition (and (clear ?x) (on-table ?x) (hand-empty))"


def _nested(depth: int, inner: str = "(clear ?x)") -> str:
    return "(and " * depth + inner + ")" * depth


def test_formula_nested_500_deep_is_a_located_error() -> None:
    text = BLOCKS.replace(PICK_PRE, f":precondition {_nested(500)}")
    line = text[: text.index("(and (and")].count("\n") + 1
    with pytest.raises(PddlSyntaxError) as info:
        parse_domain(text, "d.pddl")
    message = str(info.value)
    assert message.startswith(f"d.pddl:{line}:")
    assert f"formula nested deeper than {MAX_FORMULA_DEPTH} levels" in message


def test_formula_at_the_limit_parses() -> None:
    # MAX_FORMULA_DEPTH - 1 conjunctions around one atom: MAX_FORMULA_DEPTH formula levels
    text = BLOCKS.replace(PICK_PRE, f":precondition {_nested(MAX_FORMULA_DEPTH - 1)}")
    assert parse_domain(text, "d.pddl").actions[0].name == "pick-up"


def test_effect_nested_500_deep_is_a_located_error() -> None:
    text = BLOCKS.replace(
        ":effect (and (holding ?x) (not (clear ?x))",
        f":effect (and (holding ?x) {_nested(500, '(not (clear ?x))')}",
    )
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:\d+:\d+: effect nested deeper than 100"):
        parse_domain(text, "d.pddl")


def test_goal_nested_500_deep_is_a_located_error() -> None:
    domain = parse_domain(BLOCKS)
    problem = domain_file("blocksworld", "problems/sussman.pddl").read_text(encoding="utf-8")
    deep = problem.replace("(:goal ", "(:goal " + "(and " * 500, 1).rstrip()
    deep = deep[:-1] + ")" * 500 + ")"
    with pytest.raises(PddlSyntaxError, match=r"p\.pddl:\d+:\d+: formula nested deeper"):
        parse_problem(deep, domain, "p.pddl")


def test_deep_stream_domain_is_a_located_error() -> None:
    domain_text = domain_file("kitchen").read_text(encoding="utf-8")
    stream_text = domain_file("kitchen", "stream.pddl").read_text(encoding="utf-8")
    domain = parse_domain(domain_text)
    parse_stream_file(stream_text, domain)  # the shipped file is fine
    deep = stream_text.replace(":domain (", ":domain " + "(and " * 500 + "(", 1)
    deep = deep.replace(":outputs", ")" * 500 + " :outputs", 1)
    with pytest.raises(PddlSyntaxError, match=r"s\.pddl:\d+:\d+: formula nested deeper"):
        parse_stream_file(deep, domain, "s.pddl")


def test_deep_list_where_a_name_is_expected() -> None:
    text = BLOCKS.replace("(:predicates", "(:predicates " + "(" * 500 + ")" * 500, 1)
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:4:\d+: expected a name") as info:
        parse_domain(text, "d.pddl")
    assert len(str(info.value)) < 200  # the list is cut short in the message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("(a) b )", "t:1:5: unexpected text after the closing parenthesis"),
        ("foo (a)", "t:1:1: expected '(' but found 'foo'"),
        ("(a)\n(b", "t:2:1: unexpected text after the closing parenthesis"),
        ("(a (b)", "t:1:1: unbalanced parentheses: '(' is never closed"),
        (") (a)", "t:1:1: unbalanced parentheses: ')' without a matching '('"),
        ("(a))", "t:1:4: unbalanced parentheses: ')' without a matching '('"),
        ("\n ; x\n  ", "t:3:3: expected a definition '(define ...)' but the source is empty"),
    ],
)
def test_errors_name_the_first_problem(text: str, expected: str) -> None:
    with pytest.raises(PddlSyntaxError) as info:
        read_sexpr(text, "t")
    assert str(info.value) == expected


@pytest.mark.parametrize("enabled", [True, False])
def test_garbage_collector_state_is_restored(enabled: bool) -> None:
    was = gc.isenabled()
    try:
        if not enabled:
            gc.disable()
        read_sexpr("(a (b))")
        assert gc.isenabled() is enabled
        with pytest.raises(PddlSyntaxError):
            read_sexpr("(a))")
        assert gc.isenabled() is enabled
    finally:
        if was:
            gc.enable()
