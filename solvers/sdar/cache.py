"""The stream cache of one SDAR-M run: bound streams, their instances, and the lifted state.

Every stream instance (stream, inputs, fluents) is created once and asked for more outputs
only when a caller wants more than it has produced, so grounding, execution and recovery
share every grasp, IK solution, buffer and motion computed so far. Certified facts go into
the :class:`~solvers.sdar.state.LiftedState`, which also holds the current arrangement.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.formula_model import Atom, FunctionTerm
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem, type_facts
from solvers.sdar.state import LiftedState
from solvers.sdar.vocabulary import SdarVocabulary
from solvers.stream_planning.engine import bind_externals
from solvers.stream_planning.externals import StreamExternal, StreamInstance

InstanceKey = tuple[str, tuple[str, ...], tuple[Atom, ...]]


class StreamCache:
    """Streams of ``problem`` bound once; their outputs certified into :attr:`state`."""

    def __init__(
        self,
        problem: PDDLProblem,
        vocabulary: SdarVocabulary,
        stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    ) -> None:
        self.problem = problem
        self.voc = vocabulary
        self.table = problem.objects.copy()
        self.streams, self.functions = bind_externals(problem, stream_info)
        vocabulary.check(problem.domain, self.streams, self.functions)
        self._types: dict[str, set[str]] = {}
        hierarchy = problem.domain.types
        for name, type_name in problem.facts.objects.items():
            for ancestor in hierarchy.ancestors(type_name):
                self._types.setdefault(ancestor, set()).add(name)
        self._numeric = dict(problem.facts.numeric)
        init = set(problem.facts.init) | type_facts(problem.facts.objects, hierarchy)
        self.state = LiftedState(problem.domain, (), init, self.of_type, self._cost)
        self._instances: dict[InstanceKey, StreamInstance] = {}
        # the current arrangement, read once per state version (see LiftedState.version)
        self._fluents: dict[tuple[tuple[str, ...], frozenset[str]], tuple[Atom, ...]] = {}
        self._poses: dict[str, str] = {}
        self._version: tuple[int, int] = (0, -1)  # (id of the state, its version)
        self._arm_confs: dict[str, dict[str, str]] = {}  # cell configuration -> arm -> conf

    # -- objects and costs ---------------------------------------------------------------
    def of_type(self, type_name: str) -> Sequence[str]:
        return sorted(self._types.get(type_name, ()))

    def _cost(self, term: FunctionTerm) -> float:
        key = (term.name, tuple(term.args))
        if key not in self._numeric:
            external = self.functions.get(term.name)
            if external is None:
                raise ParameterError(f"no value for the cost term {key}")
            self._numeric[key] = float(external.evaluate(key[1], self.table))
        return self._numeric[key]

    def distance(self, d1: str, d2: str) -> float:
        """The domain's estimated motion time between two dual-arm configurations (0 if the
        domain has no distance function)."""
        if self.voc.distance not in self.functions or d1 == d2:
            return 0.0
        return float(self.functions[self.voc.distance].evaluate((d1, d2), self.table))

    def arm_distance(self, q1: str, q2: str) -> float:
        """The domain's estimated motion time of one arm between two of its configurations
        (0 if the domain has no such function)."""
        if self.voc.arm_distance not in self.functions or q1 == q2:
            return 0.0
        return float(self.functions[self.voc.arm_distance].evaluate((q1, q2), self.table))

    def next_motion(self, q: str) -> float:
        """The domain's expected extra time of an arm's next motion from ``q`` (0 if the
        domain has no such function)."""
        if self.voc.next_motion not in self.functions:
            return 0.0
        return float(self.functions[self.voc.next_motion].evaluate((q,), self.table))

    def show(self, name: str) -> str:
        """The printable value behind an object name."""
        return str(self.table.value(name))

    # -- streams -------------------------------------------------------------------------
    def outputs(
        self, stream: str, inputs: tuple[str, ...], limit: int, fluents: tuple[Atom, ...] = ()
    ) -> list[tuple[str, ...]]:
        """The first ``limit`` outputs of ``stream`` on ``inputs`` (fewer if exhausted)."""
        external: StreamExternal = self.streams[stream]
        if not external.declaration.fluents:
            fluents = ()
        key = (stream, inputs, fluents)
        instance = self._instances.get(key)
        if instance is None:
            instance = self._instances[key] = StreamInstance(external, inputs, fluents)
        while len(instance.results) < limit and not instance.exhausted:
            results, wild = instance.next(self.table)
            for result in results:
                self._certify(result.certified)
            self._certify(wild)
        return [r.outputs for r in instance.results[:limit]]

    def test(self, stream: str, inputs: tuple[str, ...]) -> bool:
        return bool(self.outputs(stream, inputs, 1))

    def _certify(self, atoms: Sequence[Atom]) -> None:
        types = self.problem.domain.types
        for atom in atoms:
            if len(atom.args) == 1 and atom.predicate in types.parents:
                for ancestor in types.ancestors(atom.predicate):
                    self._types.setdefault(ancestor, set()).add(atom.args[0])
        self.state.add_static(atoms)

    # -- the current arrangement ---------------------------------------------------------
    def fluents(self, *predicates: str, without: frozenset[str] = frozenset()) -> tuple[Atom, ...]:
        """The current atoms of ``predicates``, sorted; objects in ``without`` are lifted
        (their ``atpose`` atoms left out). Fluent predicates are read once per state version."""
        self._sync()
        key = (predicates, without)
        known = self._fluents.get(key)
        if known is not None:
            return known
        out = [
            Atom(p, args)
            for p in predicates
            for args in self.state.atoms(p)
            if not (p == self.voc.atpose and args[0] in without)
        ]
        atoms = tuple(sorted(out, key=str))
        if all(p in self.state.fluent_names for p in predicates):
            self._fluents[key] = atoms
        return atoms

    def _sync(self) -> None:
        """Forget the arrangement read at an earlier state version."""
        version = (id(self.state), self.state.version)
        if self._version != version:
            self._version = version
            self._fluents.clear()
            self._poses = {}

    def current_dualconf(self) -> str:
        (d,) = next(self.state.atoms(self.voc.atdualconf))
        return d

    def current_arm_conf(self, arm: str) -> str:
        """The configuration of ``arm`` in the current cell configuration (its ``confin``)."""
        d = self.current_dualconf()
        confs = self._arm_confs.get(d)
        if confs is None or arm not in confs:  # a cell configuration's confin facts, once
            confs = {}
            for d2, a, q in self.state.args_of(self.voc.confin):
                if d2 == d and (a not in confs or q < confs[a]):
                    confs[a] = q
            self._arm_confs[d] = confs
        if arm in confs:
            return confs[arm]
        raise ParameterError(f"no ({self.voc.confin} {d} {arm} ?q) fact for the current state")

    def current_poses(self) -> dict[str, str]:
        """Object -> pose now (a copy; read once per state version)."""
        self._sync()
        if not self._poses:
            self._poses = {o: p for o, p in self.state.atoms(self.voc.atpose)}
        return dict(self._poses)
