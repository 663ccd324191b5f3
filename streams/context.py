"""The world context the streams share: scene, every arm's kinematics and symbolic FK."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray
from streams.motion.fk_casadi import ArmFK


@dataclass(frozen=True)
class WorldContext:
    """Static facts about the world. Arms are in the scene's order (its :class:`ArmLayout`)."""

    scene: Scene
    kinematics: dict[str, ArmKinematics]
    fk: dict[str, ArmFK]

    @staticmethod
    def load(scene: Scene | Path | None = None) -> WorldContext:
        sc = scene if isinstance(scene, Scene) else load_scene(scene)
        names = sc.arm_names
        return WorldContext(
            sc,
            {a: ArmKinematics.from_scene(sc, a) for a in names},
            {a: ArmFK.from_scene(sc, a) for a in names},
        )

    @cached_property
    def layout(self) -> ArmLayout:
        """The arms' joints in a configuration vector."""
        return self.scene.layout

    @property
    def arm_names(self) -> tuple[str, ...]:
        return self.layout.names

    def others(self, arm: str) -> tuple[str, ...]:
        """Every arm but ``arm``, in layout order (none in a one-arm world)."""
        self.layout.index(arm)  # an arm of the layout
        return tuple(a for a in self.layout if a != arm)

    def other(self, arm: str) -> str:
        """The other arm of a two-arm world (:meth:`others` for any number of arms)."""
        others = self.others(arm)
        if len(others) != 1:
            raise ParameterError(f"other: defined for two arms, the scene has {len(self.layout)}")
        return others[0]

    def home(self, arm: str) -> FloatArray:
        return np.array(self.scene.arm(arm).home, dtype=np.float64)

    def new_world(self, margin: float = -1e-3, arm_margin: float = 0.0) -> CollisionWorld:
        """A fresh collision world (mutable: each stream keeps its own). Resting and held
        objects are grown by ``margin`` [m] per face (the default shrinks them 1 mm); the
        shapes of any two arms must keep ``arm_margin`` [m] apart."""
        return CollisionWorld(self.scene, tolerance=-margin, arm_margin=arm_margin)

    def split(self, q: FloatArray) -> dict[str, FloatArray]:
        """A configuration ``(layout.dof,)`` as ``arm -> (arm dof,)``."""
        return self.layout.split(q)

    def join(self, q: dict[str, FloatArray]) -> FloatArray:
        """Every arm's joints ``arm -> (arm dof,)`` as one configuration ``(layout.dof,)``."""
        return self.layout.join(q)
