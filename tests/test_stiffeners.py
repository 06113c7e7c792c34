"""The thesis' stiffener springs: exact derivatives (finite differences), geometry of equations
9-16, the element-size rule and regression preset (equations 17-28, Table 6), and a placement."""

import math
from dataclasses import replace

import numpy as np
import pytest
from test_energy_derivatives import dense, finite_differences, perturbed, random_frames

from hoseline import Hose, Mount, Problem, solve
from hoseline.mechanics.energy import BANDWIDTH, assemble, elastic_energy, joint_moments
from hoseline.mechanics.rotations import rotation_matrix
from hoseline.mechanics.stiffeners import FULL, spring_energy, spring_set, spring_terms_into
from hoseline.model.stiffeners import (
    SpringTable,
    Stiffeners,
    element_count,
    spring_angle_deg,
    thesis_deformations,
    thesis_preset,
)

# a table with soft compression, slack, a stiff rise and a plateau, scaled to the test's small frames
TABLE = SpringTable((-0.3, -0.05, 0.0, 0.04, 0.06, 0.2), (-0.2, -0.05, 0.0, 0.0, 2.0, 2.3))


def springs_for(count, h, radius=0.6, angle=60.0):
    stiffeners = Stiffeners(count, angle, TABLE)
    return spring_set(
        stiffeners.anchors(radius, h, h), stiffeners.anchors(radius, h, 0.5 * h), TABLE.deformation, TABLE.force
    )


def lagrangian(frames, start, end, stiffness, h, loads, roll_free, springs):
    n = 3 * frames.shape[0] + (1 if roll_free else 0)
    grad = np.empty(n)
    band = np.empty((n, BANDWIDTH + 1))
    e_el, e_seg = assemble(frames, start, end, stiffness, h, loads, roll_free, grad, band, True, springs)
    return e_el + e_seg, grad, band


@pytest.mark.parametrize("count, roll_free", [(8, False), (16, False), (16, True)])
def test_gradient_and_hessian_with_springs_match_finite_differences(count, roll_free):
    rng = np.random.default_rng(5 + count)
    n_seg, h = 6, 0.8
    springs = springs_for(count, h)
    frames = random_frames(rng, n_seg, spread=0.25)
    start = rotation_matrix(rng.normal(scale=0.2, size=3))
    end = frames[-1] @ rotation_matrix(rng.normal(scale=0.2, size=3)).T
    stiffness = np.array([0.3, 0.3, 2.0])
    loads = rng.normal(size=(n_seg, 3))
    energy, grad, band = lagrangian(frames, start, end, stiffness, h, loads, roll_free, springs)
    fd_grad, fd_hess = finite_differences(
        lambda f, e: lagrangian(f, start, e, stiffness, h, loads, roll_free, springs)[:2],
        frames,
        end,
        grad.size,
        roll_free,
        1e-6,
    )
    assert np.allclose(grad, fd_grad, rtol=1e-6, atol=1e-7 * np.max(np.abs(grad)))
    hess = dense(band)
    assert np.allclose(hess, 0.5 * (fd_hess + fd_hess.T), rtol=1e-5, atol=1e-6 * np.max(np.abs(hess)))
    plain, _, _ = lagrangian(frames, start, end, stiffness, h, loads, roll_free, None)
    assert energy > plain  # the springs store energy: the test exercises them


def test_spring_joint_depends_on_the_relative_rotation_only():
    """grad_b = -grad_a and H_bb = H_aa, as for the elastic joint (finite differences on frame B)."""
    rng = np.random.default_rng(2)
    springs = springs_for(16, 1.0)
    frame_a = rotation_matrix(rng.normal(size=3))
    frame_b = frame_a @ rotation_matrix(rng.normal(scale=0.3, size=3)).T
    grad_a, hess_aa, hess_ab = np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))
    energy = spring_terms_into(frame_a, frame_b, springs, FULL, grad_a, hess_aa, hess_ab)
    assert energy == pytest.approx(spring_energy(frame_a, frame_b, springs, FULL), rel=1e-14)
    eps = 1e-5

    def energy_b(delta):
        return spring_energy(frame_a, frame_b @ rotation_matrix(delta).T, springs, FULL)

    grad_b = np.array([(energy_b(eps * e) - energy_b(-eps * e)) / (2 * eps) for e in np.eye(3)])
    assert np.allclose(grad_b, -grad_a, rtol=1e-7, atol=1e-9)
    hess_bb = np.array(
        [[(energy_b(eps * (a + b)) - energy_b(eps * (a - b)) - energy_b(eps * (b - a)) + energy_b(-eps * (a + b)))
          / (4 * eps**2) for b in np.eye(3)] for a in np.eye(3)]
    )
    assert np.allclose(hess_bb, hess_aa, rtol=1e-4, atol=1e-5 * np.max(np.abs(hess_aa)))


