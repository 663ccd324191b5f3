"""SDAR-T's steps beyond two arms: rotations of closed components and greedy extension.

With ``k`` arms a synchronous step lifts up to ``k`` objects and then places them, so a group
``U`` of objects can go to their goals in one step whenever every blocker of a member is a
member too (``B(x) <= U`` for every ``x`` in ``U``), whatever the edges inside ``U``. Two kinds
of such groups matter:

* a *rotation*: a strongly connected component of ``3 <= m <= k`` objects that nothing outside
  blocks (an ``m``-cycle among them). Every object is lifted, then every object is placed: no
  buffer. With ``m = 2`` this is the dual-arm swap (SDAR-T's class 1 already has it).
* a *unit*: a strongly connected component of the graph left once a step's objects are lifted
  (one object, most of the time). :func:`extend` adds to a step, greedily, the unit whose goals
  become free with the step's objects lifted and that frees the most (then removes most edges,
  then is the largest, then comes first by object order), until ``k`` moves or nothing fits;
  a unit holding an object that must wait (:meth:`~solvers.sdar.tasks.TaskView.must_wait`) is
  never added. When the view has a :class:`~solvers.sdar.tasks.Layout` (three arms or more,
  positions given by the app), the extension is spatial: the step's objects are seated on
  arms (:func:`_seat`: each on the free arm crossing the fewest seated ones, then reaching
  least far), a unit fits only if free arms move it without crossing a seated arm
  (:meth:`~solvers.sdar.tasks.Layout.crosses`), and units farther than the layout's clearance
  from the step's poses and goals come first. :func:`extensions` offers the spatial extension
  and the one by dependencies alone.

With a layout, a step of three moves or more whose arms obviously meet is not proposed at all
(:func:`meets`): when no seating of its objects on distinct arms (every one when there are at
most :data:`SEATINGS`, else the greedy one of :func:`_seat`) keeps every pair of arms
:data:`MEET` apart over the whole transfer (:meth:`~solvers.sdar.tasks.Layout.sweep_gap`: the
plane segments from the bases to the objects compared at the picks, at the places and at three
points between, both arms at the same fraction of their transfers). :data:`MEET` is well under
the layout's clearance: the segments nearly cross, where arms collide whatever their grasps
(steps of arms a few centimetres apart in the plane do ground, at other heights or with
tilted grasps: a 3-cycle rotated by three arms comes within 0.053 m). This prunes the
extension by dependencies alone and the rotations, which are otherwise proposed without
looking at the table, and the spatial extension when the step it extends already crosses;
the smaller step remains the fallback. The test costs at most :data:`SEATINGS` seatings of
``m (m - 1) / 2`` pairs, five segment distances each, per step.

Both are bounded: rotations are at most one per component; :func:`extend` runs once per
candidate it is given (SDAR-T gives it the first ``max_candidates`` steps of its two-arm list)
and costs ``k`` rounds over the units (twice with a layout). No set of ``k`` objects is enumerated.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from sdar_tamp.graph import strongly_connected_components
from solvers.sdar.spending import moves_layout
from solvers.sdar.tasks import Layout, Move, Step, TaskView

#: The most seatings of a step's objects on arms :func:`meets` tries one by one (4 arms: 24).
SEATINGS = 120
#: [m] Two arms whose plane segments come closer than this over a step obviously meet.
MEET = 0.02
#: The first two-move steps of a list that :func:`merges` joins with a later one each.
MERGE_FIRST = 4


class TaskScene:
    """The view's blockers and predecessors by name, and how much a lift frees."""

    def __init__(self, view: TaskView) -> None:
        self.view = view
        self.names = view.remaining
        self.order = {x: k for k, x in enumerate(self.names)}
        self.blockers = {x: view.blockers(x) for x in self.names}
        self.preds = {x: sum(1 for y in self.names if x in self.blockers[y]) for x in self.names}

    def frees(self, lifted: frozenset[str]) -> tuple[int, int]:
        """Objects whose goals become free, and edges removed, when ``lifted`` move."""
        others = [y for y in self.names if y not in lifted]
        freed = sum(1 for y in others if self.blockers[y] and self.blockers[y] <= lifted)
        return freed, sum(1 for y in others for x in lifted if x in self.blockers[y])

    def units(self, lifted: frozenset[str]) -> list[tuple[str, ...]]:
        """The strongly connected components of the graph on the objects not in ``lifted``
        (members in object order)."""
        rest = [x for x in self.names if x not in lifted]
        index = {x: k for k, x in enumerate(rest)}
        edges = tuple((index[x], index[y]) for x in rest for y in self.blockers[x] if y in index)
        comps = strongly_connected_components(len(rest), edges)
        return [tuple(sorted((rest[k] for k in c), key=self.order.__getitem__)) for c in comps]

    def closed(self, group: frozenset[str]) -> bool:
        """Every blocker of a member of ``group`` is in ``group``."""
        return all(self.blockers[x] <= group for x in group)


