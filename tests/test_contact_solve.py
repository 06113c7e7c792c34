"""The banded + low-rank contact KKT solve (mechanics/contact_solve.py) against the dense one (LAPACK sytrf)
on random states of the floor, drum (cylinder), sphere and self-contact cases, and of the floor with clips."""

import numpy as np
import pytest
from scipy.linalg import null_space

from hoseline.mechanics.contact_newton import ContactModel, _kkt_step, evaluate_contact, tangent_log_det
from hoseline.mechanics.contact_solve import banded_step, dense_step, kkt_solves, log_abs_det
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, ClipHold, RodState, centerline
from hoseline.mechanics.rotations import frame_from_tangent

RADIUS, D_HAT, H, KAPPA = 1.0, 1.5, 1.0, 2.0  # mm, mm, mm, N/mm^2


def _rod(tangents, end_force):
    """props, clamps, state of a rod with the given segment tangents, clamped at both ends near its tip."""
    frames = np.array([frame_from_tangent(t / np.linalg.norm(t)) for t in tangents])
    n_seg = frames.shape[0]
    props = RodProperties(np.array([3e3, 4.5e3, 2.5e3]), H, n_seg)
    tip = centerline(frames, np.zeros(3), H)[-1]
    clamps = Clamps(np.zeros(3), frames[0].copy(), tip + 0.01, frames[-1].copy(), False, np.array([0.0, 0.0, -0.02]))
    return props, clamps, RodState(frames, np.asarray(end_force, float))


def _wavy(rng, n_seg=30):
    # a hose along +x with small waves, its stations near z = 0
    tangents = np.array([[1.0, 0.3 * np.sin(0.7 * i), 0.15 * np.cos(0.5 * i)] for i in range(n_seg)])
    return tangents + 0.05 * rng.standard_normal(tangents.shape)


def _helix(rng, n_seg=40):
    # a helix whose second turn nearly touches the first (self-contact), then rises steeply
    turn = 24
    angles = 2 * np.pi * (np.arange(n_seg) + 0.5) / turn
    radius = turn * H / (2 * np.pi)
    pitch = np.where(np.arange(n_seg) < 30, 2 * RADIUS + 0.6, 8.0)
    tangents = np.stack([-radius * np.sin(angles), radius * np.cos(angles), pitch / (2 * np.pi)], 1)
    return tangents + 0.02 * rng.standard_normal(tangents.shape)


def _case(name, seed):
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(3)
    if name == "self":
        props, clamps, state = _rod(_helix(rng), force)
        model = ContactModel(RADIUS, D_HAT, KAPPA, self_exclusion=5)
        return props, clamps, state, model
    props, clamps, state = _rod(_wavy(rng), force)
    nodes = centerline(state.frames, np.zeros(3), H)
    if name == "clips":  # a fixed, a rotating and a ball clip (more constraint rows, more unknowns) and a floor
        clamps.clips = (ClipHold(8, nodes[8] + 0.01, state.frames[8].copy(), False),
                        ClipHold(16, nodes[16] - 0.01, state.frames[16].copy(), True), ClipHold(24, nodes[24], None, False))
        state.clip_forces, state.clip_rolls = rng.standard_normal((3, 3)), np.array([0.0, 0.1, 0.0])
        name = "floor"
    if name == "floor":
        planes = np.array([[0.0, 0.0, nodes[:, 2].min() - RADIUS - 0.3, 0.0, 0.0, 1.0]])
        return props, clamps, state, ContactModel(RADIUS, D_HAT, KAPPA, planes=planes)
    if name == "drum":
        centre = nodes[12] + np.array([0.0, 0.0, -RADIUS - 4.0 - 0.4])
        capsules = np.array([[*(centre - [0.0, 20.0, 0.0]), *(centre + [0.0, 20.0, 0.0]), 4.0]])
        return props, clamps, state, ContactModel(RADIUS, D_HAT, KAPPA, capsules=capsules)
    balls = np.array([[*(nodes[8] + [0.0, 0.5, -RADIUS - 2.0 - 0.3]), 2.0], [*(nodes[20] + [0.0, 0.0, 3.5]), 2.0]])
    return props, clamps, state, ContactModel(RADIUS, D_HAT, KAPPA, balls=balls)


def _close(a, b):
    return np.linalg.norm(a - b) <= 1e-10 * np.linalg.norm(b)


