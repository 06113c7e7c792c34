"""Restoring steps of the contact Newton (mechanics/contact_newton.py, module doc): a Newton step that swings a long
stretch of hose leaves its end off the mount by the square of the turn; moved back onto the constraints, a trial the
residual refused is taken where the energy falls, nothing is within the barrier's reach and the move is clear."""

import numpy as np
import pytest

import hoseline.mechanics.contact_newton as contact_newton
from hoseline.io.problem_file import problem_from_dict
from hoseline.mechanics.contact_newton import hose_move_clear
from hoseline.procedures.placement.sequence import solve

BASE = {"hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "contact": {"placement": "along_path",  # the drum met on the path, where the restoring steps act
                    "obstacles": [{"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0],
                                   "radius": 30.0, "name": "drum"}]}}
LOOP = {"hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "torsional_stiffness": 1e5,
                 "segments": 50},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
        "end": {"point": [150.0, 2.0, 0.0], "direction": [-1.0, 0.0, 0.0]}, "contact": {"self": True}}


@pytest.mark.parametrize("data", [BASE, LOOP], ids=["drum", "loop closing on itself"])
def test_restoring_steps_reach_the_same_equilibrium_in_fewer_iterations(data, monkeypatch):
    problem = problem_from_dict(data)
    restoring = contact_newton._restored
    taken = []

    def checked(props, clamps, state, system, trial, model):
        restored = restoring(props, clamps, state, system, trial, model)
        if restored is not None:  # what a restoring step may be: see the module doc
            state_after, system_after = restored
            assert system.pairs[0].size == 0 and system_after.pairs[0].size == 0  # the rod's alone
            assert contact_newton._kkt_step(system)[2] == 0  # a stable inertia: the step goes downhill
            assert np.max(np.abs(system_after.constraint)) <= 1e-9 * props.length  # back on the mounts and clips
            lagrangian = system.energy - contact_newton._multipliers(clamps, state) @ system.constraint
            assert system_after.energy < lagrangian
            assert hose_move_clear(clamps.start_point, state.frames, clamps.start_point, state_after.frames,
                                   props.segment_length, model)
            taken.append(1)
        return restored

    monkeypatch.setattr(contact_newton, "_restored", checked)
    with_restoring = solve(problem, estimate_error=False)
    monkeypatch.setattr(contact_newton, "_restored", lambda *arguments: None)
    without = solve(problem, estimate_error=False)
    assert taken and with_restoring.iterations < without.iterations
    np.testing.assert_allclose(with_restoring.centerline, without.centerline, atol=1e-9)
    assert with_restoring.stable and without.stable
