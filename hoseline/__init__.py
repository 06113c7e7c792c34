"""hoseline: where a flexible hose lies between two mounts.

    from hoseline import load_problem, solve
    result = solve(load_problem("problem.toml"))
"""

from hoseline.model import Hose, Mount, Problem
from hoseline.procedures.result import Result
from hoseline.procedures.placement import solve, PlacementError
from hoseline.io.problem_file import load_problem, ProblemFileError

__all__ = ["Hose", "Mount", "Problem", "Result", "solve", "load_problem", "PlacementError", "ProblemFileError"]
__version__ = "0.1.0"