def test_second_order_expansion_with_springs():
    """E(exp(delta)) - (E + g.delta + 1/2 delta.H.delta) falls as eps^3 (no kink crossed)."""
    rng = np.random.default_rng(9)
    n_seg, h = 5, 1.1
    springs = springs_for(16, h)
    frames = random_frames(rng, n_seg, spread=0.2)
    # fittings turned away from their neighbours: a spring exactly at rest sits on a table breakpoint
    start = frames[0] @ rotation_matrix(rng.normal(scale=0.2, size=3)).T
    end = frames[-1] @ rotation_matrix(rng.normal(scale=0.2, size=3)).T
    stiffness = np.array([1.0, 1.0, 5.0])
    loads = np.zeros((n_seg, 3))
    e0, g, band = lagrangian(frames, start, end, stiffness, h, loads, False, springs)
    hess = dense(band)
    direction = rng.normal(size=g.size)
    errors = []
    for eps in (2e-4, 1e-4, 5e-5):
        fp, _ = perturbed(frames, end, eps * direction, False)
        e, _, _ = lagrangian(fp, start, end, stiffness, h, loads, False, springs)
        errors.append(abs(e - (e0 + eps * g @ direction + 0.5 * eps**2 * direction @ hess @ direction)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 2.8), orders


def test_energy_and_moments_include_the_springs():
    rng = np.random.default_rng(4)
    h = 0.9
    springs = springs_for(8, h)
    frames = random_frames(rng, 4, spread=0.3)
    start, end = np.eye(3), frames[-1]
    stiffness = np.array([1.0, 1.0, 1.0])
    grad = np.empty(12)
    band = np.empty((12, BANDWIDTH + 1))
    e_el, _ = assemble(frames, start, end, stiffness, h, np.zeros((4, 3)), False, grad, band, True, springs)
    assert elastic_energy(frames, start, end, stiffness, h, True, springs) == pytest.approx(e_el, rel=1e-13)
    with_springs, _ = joint_moments(frames, start, end, stiffness, h, True, springs)
    without, _ = joint_moments(frames, start, end, stiffness, h, True, None)
    # the gradient on each segment is the difference of the moments at its two nodes
    assert np.allclose(grad.reshape(4, 3), with_springs[:-1] - with_springs[1:], atol=1e-12)
    assert not np.allclose(with_springs, without)


def test_geometry_of_equations_9_to_16():
    element, radius = 8.2, 5.05
    for count in (8, 16):
        stiffeners = Stiffeners(count, 71.0, TABLE)
        anchors = stiffeners.anchors(radius, element, element)
        chord = element / math.tan(math.radians(71.0))
        top = np.linalg.norm(anchors[:, 1, :2] - anchors[:, 0, :2], axis=1)
        np.testing.assert_allclose(top, chord, rtol=1e-12)  # len_h in the top view
        np.testing.assert_allclose(np.linalg.norm(anchors[:, 1] - anchors[:, 0], axis=1), element / math.sin(math.radians(71.0)))
        np.testing.assert_allclose(anchors[:, :, 2], np.tile([-0.5 * element, 0.5 * element], (count, 1)))
    eight = Stiffeners(8, 52.0, TABLE).anchors(radius, element, element)
    half = math.asin(0.5 * element / math.tan(math.radians(52.0)) / radius)  # ang_top, equation 9
    final = math.radians(45.0) - half  # equation 10
    np.testing.assert_allclose(eight[0, 0, :2], [radius * math.sin(final), radius * math.cos(final)])  # 11, 12
    sixteen = Stiffeners(16, 71.0, TABLE).anchors(radius, element, element)
    octagon = element / math.tan(math.radians(71.0)) / (2.0 * math.cos(math.radians(67.5)))  # equations 13-16
    np.testing.assert_allclose(np.linalg.norm(sixteen[:, :, :2], axis=2), octagon)
    with pytest.raises(ValueError, match="steeper spring angle"):
        Stiffeners(8, 20.0, TABLE).anchors(radius, element, element)


def test_element_rule_and_regression_reproduce_the_thesis_tables():
    for length in np.round(np.arange(277.8, 2474.0, 0.1), 1):  # Table 10: every length at 0.1 mm, none left over
        assert 8.17 <= length / element_count(length) <= 8.4122 + 1e-12
    assert element_count(330.6) == 40  # 8.265 mm: above the regression range, so 71 deg
    assert spring_angle_deg(330.6 / 40) == 71.0
    for element, angle in ((8.1966, 71), (8.2073, 72), (8.2454, 75)):  # Table 6
        assert spring_angle_deg(element) == pytest.approx(angle, abs=0.2)
    assert spring_angle_deg(8.4122) == 71.0  # constant above 8.2454 mm
    preset = thesis_preset(8.1966 * 40)
    # equation 17 gives 71.2 deg here, so the spring is 8.661 mm against the 8.6688 mm of Table 6 (at 71 deg)
    assert preset.segments == 40 and preset.spring_length == pytest.approx(8.6688, abs=0.01)
    table = preset.stiffeners.table
    # Table 6, 71 deg: x3..x11 = 0.19 .. 0.24, 2.02, 2.3, 5.5 mm; forces 0, 0, 0, 2500, ... 8000 N
    np.testing.assert_allclose(table.deformation[2:8], [0.19, 0.20, 0.21, 0.22, 0.23, 0.24], atol=0.015)
    np.testing.assert_allclose(table.deformation[8:], [2.02, 2.3, 5.5], atol=0.05)
    assert table.force[3] == 2500.0 and table.force[-1] == 8000.0
    assert table.force_at(-20.0) == 0.0 and table.force_at(10.0) > 8000.0  # linear extrapolation
    with pytest.raises(ValueError, match="277.8-2474"):
        thesis_preset(200.0)


def test_thesis_hose_with_stiffeners_places_and_the_springs_stiffen_it():
    preset = thesis_preset(330.6)
    base = Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0,
                segments=preset.segments)
    mounts = (Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]))
    plain = solve(Problem(base, *mounts, end_twist_deg=30.0))
    stiff = solve(Problem(replace(base, stiffeners=preset.stiffeners), *mounts, end_twist_deg=30.0))
    assert stiff.stable and stiff.residual < 1e-10
    assert stiff.elastic_energy > plain.elastic_energy
    assert np.max(np.linalg.norm(stiff.centerline - plain.centerline, axis=1)) > 1.0


