"""The arm layout: which arms a configuration vector holds, in which order, with how many joints.

A configuration of the whole robot is one vector ``q`` ``(layout.dof,)`` [rad] (or a path
``(n, layout.dof)``), the arms' joints one after the other in the layout's order. Every piece
of code that needs one arm's joints asks the layout for them (:meth:`ArmLayout.slice`,
:meth:`ArmLayout.part`, :meth:`ArmLayout.split`, :meth:`ArmLayout.join`) instead of slicing by
hand, so the number of arms and their joint counts are data.
"""

from __future__ import annotations

import builtins
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from sdar_tamp.world.errors import ArmLayoutError
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class ArmLayout:
    """Arm names and their degrees of freedom, in configuration order."""

    names: tuple[str, ...]
    dofs: tuple[int, ...]

    def __post_init__(self) -> None:
        if not self.names:
            raise ArmLayoutError("arm layout: names must hold at least one arm, got none")
        if len(self.dofs) != len(self.names):
            raise ArmLayoutError(
                f"arm layout: dofs must have one entry per arm ({len(self.names)}), "
                f"got {len(self.dofs)}"
            )
        for name in self.names:
            if not isinstance(name, str) or not name:
                raise ArmLayoutError(
                    f"arm layout: arm names must be non-empty strings, got {name!r}"
                )
        repeated = sorted({n for n in self.names if self.names.count(n) > 1})
        if repeated:
            raise ArmLayoutError(f"arm layout: arm names must differ, got {repeated} twice")
        for name, dof in zip(self.names, self.dofs, strict=True):
            if isinstance(dof, bool) or not isinstance(dof, int) or dof < 1:
                raise ArmLayoutError(
                    f"arm layout: the dof of arm {name!r} must be an integer >= 1, got {dof!r}"
                )

    @staticmethod
    def uniform(names: Sequence[str], dof: int) -> ArmLayout:
        """Every arm with ``dof`` joints."""
        return ArmLayout(tuple(names), (dof,) * len(names))

    # -- arms ----------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.names)

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __contains__(self, arm: object) -> bool:
        return arm in self.names

    @property
    def dof(self) -> int:
        """Joints of the whole configuration."""
        return sum(self.dofs)

    def index(self, arm: str) -> int:
        """Position of ``arm`` in the layout."""
        try:
            return self.names.index(arm)
        except ValueError:
            raise ArmLayoutError(
                f"unknown arm {arm!r}; the layout has {list(self.names)}"
            ) from None

    def slice(self, arm: str | int) -> builtins.slice:
        """The joints of ``arm`` (a name or a position) in a configuration vector."""
        i = self.index(arm) if isinstance(arm, str) else self._position(arm)
        start = sum(self.dofs[:i])
        return builtins.slice(start, start + self.dofs[i])

    @property
    def slices(self) -> tuple[builtins.slice, ...]:
        """The joints of every arm, in layout order."""
        return tuple(self.slice(i) for i in range(len(self.names)))

    def locate(self, joint: int) -> tuple[str, int]:
        """The arm owning entry ``joint`` of a configuration vector, and its joint index."""
        if not 0 <= joint < self.dof:
            raise ArmLayoutError(f"joint must be in [0, {self.dof - 1}], got {joint}")
        for name, s in zip(self.names, self.slices, strict=True):
            if joint < s.stop:
                return name, joint - s.start
        raise AssertionError("unreachable")  # pragma: no cover

    def _position(self, i: int) -> int:
        if not 0 <= i < len(self.names):
            raise ArmLayoutError(f"arm index must be in [0, {len(self.names) - 1}], got {i}")
        return i

    # -- configurations ------------------------------------------------------------------
    def check(self, q: ArrayLike, what: str = "q") -> FloatArray:
        """``q`` as floats, after checking its last axis holds every joint of the layout."""
        arr = np.asarray(q, dtype=np.float64)
        if arr.ndim == 0 or arr.shape[-1] != self.dof:
            raise ArmLayoutError(
                f"{what}: expected shape (..., {self.dof}) for arms {list(self.names)}, "
                f"got {arr.shape}"
            )
        return arr

    def part(self, q: FloatArray, arm: str | int) -> FloatArray:
        """The joints of ``arm`` in ``q`` ``(..., dof)``: a view ``(..., arm dof)``."""
        out: FloatArray = q[..., self.slice(arm)]
        return out

    def split(self, q: ArrayLike) -> dict[str, FloatArray]:
        """``q`` ``(..., dof)`` as ``arm -> (..., arm dof)`` (copies)."""
        arr = self.check(q)
        return {name: arr[..., s].copy() for name, s in zip(self.names, self.slices, strict=True)}

    def join(self, parts: Mapping[str, ArrayLike] | Sequence[ArrayLike]) -> FloatArray:
        """One configuration from every arm's joints, by name or in layout order."""
        if isinstance(parts, Mapping):
            missing = [n for n in self.names if n not in parts]
            extra = sorted(str(n) for n in parts if n not in self.names)
            if missing or extra:
                raise ArmLayoutError(
                    f"join: expected the arms {list(self.names)}, missing {missing}, "
                    f"unknown {extra}"
                )
            seq = [parts[n] for n in self.names]
        else:
            seq = list(parts)
            if len(seq) != len(self.names):
                raise ArmLayoutError(
                    f"join: expected {len(self.names)} parts (arms {list(self.names)}), "
                    f"got {len(seq)}"
                )
        arrays = [np.asarray(p, dtype=np.float64) for p in seq]
        for name, dof, arr in zip(self.names, self.dofs, arrays, strict=True):
            if arr.ndim == 0 or arr.shape[-1] != dof:
                raise ArmLayoutError(
                    f"join: the joints of arm {name!r} must have shape (..., {dof}), "
                    f"got {arr.shape}"
                )
        return np.concatenate(arrays, axis=-1)

    def replace(self, q: FloatArray, arm: str | int, q_arm: ArrayLike) -> FloatArray:
        """A copy of ``q`` with the joints of ``arm`` set to ``q_arm``."""
        out = np.array(q, dtype=np.float64)
        out[..., self.slice(arm)] = q_arm
        return out
