"""The PDDL domain reader: :func:`parse_domain` (sections in
:mod:`sdar_tamp.language.pddl_sections`, declarations in
:mod:`sdar_tamp.language.declarations`, actions and derived predicates here).

What Fast Downward and VAL accept beyond the standard (``(aircraft?a)``, ``(in ?obj ?obj)``,
free variables in a precondition...) is accepted and noted as a
:class:`~sdar_tamp.language.leniency.Leniency`; ``strict=True`` rejects it instead.
"""

from __future__ import annotations

from collections.abc import Mapping

from sdar_tamp.language.declarations import declaration, declare_functions, declare_types
from sdar_tamp.language.domain_model import (
    ActionSchema,
    Axiom,
    Domain,
    Function,
    Predicate,
    TypeHierarchy,
)
from sdar_tamp.language.durative import DurativeActionSchema, read_durative_action
from sdar_tamp.language.errors import ArityError, DuplicateError, PddlSyntaxError, UndeclaredError
from sdar_tamp.language.formula_model import (
    OBJECT_TYPE,
    TOTAL_COST,
    TRUE,
    AndEffect,
    Exists,
    Formula,
    Parameter,
)
from sdar_tamp.language.formula_reader import FormulaReader, Vocabulary
from sdar_tamp.language.grammar import (
    expect_list,
    expect_symbol,
    parse_name_header,
    parse_options,
    parse_typed_list,
)
from sdar_tamp.language.leniency import (
    DUPLICATE_PREDICATE,
    FREE_VARIABLE,
    FUNCTION_ARITY,
    LeniencyLog,
    note_glued_variables,
)
from sdar_tamp.language.numeric import (
    NumericReader,
    is_comparison,
    is_numeric_effect,
    split_conjuncts,
)
from sdar_tamp.language.pddl_sections import DOMAIN_SECTIONS, read_requirements, split_sections
from sdar_tamp.language.sequential import compile_durative
from sdar_tamp.language.sexpr import SExpr, SList, read_sexpr


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
    for keyword, section in split_sections(root, "domain", DOMAIN_SECTIONS):
        body = section.items[1:]
        if keyword == ":requirements":
            requirements.update(read_requirements(body))
        elif keyword == ":types":
            declare_types(body, parents, log)
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
                predicate = declaration(
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
            declare_functions(body, reader, functions, parents)
            vocabulary.open_arity_functions = {
                f.name for f in functions.values() if not f.parameters and f.name != TOTAL_COST
            }
        else:
            pending.append((keyword, section))
    vocabulary.derived = frozenset(
        _derived_name(section) for keyword, section in pending if keyword == ":derived"
    )
    actions: list[ActionSchema] = []
    axioms: list[Axiom] = []
    durative: list[DurativeActionSchema] = []

    def read_condition(
        reader: FormulaReader, node: SExpr, scope: Mapping[str, str], what: str
    ) -> Formula:
        return _existential_closure(reader, node, scope, what, log)

    for keyword, section in pending:
        if keyword in (":action", ":durative-action"):
            if keyword == ":action":
                action = _action(section, reader, log)
            else:
                durative.append(read_durative_action(section, reader, read_condition))
                action = ActionSchema(durative[-1].name, (), TRUE, AndEffect(()))
            if any(existing.name == action.name for existing in actions):
                raise DuplicateError(f"action {action.name!r} is defined twice", section.location)
            actions.append(action)
        else:
            axioms.append(_axiom(section, reader, predicates, log))
    compiled = {a.name: compile_durative(a, tuple(axioms)) for a in durative}
    actions = [compiled.get(a.name, a) for a in actions]
    for fname, (arity, location) in vocabulary.function_arity_uses.items():
        log.add(
            FUNCTION_ARITY,
            f"function {fname!r} is declared with no arguments and used with {arity}; read "
            f"with {arity} (as PDDLStream does; a stream file's :function gives the arity)",
            location,
        )
        functions[fname] = Function(fname, tuple(Parameter(f"?x{i}") for i in range(arity)))
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
        durative_actions=tuple(durative),
        source=filename,
        leniencies=log.finish(),
    )


def _derived_name(section: SList) -> str:
    if len(section.items) != 3:
        raise PddlSyntaxError("expected '(:derived (predicate ?params) formula)'", section.location)
    head = expect_list(section.items[1], "the derived predicate '(name ?params)'")
    return expect_symbol(head.items[0] if head.items else head, "a predicate name").text


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
    numeric = NumericReader(reader.term, reader.function_arity)
    pre_node, comparisons = split_conjuncts(options.get(":precondition"), is_comparison)
    precondition = (
        _existential_closure(reader, pre_node, scope, f"the precondition of {what}", log)
        if pre_node is not None
        else TRUE
    )
    effect_node, changes = split_conjuncts(options.get(":effect"), is_numeric_effect)
    effect = reader.effect(effect_node, scope) if effect_node is not None else AndEffect(())
    return ActionSchema(
        name,
        params,
        precondition,
        effect,
        section.location,
        tuple(numeric.comparison(node, scope) for node in comparisons),
        tuple(numeric.effect(node, scope) for node in changes),
    )


def _axiom(
    section: SList, reader: FormulaReader, predicates: dict[str, Predicate], log: LeniencyLog
) -> Axiom:
    head = expect_list(section.items[1], "the derived predicate '(name ?params)'")
    declared = declaration(head, reader, "the derived predicate")
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
