"""Contact forces against converged references, their refinement, and the error estimate with contact.

The drum of tests/test_contact_cylinder.py (a weightless hose pulled taut over a cylinder) against a
free-boundary solution of the planar elastica wrapped on the circle R + r (solve_bvp here; it agrees with
tests/elastica_drum_shooting.py's total to 1e-9), and the floor of tests/test_contact_floor.py against
tests/elastica_floor_shooting.py.  accuracy.contact_errors must bound the measured errors."""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from elastica_floor_shooting import solve_floor_elastica
from hoseline.mechanics.contact_newton import evaluate_contact, solve_with_contact
from hoseline.mechanics.newton import node_positions
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Cylinder, Plane
from hoseline.model.problem import DEFAULT_FORCE_ACCURACY, Problem
from hoseline.procedures.contact.continuation import follow_contact
from hoseline.procedures.contact.model import bend_length, contact_model, reference_pressure
from hoseline.procedures.placement.accuracy import BARRIER_NARROWING, ContactSnapshot, contact_errors
from hoseline.procedures.placement.sequence import place_only, solve

DRUM_LENGTH, DRUM_EI, RADIUS, DRUM = 335.0, 1e5, 5.0, 40.0
FLOOR_LENGTH, FLOOR_EI, MASS, HALF_SPAN, HEIGHT = 1000.0, 2e4, 0.5, 420.0, 150.0
WEIGHT = MASS * 9.81e-3  # N/mm
COUNTS = (50, 100, 200)


def placed(problem, obstacle, pressure, end, weight_per_length, narrowed=False):
    """The hose of `problem` placed without contact, its end carried to `end` with contact on: a ContactSnapshot
    (the start reaction from the balance of the whole hose, weight_per_length in N/mm), and with narrowed=True also the same equilibrium
    solved again with BARRIER_NARROWING d_hat."""
    props, high, state, _ = place_only(problem)
    model = contact_model([obstacle], RADIUS, props.segment_length, pressure)

    def path(t):
        return replace(high, end_point=(1.0 - t) * high.end_point + t * end)

    state, _ = follow_contact("carry the end", path, props, state, model)
    weight = np.array([0.0, 0.0, -weight_per_length * props.length])

    def snap(at, with_model):
        push = evaluate_contact(props, path(1.0), at, with_model).forces.sum(axis=0)
        return ContactSnapshot(props.segment_length * np.arange(props.segments + 1),
                               node_positions(props, path(1.0), at),
                               np.array([-(at.end_force + push + weight), at.end_force]), {obstacle.name: push})

    if not narrowed:
        return snap(state, model)
    narrow = model.with_activation(BARRIER_NARROWING * model.activation)
    again, report = solve_with_contact(props, path(1.0), state, narrow)
    assert report.converged
    return snap(state, model), snap(again, narrow)


def drum_reference(guess_shape):
    """(total push on the hose (3,), end reaction (3,)) N of the exact elastica over the drum: right half from the
    lift-off point (angle psi from the top) to the mount at (100, -80) leaving straight up; on the wrap the
    curvature is -1/rho, continuous at lift-off (docs of tests/elastica_drum_shooting.py); p = (psi, n_x, n_z).
    guess_shape: a ContactSnapshot of the discrete hose, the guess."""
    rho, half = DRUM + RADIUS, 0.5 * DRUM_LENGTH

    def rhs(u, y, p):
        span = half - rho * p[0]
        return span * np.vstack([np.cos(y[2]), np.sin(y[2]), y[3], (np.sin(y[2]) * p[1] - np.cos(y[2]) * p[2]) / DRUM_EI])

    def ends(ya, yb, p):
        return np.array([ya[0] - rho * math.sin(p[0]), ya[1] - rho * math.cos(p[0]), ya[2] + p[0], ya[3] + 1 / rho,
                         yb[0] - 100.0, yb[1] + 80.0, yb[2] + 0.5 * math.pi])

    # the guess: the right free part of the finest discrete hose (stations off the drum, x > 0)
    nodes = guess_shape.centerline[:, [0, 2]]
    radial = np.hypot(nodes[:, 0], nodes[:, 1]) - rho
    free = nodes[(nodes[:, 0] > 0.0) & (radial > 0.05)]
    psi = math.atan2(free[0, 0], free[0, 1])
    u = np.linspace(0.0, 1.0, len(free))
    chords = np.diff(free, axis=0)
    angle = np.arctan2(chords[:, 1], chords[:, 0])
    angle = np.append(angle, angle[-1])
    guess = np.vstack([free[:, 0], free[:, 1], angle, np.gradient(angle, u) / (half - rho * psi)])
    solution = solve_bvp(rhs, ends, u, guess, p=[psi, *guess_shape.reactions[1, [0, 2]]], tol=1e-8, max_nodes=400000, bc_tol=1e-12)
    assert solution.status == 0, solution.message
    _, n_x, n_z = solution.p
    return np.array([0.0, 0.0, -2.0 * n_z]), np.array([n_x, 0.0, n_z])