def test_the_listed_discrepancies_of_the_thesis_tables_hold():
    """The statements of model/stiffeners.py's list of what the OCR does not settle (so the list cannot go stale)."""
    angle = spring_angle_deg  # equation 17 as printed
    for element, table_angle in ((8.1966, 71), (8.2073, 72), (8.2195, 73), (8.23171, 74), (8.2454, 75)):
        assert 0.11 < angle(element) - table_angle < 0.17  # a constant offset: rounded coefficients
    assert -16446.9 + 3937.17 * 8.4122 - 234.48 * 8.4122**2 == pytest.approx(80.36, abs=0.01)  # text: 80.21 deg
    assert 8.2195 / math.sin(math.radians(73)) == pytest.approx(8.5951, abs=1e-4)  # Table 6 prints 8.571
    for element, table_angle, spring in ((8.1966, 71, 8.6688), (8.2073, 72, 8.6296), (8.23171, 74, 8.563),
                                         (8.2454, 75, 8.5362)):
        assert element / math.sin(math.radians(table_angle)) == pytest.approx(spring, abs=6e-4)
    assert 8.4122 / math.sin(math.radians(75)) == pytest.approx(8.70895, abs=1e-5)  # Table 11, said to be 71 deg
    x9_without_square = -464.698 + 107.589 * 8.6688 - 6.20050 * 8.6688
    assert x9_without_square > 400 and thesis_deformations(8.6688)[8] == pytest.approx(2.02, abs=0.01)
