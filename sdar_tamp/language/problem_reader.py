"""The PDDL problem reader: :func:`parse_problem` for a parsed domain (objects, ``:init``
facts, numeric ones included, the goal and the ``total-cost`` metric).

What Fast Downward and VAL accept beyond the standard (predicates used only in ``:init`` or the
goal, an initial fact whose argument has another type than declared...) is accepted and noted as
a :class:`~sdar_tamp.language.leniency.Leniency`; ``strict=True`` rejects it instead.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.domain_model import Domain, Problem
from sdar_tamp.language.errors import DuplicateError, PddlSyntaxError, UnknownKeywordError
from sdar_tamp.language.formula_model import OBJECT_TYPE, TOTAL_COST, TRUE, Atom
from sdar_tamp.language.formula_reader import FormulaReader, Vocabulary
from sdar_tamp.language.grammar import (
    expect_list,
    expect_symbol,
    parse_name_header,
    parse_number,
    parse_typed_list,
)
from sdar_tamp.language.leniency import (
    IMPLICIT_PREDICATE,
    INIT_TYPE,
    LeniencyLog,
    note_glued_variables,
)
from sdar_tamp.language.pddl_sections import PROBLEM_SECTIONS, split_sections
from sdar_tamp.language.sexpr import SExpr, SList, Symbol, collector_paused, read_sexpr


def parse_problem(
    text: str, domain: Domain, filename: str | None = None, *, strict: bool = False
) -> Problem:
    """Parse a PDDL problem for ``domain``.

    Each section may appear once and ``:goal`` is required. Predicates that the domain does not
    declare may be used in ``:init`` and the goal (declared by their first use). Leniencies are
    kept in ``Problem.leniencies`` and logged, or with ``strict=True`` rejected.

    Raises:
        PddlError: a subclass naming ``file:line:col`` and what was expected.
        StrictModeError: ``strict=True`` and the problem needs a leniency.
    """
    with collector_paused():
        return _parse_problem(text, domain, filename, strict)


def _parse_problem(text: str, domain: Domain, filename: str | None, strict: bool) -> Problem:
    root = read_sexpr(text, filename)
    log = LeniencyLog(strict)
    note_glued_variables(root, log)
    name = parse_name_header(root.items[1] if len(root.items) > 1 else root, "problem")
    types = frozenset(domain.types.types())
    objects: dict[str, str] = dict(domain.constants)
    vocabulary = Vocabulary(
        {p.name: p.arity for p in domain.predicates.values()},
        types,
        objects,
        {f.name: len(f.parameters) for f in domain.functions.values()},
        derived=domain.derived_predicates,
        filename=filename,
        implicit_predicates={},
    )
    reader = FormulaReader(vocabulary)
    domain_name = domain.name
    sections = split_sections(root, "problem", PROBLEM_SECTIONS)
    seen: dict[str, SList] = {}
    for keyword, section in sections:
        if keyword in seen:
            raise DuplicateError(
                f"section {keyword} appears twice (first at {seen[keyword].location})",
                section.location,
            )
        seen[keyword] = section
    own: dict[str, str] = {}
    for keyword, section in sections:
        if keyword == ":domain":
            domain_name = expect_symbol(
                section.items[1] if len(section.items) > 1 else section, "the domain name"
            ).text
            if domain_name != domain.name:
                raise PddlSyntaxError(
                    f"problem is for domain {domain_name!r}, but the domain is {domain.name!r}",
                    section.location,
                )
        elif keyword == ":objects":
            # (a name declared twice is rejected there)
            parsed = parse_typed_list(section.items[1:], "the objects", types, variables=False)
            own = {obj: type_name for obj, type_name, _ in parsed}
            objects.update(own)
    init: list[Atom] = []
    numeric: dict[tuple[str, tuple[str, ...]], float] = {}
    goal = TRUE
    minimize = False
    init_nodes: list[SExpr] = []  # where each initial fact is
    for keyword, section in sections:
        if keyword == ":init":
            nodes = section.items[1:]
            derived = vocabulary.derived
            plain_atoms = reader.plain_atoms(nodes, {})
            for node, atom in zip(nodes, plain_atoms, strict=True):
                if atom is None or atom.predicate in derived:
                    atom = _init_fact(node, reader, numeric)  # the general case, or the error
                if atom is not None:
                    init.append(atom)
                    init_nodes.append(node)
        elif keyword == ":goal":
            if len(section.items) != 2:
                raise PddlSyntaxError("expected '(:goal formula)'", section.location)
            goal = reader.formula(section.items[1], {})
        elif keyword == ":metric":
            minimize = _metric(section, domain.temporal)
    if ":goal" not in seen:
        raise PddlSyntaxError(
            f"expected a '(:goal ...)' section in problem {name!r}", root.location
        )
    _check_init_types(init, init_nodes, domain, objects, log)
    for predicate, location in (vocabulary.implicit_predicates or {}).items():
        log.add(
            IMPLICIT_PREDICATE,
            f"predicate {predicate!r} is not declared in the domain; declared by this first use "
            f"with {vocabulary.predicates[predicate]} argument(s)",
            location,
        )
    return Problem(
        name,
        domain_name,
        dict(own),
        tuple(init),
        numeric,
        goal,
        minimize,
        filename,
        leniencies=log.finish(),
    )


def _init_fact(
    node: SExpr, reader: FormulaReader, numeric: dict[tuple[str, tuple[str, ...]], float]
) -> Atom | None:
    """The atom of an initial fact, or None for a numeric one (stored in ``numeric``)."""
    lst = expect_list(node, "an initial fact")
    head = lst.items[0] if lst.items else lst
    if (
        isinstance(head, Symbol)
        and head.text == "="
        and len(lst.items) == 3
        and isinstance(lst.items[1], SList)
    ):
        term = lst.items[1]
        fname = expect_symbol(term.items[0] if term.items else term, "a function name")
        args = tuple(reader.term(arg, {}) for arg in term.items[1:])
        reader.function_arity(fname, len(args), term.location)
        value_node = expect_symbol(lst.items[2], "a number")
        value = parse_number(value_node, "a finite number")
        if fname.text == TOTAL_COST and value < 0:
            raise PddlSyntaxError(
                f"expected a non-negative initial total-cost, found {value_node.text!r}",
                value_node.location,
            )
        numeric[(fname.text, args)] = value
        return None
    atom = reader.atom(lst, {})
    if atom.predicate in reader.vocabulary.derived:
        raise PddlSyntaxError(
            f"derived predicate {atom.predicate!r} cannot be in :init", lst.location
        )
    return atom


def _check_init_types(
    facts: Sequence[Atom],
    nodes: Sequence[SExpr],
    domain: Domain,
    objects: Mapping[str, str],
    log: LeniencyLog,
) -> None:
    """Note an argument whose type is not the predicate's parameter type (``nodes[i]`` is
    where ``facts[i]`` is written).

    An object's type is its declared one, or a subtype given by a unary type fact in :init.
    """
    hierarchy = domain.types
    parents = hierarchy.parents
    types = dict(objects)
    for atom in facts:
        if atom.predicate in parents and len(atom.args) == 1:
            current = types.get(atom.args[0], OBJECT_TYPE)
            if hierarchy.is_subtype(atom.predicate, current):
                types[atom.args[0]] = atom.predicate
    # (predicate, the types of its arguments) -> the arguments that do not fit, as (position,
    # expected type): the facts are many, the combinations of types few
    misfits: dict[tuple[str, ...], list[tuple[int, str]]] = {}
    declarations = domain.predicates
    type_of = types.get
    untyped = itertools.repeat(OBJECT_TYPE)
    for index, atom in enumerate(facts):
        if atom.predicate not in declarations:
            continue
        key = (atom.predicate, *map(type_of, atom.args, untyped))
        found = misfits.get(key)
        if found is None:
            parameters = declarations[atom.predicate].parameters
            found = misfits[key] = [
                (position, parameter.type)
                for position, (own, parameter) in enumerate(
                    zip(key[1:], parameters, strict=True), 1
                )
                if not hierarchy.is_subtype(own, parameter.type)
            ]
        for position, expected in found:
            log.add(
                INIT_TYPE,
                f"argument {position} of {atom} is {atom.args[position - 1]!r} of type "
                f"{key[position]!r}, but {atom.predicate!r} expects a {expected!r}",
                nodes[index].location,  # worked out only for a fact that is noted
            )


def _metric(section: SList, temporal: bool) -> bool:
    """``(:metric minimize (total-cost))``, or for a domain with durative actions ``(:metric
    minimize (total-time))`` (their plans run one action after another, so the makespan is
    the sum of the durations, which is the cost)."""
    items = section.items[1:]
    text = " ".join(str(item) for item in items)
    allowed = [f"minimize ({TOTAL_COST})", *(["minimize (total-time)"] if temporal else [])]
    if text not in allowed:
        location: SourceLocation = section.location
        expected = " or ".join(repr(a) for a in allowed)
        raise UnknownKeywordError(f"unsupported metric {text!r}; expected {expected}", location)
    return True
