"""The world context the streams share: scene, both arms' kinematics and symbolic FK."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray
from streams.fk_casadi import ArmFK


@dataclass(frozen=True)
class WorldContext:
    """Static facts about the dual-arm world. Arms are in the scene's order (left first)."""

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

    @property
    def arm_names(self) -> tuple[str, str]:
        a, b = self.scene.arm_names
        return a, b

    def other(self, arm: str) -> str:
        a, b = self.arm_names
        return b if arm == a else a

    def home(self, arm: str) -> FloatArray:
        return np.array(self.scene.arm(arm).home, dtype=np.float64)

    def new_world(self, margin: float = -1e-3) -> CollisionWorld:
        """A fresh collision world (mutable: each stream keeps its own). Resting and held
        objects are grown by ``margin`` [m] per face (the default shrinks them 1 mm)."""
        return CollisionWorld(self.scene, tolerance=-margin)

    def split(self, q: FloatArray) -> dict[str, FloatArray]:
        """A dual-arm configuration ``(12,)`` as ``arm -> (6,)``."""
        a, b = self.arm_names
        return {a: np.asarray(q[:6], dtype=np.float64), b: np.asarray(q[6:], dtype=np.float64)}

    def join(self, q: dict[str, FloatArray]) -> FloatArray:
        a, b = self.arm_names
        return np.concatenate([q[a], q[b]])
