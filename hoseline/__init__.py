"""hoseline: where a flexible hose lies between two mounts.

    from hoseline import load_problem, solve
    result = solve(load_problem("problem.toml"))

The names below are loaded on first use (PEP 562), so that importing a part of the package,
such as the command line, does not load the solver.
"""

from importlib import import_module

_EXPORTS = {
    "Hose": "hoseline.model",
    "Mount": "hoseline.model",
    "Problem": "hoseline.model",
    "Result": "hoseline.procedures.placement.result",
    "solve": "hoseline.procedures.placement.sequence",
    "PlacementError": "hoseline.procedures.placement.continuation",
    "load_problem": "hoseline.io.problem_file",
    "ProblemFileError": "hoseline.io.problem_file",
}
__all__ = list(_EXPORTS)
__version__ = "0.1.0"


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'hoseline' has no attribute {name!r}")
    return getattr(import_module(_EXPORTS[name]), name)


def __dir__():
    return sorted([*globals(), *__all__])
