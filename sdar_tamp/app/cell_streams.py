"""The stream file of a cell of ``k`` arms, from the shipped declaration for two.

``domains/dual_arm_rearrangement/stream.pddl`` declares ``combine-confs`` for the shipped
two-arm cell: its inputs are one (arm, configuration) pair per arm, ``?a1 ?q1 ?a2 ?q2``, and
its ``:domain`` and ``:certified`` facts are a per-arm pattern (``(confof ?a1 ?q1)``,
``(confin ?d ?a1 ?q1)``, the same with ``2``) beside facts of no arm (``(dualconf ?d)``). A
PDDL stream has a fixed arity, so a cell of ``k`` arms gets that declaration with ``k`` pairs
when its problem is built (:func:`streams_for_arms`): the first arm's variables (those ending
in ``1``) are renumbered for every arm, and every fact of the first arm is repeated for each.
The other streams and the domain do not depend on the number of arms: a cell configuration
holds one ``confin`` fact per arm, a ``move`` takes every arm, and a gripper action is one
arm's. The file stays the one readers see; for two arms it is used as it is.
"""

from __future__ import annotations

from collections.abc import Sequence

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.errors import StreamDefinitionError
from sdar_tamp.language.sexpr import SExpr, SList, Symbol, read_sexpr

#: The stream whose inputs hold one (arm, configuration) pair per arm.
CELL_STREAM = "combine-confs"


def streams_for_arms(text: str, arms: int, stream: str = CELL_STREAM) -> str:
    """``text`` (a stream file) with ``stream`` declared for ``arms`` arms (see the module
    docstring); ``text`` itself for two arms.

    Raises:
        ParameterError: ``arms`` < 1.
        StreamDefinitionError: the file has no ``stream`` or its declaration is not the per-arm
            pattern of two arms (located at the declaration).
    """
    if arms < 1:
        raise ParameterError(f"arms must be >= 1, got {arms}")
    if arms == 2:
        return text
    node, start, end = _find(text, stream)
    return text[:start] + declaration_for_arms(node, arms) + text[end:]


def declaration_for_arms(node: SList, arms: int) -> str:
    """The text of the declaration ``node`` (a two-arm ``:stream``) for ``arms`` arms."""
    fields = _fields(node)
    inputs = [_variable(v, node) for v in _items(fields.get(":inputs"), node, ":inputs")]
    half = len(inputs) // 2
    first, second = inputs[:half], inputs[half:]
    if not first or len(inputs) % 2 or any(not v.endswith("1") for v in first):
        raise _error(node, "expected the inputs of two arms, first arm's ending in 1")
    if second != [_renumber(v, 2) for v in first]:
        raise _error(node, "expected the second arm's inputs to be the first's ending in 2")
    parts = [f"(:stream {_name(node)}"]
    arm_inputs = [_renumber(v, i) for i in range(1, arms + 1) for v in first]
    parts.append(f"    :inputs ({' '.join(arm_inputs)})")
    for key in (":domain", ":fluents", ":outputs", ":certified"):
        value = fields.get(key)
        if value is None:
            continue
        if key in (":domain", ":certified"):
            parts.append(f"    {key} {_facts(value, first, second, arms, node)}")
        else:
            parts.append(f"    {key} {value}")
    return "\n".join(parts) + ")"


def _facts(
    value: SExpr, first: Sequence[str], second: Sequence[str], arms: int, node: SList
) -> str:
    """A conjunction of facts: the first arm's repeated for every arm, the second arm's left
    out (they are the first's for arm 2), the others kept."""
    atoms = list(value.items[1:]) if isinstance(value, SList) and _is_and(value) else [value]
    out: list[str] = []
    seconds: list[str] = []
    for atom in atoms:
        names = set(_symbols(atom))
        ones, twos = names & set(first), names & set(second)
        if ones and twos:
            raise _error(node, f"a fact mixes the arms' variables: {atom}")
        if twos:
            seconds.append(_rename(atom, first, second, back=True))
        elif ones:
            out.extend(_rename(atom, first, first, index=i) for i in range(1, arms + 1))
        else:
            out.append(str(atom))
    firsts = [str(a) for a in atoms if set(_symbols(a)) & set(first)]
    if sorted(seconds) != sorted(firsts):
        raise _error(node, "expected the second arm's facts to repeat the first arm's")
    return f"(and {' '.join(out)})"


def _rename(
    atom: SExpr,
    first: Sequence[str],
    source: Sequence[str],
    *,
    index: int = 1,
    back: bool = False,
) -> str:
    """``atom`` with the variables of ``source`` renamed: to the first arm's (``back``), else
    the first arm's to arm ``index``'s."""
    mapping = (
        dict(zip(source, first, strict=True)) if back else {v: _renumber(v, index) for v in first}
    )
    if isinstance(atom, Symbol):
        return mapping.get(atom.text, atom.text)
    return "(" + " ".join(_rename(x, first, source, index=index, back=back)
                          for x in atom.items) + ")"  # fmt: skip


def _renumber(variable: str, index: int) -> str:
    return f"{variable[:-1]}{index}"


def _symbols(node: SExpr) -> list[str]:
    if isinstance(node, Symbol):
        return [node.text]
    return [s for item in node.items for s in _symbols(item)]


def _is_and(node: SExpr) -> bool:
    return (
        isinstance(node, SList)
        and bool(node.items)
        and isinstance(node.items[0], Symbol)
        and node.items[0].text == "and"
    )


def _name(node: SList) -> str:
    return str(node.items[1])


def _fields(node: SList) -> dict[str, SExpr]:
    items = node.items[2:]
    if len(items) % 2:
        raise _error(node, "expected keyword and value pairs")
    return {str(items[k]): items[k + 1] for k in range(0, len(items), 2)}


def _items(value: SExpr | None, node: SList, key: str) -> tuple[SExpr, ...]:
    if not isinstance(value, SList):
        raise _error(node, f"expected a list of variables after {key}")
    return value.items


def _variable(value: SExpr, node: SList) -> str:
    if not isinstance(value, Symbol) or not value.text.startswith("?"):
        raise _error(node, f"expected a variable, got {value}")
    return value.text


def _error(node: SList, message: str) -> StreamDefinitionError:
    return StreamDefinitionError(f"{_name(node)} for k arms: {message}", node.location)


def _find(text: str, stream: str) -> tuple[SList, int, int]:
    """The declaration of ``stream`` and where its text starts and ends."""
    root = read_sexpr(text, "stream.pddl")
    for item in root.items:
        if (
            isinstance(item, SList)
            and len(item.items) >= 2
            and str(item.items[0]) == ":stream"
            and str(item.items[1]) == stream
        ):
            return item, item.offset, _closing(text, item.offset)
    raise StreamDefinitionError(f"no stream {stream!r} to declare for k arms", root.location)


def _closing(text: str, start: int) -> int:
    """The offset after the parenthesis closing the one at ``start`` (comments skipped)."""
    depth, k = 0, start
    while k < len(text):
        c = text[k]
        if c == ";":
            k = text.find("\n", k)
            if k < 0:
                break
            continue
        depth += (c == "(") - (c == ")")
        k += 1
        if depth == 0:
            return k
    raise StreamDefinitionError("unbalanced parentheses", None)
