"""What the streams of ``domains/dual_arm_rearrangement/stream.pddl`` exchange and how the
wiring layer calls them: the configurations of one arm and of the whole cell, and the kind
of every stream (generator, test or function)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray

#: Kind of every stream of the file: "gen" (generator of output tuples), "test" or "function".
STREAM_KINDS: Mapping[str, str] = MappingProxyType(
    {
        "sample-grasp": "gen",
        "inverse-kinematics": "gen",
        "sample-buffer": "gen",
        "combine-confs": "gen",
        "plan-dual-motion": "gen",
        "plan-dual-motion-quick": "gen",
        "test-overlap": "test",
        "test-cfree": "test",
        "test-blocks-grasps": "test",
        "test-grasp-cfree": "test",
        "Duration": "function",
        "Distance": "function",
        "ArmDistance": "function",
        "NextMotion": "function",
    }
)


@dataclass(frozen=True)
class ArmConf:
    """A configuration of one arm [rad]; ``grasp`` and ``pre`` are set for grasp poses."""

    arm: str
    q: tuple[float, ...]
    pre: tuple[float, ...] | None = None  # the pre-grasp configuration, if any


@dataclass(frozen=True, init=False)
class CellConf:
    """A configuration of every arm, in the scene's arm order: ``CellConf(first, second)``."""

    arms: tuple[ArmConf, ...]

    def __init__(self, *arms: ArmConf) -> None:
        if not arms:
            raise ParameterError("CellConf: expected one ArmConf per arm, got none")
        object.__setattr__(self, "arms", tuple(arms))

    @property
    def q(self) -> FloatArray:
        """Every arm's joints ``(dof,)`` [rad], in the scene's layout."""
        return np.concatenate([np.asarray(a.q, dtype=np.float64) for a in self.arms])

    def arm(self, name: str) -> ArmConf:
        """The configuration of arm ``name``."""
        for a in self.arms:
            if a.arm == name:
                return a
        raise ParameterError(f"arm must be one of {[a.arm for a in self.arms]}; got {name!r}")
