"""Stream-file parser (PDDLStream syntax).

``(define (stream NAME) (:stream ...) (:function ...) (:predicate ...) (:rule ...))``.

Well-formedness: domain and certified are conjunctions of atoms; parameters are unique; every domain
parameter is an input; every certified parameter is an input or an output. Predicates must be
declared in the domain, be type names, or be certified by some stream of the file (stream-only
predicates, whose arity must then be consistent). As in PDDLStream, a predicate used only in a
``:domain`` (a fact the problem's init provides) is declared by its first use and noted as a
leniency; ``strict=True`` rejects it.
"""

from __future__ import annotations

from collections.abc import Iterable

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.errors import (
    ArityError,
    DuplicateError,
    PddlSyntaxError,
    StreamDefinitionError,
    UndeclaredError,
    UnknownKeywordError,
    UnsupportedFeatureError,
)
from sdar_tamp.language.formula_model import Atom, FunctionTerm
from sdar_tamp.language.formula_reader import FormulaReader, Vocabulary
from sdar_tamp.language.grammar import (
    expect_head,
    expect_list,
    expect_symbol,
    parse_name_header,
    parse_options,
)
from sdar_tamp.language.leniency import IMPLICIT_PREDICATE, LeniencyLog, note_glued_variables
from sdar_tamp.language.sexpr import SExpr, SList, Symbol, read_sexpr
from sdar_tamp.language.stream_model import Rule, Stream, StreamFile
from sdar_tamp.language.stream_model import StreamFunction as StreamFunctionDecl
from sdar_tamp.language.stream_model import StreamPredicate as StreamPredicateDecl

STREAM_SECTIONS = (":stream", ":function", ":predicate", ":rule", ":optimizer")
STREAM_OPTIONS = (":inputs", ":domain", ":fluents", ":outputs", ":certified")
RULE_OPTIONS = (":inputs", ":parameters", ":domain", ":certified")


def parse_stream_file(
    text: str, domain: Domain, filename: str | None = None, *, strict: bool = False
) -> StreamFile:
    """Parse a stream file against ``domain`` (whose predicates, types and constants it may use).

    Raises:
        PddlError: a subclass naming ``file:line:col`` and what was expected.
        StrictModeError: ``strict=True`` and the file needs a leniency.
    """
    root = read_sexpr(text, filename)
    log = LeniencyLog(strict)
    note_glued_variables(root, log)
    expect_head(root, "define", "a stream file '(define (stream NAME) ...)'")
    name = parse_name_header(root.items[1] if len(root.items) > 1 else root, "stream")
    sections: list[tuple[str, SList]] = []
    for node in root.items[2:]:
        section = expect_list(node, "a stream-file section such as (:stream ...)")
        keyword = expect_symbol(section.items[0] if section.items else section, "a keyword")
        if keyword.text == ":optimizer":
            raise UnsupportedFeatureError(
                "':optimizer' is not supported; declare its outputs as ':stream's", keyword.location
            )
        if keyword.text not in STREAM_SECTIONS:
            raise UnknownKeywordError(
                f"unknown stream-file section {keyword.text!r}; expected one of "
                f"{', '.join(STREAM_SECTIONS[:-1])}",
                keyword.location,
            )
        sections.append((keyword.text, section))

    predicates = {p.name: p.arity for p in domain.predicates.values()}
    _declare_certified(sections, predicates, frozenset(domain.types.types()))
    _declare_domain_only(sections, predicates, frozenset(domain.types.types()), log)
    vocabulary = Vocabulary(
        predicates,
        frozenset(domain.types.types()),
        dict(domain.constants),
        {f.name: len(f.parameters) for f in domain.functions.values()},
        allow_new_functions=True,
        filename=filename,
    )
    reader = FormulaReader(vocabulary)
    streams: list[Stream] = []
    functions: list[StreamFunctionDecl] = []
    external: list[StreamPredicateDecl] = []
    rules: list[Rule] = []
    names: set[str] = set()
    for kind, section in sections:
        if kind == ":stream":
            stream = _stream(section, reader)
            _unique(stream.name, names, section.location)
            streams.append(stream)
        elif kind == ":function":
            function = _function(section, reader)
            _unique(function.name, names, section.location)
            functions.append(function)
        elif kind == ":predicate":
            predicate = _predicate(section, reader)
            _unique(predicate.name, names, section.location)
            external.append(predicate)
        else:
            rules.append(_rule(section, reader))
    return StreamFile(
        name,
        tuple(streams),
        tuple(functions),
        tuple(external),
        tuple(rules),
        filename,
        leniencies=log.finish(),
    )