@pytest.fixture(scope="module")
def drum():
    """{segments: (snapshot, narrowed snapshot)} and the reference (push, end reaction)."""
    up = np.array([0.0, 0.0, 1.0])
    cylinder = Cylinder(np.array([0.0, -200.0, 0.0]), np.array([0.0, 200.0, 0.0]), DRUM, "drum")
    pressure = reference_pressure(0.0, DRUM_EI, bend_length(DRUM_LENGTH, [cylinder], RADIUS))
    runs = {}
    for count in COUNTS:
        hose = Hose(length=DRUM_LENGTH, outer_diameter=2 * RADIUS, bending_stiffness=DRUM_EI,
                    torsional_stiffness=DRUM_EI, segments=count)
        problem = Problem(hose, Mount(np.array([-100.0, 0.0, -80.0]), up), Mount(np.array([60.0, 0.0, 150.0]), up))
        runs[count] = placed(problem, cylinder, pressure, np.array([100.0, 0.0, -80.0]), 0.0, narrowed=True)
    return runs, drum_reference(runs[COUNTS[-1]][0])


@pytest.fixture(scope="module")
def floor():
    """{segments: (snapshot, narrowed snapshot)} and the reference (floor load (3,), end reaction (3,))."""
    down = np.array([0.0, 0.0, -1.0])
    plane = Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor")
    runs = {}
    for count in COUNTS:
        hose = Hose(length=FLOOR_LENGTH, outer_diameter=2 * RADIUS, bending_stiffness=FLOOR_EI,
                    torsional_stiffness=FLOOR_EI, mass_per_length=MASS, segments=count)
        problem = Problem(hose, Mount(np.array([-HALF_SPAN, 0.0, HEIGHT]), down),
                          Mount(np.array([300.0, 0.0, 500.0]), down), gravity=np.array([0.0, 0.0, -9.81]))
        runs[count] = placed(problem, plane, reference_pressure(WEIGHT, FLOOR_EI, FLOOR_LENGTH),
                             np.array([HALF_SPAN, 0.0, HEIGHT]), WEIGHT, narrowed=True)
    exact = solve_floor_elastica(FLOOR_LENGTH, FLOOR_EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)
    load = WEIGHT * (FLOOR_LENGTH - 2 * exact.lifted) + 2 * exact.reaction
    end = np.array([exact.horizontal, 0.0, WEIGHT * exact.lifted - exact.reaction])  # the suspended half less R
    return runs, (np.array([0.0, 0.0, load]), end)


def relative_errors(snapshot, reference, name):
    """(total force, end reaction) errors relative to the reference's magnitudes."""
    push, end = reference
    return (float(np.linalg.norm(snapshot.forces[name] - push) / np.linalg.norm(push)),
            float(np.linalg.norm(snapshot.reactions[1] - end) / np.linalg.norm(end)))


def test_drum_forces_within_half_a_percent_at_the_default_segments(drum):
    runs, reference = drum
    push_error, reaction_error = relative_errors(runs[100][0], reference, "drum")
    # measured: 0.10 % and 0.06 %; most of it the barrier's standoff (the hose taut over the drum: the push
    # grows 0.15 % per micrometre of wrap radius), not the segments
    assert push_error < 0.005 and reaction_error < 0.005, (push_error, reaction_error)
    np.testing.assert_allclose(runs[100][0].reactions[0] * [-1.0, 1.0, 1.0], runs[100][0].reactions[1], rtol=1e-6,
                               atol=1e-6)  # the start's is the mirror image