def rotations(scene: TaskScene, arms: int) -> list[tuple[tuple[int, ...], Step]]:
    """Closed components of ``3 <= m <= arms`` objects, each as one step of ``m`` goal moves
    (kind ``rotate``); the key ``(-freed, -edges removed, first object's order)`` ranks them."""
    out: list[tuple[tuple[int, ...], Step]] = []
    for unit in scene.units(frozenset()):
        group = frozenset(unit)
        if 3 <= len(unit) <= arms and scene.closed(group) and not meets(scene.view, unit):
            freed, removed = scene.frees(group)
            key = (-freed, -removed, scene.order[unit[0]])
            out.append((key, Step(tuple(Move(x) for x in unit), "rotate", 0, key[:-1])))
    return out


def extend(scene: TaskScene, step: Step, arms: int, spatial: bool = True) -> Step:
    """``step`` with goal moves of units added greedily (see the module docstring); ``step``
    itself when nothing fits. The added moves follow the step's own, in the order added.
    ``spatial``: with a layout in the view, only units an arm can move without crossing the
    arms already in the step (:func:`_seat`), those away from the step's objects first;
    False: by dependencies only."""
    lifted = frozenset(step.objects)
    if len(lifted) >= arms:
        return step
    view = scene.view
    layout = view.layout if spatial else None
    units = [u for u in scene.units(lifted) if not any(view.must_wait(x) for x in u)]
    seated = _seat(layout, (), step.objects)[1] if layout is not None else ()
    added: list[str] = []
    while len(lifted) < arms:
        fits = [
            u
            for u in units
            if len(u) <= arms - len(lifted)
            and all(scene.blockers[y] <= lifted | frozenset(u) for y in u)
        ]
        if layout is not None:
            seats = {u: _seat(layout, seated, u) for u in fits}
            fits = [u for u in fits if seats[u][0] == 0]
        if not fits:
            break
        worth = {u: _worth(scene, lifted, u) for u in fits}
        if layout is not None:
            near = {u: int(layout.gap(u, lifted) < layout.clearance) for u in fits}
            worth = {u: (near[u], *w) for u, w in worth.items()}
        best = min(fits, key=worth.__getitem__)
        if layout is not None:
            seated = seats[best][1]
        added.extend(best)
        lifted = lifted | frozenset(best)
        units.remove(best)
    if not added:
        return step
    return Step((*step.moves, *(Move(x) for x in added)), step.kind, step.rank, step.tie)


def extensions(scene: TaskScene, step: Step, arms: int) -> list[Step]:
    """The extensions of ``step`` SDAR-T offers, best first: the spatial one and, when the view
    has a layout and it differs, the one by dependencies only; empty when nothing fits."""
    out: list[Step] = []
    for spatial in (True, False) if scene.view.layout is not None else (False,):
        wider = extend(scene, step, arms, spatial)
        if meets(scene.view, wider.objects):
            continue
        if wider is not step and all(set(w.moves) != set(wider.moves) for w in out):
            out.append(wider)
    return out