def _unique(name: str, names: set[str], location: SourceLocation) -> None:
    if name in names:
        raise DuplicateError(f"stream {name!r} is defined twice", location)
    names.add(name)


def _declare_certified(
    sections: Iterable[tuple[str, SList]], predicates: dict[str, int], types: frozenset[str]
) -> None:
    """Stream-only predicates: certified (or external) ones that the domain does not declare."""
    for keyword, section in sections:
        if (
            keyword == ":predicate"
            and len(section.items) > 1
            and isinstance(section.items[1], SList)
        ):
            _declare_atom(section.items[1], predicates, types)
        if keyword not in (":stream", ":rule"):
            continue
        start = 2 if keyword == ":stream" else 1
        items = section.items[start:]
        for key, value in zip(items[::2], items[1::2], strict=False):
            if isinstance(key, Symbol) and key.text == ":certified" and isinstance(value, SList):
                parts = value.items[1:] if _is_and(value) else (value,)
                for part in parts:
                    _declare_atom(part, predicates, types)


def _declare_domain_only(
    sections: Iterable[tuple[str, SList]],
    predicates: dict[str, int],
    types: frozenset[str],
    log: LeniencyLog,
) -> None:
    """Predicates used in a ``:domain`` that neither the domain nor the file declares."""
    for keyword, section in sections:
        if keyword in (":function", ":predicate"):
            nodes = section.items[2:3]
        else:
            start = 2 if keyword == ":stream" else 1
            items = section.items[start:]
            nodes = tuple(
                value
                for key, value in zip(items[::2], items[1::2], strict=False)
                if isinstance(key, Symbol) and key.text == ":domain"
            )
        for node in nodes:
            if not isinstance(node, SList):
                continue
            for part in node.items[1:] if _is_and(node) else (node,):
                head = _declare_atom(part, predicates, types)
                if head is not None:
                    log.add(
                        IMPLICIT_PREDICATE,
                        f"predicate {head.text!r} is declared neither in the domain nor by a "
                        f"stream's :certified; declared by this first use with "
                        f"{predicates[head.text]} argument(s)",
                        head.location,
                    )


def _declare_atom(node: SExpr, predicates: dict[str, int], types: frozenset[str]) -> Symbol | None:
    """Declare ``node``'s predicate unless known; return its head when it was new."""
    if not isinstance(node, SList) or not node.items:
        return None
    head = node.items[0]
    if not isinstance(head, Symbol) or head.text in types or head.text == "=":
        return None
    arity = len(node.items) - 1
    if head.text in ("and", "or", "not", "imply", "exists", "forall"):
        return None
    new = head.text not in predicates
    if predicates.setdefault(head.text, arity) != arity:
        raise ArityError(
            f"predicate {head.text!r} takes {predicates[head.text]} argument(s), got {arity}",
            node.location,
        )
    return head if new else None


def _is_and(node: SList) -> bool:
    return bool(node.items) and isinstance(node.items[0], Symbol) and node.items[0].text == "and"


def _variables(node: SExpr, what: str) -> tuple[tuple[str, SourceLocation], ...]:
    lst = expect_list(node, what)
    result: list[tuple[str, SourceLocation]] = []
    for item in lst.items:
        symbol = expect_symbol(item, f"a variable in {what}")
        if not symbol.text.startswith("?"):
            raise PddlSyntaxError(
                f"expected a variable starting with '?' in {what}, found {symbol.text!r}",
                symbol.location,
            )
        result.append((symbol.text, symbol.location))
    return tuple(result)


def _check_unique(names: Iterable[tuple[str, SourceLocation]], what: str) -> None:
    seen: set[str] = set()
    for name, location in names:
        if name in seen:
            raise DuplicateError(f"parameter {name} appears twice in {what}", location)
        seen.add(name)


