"""The discretisation error estimate and --accuracy against five independent references (accuracy_references.py:
the Kirchhoff rod by solve_bvp, no hoseline code beyond a first guess)."""

import pytest
from accuracy_references import CASES, problem_of, true_error

from hoseline import solve
from hoseline.procedures.placement.refinement import ESTIMATE_MARGIN, solve_to_accuracy


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("segments", [20, 40, 100])
def test_the_estimate_times_its_margin_bounds_the_true_error(name, segments):
    # measured estimate/true 0.981-1.825 (docs/model.md, How accurate is it?); the non-coplanar hose gave 0.60 while
    # the coarse rod kept the fine rod's lock angle
    result = solve(problem_of(name, segments))
    actual = true_error(name, result)
    assert actual <= ESTIMATE_MARGIN * result.discretisation_error
    assert result.discretisation_error <= 2.0 * actual  # and not far too pessimistic


@pytest.mark.parametrize("name", list(CASES))
def test_accuracy_delivers_at_most_what_was_asked(name):
    for asked in (0.1, 0.02):  # mm
        result = solve_to_accuracy(problem_of(name, 20), asked)
        assert true_error(name, result) <= asked
