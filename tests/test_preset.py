"""Preset (natural curvature from storage): exact derivatives of the preset joints (finite
differences), the stress-free shape carries no load, and a U-bend moves to the side of the set."""

import math
from dataclasses import replace

import numpy as np
import pytest
from test_energy_derivatives import dense, finite_differences, random_frames

from hoseline import Hose, Mount, Problem, solve
from hoseline.mechanics.energy import BANDWIDTH, assemble, elastic_energy, joint_moments
from hoseline.mechanics.rotations import frame_from_tangent, rotation_matrix
from hoseline.model.preset import Preset, preset_rest_rotations, rest_rotations, stress_free_shape


def lagrangian(frames, start, end, stiffness, h, loads, roll_free, rest):
    n = 3 * frames.shape[0] + (1 if roll_free else 0)
    grad = np.empty(n)
    band = np.empty((n, BANDWIDTH + 1))
    e_el, e_seg = assemble(frames, start, end, stiffness, h, loads, roll_free, grad, band, True, None, rest)
    return e_el + e_seg, grad, band


@pytest.mark.parametrize("stiffness, roll_free", [((1.0, 1.0, 0.7), False), ((1.0, 2.5, 25.0), True)])
def test_gradient_and_hessian_with_preset_match_finite_differences(stiffness, roll_free):
    rng = np.random.default_rng(13)
    count, h = 6, 0.8
    frames = random_frames(rng, count)
    start = rotation_matrix(rng.normal(size=3))
    end = rotation_matrix(rng.normal(size=3))
    stiffness = np.array(stiffness)
    loads = rng.normal(size=(count, 3))
    rest = rest_rotations(rng.normal(scale=0.5, size=(count + 1, 3)), h)  # bend and twist, different per joint
    energy, grad, band = lagrangian(frames, start, end, stiffness, h, loads, roll_free, rest)
    fd_grad, fd_hess = finite_differences(
        lambda f, e: lagrangian(f, start, e, stiffness, h, loads, roll_free, rest)[:2], frames, end, grad.size,
        roll_free, 1e-5,
    )
    assert np.allclose(grad, fd_grad, rtol=1e-7, atol=1e-8 * np.max(np.abs(grad)))
    hess = dense(band)
    assert np.allclose(hess, 0.5 * (fd_hess + fd_hess.T), rtol=1e-6, atol=1e-6 * np.max(np.abs(hess)))
    plain = lagrangian(frames, start, end, stiffness, h, loads, roll_free, None)[0]
    assert abs(energy - plain) > 1e-3 * abs(plain)  # the preset changes the energy: the test exercises it
    e_seg = -np.sum(loads * frames[:, 2])
    assert elastic_energy(frames, start, end, stiffness, h, True, None, rest) == pytest.approx(energy - e_seg,
                                                                                              rel=1e-12)


def test_rest_rotation_has_the_natural_darboux_vector():
    """The stress-free shape's discrete Darboux vector is kappa0 at every joint, its energy and moments zero."""
    rng = np.random.default_rng(2)
    count, h = 8, 2.0
    darboux = rng.normal(scale=0.05, size=(count + 1, 3))
    rest = rest_rotations(darboux, h)
    start = rotation_matrix(rng.normal(size=3))
    frames, _, end = stress_free_shape(rest, np.zeros(3), start, h)
    stiffness = np.array([3.0, 2.0, 5.0])
    moments, measured = joint_moments(frames, start, end, stiffness, h, True, None, rest)
    assert np.allclose(measured, darboux, atol=1e-13)
    assert np.allclose(moments, 0.0, atol=1e-13)
    assert elastic_energy(frames, start, end, stiffness, h, True, None, rest) == pytest.approx(0.0, abs=1e-24)
    assert elastic_energy(frames, start, end, stiffness, h, True, None, None) > 0.0


def preset_hose(preset, segments=40):
    return Hose(length=300.0, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=1.0e5,
                segments=segments, preset=preset)