def _stream(section: SList, reader: FormulaReader) -> Stream:
    if len(section.items) < 2:
        raise PddlSyntaxError("expected a stream name after ':stream'", section.location)
    name = expect_symbol(section.items[1], "a stream name").text
    what = f"stream {name!r}"
    options = parse_options(section, STREAM_OPTIONS, what, 2)
    empty = section.with_items(())
    inputs = _variables(options.get(":inputs", empty), f"the inputs of {what}")
    outputs = _variables(options.get(":outputs", empty), f"the outputs of {what}")
    _check_unique((*inputs, *outputs), what)
    input_scope = {n: "object" for n, _ in inputs}
    domain_node = options.get(":domain", empty)
    domain = reader.conjunction(
        domain_node, _scope_for(domain_node, input_scope, "an input", what), f"the domain of {what}"
    )
    _inputs_in_domain(inputs, domain, what)
    full_scope = {**input_scope, **{n: "object" for n, _ in outputs}}
    certified_node = options.get(":certified", empty)
    certified = reader.conjunction(
        certified_node,
        _scope_for(certified_node, full_scope, "an input or an output", what),
        f"the certified facts of {what}",
    )
    fluents: list[str] = []
    for item in expect_list(options.get(":fluents", empty), f"the fluents of {what}").items:
        fluent = expect_symbol(item, "a predicate name")
        if fluent.text not in reader.vocabulary.predicates:
            raise UndeclaredError(
                f"undeclared fluent predicate {fluent.text!r} in {what}", fluent.location
            )
        fluents.append(fluent.text)
    return Stream(
        name,
        tuple(n for n, _ in inputs),
        domain,
        tuple(n for n, _ in outputs),
        certified,
        tuple(fluents),
        section.location,
    )


def _inputs_in_domain(
    inputs: Iterable[tuple[str, SourceLocation]], domain: tuple[Atom, ...], what: str
) -> None:
    """Every input must be constrained by the domain, or instances would range over all objects."""
    used = {term for atom in domain for term in atom.args}
    for name, location in inputs:
        if name not in used:
            raise StreamDefinitionError(
                f"input {name} of {what} must appear in its :domain", location
            )


def _scope_for(node: SExpr, scope: dict[str, str], role: str, what: str) -> dict[str, str]:
    """Check that every variable in ``node`` is in ``scope``; say which role it must have."""
    stack = [node]
    while stack:
        current = stack.pop()
        if isinstance(current, SList):
            stack.extend(current.items)
        elif current.text.startswith("?") and current.text not in scope:
            raise StreamDefinitionError(
                f"{current.text} in {what} must be {role} of the stream", current.location
            )
    return scope


def _head(section: SList, keyword: str) -> tuple[SList, Symbol]:
    if len(section.items) not in (2, 3):
        raise PddlSyntaxError(f"expected '({keyword} (name ?inputs) [domain])'", section.location)
    head = expect_list(section.items[1], f"the head '(name ?inputs)' of {keyword}")
    return head, expect_symbol(head.items[0] if head.items else head, "a name")


def _function(section: SList, reader: FormulaReader) -> StreamFunctionDecl:
    head, name = _head(section, ":function")
    inputs = _variables(head.with_items(head.items[1:]), f"function {name.text!r}")
    _check_unique(inputs, f"function {name.text!r}")
    scope = {n: "object" for n, _ in inputs}
    reader.function_arity(name, len(inputs), head.location)
    domain = _optional_domain(section, reader, scope, f"function {name.text!r}")
    _inputs_in_domain(inputs, domain, f"function {name.text!r}")
    return StreamFunctionDecl(FunctionTerm(name.text, tuple(scope)), domain, section.location)


def _predicate(section: SList, reader: FormulaReader) -> StreamPredicateDecl:
    head, name = _head(section, ":predicate")
    inputs = _variables(head.with_items(head.items[1:]), f"predicate {name.text!r}")
    _check_unique(inputs, f"predicate {name.text!r}")
    scope = {n: "object" for n, _ in inputs}
    atom = reader.atom(head, scope)
    domain = _optional_domain(section, reader, scope, f"predicate {name.text!r}")
    _inputs_in_domain(inputs, domain, f"predicate {name.text!r}")
    return StreamPredicateDecl(atom, domain, section.location)


def _optional_domain(
    section: SList, reader: FormulaReader, scope: dict[str, str], what: str
) -> tuple[Atom, ...]:
    if len(section.items) < 3:
        return ()
    node = section.items[2]
    return reader.conjunction(
        node, _scope_for(node, scope, "an input", what), f"the domain of {what}"
    )


def _rule(section: SList, reader: FormulaReader) -> Rule:
    options = parse_options(section, RULE_OPTIONS, "a rule", 1)
    empty = section.with_items(())
    params_node = options.get(":inputs", options.get(":parameters", empty))
    params = _variables(params_node, "the parameters of a rule")
    _check_unique(params, "a rule")
    scope = {n: "object" for n, _ in params}
    domain_node = options.get(":domain", empty)
    certified_node = options.get(":certified", empty)
    domain = reader.conjunction(
        domain_node, _scope_for(domain_node, scope, "a parameter", "a rule"), "the domain of a rule"
    )
    certified = reader.conjunction(
        certified_node,
        _scope_for(certified_node, scope, "a parameter", "a rule"),
        "the certified facts of a rule",
    )
    return Rule(tuple(scope), domain, certified, section.location)
