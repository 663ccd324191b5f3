"""PDDLStream's public surface under its usual names: change the imports, keep the code.

from sdar_tamp.compat.pddlstream import (PDDLProblem, And, Equal, from_gen_fn, from_test,
                                         solve, print_solution, read, StreamInfo)
"""

from sdar_tamp.language.formulas import (
    INF,
    TOTAL_COST,
    And,
    Equal,
    Exists,
    ForAll,
    Imply,
    Not,
    Or,
    read,
)
from sdar_tamp.language.generators import (
    WildOutput,
    fn_from_constant,
    from_constant,
    from_fn,
    from_gen_fn,
    from_list_fn,
    from_list_gen_fn,
    from_sampler,
    from_test,
    negate_test,
)
from sdar_tamp.language.options import WILD, FunctionInfo, PlanConstraints, StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Action, Certificate, Solution, print_solution
from solvers.solve import create_parser, solve

__all__ = [
    "INF",
    "TOTAL_COST",
    "WILD",
    "Action",
    "And",
    "Certificate",
    "Equal",
    "Exists",
    "ForAll",
    "FunctionInfo",
    "Imply",
    "Not",
    "Or",
    "PDDLProblem",
    "PlanConstraints",
    "Solution",
    "StreamInfo",
    "WildOutput",
    "create_parser",
    "fn_from_constant",
    "from_constant",
    "from_fn",
    "from_gen_fn",
    "from_list_fn",
    "from_list_gen_fn",
    "from_sampler",
    "from_test",
    "negate_test",
    "print_solution",
    "read",
    "solve",
]