def test_the_set_bends_towards_cos_psi_d1_plus_sin_psi_d2():
    """Convention of model/preset.py: start direction +y gives d1 = +x, d2 = -z; psi = 0 curls towards +x, 90 to -z."""
    start = frame_from_tangent(np.array([0.0, 1.0, 0.0]))
    assert np.allclose(start, [[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    for angle, side in ((0.0, [1.0, 0.0, 0.0]), (90.0, [0.0, 0.0, -1.0]), (200.0, [math.cos(math.radians(200)), 0.0,
                                                                                    -math.sin(math.radians(200))])):
        rest = preset_rest_rotations(Preset(1.0 / 200.0, angle), 30, 2.0)
        _, nodes, _ = stress_free_shape(rest, np.zeros(3), start, 2.0)
        sideways = nodes[-1] - nodes[-1][1] * np.array([0.0, 1.0, 0.0])
        assert np.allclose(sideways / np.linalg.norm(sideways), side, atol=1e-12)


def test_preset_hose_between_mounts_of_its_stress_free_shape_carries_no_load():
    """Mounts at the ends of the natural arc (120 degrees of set), with its end frames: no reactions, the arc itself."""
    preset = Preset(curvature=(2.0 * math.pi / 3.0) / 300.0, angle_deg=30.0)
    hose = preset_hose(preset)
    start = Mount([0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    rest = preset_rest_rotations(preset, hose.segments, hose.segment_length)
    _, nodes, end_frame = stress_free_shape(rest, start.point, frame_from_tangent(start.direction), hose.segment_length)
    result = solve(Problem(hose, start, Mount(nodes[-1], -end_frame[2]), 0.0), estimate_error=False)
    scale = hose.bending_stiffness * preset.curvature  # the moment the set would carry if straightened, N*mm
    assert np.max(np.abs(result.centerline - nodes)) < 1e-6
    assert np.linalg.norm(result.end_force) < 1e-8 * scale / hose.length
    assert np.linalg.norm(result.end_moment) < 1e-8 * scale
    assert np.linalg.norm(result.start_moment) < 1e-8 * scale
    assert abs(result.lock_angle_deg) < 1e-6  # the arc's own end frame: no roll to release
    plain = solve(Problem(replace(hose, preset=None), start, Mount(nodes[-1], -end_frame[2]), 0.0),
                  estimate_error=False)
    assert np.linalg.norm(plain.end_moment) > 0.5 * scale  # without the set the same arc is loaded


def u_bend(angle_deg, curvature=1.0 / 150.0, segments=40):
    """The hose in a U between parallel mounts 100 mm apart in the x-y plane, the set at angle_deg."""
    hose = preset_hose(None if curvature == 0.0 else Preset(curvature, angle_deg), segments)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]), Mount([100.0, 0.0, 0.0], [0.0, 1.0, 0.0]), 0.0)
    return solve(problem, estimate_error=False).centerline


def test_u_bend_moves_to_the_side_of_the_set():
    """A set out of the U's plane (towards -z at psi = 90: d2 = -z all along the planar U) takes the bend off the
    plane to the side of the set; the opposite set gives the mirror image.  (Not symmetric about the U's mid-plane:
    the end fitting is clamped at the torque-free roll found in the placement, about -62 degrees here.)"""
    straight = u_bend(0.0, curvature=0.0)
    assert np.max(np.abs(straight[:, 2])) < 1e-9  # a planar U without set
    down, up = u_bend(90.0), u_bend(-90.0)
    apex = np.argmax(straight[:, 1])
    assert down[apex, 2] < -20.0  # mm, towards the set (-z): about -32 mm
    assert np.allclose(up, down * [1.0, 1.0, -1.0], atol=1e-6)  # the mirror image


@pytest.mark.parametrize("direction, d1", [((0.0, 1.0, 0.0), (1.0, 0.0, 0.0)), ((0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
                                           ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))])
def test_the_set_reference_ties_go_to_the_first_axis_and_survive_cad_rounding(direction, d1):
    # axis-aligned mounts tie between two world axes: the first of x, y, z is d1, also after rounding of a CAD direction
    assert np.allclose(frame_from_tangent(direction)[0], d1)
    rounded = np.array(direction) + np.array([2e-16, 1e-16, 1e-16]) * (np.array(direction) == 0.0)
    assert np.allclose(frame_from_tangent(rounded)[0], d1)
    hose = preset_hose(Preset(1.0 / 150.0, 90.0), 40)
    exact, off = (solve(Problem(hose, Mount([0.0, 0.0, 0.0], start), Mount([100.0, 0.0, 0.0], [0.0, 1.0, 0.0]), 0.0),
                        estimate_error=False).centerline for start in ([0.0, 1.0, 0.0], [1e-16, 1.0, 0.0]))
    assert np.allclose(exact, off, atol=1e-6)  # the set's side does not turn by 90 degrees


def test_a_set_out_of_plane_converges_at_second_order_and_its_error_estimate_holds():
    """The thesis hose (weight, 25x torsion) with a set of R 300 mm towards 60 deg, twisted to 180 deg: bend and
    twist out of the set's plane.  Against a 512-segment solve the largest station error falls at order 2 (measured
    2.06-2.10 from 32 to 256 segments; 0.126 and 0.030 mm at 64 and 128) and the Richardson estimate, which assumes
    order 2, holds it (estimate/error 1.06-1.09).  With the stress-free rotation applied on one side of each joint
    (R0^T Q) the order was 0.9-1.2, 1.11 and 0.54 mm at 64 and 128 segments, and the estimate a third of the error."""
    from dataclasses import replace as with_fields
    from validation_cases import brake_hose
    from scipy.interpolate import CubicSpline

    def placed(segments):
        problem = brake_hose(segments=segments, twist=180.0)
        return solve(with_fields(problem, hose=with_fields(problem.hose, preset=Preset(1.0 / 300.0, 60.0))))

    reference = placed(512)
    exact = CubicSpline(reference.s, reference.centerline, axis=0)
    errors = {}
    for segments in (64, 128):
        result = placed(segments)
        errors[segments] = float(np.max(np.linalg.norm(result.centerline - exact(result.s), axis=1)))
        assert 1.0 <= result.discretisation_error / errors[segments] < 1.3
    assert math.log2(errors[64] / errors[128]) > 1.8


def test_a_set_in_the_plane_of_a_u_bend_leaves_it_unchanged_as_segments_shrink():
    """Continuum: for a planar clamped shape the set adds -EI kappa0 int kappa ds, fixed by the end tangents, so the
    shape does not change.  The discrete rest rotations match (kappa - kappa0)^2 to O(h^2): the change falls as h^2."""
    changes = [np.max(np.abs(u_bend(0.0, segments=n) - u_bend(0.0, curvature=0.0, segments=n))) for n in (40, 80)]
    assert changes[0] < 0.05  # mm
    assert changes[0] / changes[1] > 3.5


def problem_dict(**hose_keys):
    return {
        "hose": {"length": 300.0, "outer_diameter": 10.0, "bending_stiffness": 1.5e5, **hose_keys},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [0.0, 1.0, 0.0]},
        "end": {"point": [100.0, 0.0, 0.0], "direction": [0.0, 1.0, 0.0]},
    }


def test_problem_file_keys_round_trip_and_bad_input_is_refused():
    from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_dict

    problem = problem_from_dict(problem_dict(preset_radius=250.0, preset_angle_deg=-40.0))
    assert problem.hose.preset == Preset(1.0 / 250.0, -40.0)
    again = problem_from_dict(problem_to_dict(problem))
    assert again.hose.preset.radius == pytest.approx(250.0) and again.hose.preset.angle_deg == -40.0
    assert problem_from_dict(problem_dict(preset_radius=250.0)).hose.preset.angle_deg == 0.0
    assert problem_from_dict(problem_dict()).hose.preset is None
    for keys, words in (({"preset_angle_deg": 10.0}, "without preset_radius"),
                        ({"preset_radius": -5.0}, "preset_radius"),
                        ({"preset_radius": 100.0, "stiffeners": {"preset": "thesis"}}, "stiffeners")):
        with pytest.raises(ProblemFileError, match=words):
            problem_from_dict(problem_dict(**keys))
    ball = {"type": "ball", "arc_length": 150.0, "point": [50, 80, 0]}
    clipped = problem_dict(preset_radius=250.0) | {"clips": [ball]}
    with pytest.raises(ProblemFileError, match="clips"):
        problem_from_dict(clipped)
