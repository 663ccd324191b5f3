"""Adapters turn every sampler shape into the one list-generator form."""

import itertools

import numpy as np
import pytest

from sdar_tamp.language.generators import (
    TruthValueError,
    WildOutput,
    fn_from_constant,
    from_constant,
    from_fn,
    from_gen_fn,
    from_list_fn,
    from_list_gen_fn,
    from_sampler,
    from_test,
    negate_test,
    truth_value,
)
from sdar_tamp.language.objects import ObjectTable
from sdar_tamp.language.options import WILD, StreamInfo


def test_from_gen_fn_wraps_each_output_and_none() -> None:
    stream = from_gen_fn(lambda x: iter([(x + 1,), None, (x + 2,)]))
    assert list(stream(1)) == [[(2,)], [], [(3,)]]


def test_from_list_gen_fn_and_wild_output() -> None:
    wild = WildOutput([(1,)], [("extra", 1)])
    stream = from_list_gen_fn(lambda: iter([[(0,), (1,)], wild, None]))
    assert list(stream()) == [[(0,), (1,)], wild, []]


def test_from_sampler_calls_forever_or_bounded() -> None:
    counter = itertools.count()
    stream = from_sampler(lambda: (next(counter),))
    assert list(itertools.islice(stream(), 3)) == [[(0,)], [(1,)], [(2,)]]
    assert len(list(from_sampler(lambda: None, max_attempts=4)())) == 4


def test_once_adapters() -> None:
    assert list(from_fn(lambda x: (x * 2,))(3)) == [[(6,)]]
    assert list(from_fn(lambda x: None)(3)) == [[]]
    assert list(from_list_fn(lambda: [(1,), (2,)])()) == [[(1,), (2,)]]
    assert list(from_test(lambda x: x > 0)(1)) == [[()]]
    assert list(from_test(lambda x: x > 0)(-1)) == [[]]
    assert list(from_constant((7, 8))()) == [[(7, 8)]]
    assert fn_from_constant(3)("anything") == 3
    assert negate_test(lambda: True)() is False


def test_object_table_by_value_and_identity() -> None:
    table = ObjectTable({"table": "T"})
    assert table.name("T") == "table"
    first = table.name((1, 2))
    assert table.name((1, 2)) == first
    assert table.name(True) != table.name(1)
    a, b = [1], [1]
    assert table.name(a) != table.name(b)
    assert table.value(table.name(a)) is a
    copy = table.copy()
    copy.name("new")
    assert "new" not in [table.value(n) for n in table.names()]


def test_stream_info_validates_values() -> None:
    with pytest.raises(ValueError, match="p_success"):
        StreamInfo(p_success=1.5)
    with pytest.raises(ValueError, match="overhead"):
        StreamInfo(overhead=-1)
    with pytest.raises(ValueError, match="opt_gen_fn"):
        StreamInfo(opt_gen_fn="sometimes")
    assert repr(WILD) == "WILD"


def test_truth_values_are_bools_numpy_bools_or_none() -> None:
    assert truth_value(True) is True and truth_value(False) is False
    assert truth_value(np.True_) is True and truth_value(np.float64(1.0) < 0) is False
    assert truth_value(None) is False  # a test that falls off its end
    for value in ("no", 1, 0, 1.0, [True], (), np.array([True])):
        with pytest.raises(TruthValueError) as info:
            truth_value(value)
        assert info.value.value is value and repr(value) in str(info.value)


def test_from_test_and_negate_test_check_the_answer() -> None:
    assert list(from_test(lambda: np.True_)()) == [[()]]
    assert list(from_test(lambda: None)()) == [[]]
    with pytest.raises(TruthValueError, match="str: 'no'"):
        list(from_test(lambda: "no")())
    assert negate_test(lambda: None)() is True
    with pytest.raises(TruthValueError, match="int: 1"):
        negate_test(lambda: 1)()