def test_floor_load_within_half_a_percent_and_its_refinement(floor):
    runs, reference = floor
    errors = [relative_errors(runs[count][0], reference, "floor") for count in COUNTS]
    load, reaction = np.array(errors).T
    assert load[1] < 0.005, load  # measured 0.11 %
    # the touch-down falls between stations: first order at least (measured 1.5: 0.30, 0.107, 0.039 %
    # for the load, 4.5, 1.6, 0.57 % for the end reaction's vector)
    assert np.all(np.log2(load[:-1] / load[1:]) > 1.0), load
    assert np.all(np.log2(reaction[:-1] / reaction[1:]) > 1.0), reaction


def test_floor_reaction_within_half_a_percent_with_the_default_force_accuracy():
    """The placement alone is 1.6 % off at 100 segments (above); the force accuracy a problem file without
    hose.segments asks for (force_accuracy.py) refines it to within 0.5 %, and its estimate bounds the error."""
    down = np.array([0.0, 0.0, -1.0])
    hose = Hose(length=FLOOR_LENGTH, outer_diameter=2 * RADIUS, bending_stiffness=FLOOR_EI,
                torsional_stiffness=FLOOR_EI, mass_per_length=MASS, segments=100)
    problem = Problem(hose, Mount(np.array([-HALF_SPAN, 0.0, HEIGHT]), down), Mount(np.array([HALF_SPAN, 0.0, HEIGHT]), down),
                      gravity=np.array([0.0, 0.0, -9.81]), contact=(Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor"),))
    result = solve(problem, force_accuracy=DEFAULT_FORCE_ACCURACY)
    exact = solve_floor_elastica(FLOOR_LENGTH, FLOOR_EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)
    end = np.array([exact.horizontal, 0.0, WEIGHT * exact.lifted - exact.reaction])
    error = float(np.linalg.norm(result.end_force - end) / np.linalg.norm(end))
    # measured: 0.18 % at 400 segments, estimated 0.48 % (the order observed on 100, 200 and 400 segments: 1.35)
    assert error < 0.005 and result.force_refinement.met, (error, result.force_refinement)
    assert result.force_refinement.estimated >= error


def test_the_lifted_span_alone_misses_half_a_percent_at_the_default_segment_length():
    """The floor's lifted span as its own hose, clamped at the mount and horizontal at the exact touch-down point (no
    contact): its mount reaction is the rod's own error, which no contact treatment removes (docs/model.md, Accuracy
    of the forces).  Second order, and at the default segment length (10 mm) about the issue's 0.5 % by itself."""
    exact = solve_floor_elastica(FLOOR_LENGTH, FLOOR_EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)
    reference = np.array([-exact.horizontal, 0.0, WEIGHT * exact.lifted - exact.reaction])  # the start mount's
    errors = []
    for count in (28, 56):  # h = 10.1 and 5.05 mm
        hose = Hose(length=exact.lifted, outer_diameter=2 * RADIUS, bending_stiffness=FLOOR_EI,
                    torsional_stiffness=FLOOR_EI, mass_per_length=MASS, segments=count)
        problem = Problem(hose, Mount(np.array([-HALF_SPAN, 0.0, HEIGHT]), np.array([0.0, 0.0, -1.0])),
                          Mount(np.array([-exact.touchdown, 0.0, RADIUS]), np.array([-1.0, 0.0, 0.0])),
                          gravity=np.array([0.0, 0.0, -9.81]))
        _, _, state, _ = place_only(problem)
        start = -(state.end_force + np.array([0.0, 0.0, -WEIGHT * exact.lifted]))
        errors.append(float(np.linalg.norm(start - reference) / np.linalg.norm(reference)))
    # measured: 0.51 % and 0.15 %
    assert 0.004 < errors[0] < 0.006 and np.log2(errors[0] / errors[1]) > 1.5, errors


@pytest.mark.parametrize("case, name", [("drum", "drum"), ("floor", "floor")])
@pytest.mark.parametrize("fine", [100, 200])
def test_the_estimate_with_contact_bounds_the_force_and_reaction_errors(case, name, fine, request):
    runs, (push, end) = request.getfixturevalue(case)
    (snapshot, narrowed), (coarse, _) = runs[fine], runs[fine // 2]
    errors = contact_errors(snapshot, coarse, narrowed)
    actual_force = float(np.linalg.norm(snapshot.forces[name] - push))
    actual_reaction = float(np.linalg.norm(snapshot.reactions[1] - end))
    assert errors.forces[name] >= actual_force, (errors.forces[name], actual_force)
    assert errors.reactions >= actual_reaction, (errors.reactions, actual_reaction)
