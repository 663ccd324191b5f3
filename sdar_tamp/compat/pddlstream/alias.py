"""Make ``import pddlstream...`` resolve to this compatibility tree (opt-in).

After :func:`install_alias` (or ``import sdar_tamp.compat.pddlstream.install``), every import of
``pddlstream`` or ``pddlstream.X.Y`` gives the module ``sdar_tamp.compat.pddlstream.X.Y``: the
same module object under both names, so classes, flags set on modules
(``pddlstream.algorithms.refinement.CONSTRAIN_PLANS = False``) and ``isinstance`` checks agree
whichever name a program uses. The finder goes first on :data:`sys.meta_path`, so a real
PDDLStream checkout on ``sys.path`` is shadowed, never mixed in.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Sequence
from types import ModuleType

from sdar_tamp.errors import SdarError

ALIAS = "pddlstream"
TARGET = "sdar_tamp.compat.pddlstream"


class AliasError(SdarError):
    """The alias cannot be installed (a real ``pddlstream`` module is already imported)."""


class _AliasLoader(importlib.abc.Loader):
    def __init__(self, target: str) -> None:
        self.target = target

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        module = importlib.import_module(self.target)
        _remember_spec(module)
        return module

    def exec_module(self, module: ModuleType) -> None:
        # the import system stamped the alias spec on the shared module: give it its own back
        original = vars(module).get("__compat_spec__")
        if original is not None:
            module.__spec__ = original


class AliasFinder(importlib.abc.MetaPathFinder):
    """Finds ``pddlstream`` and its submodules in :data:`TARGET`."""

    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None = None,
        target: ModuleType | None = None,
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != ALIAS and not fullname.startswith(ALIAS + "."):
            return None
        real_name = TARGET + fullname[len(ALIAS) :]
        try:
            real_spec = importlib.util.find_spec(real_name)
        except ModuleNotFoundError:
            real_spec = None
        if real_spec is None:
            return None  # the import fails with the usual ModuleNotFoundError
        return importlib.machinery.ModuleSpec(
            fullname,
            _AliasLoader(real_name),
            is_package=real_spec.submodule_search_locations is not None,
        )


def _remember_spec(module: ModuleType) -> None:
    if "__compat_spec__" not in vars(module):
        module.__compat_spec__ = module.__spec__  # type: ignore[attr-defined]


def is_installed() -> bool:
    """True when ``import pddlstream`` resolves to this compatibility tree."""
    return any(isinstance(finder, AliasFinder) for finder in sys.meta_path)


def install_alias() -> None:
    """Make ``import pddlstream...`` give this package's modules (idempotent).

    Raises:
        AliasError: a module named ``pddlstream`` (the real one) is already imported; install
            the alias before anything imports PDDLStream.
    """
    loaded = sys.modules.get(ALIAS)
    if loaded is not None and not loaded.__name__.startswith(TARGET):
        raise AliasError(
            f"a real 'pddlstream' module is already imported (from "
            f"{getattr(loaded, '__file__', '?')}); install the alias before importing it"
        )
    if is_installed():
        return
    sys.meta_path.insert(0, AliasFinder())


def uninstall_alias() -> None:
    """Undo :func:`install_alias`: drop the finder and the ``pddlstream`` names."""
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, AliasFinder)]
    for name in [n for n in sys.modules if n == ALIAS or n.startswith(ALIAS + ".")]:
        del sys.modules[name]
