"""PDDL domain and problem parser.

Supported requirements: ``:strips :typing :negative-preconditions :disjunctive-preconditions
:equality :existential-preconditions :universal-preconditions :quantified-preconditions
:conditional-effects :derived-predicates :action-costs :adl``. Names are case-insensitive.

What Fast Downward and VAL accept beyond the standard (``(aircraft?a)``, ``(in ?obj ?obj)``,
predicates used only in ``:init`` or the goal...) is accepted and noted as a
:class:`~sdar_tamp.language.leniency.Leniency`; ``strict=True`` rejects it instead.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import (
    ArityError,
    DuplicateError,
    PddlSyntaxError,
    UndeclaredError,
    UnknownKeywordError,
)
from sdar_tamp.language.grammar import (
    FormulaReader,
    Vocabulary,
    expect_head,
    expect_list,
    expect_symbol,
    parse_name_header,
    parse_number,
    parse_options,
    parse_typed_list,
)
from sdar_tamp.language.leniency import (
    DUPLICATE_PREDICATE,
    DUPLICATE_TYPE,
    FREE_VARIABLE,
    IMPLICIT_PREDICATE,
    INIT_TYPE,
    REPEATED_VARIABLE,
    UNDECLARED_PARENT_TYPE,
    LeniencyLog,
    note_glued_variables,
)
from sdar_tamp.language.model import (
    OBJECT_TYPE,
    TOTAL_COST,
    TRUE,
    ActionSchema,
    AndEffect,
    Atom,
    Axiom,
    Domain,
    Exists,
    Formula,
    Function,
    Parameter,
    Predicate,
    Problem,
    TypeHierarchy,
)
from sdar_tamp.language.sexpr import SExpr, SList, Symbol, collector_paused, read_sexpr

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
    }
)
DOMAIN_SECTIONS = (
    ":requirements",
    ":types",
    ":constants",
    ":predicates",
    ":functions",
    ":action",
    ":derived",
)
PROBLEM_SECTIONS = (":domain", ":requirements", ":objects", ":init", ":goal", ":metric")


def _sections(root: SList, kind: str, allowed: Iterable[str]) -> list[tuple[str, SList]]:
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


def parse_domain(text: str, filename: str | None = None, *, strict: bool = False) -> Domain:
    """Parse a PDDL domain.

    Leniencies (see :mod:`sdar_tamp.language.leniency`) are kept in ``Domain.leniencies`` and
    logged, or with ``strict=True`` rejected.

    Raises:
        PddlError: a subclass naming ``file:line:col`` and what was expected.
        StrictModeError: ``strict=True`` and the domain needs a leniency.
    """
    root = read_sexpr(text, filename)
    log = LeniencyLog(strict)
    note_glued_variables(root, log)
    name = parse_name_header(root.items[1] if len(root.items) > 1 else root, "domain")
    requirements: set[str] = set()
    parents: dict[str, str] = {}
    constants: dict[str, str] = {}
    predicates: dict[str, Predicate] = {}
    functions: dict[str, Function] = {}
    vocabulary = Vocabulary(
        {}, frozenset({OBJECT_TYPE}), constants, {}, filename=filename, allow_new_functions=True
    )
    reader = FormulaReader(vocabulary)
    pending: list[tuple[str, SList]] = []
    for keyword, section in _sections(root, "domain", DOMAIN_SECTIONS):
        body = section.items[1:]
        if keyword == ":requirements":
            for token in body:
                symbol = expect_symbol(token, "a requirement")
                if symbol.text not in REQUIREMENTS:
                    raise UnknownKeywordError(
                        f"unsupported requirement {symbol.text!r}; supported: "
                        f"{', '.join(sorted(REQUIREMENTS))}",
                        symbol.location,
                    )
                requirements.add(symbol.text)
        elif keyword == ":types":
            _declare_types(body, parents, log)
            vocabulary.types = frozenset({OBJECT_TYPE, *parents})
        elif keyword == ":constants":
            for const, type_name, token in parse_typed_list(
                body, "the constants", vocabulary.types, variables=False
            ):
                if const in constants:
                    raise DuplicateError(f"constant {const!r} is declared twice", token.location)
                constants[const] = type_name
        elif keyword == ":predicates":
            for node in body:
                predicate = _declaration(
                    node, reader, "a predicate declaration", log, parents=parents
                )
                if predicate.name in vocabulary.types:
                    raise DuplicateError(
                        f"predicate {predicate.name!r} has the name of a type", node.location
                    )
                if predicate.name in predicates:
                    first = predicates[predicate.name]
                    if first.arity != predicate.arity:
                        raise DuplicateError(
                            f"predicate {predicate.name!r} is declared twice with different "
                            f"arities ({first.arity} and {predicate.arity})",
                            node.location,
                        )
                    log.add(
                        DUPLICATE_PREDICATE,
                        f"predicate {predicate.name!r} is declared twice; the first declaration "
                        "is kept",
                        node.location,
                    )
                    continue
                predicates[predicate.name] = predicate
                vocabulary.predicates[predicate.name] = predicate.arity
        elif keyword == ":functions":
            _declare_functions(body, reader, functions, parents)
        else:
            pending.append((keyword, section))
    vocabulary.derived = frozenset(
        _derived_name(section) for keyword, section in pending if keyword == ":derived"
    )
    actions: list[ActionSchema] = []
    axioms: list[Axiom] = []
    for keyword, section in pending:
        if keyword == ":action":
            action = _action(section, reader, log)
            if any(existing.name == action.name for existing in actions):
                raise DuplicateError(f"action {action.name!r} is defined twice", section.location)
            actions.append(action)
        else:
            axioms.append(_axiom(section, reader, predicates, log))
    for fname, arity in vocabulary.functions.items():
        if fname not in functions:
            params = tuple(Parameter(f"?x{i}") for i in range(arity))
            functions[fname] = Function(fname, params)
    return Domain(
        name=name,
        requirements=frozenset(requirements),
        types=TypeHierarchy(dict(parents)),
        constants=dict(constants),
        predicates=dict(predicates),
        functions=dict(functions),
        actions=tuple(actions),
        axioms=tuple(axioms),
        source=filename,
        leniencies=log.finish(),
    )


def _derived_name(section: SList) -> str:
    if len(section.items) != 3:
        raise PddlSyntaxError("expected '(:derived (predicate ?params) formula)'", section.location)
    head = expect_list(section.items[1], "the derived predicate '(name ?params)'")
    return expect_symbol(head.items[0] if head.items else head, "a predicate name").text


def _declare_types(body: tuple[SExpr, ...], parents: dict[str, str], log: LeniencyLog) -> None:
    repeats: list[tuple[str, SourceLocation]] = []
    declared = parse_typed_list(body, "the types", None, variables=False, repeats=repeats)
    for child, parent, token in declared:
        if child == OBJECT_TYPE:
            continue
        earlier = parents.get(child)
        if earlier is not None and OBJECT_TYPE not in (earlier, parent) and earlier != parent:
            raise DuplicateError(
                f"type {child!r} is declared twice, as a subtype of {earlier!r} and of {parent!r}",
                token.location,
            )
        if earlier is not None:
            kept = earlier if parent == OBJECT_TYPE else parent
            log.add(
                DUPLICATE_TYPE,
                f"type {child!r} is declared twice; kept as a subtype of {kept!r}",
                token.location,
            )
            parent = kept
        parents[child] = parent
    noted: set[str] = set()
    for dash, node in itertools.pairwise(body):
        if (
            isinstance(dash, Symbol)
            and dash.text == "-"
            and isinstance(node, Symbol)
            and node.text not in parents
            and node.text != OBJECT_TYPE
            and node.text not in noted
        ):
            noted.add(node.text)
            log.add(
                UNDECLARED_PARENT_TYPE,
                f"parent type {node.text!r} is not declared in :types; it is taken to be a "
                "subtype of 'object'",
                node.location,
            )
    for child, parent in list(parents.items()):
        seen = {child}
        while parent != OBJECT_TYPE:
            if parent not in parents:
                parents[parent] = OBJECT_TYPE  # an undeclared supertype is implicitly an object
                break
            if parent in seen:
                raise PddlSyntaxError(
                    f"type {child!r} is its own ancestor", body[0].location if body else None
                )
            seen.add(parent)
            parent = parents[parent]


def common_supertype(members: tuple[str, ...], parents: Mapping[str, str]) -> str:
    """The most specific type that every one of ``members`` is a subtype of (given the
    ``parents`` of the declared types)."""
    chains = [TypeHierarchy(parents).ancestors(member) for member in members]
    return next(t for t in chains[0] if all(t in chain for chain in chains[1:]))


def _declaration(
    node: SExpr,
    reader: FormulaReader,
    what: str,
    log: LeniencyLog | None = None,
    parents: Mapping[str, str] | None = None,
) -> Predicate:
    """``(name ?a - t ?b)``; with ``log``, a repeated variable name is noted, not an error.
    With ``parents`` (predicate and function declarations, whose types only describe the
    arguments), ``?a - (either t1 t2)`` is read as the most specific common supertype of its
    members."""
    lst = expect_list(node, what)
    head = expect_symbol(lst.items[0] if lst.items else lst, "a name")
    repeats: list[tuple[str, SourceLocation]] = []
    params = parse_typed_list(
        lst.items[1:],
        f"the parameters of {head.text!r}",
        reader.vocabulary.types,
        variables=True,
        repeats=repeats if log is not None else None,
        either=None if parents is None else (lambda members: common_supertype(members, parents)),
    )
    if log is not None:
        for variable, location in repeats:
            log.add(
                REPEATED_VARIABLE,
                f"variable {variable} appears twice in the declaration of {head.text!r}",
                location,
            )
    return Predicate(head.text, tuple(Parameter(n, t) for n, t, _ in params))


def _declare_functions(
    body: tuple[SExpr, ...],
    reader: FormulaReader,
    functions: dict[str, Function],
    parents: Mapping[str, str],
) -> None:
    index = 0
    while index < len(body):
        node = body[index]
        if isinstance(node, Symbol) and node.text == "-":
            index += 2  # "- number": the only function type
            continue
        declaration = _declaration(node, reader, "a function declaration", parents=parents)
        functions[declaration.name] = Function(declaration.name, declaration.parameters)
        reader.vocabulary.functions[declaration.name] = declaration.arity
        index += 1


def _action(section: SList, reader: FormulaReader, log: LeniencyLog) -> ActionSchema:
    if len(section.items) < 2:
        raise PddlSyntaxError("expected an action name after ':action'", section.location)
    name = expect_symbol(section.items[1], "an action name").text
    what = f"action {name!r}"
    options = parse_options(section, (":parameters", ":precondition", ":effect"), what, 2)
    params = (
        reader.parameters(options[":parameters"], f"the parameters of {what}")
        if ":parameters" in options
        else ()
    )
    scope = {p.name: p.type for p in params}
    precondition = (
        _existential_closure(
            reader, options[":precondition"], scope, f"the precondition of {what}", log
        )
        if ":precondition" in options
        else TRUE
    )
    effect = reader.effect(options[":effect"], scope) if ":effect" in options else AndEffect(())
    return ActionSchema(name, params, precondition, effect, section.location)


def _axiom(
    section: SList, reader: FormulaReader, predicates: dict[str, Predicate], log: LeniencyLog
) -> Axiom:
    head = expect_list(section.items[1], "the derived predicate '(name ?params)'")
    declared = _declaration(head, reader, "the derived predicate")
    if declared.name not in predicates:
        raise UndeclaredError(
            f"derived predicate {declared.name!r} is not declared in :predicates", head.location
        )
    if declared.arity != predicates[declared.name].arity:
        raise ArityError(
            f"predicate {declared.name!r} takes {predicates[declared.name].arity} argument(s), "
            f"got {declared.arity}",
            head.location,
        )
    params = tuple(
        Parameter(p.name, decl.type if p.type == OBJECT_TYPE else p.type)
        for p, decl in zip(declared.parameters, predicates[declared.name].parameters, strict=True)
    )
    scope = {p.name: p.type for p in params}
    what = f"the body of derived predicate {declared.name!r}"
    body = _existential_closure(reader, section.items[2], scope, what, log)
    return Axiom(declared.name, params, body, section.location)


def _existential_closure(
    reader: FormulaReader, node: SExpr, scope: Mapping[str, str], what: str, log: LeniencyLog
) -> Formula:
    """``node`` read as a formula, its free variables existentially quantified (noted)."""
    formula, free = reader.open_formula(node, scope)
    if not free:
        return formula
    for variable, location in free.items():
        log.add(
            FREE_VARIABLE,
            f"variable {variable} in {what} is neither a parameter nor quantified; read as "
            "existentially quantified (as Fast Downward does)",
            location,
        )
    return Exists(tuple(Parameter(variable) for variable in free), formula)


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
    sections = _sections(root, "problem", PROBLEM_SECTIONS)
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
            minimize = _metric(section)
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


def _metric(section: SList) -> bool:
    items = section.items[1:]
    text = " ".join(str(item) for item in items)
    if text != f"minimize ({TOTAL_COST})":
        location: SourceLocation = section.location
        raise UnknownKeywordError(
            f"unsupported metric {text!r}; expected 'minimize (total-cost)'", location
        )
    return True
