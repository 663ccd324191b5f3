"""PDDLStream's module tree exists here, and the flat module holds the tree's public names."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import sdar_tamp.compat.pddlstream as flat
from sdar_tamp.compat.pddlstream.unsupported import NotProvidedError

#: every module of PDDLStream's package (``find pddlstream -name '*.py'`` in its checkout,
#: github caelan/pddlstream at 2c7d6f5), as dotted paths below ``pddlstream``
UPSTREAM_MODULES = (
    "algorithms",
    "algorithms.advanced",
    "algorithms.algorithm",
    "algorithms.common",
    "algorithms.constraints",
    "algorithms.disable_skeleton",
    "algorithms.disabled",
    "algorithms.downward",
    "algorithms.focused",
    "algorithms.incremental",
    "algorithms.instantiate_task",
    "algorithms.instantiation",
    "algorithms.meta",
    "algorithms.recover_optimizers",
    "algorithms.refinement",
    "algorithms.relation",
    "algorithms.reorder",
    "algorithms.satisfaction",
    "algorithms.scheduling",
    "algorithms.scheduling.add_optimizers",
    "algorithms.scheduling.apply_fluents",
    "algorithms.scheduling.negative",
    "algorithms.scheduling.plan_streams",
    "algorithms.scheduling.postprocess",
    "algorithms.scheduling.recover_axioms",
    "algorithms.scheduling.recover_functions",
    "algorithms.scheduling.recover_streams",
    "algorithms.scheduling.reinstantiate",
    "algorithms.scheduling.stream_action",
    "algorithms.scheduling.utils",
    "algorithms.search",
    "algorithms.serialized",
    "algorithms.simultaneous",
    "algorithms.skeleton",
    "algorithms.visualization",
    "language",
    "language.attachments",
    "language.constants",
    "language.conversion",
    "language.exogenous",
    "language.external",
    "language.fluent",
    "language.function",
    "language.generator",
    "language.object",
    "language.optimizer",
    "language.rule",
    "language.statistics",
    "language.stream",
    "language.temporal",
    "language.write_pddl",
    "retired",
    "retired.execution",
    "retired.reorder_actions",
    "retired.satisfaction",
    "retired.skeleton",
    "retired.successor_generator",
    "retired.synthesizer",
    "utils",
)

#: names PDDLStream programs import that were missing once (module, name)
NAMED = (
    ("utils", "negate_test"),
    ("algorithms.search", "ABSTRIPSLayer"),
    ("algorithms.common", "SOLUTIONS"),
    ("language.constants", "AND"),
    ("language.optimizer", "OptimizerOutput"),
    ("algorithms.instantiate_task", "instantiate_task"),
)

#: modules of the tree that are this project's own (the runner, the alias, helpers)
OWN = {"__main__", "alias", "check", "install", "language.problem", "unsupported"}
ROOT = "sdar_tamp.compat.pddlstream"


def _tree() -> list[str]:
    return sorted(m.name[len(ROOT) + 1 :] for m in pkgutil.walk_packages(flat.__path__, ROOT + "."))


@pytest.mark.parametrize("module", UPSTREAM_MODULES)
def test_every_upstream_module_exists(module: str) -> None:
    imported = importlib.import_module(f"{ROOT}.{module}")
    assert isinstance(imported.__all__, list)


def test_the_tree_has_no_module_pddlstream_lacks_beyond_its_own() -> None:
    assert set(_tree()) - set(UPSTREAM_MODULES) == OWN


@pytest.mark.parametrize(("module", "name"), NAMED)
def test_named_imports_resolve_in_tree_and_flat(module: str, name: str) -> None:
    value = getattr(importlib.import_module(f"{ROOT}.{module}"), name)
    assert getattr(flat, name) is value


def test_tree_and_flat_hold_the_same_public_names() -> None:
    tree: dict[str, object] = {}
    for module in UPSTREAM_MODULES:
        imported = importlib.import_module(f"{ROOT}.{module}")
        for name in imported.__all__:
            value = getattr(imported, name)
            assert tree.setdefault(name, value) is value or tree[name] == value, (module, name)
    own = {"install_alias", "uninstall_alias"}
    assert set(flat.__all__) == set(tree) | own
    for name, value in tree.items():
        assert getattr(flat, name) is value or getattr(flat, name) == value, name


def test_an_unprovided_name_says_what_is_not_supported() -> None:
    with pytest.raises(NotProvidedError, match=r"algorithms\.skeleton\.SkeletonQueue .*skeleton"):
        from sdar_tamp.compat.pddlstream.algorithms.skeleton import (  # noqa: F401
            SkeletonQueue,  # type: ignore[attr-defined]
        )
    skeleton = importlib.import_module(f"{ROOT}.algorithms.skeleton")
    with pytest.raises(AttributeError):
        skeleton._private  # noqa: B018


def test_an_unsupported_function_imports_and_raises_when_called() -> None:
    from sdar_tamp.compat.pddlstream.algorithms.instantiate_task import instantiate_task

    with pytest.raises(NotProvidedError, match=r"instantiate_task\(\) is not supported.*Fast"):
        instantiate_task(None)


def test_abstrips_layer_checks_its_arguments() -> None:
    from sdar_tamp.compat.pddlstream.algorithms.search import ABSTRIPSLayer
    from sdar_tamp.errors import ParameterError

    layer = ABSTRIPSLayer(pos_pre=["AtBConf"])
    assert layer.pos_pre == ["AtBConf"]
    assert "AtBConf" in repr(layer)
    with pytest.raises(ParameterError, match="horizon"):
        ABSTRIPSLayer(horizon=0)
    with pytest.raises(NotProvidedError, match="effect layers"):
        ABSTRIPSLayer(pos_eff=["AtBConf"])


def test_a_submodule_is_imported_from_a_package_that_provides_nothing() -> None:
    """``from pkg import submodule`` asks the package's ``__getattr__`` first: it imports the
    submodule, and a name that is no submodule still raises NotProvidedError."""
    from sdar_tamp.compat.pddlstream.algorithms import scheduling
    from sdar_tamp.compat.pddlstream.algorithms.scheduling import negative

    assert negative.__name__.endswith("scheduling.negative")
    with pytest.raises(NotProvidedError, match="scheduling internals"):
        scheduling.no_such_name  # noqa: B018
