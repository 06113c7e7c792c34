"""The contact Newton's downhill mode (minimise_with_contact) and the twisted hose that loops onto itself.

A saddle with contact: a clamped-clamped hose buckled into two bumps (an unstable equilibrium of
the end-shortened elastica) over a floor, under heavy weight; the downhill mode must end at a
stable equilibrium of lower energy that rests on the floor with a gap in (0, d_hat).  The
plectoneme (issue 11): a hose between coaxial mounts, slack, twisted two turns: the path snaps
(follow_contact relaxes downhill and records each snap) until a loop forms whose passes touch
with a gap in (0, d_hat], held there by the self-contact (without it the same shape is not in
equilibrium), the linking number of the hose's ribbon up by the two turns (no passage through
itself); without self-contact the hose relaxes from the loop through itself (the linking number,
which changes only by a passage, drops by 2).  The heavy hose placed from a problem file with gravity ramped in: the place phase
loses stability, snaps down onto the floor and rests on it, the mounts and the floor carrying the weight.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq
from scipy.special import j0

from hoseline.io.problem_file import problem_from_dict
from hoseline.mechanics.contact_newton import (
    ContactModel,
    _kkt_step,
    _multipliers,
    evaluate_contact,
    merit,
    merit_model,
    minimise_with_contact,
    minimum_gap,
    solve_with_contact,
)
from hoseline.mechanics.newton import RodProperties, apply_step, solve_equilibrium
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.procedures.contact.continuation import follow_contact
from hoseline.procedures.contact.model import contact_model, reference_pressure
from hoseline.procedures.placement.continuation import ContinuationLog
from hoseline.procedures.placement.sequence import solve

AXIS = frame_from_tangent(np.array([1.0, 0.0, 0.0]))  # both mounts point along +x


def _bowed(segments, length, shortening, waves):
    """Frames (N, 3, 3) of a planar hose whose tangent angle is A sin(2 pi waves s / L), and its tip (mm),
    A such that the tip is `shortening` times the length from the start."""
    h = length / segments
    amplitude = brentq(lambda a: j0(a) - shortening, 0.0, 2.4)  # mean cos(A sin) over whole waves = J0(A)
    angle = amplitude * np.sin(2 * np.pi * waves * (np.arange(segments) + 0.5) * h / length)
    frames = np.array([frame_from_tangent(np.array([np.cos(a), 0.0, np.sin(a)])) for a in angle])
    return frames, centerline(frames, np.zeros(3), h)[-1]


def _linking_number(first, second):
    """Gauss linking number of two closed polygons (k, 3) (last point = first point): the exact solid-angle
    sum over pairs of edges (Klenin & Langowski, Biopolymers 54, 2000), written out: no library has it."""
    p1, p2 = first[:-1, None, :], first[1:, None, :]
    q1, q2 = second[None, :-1, :], second[None, 1:, :]
    corners = (q1 - p1, q2 - p1, q2 - p2, q1 - p2)
    normals = [np.cross(corners[k], corners[(k + 1) % 4]) for k in range(4)]
    normals = [n / np.linalg.norm(n, axis=-1, keepdims=True) for n in normals]
    omega = sum(np.arcsin(np.clip(np.sum(normals[k] * normals[(k + 1) % 4], axis=-1), -1.0, 1.0)) for k in range(4))
    sign = np.sign(np.sum(np.cross(q2 - q1, p2 - p1) * (q1 - p1), axis=-1))
    return float(np.sum(omega * sign)) / (4 * np.pi)


def _ribbon_linking(props, state, far=1e4):
    """Linking number of the centreline and its edge (0.2 mm along d1), both closed far away by the same
    route (out along the mounts' axis, over, back): it changes only when the hose passes through itself."""
    nodes = centerline(state.frames, np.zeros(3), props.segment_length)
    d1 = state.frames[:, 0]
    edge = nodes + 0.2 * np.vstack([d1[0], 0.5 * (d1[1:] + d1[:-1]), d1[-1]])

    def closed(curve):
        out, back, up = curve[-1] + [far, 0.0, 0.0], curve[0] - [far, 0.0, 0.0], [0.0, 0.0, far]
        return np.vstack([curve, out, out + up, back + up, back, curve[0]])

    return _linking_number(closed(nodes), closed(edge))


def test_the_linking_number_counts_links():
    angle = np.linspace(0.0, 2 * np.pi, 41)
    ring = np.stack([np.cos(angle), np.sin(angle), 0 * angle], 1)
    linked = np.stack([1.0 + np.cos(angle), 0 * angle, np.sin(angle)], 1)  # through the ring once
    apart = linked + [5.0, 0.0, 0.0]
    assert abs(abs(_linking_number(ring, linked)) - 1.0) < 1e-9
    assert abs(_linking_number(ring, apart)) < 1e-9


def _tangent_eigenvalues(props, clamps, state, model):
    system = evaluate_contact(props, clamps, state, model)
    basis = scipy.linalg.null_space(system.jac_t.T)
    return scipy.linalg.eigvalsh(basis.T @ system.dense() @ basis)


def test_downhill_mode_leaves_a_saddle_for_a_stable_state_of_lower_energy_on_the_floor():
    segments, length, radius = 40, 200.0, 2.0
    frames, tip = _bowed(segments, length, 0.94, 2)  # two bumps up: a saddle of the clamped elastica
    props = RodProperties(np.array([1e5, 1e5, 8e4]), length / segments, segments)
    clamps = Clamps(np.zeros(3), AXIS.copy(), tip, AXIS.copy(), False, np.array([0.0, 0.0, -0.3]))
    model = ContactModel(radius, 0.5, 2.0, planes=np.array([[0.0, 0.0, -6.0, 0.0, 0.0, 1.0]]))
    saddle, report = solve_with_contact(props, clamps, RodState(frames, np.zeros(3)), model)
    assert report.converged and report.unstable_directions >= 1  # the start is an unstable equilibrium
    relaxed, report = minimise_with_contact(props, clamps, saddle, model)
    assert report.converged and report.unstable_directions == 0
    assert np.min(_tangent_eigenvalues(props, clamps, relaxed, model)) > 0.0  # stable, by an independent dense check
    energy = evaluate_contact(props, clamps, relaxed, model).energy
    assert energy < evaluate_contact(props, clamps, saddle, model).energy - 100.0
    nodes = centerline(relaxed.frames, np.zeros(3), props.segment_length)
    assert 0.0 < minimum_gap(props, clamps, relaxed, model) < model.activation  # it rests on the floor
    assert np.min(nodes[:, 2]) < -6.0 + radius + model.activation
    again, check = solve_with_contact(props, clamps, relaxed, model, tolerance=1e-9)  # an equilibrium, as it is
    assert check.converged and check.iterations == 0


def _lowered_arch(d_hat):
    """(props, the arch in equilibrium, its clamps with the end fitting lowered by d_hat mm): a state that violates the
    end's position constraint by d_hat."""
    segments, length = 40, 200.0
    frames, tip = _bowed(segments, length, 0.9, 1)  # one bump up: the stable buckled arch
    props = RodProperties(np.array([1e5, 1e5, 8e4]), length / segments, segments)
    arch, report = solve_equilibrium(props, Clamps(np.zeros(3), AXIS.copy(), tip, AXIS.copy(), False, np.zeros(3)),
                                     RodState(frames, np.zeros(3)))
    assert report.converged
    return props, arch, Clamps(np.zeros(3), AXIS.copy(), tip - [0.0, 0.0, d_hat], AXIS.copy(), False, np.zeros(3))


@pytest.mark.parametrize("sigma", [0.0, 1e3])
def test_the_downhill_merit_model_predicts_the_merit_of_a_step_cut_short(sigma):
    """The downhill mode's model of its merit (merit_model) against the merit itself (merit) along a KKT step from
    a state off its constraint, cut to alpha (as the step filter cuts it), agree to 1 %: the arch is near enough to
    quadratic over the step.  Counting the constraint's whole fall for a cut step (the rule before) promised about
    1 / (alpha (2 - alpha)) times the fall, and the walk gave up at a snap of the plectoneme (its path followed
    with other steps)."""
    props, arch, lowered = _lowered_arch(0.5)
    model = ContactModel(2.0, 0.5, 2.0)  # nothing to touch
    system = evaluate_contact(props, lowered, arch, model)
    step, force_step, _, _ = _kkt_step(system, sigma)
    multipliers = _multipliers(lowered, arch)
    whole = merit_model(system, 1.0, step, 0.0, 1.0)[0]  # the Lagrangian's part alone (the penalty ~0)
    weighty = 4.0 * abs(whole) / float(system.constraint @ system.constraint)  # the penalty's part as large, or more
    errors = []
    for alpha in (0.5, 0.1, 0.01):
        predicted, penalty = merit_model(system, alpha, alpha * step, weighty, 1.0)
        trial = evaluate_contact(props, lowered, apply_step(props, lowered, arch, alpha * step, alpha * force_step),
                                 model)
        actual = merit(trial, multipliers, penalty) - merit(system, multipliers, penalty)
        assert predicted < 0.0 and actual < 0.0
        errors.append(abs(actual / predicted - 1.0))
    assert max(errors) < 0.01, errors


def test_downhill_mode_restores_the_clamps_where_that_brings_the_hose_into_the_barrier():
    """A step of the downhill mode restores the end's position constraint (its part -J^T (J J^T)^-1 c, which no
    shift of the Hessian shortens); where that carries the hose into the barrier of an obstacle, the step must be
    shortened, not only shifted: an arch over a floor, its end fitting lowered by d_hat towards the floor, relaxes
    onto it (the shift alone grew to 1e26 and gave up: "no descent step found")."""
    radius, d_hat = 2.0, 0.5
    props, arch, lowered = _lowered_arch(d_hat)
    floor = ContactModel(radius, d_hat, 2.0, planes=np.array([[0.0, 0.0, -(radius + 1.5 * d_hat), 0.0, 0.0, 1.0]]))
    relaxed, report = minimise_with_contact(props, lowered, arch, floor)
    assert report.converged and report.unstable_directions == 0, report
    assert np.min(_tangent_eigenvalues(props, lowered, relaxed, floor)) > 0.0
    np.testing.assert_allclose(centerline(relaxed.frames, np.zeros(3), props.segment_length)[-1], lowered.end_point,
                               atol=1e-9)
    assert 0.0 < minimum_gap(props, lowered, relaxed, floor) < d_hat  # the end's neighbours rest on the floor
    again, check = solve_with_contact(props, lowered, relaxed, floor, tolerance=1e-9)
    assert check.converged and check.iterations == 0


def test_a_slack_hose_twisted_between_coaxial_mounts_loops_onto_itself_and_stops_at_contact():
    segments, length, radius, bending = 40, 200.0, 2.0, 1e5
    frames, tip = _bowed(segments, length, 0.5, 1)
    tip[1:] = 0.0  # coaxial mounts, 100 mm apart
    props = RodProperties(np.array([bending, bending, 8e4]), length / segments, segments)
    turns = 2.0

    def twisted(t):
        angle = 2 * np.pi * turns * t
        end = AXIS.copy()
        end[0] = math.cos(angle) * AXIS[0] + math.sin(angle) * AXIS[1]
        end[1] = -math.sin(angle) * AXIS[0] + math.cos(angle) * AXIS[1]
        return Clamps(np.zeros(3), AXIS.copy(), tip, end, False, np.zeros(3))

    model = contact_model([], radius, props.segment_length, reference_pressure(0.0, bending, math.pi * radius),
                          self_contact=True)
    state, report = solve_with_contact(props, twisted(0.0), RodState(frames, np.zeros(3)), model)
    assert report.converged and report.unstable_directions == 0
    log = ContinuationLog()
    looped, _ = follow_contact("twist", twisted, props, state, model, log=log)
    assert log.events and all("snaps downhill" in event for event in log.events)  # the path passed folds
    nodes = centerline(looped.frames, np.zeros(3), props.segment_length)
    kinds, first, second, gaps = model.pairs(nodes, math.inf)
    passes = (second - first) > segments // 3  # pairs far apart along the hose: two passes of a loop
    assert 0.0 < np.min(gaps[passes]) <= model.activation
    final = evaluate_contact(props, twisted(1.0), looped, model)
    assert final.residual < 1e-8
    without = evaluate_contact(props, twisted(1.0), looped, replace(model, self_exclusion=-1))
    assert without.residual > 1e3 * final.residual  # the touch carries load: without it, no equilibrium
    # the two turns went into the loop without the hose passing through itself (linking number 0 -> 2) ...
    assert abs(_ribbon_linking(props, state)) < 1e-6 and abs(_ribbon_linking(props, looped) - turns) < 1e-6
    # ... while without self-contact the hose walks downhill from the loop through itself (linking number -2)
    through, report = solve_equilibrium(props, twisted(1.0), looped, minimise=True, max_iterations=300)
    assert report.converged and abs(_ribbon_linking(props, through) - (turns - 2.0)) < 1e-6


@pytest.mark.parametrize("itself", [False, True])
def test_a_heavy_hose_placed_with_gravity_ramped_in_snaps_down_onto_the_floor_and_rests_on_it(itself):
    """With self-contact on as well (itself), the step filter watches station-plane and segment-segment pairs
    together; the hose does not touch itself, so the answer is the same."""
    weight = 0.5 * 9.81 * 0.4  # N: 0.5 kg/m, 400 mm
    data = {"hose": {"length": 400.0, "outer_diameter": 8.0, "bending_stiffness": 500.0, "mass_per_length": 0.5,
                     "segments": 30},
            "start": {"point": [0.0, 0.0, 100.0], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [150.0, 0.0, 100.0], "direction": [-1.0, 0.0, 0.0]},
            "environment": {"gravity": [0.0, 0.0, -9.81]},
            "contact": {"self": itself, "placement": "along_path",
                        "obstacles": [{"kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "name": "floor"}]}}
    result = solve(problem_from_dict(data), estimate_error=False)
    assert any("snaps downhill" in event for event in result.events)  # the place phase lost stability
    floor = result.contacts[0]
    assert 0.0 < floor.min_gap < 0.01 and floor.length_in_contact > 50.0
    assert result.stable and result.residual < 1e-8
    # the mounts' reactions and the floor's push carry the weight
    np.testing.assert_allclose(result.start_force + result.end_force + floor.total_force, [0.0, 0.0, weight],
                               atol=1e-6 * weight)
    assert 0.0 < floor.total_force[2] < weight


def test_a_path_that_keeps_snapping_fails_saying_so(monkeypatch):
    """A contact path that snaps more than MOST_SNAPS times fails with a message that says so (the fuzzing campaign
    found a coarse hose coiling on itself that crept on by hundreds of snaps for minutes); here the limit is set to
    one below the plectoneme's snaps."""
    import hoseline.procedures.contact.continuation as continuation
    from hoseline.procedures.placement.continuation import PlacementError

    problem = problem_from_dict({"hose": {"length": 200.0, "outer_diameter": 4.0, "bending_stiffness": 1e5,
                                          "torsional_stiffness": 8e4, "segments": 40},
                                 "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
                                 "end": {"point": [100.0, 0.0, 0.0], "direction": [-1.0, 0.0, 0.0], "twist": 720.0},
                                 "contact": {"self": True}})
    snaps = sum("snaps downhill" in event for event in solve(problem, estimate_error=False).events)
    assert snaps >= 1
    monkeypatch.setattr(continuation, "MOST_SNAPS", snaps - 1)
    with pytest.raises(PlacementError, match=f"snapped more than {snaps - 1} times"):
        solve(problem, estimate_error=False)


def test_a_path_that_creeps_fails_saying_so(monkeypatch):
    """A contact path that takes more than MOST_ITERATIONS Newton iterations fails, saying so, instead of creeping on
    (the fuzzing campaign found a soft hose of 250 mm segments that took 222 785 iterations in 75 s before it failed);
    here the limit is set below the drum's path."""
    import hoseline.procedures.contact.continuation as continuation
    from hoseline.procedures.placement.continuation import PlacementError

    problem = problem_from_dict({"hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5,
                                          "segments": 50},
                                 "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
                                 "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
                                 "contact": {"placement": "along_path",
                                             "obstacles": [{"kind": "cylinder", "start": [0.0, -200.0, 0.0],
                                                            "end": [0.0, 200.0, 0.0], "radius": 30.0}]}})
    assert solve(problem, estimate_error=False).stable
    monkeypatch.setattr(continuation, "MOST_ITERATIONS", 20)
    with pytest.raises(PlacementError, match="took more than 20 Newton iterations .* try more segments"):
        solve(problem, estimate_error=False)
