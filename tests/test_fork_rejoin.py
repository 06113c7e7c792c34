"""A fork's branch that reaches the lock on the path's own equilibrium there has met the answer: the twist from the
same state is the same, so the uniqueness check does not follow it again (uniqueness.fork_branches)."""

from dataclasses import replace

import numpy as np

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
    """The thesis hose at 180 deg: the other branch of the fork at 0.775 of the place phase meets the path taken at
    the lock (measured: 7e-12 mm apart); followed through the twist anyway it ends on the same shape."""
    _, props, run, log, (final, state, _, _) = placed(180.0)
    (fork,) = log.forks
    short_log = ContinuationLog()
    shortcut = run.finish(short_log, "place", fork.fraction, fork.others[0])
    assert shortcut is run.main_end
    assert any("rejoined the main run's equilibrium at the lock" in event for event in short_log.events)
    monkeypatch.setattr(sequence._Sequence, "_rejoins_main", lambda self, clamps, locked: False)
    full_clamps, full_state, _, _ = run.finish(ContinuationLog(), "place", fork.fraction, fork.others[0])
    nodes = sequence.node_positions(props, final, state)
    assert np.max(np.abs(sequence.node_positions(props, full_clamps, full_state) - nodes)) < 1e-6 * props.length


def test_only_the_path_s_own_equilibrium_at_the_lock_counts_as_rejoined():
    """The main run's state at the lock rejoins (its end roll a whole turn off too: the same clamp); the same state
    with one segment turned by 1e-5 rad (stations moved 1e-3 mm), or its end roll turned by 1e-5 rad, does not: its
    twist would be followed."""
    _, _, run, _, _ = placed(180.0)
    lock, main = run.path.place(1.0), run.locked_state
    assert run._rejoins_main(lock, main)
    assert run._rejoins_main(lock, replace(main, roll=main.roll + 2.0 * np.pi))
    frames = main.frames.copy()
    frames[5] = rotation_matrix(np.array([0.0, 0.0, 1e-5])) @ frames[5]
    assert not run._rejoins_main(lock, replace(main, frames=frames))
    assert not run._rejoins_main(lock, replace(main, roll=main.roll + 1e-5))