@pytest.mark.parametrize("name", ["floor", "drum", "sphere", "self", "clips"])
def test_low_rank_hessian_is_the_dense_one(name):
    for seed in range(3):
        props, clamps, state, model = _case(name, seed)
        system = evaluate_contact(props, clamps, state, model)
        assert len(system.pairs[0]) >= 3  # contact is on
        n = system.grad.size
        band_part = np.zeros((n, n))
        for k in range(system.band.shape[1]):
            rows = np.arange(k, n)
            band_part[rows, rows - k] = band_part[rows - k, rows] = system.band[k:, k]
        low_rank = band_part + system.columns @ np.diag(system.signs) @ system.columns.T
        dense = system.dense()
        assert np.max(np.abs(low_rank - dense)) <= 1e-11 * np.max(np.abs(dense))
        assert system.columns.shape[1] < n  # low rank


@pytest.mark.parametrize("name", ["floor", "drum", "sphere", "self", "clips"])
def test_step_multipliers_and_inertia_equal_the_dense_solve(name):
    for seed in range(6):
        props, clamps, state, model = _case(name, seed)
        system = evaluate_contact(props, clamps, state, model)
        solved = banded_step(system.band, system.jac_t, system.columns, system.signs, system.grad, system.constraint)
        assert solved is not None
        step, mu, unstable, pivots = solved
        reference = dense_step(system.dense(), system.jac_t, system.grad, system.constraint)
        assert _close(step, reference[0]) and _close(mu, reference[1])
        assert unstable == reference[2]
        dense_log_det = log_abs_det(*reference[3])
        assert log_abs_det(*pivots) == pytest.approx(dense_log_det, abs=1e-8 * abs(dense_log_det) + 1e-8)


def test_unstable_directions_are_counted_as_the_dense_solve_does():
    # an arc sagging onto the floor: stable when pulled, unstable directions when pushed hard along itself;
    # the count also equals that of the Hessian's eigenvalues on the constraint tangent space
    counts = {}
    for pull in (50.0, -2e3, -5e3):  # N
        angles = np.linspace(-0.6, 0.6, 30)
        props, clamps, state = _rod(np.stack([np.cos(angles), 0 * angles, np.sin(angles)], 1), [pull, 0.0, 0.0])
        nodes = centerline(state.frames, np.zeros(3), H)
        planes = np.array([[0.0, 0.0, nodes[:, 2].min() - RADIUS - 0.3, 0.0, 0.0, 1.0]])
        system = evaluate_contact(props, clamps, state, ContactModel(RADIUS, D_HAT, KAPPA, planes=planes))
        assert len(system.pairs[0]) >= 3
        step, mu, unstable, pivots = banded_step(system.band, system.jac_t, system.columns, system.signs, system.grad,
                                                  system.constraint)
        reference = dense_step(system.dense(), system.jac_t, system.grad, system.constraint)
        assert _close(step, reference[0]) and _close(mu, reference[1])
        tangent_space = null_space(system.jac_t.T)
        values = np.linalg.eigvalsh(tangent_space.T @ system.dense() @ tangent_space)
        assert unstable == reference[2] == np.sum(values < 0)
        # the fold watch's determinant: the tangent space's, from the KKT factor (det KKT = +-det(Jc Jc^T) det(Z^T H Z))
        assert tangent_log_det(system.jac_t, pivots) == pytest.approx(np.sum(np.log(np.abs(values))), rel=1e-9)
        counts[pull] = unstable
    assert counts[50.0] == 0 and 0 < counts[-2e3] < counts[-5e3], counts


def test_a_singular_banded_part_falls_back_to_the_dense_solve():
    props, clamps, state, model = _case("floor", 0)
    system = evaluate_contact(props, clamps, state, model)
    system.band[5:8] = 0.0  # B singular (the total need not be: the reference below is made consistent)
    system.band[6:9, 1] = 0.0
    system.band[7:10, 2] = 0.0
    system.band[8:11, 3] = 0.0
    system.band[9:12, 4] = 0.0
    system.band[10:13, 5] = 0.0
    assert banded_step(system.band, system.jac_t, system.columns, system.signs, system.grad, system.constraint) is None
    system.stations = (system.band, *system.stations[1:])
    before = kkt_solves["dense"]
    step, mu, unstable, _ = _kkt_step(system)
    assert kkt_solves["dense"] == before + 1
    reference = dense_step(system.dense(), system.jac_t, system.grad, system.constraint)
    np.testing.assert_array_equal(step, reference[0])
