"""The successor generator's trie walk compiled with numba: the same operators in the same
order as :meth:`~solvers.classical.bitset_task.CompiledTask.applicable`, about 10x faster.
Loading and compiling: :mod:`.jit`.
"""

from __future__ import annotations

from collections import deque
from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt

from solvers.classical.jit import (
    CompiledCodeUnavailable,
    IntArray,
    compile_kernel,
    compressed_rows,
)


def _applicable(
    raw: npt.NDArray[np.uint8],
    node_ops_start: IntArray,
    node_ops: IntArray,
    child_start: IntArray,
    child_fact: IntArray,
    child_node: IntArray,
    neg_start: IntArray,
    neg_flat: IntArray,
) -> IntArray:
    """The operators applicable in the state packed in ``raw``: the successor-generator trie
    walked depth first exactly as :meth:`CompiledTask.applicable` walks it (same order)."""
    found = np.empty(node_ops.shape[0], dtype=np.int64)
    n_found = 0
    stack = np.empty(child_node.shape[0] + 1, dtype=np.int64)
    stack[0] = 0
    n_stack = 1
    while n_stack > 0:
        n_stack -= 1
        node = stack[n_stack]
        for k in range(node_ops_start[node], node_ops_start[node + 1]):
            found[n_found] = node_ops[k]
            n_found += 1
        for k in range(child_start[node], child_start[node + 1]):
            fact = child_fact[k]
            if (raw[fact >> 3] >> (fact & 7)) & 1:
                stack[n_stack] = child_node[k]
                n_stack += 1
    result = np.empty(n_found, dtype=np.int64)
    n_result = 0
    for i in range(n_found):
        op = found[i]
        ok = True
        for k in range(neg_start[op], neg_start[op + 1]):
            fact = neg_flat[k]
            if (raw[fact >> 3] >> (fact & 7)) & 1:
                ok = False
                break
        if ok:
            result[n_result] = op
            n_result += 1
    return result[:n_result]


@lru_cache(maxsize=1)
def _applicable_kernel() -> Any:
    """:func:`_applicable` compiled (or loaded from numba's cache) on first use."""
    return compile_kernel(_applicable)


def kernel_loaded() -> bool:
    """Whether this process has loaded the compiled trie walk already."""
    info = getattr(_applicable_kernel, "cache_info", None)  # (None: the kernel was replaced)
    return info is not None and info().currsize > 0


class JitSuccessors:
    """A successor-generator trie as arrays, walked by compiled code.

    ``trie`` is :class:`CompiledTask`'s nested ``(operators, ((fact bit, child), ...))``;
    ``negative`` the negative-precondition facts of each operator; ``facts`` the number of facts.
    """

    def __init__(self, trie: Any, negative: list[tuple[int, ...]], facts: int) -> None:
        nodes: list[Any] = []
        order = deque([trie])
        while order:  # breadth first: node ids in the order they are listed
            node = order.popleft()
            nodes.append(node)
            order.extend(child for _bit, child in node[1])
        ids = {id(node): i for i, node in enumerate(nodes)}
        self.nbytes = facts // 8 + 1
        node_ops_start, node_ops = compressed_rows([tuple(node[0]) for node in nodes])
        child_start, child_fact = compressed_rows(
            [tuple(bit.bit_length() - 1 for bit, _child in node[1]) for node in nodes]
        )
        _start, child_node = compressed_rows(
            [tuple(ids[id(child)] for _bit, child in node[1]) for node in nodes]
        )
        neg_start, neg_flat = compressed_rows(negative)
        self.arrays = (
            node_ops_start,
            node_ops,
            child_start,
            child_fact,
            child_node,
            neg_start,
            neg_flat,
        )
        self.kernel = _applicable_kernel()
        try:  # compiles, or loads from numba's cache, now rather than in the search
            self.applicable(0)
        except Exception as error:
            raise CompiledCodeUnavailable(
                f"numba cannot run the successor walk: {error}"
            ) from error

    def applicable(self, state: int) -> list[int]:
        raw = np.frombuffer(state.to_bytes(self.nbytes, "little"), dtype=np.uint8)
        result: list[int] = self.kernel(raw, *self.arrays).tolist()
        return result
