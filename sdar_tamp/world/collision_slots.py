"""A collision world's scene geometry updated in place, one slot per object.

Building a scene geometry (:func:`~sdar_tamp.world.collision_model.build_scene_geometry`)
costs tens of milliseconds with a few arms, most of it pinocchio's per-pair data for every
checked pair. A planner moves one or two objects at a time, so :class:`SlotGeometry` builds
the geometry once for a set of objects: the arms' shapes, the table and one box per object
(its *slot*), with every pair any arrangement of these objects may check. An arrangement is
then applied by moving the slots (a resting object on the universe joint at its pose, a held
one on its arm's last joint at its grasp) and by switching on exactly the pairs
:class:`~sdar_tamp.world.collision.CollisionWorld` checks for it (its rules, see
:meth:`SlotGeometry.wanted`); an object not on the table has its slot disabled. Only the
pairs and slots that change are touched.

The answers equal those of a geometry built afresh for the arrangement (same pairs, same
shapes, same placements, same arm margins); only the order of the pairs may differ.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from sdar_tamp.world import _coal
from sdar_tamp.world import collision_model as cm
from sdar_tamp.world._pin import array_to_se3
from sdar_tamp.world.transforms import FloatArray, translation

#: resting objects ``name -> (T_world_obj, size)``; held objects ``arm -> (name, T_tool0_obj,
#: size)`` (as :func:`~sdar_tamp.world.collision_model.build_scene_geometry` takes them)
Resting = Mapping[str, tuple[FloatArray, FloatArray]]
Held = Mapping[str, tuple[str, FloatArray, FloatArray]]

_ABSENT, _RESTING, _HELD = 0, 1, 2


class SlotGeometry:
    """The scene geometry of the objects ``sizes`` (name -> shrunk box size) in any
    arrangement: :meth:`apply` one, then query :attr:`scene` (its ``manager`` answers for
    the applied arrangement; results of the pairs :attr:`active` only)."""

    def __init__(
        self,
        arms: cm.CellCollisionModel,
        table_size: tuple[float, float, float],
        sizes: Mapping[str, FloatArray],
        arm_margin: float = 0.0,
    ) -> None:
        self.arms = arms
        self.sizes = {name: np.array(size, dtype=np.float64) for name, size in sizes.items()}
        geometry = arms.arm_geometry.copy()
        sx, sy, sz = table_size
        geometry.addGeometryObject(
            pin.GeometryObject(
                "table", 0, array_to_se3(translation(0.0, 0.0, -sz / 2)), _coal.box((sx, sy, sz))
            )
        )
        n_shapes = len(arms.shapes)
        self._table = n_shapes
        self._slot = {name: n_shapes + 1 + k for k, name in enumerate(self.sizes)}
        for name, size in self.sizes.items():
            obj = pin.GeometryObject(f"slot:{name}", 0, pin.SE3.Identity(), _coal.box(size))
            obj.disableCollision = True
            geometry.addGeometryObject(obj)
        n = n_shapes + 1 + len(self.sizes)
        # per geometry: the arm it belongs to (-1: none) and its link index
        arm_of = np.full(n, -1, dtype=np.intp)
        link = np.zeros(n, dtype=np.intp)
        rank = np.full(n, n, dtype=np.intp)  # an arm shape's place in ``arms.shapes``
        for k, s in enumerate(arms.shapes):
            arm_of[s.index] = arms.layout.index(s.arm)
            link[s.index] = s.link_index
            rank[s.index] = k
        is_arm = arm_of >= 0
        union = np.zeros((n, n), dtype=bool)
        a, b = np.triu_indices(n, 1)
        both_arms = is_arm[a] & is_arm[b]
        fixed = both_arms & ((arm_of[a] != arm_of[b]) | (np.abs(link[a] - link[b]) >= 2))
        fixed |= is_arm[a] & (b == self._table) & (link[a] >= 2)
        union[a[fixed], b[fixed]] = True
        union[:, n_shapes + 1 :] = True  # every pair with an object slot
        union[np.tril_indices(n)] = False
        geometry.setCollisionPairs(union, True)
        self._first, self._second = np.nonzero(union)  # row-major: pinocchio's pair order
        self._fixed = ~(self._second > n_shapes)  # pairs without an object slot
        self._arm_of, self._link = arm_of, link
        # pairs named the other way round: two arm shapes in the order of ``arms.shapes``
        self._flip = rank[self._first] > rank[self._second]
        self._names = [str(obj.name) for obj in geometry.geometryObjects]
        data = geometry.createData()
        if arm_margin > 0.0:
            margins = np.where(
                union & is_arm[:, None] & is_arm[None, :] & (arm_of[:, None] != arm_of[None, :]),
                arm_margin, 0.0,
            )  # fmt: skip
            data.setSecurityMargins(geometry, margins, True, False)
        for k in np.nonzero(~self._fixed)[0].tolist():
            data.deactivateCollisionPair(k)
        self._on = self._fixed.copy()
        self._state = np.full(n, _ABSENT, dtype=np.intp)  # per geometry (slots only used)
        self._holder = np.full(n, -1, dtype=np.intp)  # the arm holding a slot's object
        self._placed: dict[str, tuple[int, bytes]] = {}  # name -> (parent joint, placement)
        manager = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(arms.model, geometry, data)
        self.scene = cm.SceneGeometry(geometry, data, manager, ())
        self.active = np.nonzero(self._on)[0]
        """Indices of the pairs checked in the applied arrangement, in pinocchio's order."""
        self._pair_names: tuple[tuple[str, str], ...] | None = None

    def fits(self, resting: Resting, held: Held) -> bool:
        """Whether every object of the arrangement has a slot of its size."""
        boxes = [(n, s) for n, (_, s) in resting.items()]
        boxes += [(n, s) for n, _, s in held.values()]
        return all(n in self.sizes and np.array_equal(self.sizes[n], s) for n, s in boxes)

    def apply(self, resting: Resting, held: Held) -> None:
        """Move the slots and switch the pairs for this arrangement (it must :meth:`fits`)."""
        arms, layout = self.arms, self.arms.layout
        state = self._state.copy()
        holder = self._holder.copy()
        slots = self._slot
        state[list(slots.values())] = _ABSENT
        holder[:] = -1
        placements: dict[str, tuple[int, FloatArray]] = {}
        for name, (T, _) in resting.items():
            state[slots[name]] = _RESTING
            placements[name] = (0, T)
        for arm, (name, T_tool0_obj, _) in held.items():
            state[slots[name]] = _HELD
            holder[slots[name]] = layout.index(arm)
            placements[name] = (arms.wrist_joint[arm], arms.T_wrist_tool[arm] @ T_tool0_obj)
        objects = self.scene.geometry.geometryObjects
        for name, (joint, T) in placements.items():
            key = (joint, np.ascontiguousarray(T).tobytes())
            if self._placed.get(name) != key:
                obj = objects[slots[name]]
                obj.parentJoint = joint
                obj.placement = array_to_se3(T)
                self._placed[name] = key
        for slot in slots.values():
            if (state[slot] == _ABSENT) != (self._state[slot] == _ABSENT):
                objects[slot].disableCollision = bool(state[slot] == _ABSENT)
        self._state, self._holder = state, holder
        want = self.wanted()
        data = self.scene.data
        for k in np.nonzero(want & ~self._on)[0].tolist():
            data.activateCollisionPair(k)
        for k in np.nonzero(self._on & ~want)[0].tolist():
            data.deactivateCollisionPair(k)
        self._on = want
        self.active = np.nonzero(want)[0]
        self._pair_names = None

    def wanted(self) -> Any:
        """The pairs checked in the applied arrangement (a bool per pair): pairs without an
        object always; an arm's shape and a resting object; a held object and every shape of
        the other arms and of its own arm's links before the last; a held object and the
        table, a resting object or another held object."""
        first, second = self._first, self._second
        state, holder = self._state, self._holder
        s1, s2 = state[first], state[second]  # the second is the slot in every object pair
        a1 = self._arm_of[first]
        last = np.array(self.arms.layout.dofs, dtype=np.intp)
        own = holder[second]
        arm_pair = (a1 >= 0) & (
            (s2 == _RESTING)
            | ((s2 == _HELD) & ((a1 != own) | (self._link[first] < last[np.maximum(own, 0)])))
        )
        table_pair = (first == self._table) & (s2 == _HELD)
        object_pair = (first > self._table) & (s1 != _ABSENT) & (s2 != _ABSENT)
        object_pair &= (s1 == _HELD) | (s2 == _HELD)
        return self._fixed | arm_pair | table_pair | object_pair

    @property
    def pair_names(self) -> tuple[tuple[str, str], ...]:
        """The names of the :attr:`active` pairs, as a fresh geometry names them (``object:o``
        resting, ``held:o`` held, a held object before the table or a resting object, two
        arms' shapes in the order of the model's shapes)."""
        if self._pair_names is None:
            names = list(self._names)
            held = set()
            for name, slot in self._slot.items():
                held_here = self._state[slot] == _HELD
                names[slot] = f"held:{name}" if held_here else f"object:{name}"
                if held_here:
                    held.add(slot)
            out = []
            for k in self.active.tolist():
                i, j = int(self._first[k]), int(self._second[k])
                if self._flip[k] or (j in held and i not in held and i >= self._table):
                    i, j = j, i
                out.append((names[i], names[j]))
            self._pair_names = tuple(out)
        return self._pair_names