def merges(scene: TaskScene, steps: Sequence[Step], arms: int) -> list[Step]:
    """Two steps of two moves each made at once, with four arms or more and a layout: each of
    the first :data:`MERGE_FIRST` two-move ``steps`` joined with the first later two-move step
    of other objects that fits (kind and rank of the first; none when nothing fits). It fits
    when its objects lie in other components of the dependency graph than the first's (each
    step breaks its own cycle or chain, so the buffer moves stay those of the minimum buffer
    set), no object of one waits for one of the other
    (:attr:`~solvers.sdar.tasks.TaskView.waits`) and, the four objects seated on arms
    (:func:`_seat`; a buffer move at its object's pose:
    :func:`~solvers.sdar.spending.moves_layout`), no arm of one step crosses an arm of the other
    (:meth:`~solvers.sdar.tasks.Layout.crosses`; within a step as SDAR-M finds). Each step is valid
    alone (its goals free once its own objects are lifted), so both are valid at once; two
    cycle breaks in far regions of the table take one step instead of two. At most
    :data:`MERGE_FIRST` x ``len(steps)`` pairs are looked at."""
    view = scene.view
    layout = view.layout
    if arms < 4 or layout is None:
        return []
    twos = [s for s in steps if len(s.moves) == 2 and all(x in layout.places for x in s.objects)]
    part = {x: k for k, unit in enumerate(scene.units(frozenset())) for x in unit}
    out: list[Step] = []
    for i, first in enumerate(twos[:MERGE_FIRST]):
        mine = {part[x] for x in first.objects}
        for other in twos[i + 1 :]:
            if any(part[x] in mine for x in other.objects):
                continue
            if any((x, y) in view.waits or (y, x) in view.waits
                   for x in first.objects for y in other.objects):  # fmt: skip
                continue
            moves = (*first.moves, *other.moves)
            plane = moves_layout(layout, moves)
            seats = {x: a for a, x in _seat(plane, (), tuple(m.obj for m in moves))[1]}
            if any(plane.crosses(seats[x], x, seats[y], y)
                   for x in first.objects for y in other.objects):  # fmt: skip
                continue
            out.append(Step((*first.moves, *other.moves), first.kind, first.rank, first.tie))
            break
    return out


def meets(view: TaskView, objects: tuple[str, ...]) -> bool:
    """With a layout in ``view``, ``objects`` (three or more) moved in one step: no seating of
    them on arms keeps the arms apart (see the module docstring); False otherwise."""
    layout = view.layout
    if layout is None or len(objects) < 3 or any(x not in layout.places for x in objects):
        return False
    arms = range(len(layout.bases))
    if math.perm(len(arms), len(objects)) > SEATINGS:  # the greedy seating
        seats = dict(_seat(layout, (), objects)[1])
        return any(
            layout.sweep_gap(a, x, b, y) < MEET
            for (a, x), (b, y) in itertools.combinations(seats.items(), 2)
        )
    pairs = list(itertools.combinations(range(len(objects)), 2))
    return all(
        any(layout.sweep_gap(seats[i], objects[i], seats[j], objects[j]) < MEET for i, j in pairs)
        for seats in itertools.permutations(arms, len(objects))
    )


def _seat(
    layout: Layout, seated: tuple[tuple[int, str], ...], objs: tuple[str, ...]
) -> tuple[int, tuple[tuple[int, str], ...]]:
    """Arms for ``objs`` besides those ``seated`` (arm index, object), greedily in order:
    each the free arm crossing the fewest seated ones (:meth:`~solvers.sdar.tasks.Layout.
    crosses`), then reaching least far; the crossings added and every seat. An object with
    no free arm counts one crossing per seated arm."""
    crossings = 0
    out = list(seated)
    for x in objs:
        free = [a for a in range(len(layout.bases)) if all(a != b for b, _ in out)]
        if not free:
            crossings += len(out)
            continue
        cost = {a: sum(1 for b, y in out if layout.crosses(a, x, b, y)) for a in free}
        arm = min(free, key=lambda a: (cost[a], layout.reach(a, x), a))
        crossings += cost[arm]
        out.append((arm, x))
    return crossings, tuple(out)


def _worth(scene: TaskScene, lifted: frozenset[str], unit: tuple[str, ...]) -> tuple[int, ...]:
    """Order of the units that fit a step: more freed, more edges removed, larger, first."""
    freed, removed = scene.frees(lifted | frozenset(unit))
    return (-freed, -removed, -len(unit), scene.order[unit[0]])
