"""Collision checking of a cell's arms and scene with coal (through pinocchio's broad phase).

Checked pairs (for a cell of any number of arms):

* arm against arm, for every pair of arms (every link and gripper shape of one arm against
  every one of the other);
* one arm against itself, links at least two joints apart (adjacent links are excluded);
* arm against table (except the links fixed to the base and moved by the first joint, which
  stand on it);
* arm against every resting object;
* a held object against every other arm, its own arm's links but the last (never its last link
  and gripper, which hold it), the table, every resting object and every other held object.

Resting objects are not checked against each other or the table (that is the arrangement's
job, see :mod:`sdar_tamp.world.instance`). Object boxes are shrunk by ``tolerance`` on every
face, so an object resting on the table or touching a neighbour does not count as colliding.

A query costs one pinocchio call: forward kinematics, placements, an AABB-tree broad phase and
the coal narrow phase on the surviving pairs, all in C++.
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from collections.abc import Hashable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from sdar_tamp.world import collision_model as cm
from sdar_tamp.world.collision_slots import SlotGeometry
from sdar_tamp.world.errors import ArmLayoutError, CollisionModelError
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse


@functools.lru_cache(maxsize=4)
def _shared_arms(scene: Scene) -> cm.CellCollisionModel:
    return cm.build_dual_arm(scene)


def _dual_arm(scene: Scene) -> cm.CellCollisionModel:
    """The arms' model of ``scene``, built once per scene and shared by its worlds (the model
    and the arm shapes are only read); each world gets its own pinocchio data."""
    shared = _shared_arms(scene)
    return replace(shared, data=shared.model.createData())


@dataclass(frozen=True)
class ObjectBox:
    """A cuboid: pose of its centre ``T_world_obj`` ``(4, 4)`` and side lengths [m]."""

    T_world_obj: FloatArray
    size: tuple[float, float, float]


@dataclass(frozen=True)
class CollisionPair:
    """Two colliding (or closest) shapes, e.g. ``left_forearm_link_0`` and ``object:o3``."""

    first: str
    second: str


@dataclass(frozen=True)
class Clearance:
    """The smallest signed distance over all checked pairs [m] and the pair realising it."""

    distance: float
    pair: CollisionPair | None


class CollisionWorld:
    """The cell's arms (one or more), the table, resting and held objects; answers collision
    queries.

    Configurations ``q`` ``(layout.dof,)`` hold every arm's joints in the scene's
    :class:`~sdar_tamp.world.layout.ArmLayout` (``scene.layout``).
    Changing objects or grasps rebuilds the geometry lazily (several milliseconds for a dozen
    objects; updated in place for objects seen before, see
    :mod:`~sdar_tamp.world.collision_slots`); queries at a fixed object set are the fast
    path. With ``keep`` > 0 the last
    ``keep`` geometries are kept by arrangement (resting boxes and held objects, compared
    exactly), so going back to an arrangement seen before costs no rebuild (for a user that
    goes back and forth, such as the asynchronous scheduler's sweep; each kept geometry holds a
    copy of the arms' shapes, tens of MB for a dozen). With ``arm_margin`` [m] > 0, shapes of
    two different arms collide when they come closer than that (a planner's safety distance:
    its samples then keep the arms apart between samples too). With ``incremental`` False
    (or ``keep`` > 0) every arrangement gets a geometry built afresh.
    """

    def __init__(
        self,
        scene: Scene,
        *,
        tolerance: float = 1e-3,
        keep: int = 0,
        arm_margin: float = 0.0,
        incremental: bool = True,
    ) -> None:
        if keep < 0:
            raise CollisionModelError(f"keep: expected a number of geometries >= 0, got {keep}")
        if not 0.0 <= arm_margin < 0.05:
            raise CollisionModelError(
                f"arm_margin: expected a distance in [0, 0.05) [m], got {arm_margin}"
            )
        self._arm_margin = float(arm_margin)
        self._keep = keep
        self._incremental = incremental and not keep
        self._scene = scene
        self._tolerance = tolerance
        self._arms = _dual_arm(scene)
        self._owners = {shape.name: shape.arm for shape in self._arms.shapes}
        self._resting: dict[str, ObjectBox] = {}
        self._held: dict[str, tuple[str, FloatArray, ObjectBox]] = {}
        self.layout = scene.layout
        self._q = scene.home
        self._geometry: cm.SceneGeometry | None = None
        self._built: OrderedDict[Hashable, cm.SceneGeometry] = OrderedDict()
        self._slots: SlotGeometry | None = None  # the geometry updated in place (keep == 0)

    # -- objects and grasps ---------------------------------------------------------------
    @property
    def objects(self) -> dict[str, ObjectBox]:
        """Resting objects, name -> box (a copy)."""
        return dict(self._resting)

    def set_objects(self, objects: Mapping[str, ObjectBox]) -> None:
        """Replace every resting object (held objects stay held)."""
        clash = set(objects) & {name for name, _, _ in self._held.values()}
        if clash:
            raise CollisionModelError(f"objects {sorted(clash)} are held; detach them first")
        self._resting = dict(objects)
        self._geometry = None

    def set_object(self, name: str, box: ObjectBox) -> None:
        self.set_objects({**self._resting, name: box})

    def remove_object(self, name: str) -> None:
        if name not in self._resting:
            raise CollisionModelError(f"no resting object {name!r}")
        self.set_objects({k: v for k, v in self._resting.items() if k != name})

    def held_by(self, arm: str) -> str | None:
        self._arm(arm)
        held = self._held.get(arm)
        return held[0] if held else None

    def attach(self, arm: str, name: str, q_arm: FloatArray | None = None) -> None:
        """Let ``arm`` hold resting object ``name`` rigidly, in its pose relative to the
        tool at ``q_arm`` (default: the arm's current configuration)."""
        self._arm(arm)
        if arm in self._held:
            raise CollisionModelError(f"arm {arm!r} already holds {self._held[arm][0]!r}")
        if name not in self._resting:
            raise CollisionModelError(f"no resting object {name!r} to attach")
        T_world_tool0 = self.tool0_pose(arm, q_arm)
        box = self._resting.pop(name)
        self._held[arm] = (name, inverse(T_world_tool0) @ box.T_world_obj, box)
        self._geometry = None

    def detach(self, arm: str, q_arm: FloatArray | None = None) -> ObjectBox:
        """Release the object held by ``arm``; it rests where the tool leaves it."""
        self._arm(arm)
        if arm not in self._held:
            raise CollisionModelError(f"arm {arm!r} holds nothing")
        name, T_tool0_obj, box = self._held.pop(arm)
        placed = ObjectBox(self.tool0_pose(arm, q_arm) @ T_tool0_obj, box.size)
        self._resting[name] = placed
        self._geometry = None
        return placed

    # -- configurations -------------------------------------------------------------------
    def set_configuration(self, q: FloatArray) -> None:
        """Set every arm's joints: ``q`` ``(layout.dof,)`` [rad]."""
        self._set(q)

    @property
    def configuration(self) -> FloatArray:
        """The current configuration ``(layout.dof,)`` (a copy)."""
        return self._q.copy()

    def tool0_pose(self, arm: str, q_arm: FloatArray | None = None) -> FloatArray:
        """``T_world_tool0`` of ``arm`` at ``q_arm`` (default: current configuration)."""
        self._arm(arm)
        q = self._q if q_arm is None else self.layout.replace(self._q, arm, q_arm)
        return cm.tool0_pose(self._arms, q, arm)

    # -- queries --------------------------------------------------------------------------
    def in_collision(self, q: FloatArray | None = None) -> bool:
        """True if any checked pair collides at ``q`` ``(layout.dof,)`` (default: current)."""
        geometry = self._geometry or self._scene_geometry()
        self._set(q)
        return cm.any_collision(self._arms, geometry, self._q)

    def report(self, q: FloatArray | None = None) -> tuple[CollisionPair, ...]:
        """Every colliding pair at ``q`` (default: current), by shape names (empty when
        collision-free)."""
        geometry = self._scene_geometry()
        self._set(q)
        hits = cm.colliding_pairs(self._arms, geometry, self._q)
        names = self._pair_names(geometry)
        if self._slots is not None:  # results of the pairs checked now, by position
            active = self._slots.active
            at = np.searchsorted(active, hits)
            hits = [
                int(p) for p, i in zip(at, hits, strict=True) if p < active.size and active[p] == i
            ]
        return tuple(CollisionPair(*names[i]) for i in hits)

    def min_distance(self, q: FloatArray | None = None) -> Clearance:
        """Smallest signed distance over every checked pair at ``q`` (default: current) [m]
        (negative: penetration)."""
        geometry = self._scene_geometry()
        self._set(q)
        d = self._distances(geometry)
        if d.size == 0:
            return Clearance(float("inf"), None)
        i = int(np.argmin(d))
        return Clearance(float(d[i]), CollisionPair(*self._pair_names(geometry)[i]))

    def owner(self, shape: str) -> str | None:
        """The arm a shape belongs to: the arm of a link or gripper shape, the arm holding a
        ``held:`` object; None for the table and resting objects."""
        if shape.startswith("held:"):
            name = shape[len("held:") :]
            return next((arm for arm, held in self._held.items() if held[0] == name), None)
        return self._owners.get(shape)

    def arm_clearances(self, q: FloatArray | None = None) -> dict[tuple[str, str], Clearance]:
        """For every pair of arms (scene order, each arm with what it holds), the smallest
        signed distance between their shapes at ``q`` (default: current) [m] and the pair of
        shapes realising it (an empty mapping for a cell of one arm)."""
        geometry = self._scene_geometry()
        self._set(q)
        d = self._distances(geometry)
        names = self.layout.names
        out = {
            (a, b): Clearance(float("inf"), None)
            for i, a in enumerate(names)
            for b in names[i + 1 :]
        }
        for k, (first, second) in enumerate(self._pair_names(geometry)):
            a, b = self.owner(first), self.owner(second)
            if a is None or b is None or a == b:
                continue
            key = (a, b) if names.index(a) < names.index(b) else (b, a)
            if d[k] < out[key].distance:
                out[key] = Clearance(float(d[k]), CollisionPair(first, second))
        return out

    # -- internals ------------------------------------------------------------------------
    def _set(self, q: FloatArray | None) -> None:
        if q is not None:
            if np.shape(q) != self._q.shape:
                raise ArmLayoutError(
                    f"q: expected shape ({self.layout.dof},) for arms {list(self.layout.names)}, "
                    f"got {np.shape(q)}"
                )
            self._q[:] = q

    def _arm(self, arm: str) -> slice:
        if arm not in self.layout:
            raise CollisionModelError(f"unknown arm {arm!r}; expected one of {self.layout.names}")
        return self.layout.slice(arm)

    def _shrunk(self, box: ObjectBox) -> FloatArray:
        return np.maximum(np.array(box.size) - 2.0 * self._tolerance, 1e-6)

    def _pair_names(self, geometry: cm.SceneGeometry) -> tuple[tuple[str, str], ...]:
        return geometry.pair_names if self._slots is None else self._slots.pair_names

    def _distances(self, geometry: cm.SceneGeometry) -> FloatArray:
        """Signed distance of every checked pair, in :meth:`_pair_names`' order."""
        d = cm.pair_distances(self._arms, geometry, self._q)
        return d if self._slots is None else d[self._slots.active]

    def _scene_geometry(self) -> cm.SceneGeometry:
        if self._geometry is None and self._incremental:
            resting = {n: (b.T_world_obj, self._shrunk(b)) for n, b in self._resting.items()}
            held = {a: (n, T, self._shrunk(b)) for a, (n, T, b) in self._held.items()}
            if self._slots is None or not self._slots.fits(resting, held):
                # the objects seen before keep their slots (they may come back)
                sizes = {} if self._slots is None else dict(self._slots.sizes)
                sizes.update({n: s for n, (_, s) in resting.items()})
                sizes.update({n: s for n, _, s in held.values()})
                self._slots = SlotGeometry(
                    self._arms, self._scene.table.size, sizes, self._arm_margin
                )
            self._slots.apply(resting, held)
            self._geometry = self._slots.scene
        if self._geometry is None:
            key = self.arrangement_key()
            cached = self._built.get(key)
            if cached is not None:
                self._built.move_to_end(key)
                self._geometry = cached
                return cached
            resting = {n: (b.T_world_obj, self._shrunk(b)) for n, b in self._resting.items()}
            held = {a: (n, T, self._shrunk(b)) for a, (n, T, b) in self._held.items()}
            self._geometry = cm.build_scene_geometry(
                self._arms, self._scene.table.size, resting, held, self._pairs(),
                self._arm_margin,
            )  # fmt: skip
            if self._keep:
                self._built[key] = self._geometry
                if len(self._built) > self._keep:
                    self._built.popitem(last=False)
        return self._geometry

    def arrangement_key(self) -> Hashable:
        """What the geometry is built from, exactly: the resting boxes in order, and each
        arm's held object with its pose in the tool frame. Two worlds with equal keys (and
        the same scene and margins) give the same answer to every query at every ``q``."""
        resting = tuple(
            (n, b.T_world_obj.tobytes(), tuple(b.size)) for n, b in self._resting.items()
        )
        held = tuple(
            (a, n, T.tobytes(), tuple(b.size)) for a, (n, T, b) in sorted(self._held.items())
        )
        return resting, held

    def _pairs(self) -> list[tuple[str, str]]:
        shapes = self._arms.shapes
        pairs: list[tuple[str, str]] = []
        for i, a in enumerate(shapes):
            for b in shapes[i + 1 :]:
                if a.arm != b.arm or abs(a.link_index - b.link_index) >= 2:
                    pairs.append((a.name, b.name))
            if a.link_index >= 2:
                pairs.append((a.name, "table"))
            pairs.extend((a.name, f"object:{o}") for o in self._resting)
        held = list(self._held.items())
        layout = self._arms.layout
        for k, (arm, (name, _, _)) in enumerate(held):
            h = f"held:{name}"
            last = layout.dofs[layout.index(arm)]  # the link of the arm's last joint + gripper
            pairs.extend((s.name, h) for s in shapes if s.arm != arm or s.link_index < last)
            pairs.append((h, "table"))
            pairs.extend((h, f"object:{o}") for o in self._resting)
            pairs.extend((h, f"held:{other}") for _, (other, _, _) in held[k + 1 :])
        return pairs
