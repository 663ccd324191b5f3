"""The declarative language: PDDL domains and problems, stream files, and ``PDDLProblem``."""

from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.errors import (
    ArityError,
    DuplicateError,
    PddlError,
    PddlSyntaxError,
    ProblemDefinitionError,
    StreamDefinitionError,
    StreamMapError,
    UnboundVariableError,
    UndeclaredError,
    UnknownKeywordError,
    UnsupportedFeatureError,
)
from sdar_tamp.language.leniency import Leniency, StrictModeError
from sdar_tamp.language.problem_reader import parse_problem
from sdar_tamp.language.streams import parse_stream_file

__all__ = [
    "ArityError",
    "DuplicateError",
    "Leniency",
    "PddlError",
    "PddlSyntaxError",
    "ProblemDefinitionError",
    "StreamDefinitionError",
    "StreamMapError",
    "StrictModeError",
    "UnboundVariableError",
    "UndeclaredError",
    "UnknownKeywordError",
    "UnsupportedFeatureError",
    "parse_domain",
    "parse_problem",
    "parse_stream_file",
]
