"""The uniqueness check's forks of the path (uniqueness.fork_branches): a branch not taken is followed with the step the
path took on from the fork, and one that reaches the lock on the path's own equilibrium there has met the answer (the
twist from the same state is the same, so it is not followed again)."""

from dataclasses import replace

import numpy as np
import pytest

from hoseline import Hose, Mount, Problem
from hoseline.demos.thesis_hose import demo_problem
from hoseline.mechanics.rotations import rotation_matrix
from hoseline.procedures.placement import sequence
from hoseline.procedures.placement.continuation import ContinuationLog, StepControl


def placed(twist_deg, segments=40):
    """The problem, its sequence after the main run, and the main run's end."""
    problem = demo_problem(twist_deg)
    problem = replace(problem, hose=replace(problem.hose, segments=segments))
    props = sequence.rod_properties(problem)
    run = sequence._Sequence(problem, props, StepControl(), None)
    log = ContinuationLog()
    state, first = sequence._initial_buckle(run.place_props, run.path.place, 0.1, run.path.axis, log)
    end = run.finish(log, "place", first, state)
    return problem, props, run, log, end


def test_the_branch_not_taken_ends_where_it_would_have_ended_followed_in_full(monkeypatch):
    """The thesis hose at 180 deg: the path leaves its plane at 0.775 of the place phase (a symmetric fork) and goes on
    to the lock in one step of 0.25; the other branch, followed with that step, meets the path taken at the lock
    (measured: 7e-12 mm apart) in one step.  Followed in full through the twist anyway, and from the phase's first
    step of 0.1 (it then loses its stability at 0.875 and comes back into the plane), it ends on the same shape."""
    _, props, run, log, (final, state, _, _) = placed(180.0)
    (fork,) = log.forks
    assert fork.fraction == 0.775 and fork.step == 0.25
    short_log = ContinuationLog()
    assert run.finish(short_log, "place", fork.fraction, fork.others[0], first_step=fork.step) is run.main_end
    assert short_log.steps == 1
    assert any("rejoined the main run's equilibrium at the lock" in event for event in short_log.events)
    monkeypatch.setattr(sequence._Sequence, "_rejoins_main", lambda self, clamps, locked: False)
    nodes = sequence.node_positions(props, final, state)
    for first_step in (fork.step, None):
        full_log = ContinuationLog()
        clamps, end_state, _, _ = run.finish(full_log, "place", fork.fraction, fork.others[0], first_step=first_step)
        assert np.max(np.abs(sequence.node_positions(props, clamps, end_state) - nodes)) < 1e-6 * props.length
        assert any(event.startswith("place: stability lost") for event in full_log.events) == (first_step is None)


def test_a_branch_that_ends_elsewhere_is_still_reported():
    """A hose whose mounts lie in one plane leaves it at 0.65 of the place phase; the other side, followed to the end,
    is the other side's shape, clocked differently (end fitting locked at -29.92 deg, 97.2 mm away): not unique, as
    when branches were followed from the phase's first step (measured before that change: the same 97.228 mm)."""
    hose = Hose(length=300.0, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=1.95e5, segments=40)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [-0.3138, 0.9495, 0.0]),
                      Mount([7.32, 53.61, 0.0], [0.7288, -0.6848, 0.0]), 0.0)
    result = sequence.solve(problem, estimate_error=False)
    assert len(result.path_forks) == 1 and result.path_forks[0].startswith("place at fraction 0.6500")
    (other,) = result.other_equilibria
    assert result.unique is False and other.origin.startswith("the other branch of the fork met in phase 'place'")
    assert other.max_distance == pytest.approx(97.228, abs=1e-3) and not other.same_clamps


def test_only_the_path_s_own_equilibrium_at_the_lock_counts_as_rejoined():
    """The main run's state at the lock rejoins (its end roll a whole turn off too: the same clamp); the same state
    with one segment turned by 1e-5 rad (stations moved 1e-3 mm), its end roll turned by 1e-5 rad, or a sliding clip
    the main run has not, does not: its twist would be followed."""
    _, _, run, _, _ = placed(180.0)
    lock, main = run.path.place(1.0), run.locked_state
    assert run._rejoins_main(lock, main)
    assert run._rejoins_main(lock, replace(main, roll=main.roll + 2.0 * np.pi))
    frames = main.frames.copy()
    frames[5] = rotation_matrix(np.array([0.0, 0.0, 1e-5])) @ frames[5]
    assert not run._rejoins_main(lock, replace(main, frames=frames))
    assert not run._rejoins_main(lock, replace(main, roll=main.roll + 1e-5))
    assert not run._rejoins_main(lock, replace(main, clip_arc_lengths=np.array([100.0])))  # not the same clips


def test_solve_follows_the_branch_with_the_step_the_path_took(monkeypatch):
    """In solve, the uniqueness check resumes the thesis hose's fork with the path's step after it (0.25)."""
    calls = []
    finish = sequence._Sequence.finish

    def recorded(self, log, phase, fraction, state, twist_deg=None, first_step=None):
        calls.append((phase, fraction, first_step))
        return finish(self, log, phase, fraction, state, twist_deg, first_step)

    monkeypatch.setattr(sequence._Sequence, "finish", recorded)
    problem = demo_problem(180.0)
    result = sequence.solve(replace(problem, hose=replace(problem.hose, segments=40)), estimate_error=False)
    assert calls == [("place", 0.1, None), ("place", 0.775, 0.25)]
    assert any("meets the path taken at the lock" in event for event in result.events)
