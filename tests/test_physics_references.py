"""The physics against references that do not come from the solver: closed forms (a twisted
straight hose, a circular arc), a construction (the torque-free lock as a twist-free transport of
the start frame) and an independent solver (the Kirchhoff equations as a SciPy boundary-value
problem, kirchhoff_bvp.py, with its frames and twists from scipy.spatial.transform).

Tolerances are about 3x the agreement measured at the segment counts used (the discrete rod is
second order: the figures fall 4x per doubling of the segments), noted beside each."""

import math
from dataclasses import replace

import numpy as np
import pytest
from kirchhoff_bvp import KirchhoffRod, guess_from_result
from reference_shapes import heavy_thesis_hose
from scipy.spatial.transform import Rotation
from validation_cases import brake_hose

from hoseline import Hose, Mount, Problem, solve
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.procedures.placement.hose_health import hose_health

EI = 1.5e5  # N*mm^2
GJ_ISOTROPIC = EI / 1.5


def test_a_straight_hose_twisted_carries_gj_theta_over_l_at_a_uniform_rate():
    """Mounts facing each other on the x axis, 1 um closer than the length (the hose bows by 0.24 mm):
    turning the end fitting by theta about end.direction (= -x, so by -theta about the hose's
    tangent +x) twists the hose uniformly at -theta/L, against the moment GJ theta / L."""
    length, segments, theta = 200.0, 20, math.radians(90.0)
    hose = Hose(length=length, outer_diameter=10.0, bending_stiffness=EI, torsional_stiffness=GJ_ISOTROPIC,
                segments=segments)
    end = Mount([length - 1e-3, 0.0, 0.0], [-1.0, 0.0, 0.0])
    result = solve(Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), end, math.degrees(theta)))
    moment = GJ_ISOTROPIC * theta / length
    # measured 2.0e-3 relative: the joints' moment is K phi (1 + phi^2 / 3) for phi = theta / N per joint
    np.testing.assert_allclose(result.twisting_moment, -moment, rtol=6e-3)
    assert result.end_moment @ end.direction == pytest.approx(moment, rel=6e-3)  # the mount turns the hose its way
    np.testing.assert_allclose(result.twist_rate, -theta / length, rtol=5e-3)  # measured 1.6e-3 (end joints)


U_STIFFNESS = (EI, EI, 2.5e5)  # EI1, EI2, GJ: N*mm^2


def _u_bend(segments, twist_deg, stiffness=U_STIFFNESS, tilt=0.0):
    """A 300 mm hose from the origin to (0, 80, 0), both directions about +x (tilted by `tilt` in
    y, mirror-symmetrically): a U in the plane z = 0."""
    hose = Hose(length=300.0, outer_diameter=10.0, bending_stiffness=stiffness[0], bending_stiffness_2=stiffness[1],
                torsional_stiffness=stiffness[2], segments=segments)
    return Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, tilt, 0.0]), Mount([0.0, 80.0, 0.0], [1.0, -tilt, 0.0]), twist_deg)


def _untwisted_u_reference(problem, stiffness, start_frame):
    """The Kirchhoff BVP (stiffness EI1, EI2, GJ) of a planar U problem at zero twist: the end frame
    is the start frame turned about +z by the angle from the start tangent to the arriving tangent
    (no twist along the plane).  Returns the rod, its solution and that end frame."""
    t0, t1 = problem.start.direction, -problem.end.direction
    turn = Rotation.from_rotvec([0.0, 0.0, math.atan2(np.cross(t0, t1)[2], t0 @ t1)])
    rod = KirchhoffRod(stiffness, problem.start.point, start_frame, problem.end.point)
    guess = solve(replace(problem, end_twist_deg=0.0))
    untwisted_end = turn * start_frame
    return rod, rod.solve(*guess_from_result(guess), end_frame=untwisted_end), untwisted_end


def test_twisting_a_u_bend_turns_it_out_of_plane_by_the_right_hand_rule():
    """The U's end fitting turned by +30 deg about end.direction.  Which way the hose leaves its
    plane follows from the BVP, whose end frame is turned by scipy's right-hand rotation; the
    mount layout is symmetric under the half turn about the line y = 40 mm (along x), so the two
    halves leave the plane to opposite sides and the midpoint stays in it."""
    problem = _u_bend(40, 30.0)
    result = solve(problem)
    start_frame = Rotation.from_matrix(result.start_frame.T)  # isotropic: any frame with d3 = start.direction
    rod, untwisted, untwisted_end = _untwisted_u_reference(problem, U_STIFFNESS, start_frame)
    reference = rod.twisted(untwisted, untwisted_end, problem.end.direction, 30.0)
    exact = reference.sol(result.s)
    # measured 0.124 mm at 40 segments (0.494 at 20, 0.031 at 80)
    assert np.max(np.linalg.norm(result.centerline - exact[:3].T, axis=1)) < 0.37
    for station in (10, 30):  # s = L/4 and 3L/4: 2.84 mm out of the plane, on opposite sides
        assert abs(exact[2, station]) > 2.0
        assert np.sign(result.centerline[station, 2]) == np.sign(exact[2, station])
    # an isotropic section carries the same twisting moment everywhere: m . d3 of the BVP
    tangents = Rotation.from_quat(exact[3:7].T).as_matrix()[:, :, 2]
    twisting = np.einsum("ij,ij->i", exact[10:13].T, tangents)
    assert np.ptp(twisting) < 1e-6 * abs(twisting[0])
    np.testing.assert_allclose(result.twisting_moment, twisting[0], rtol=0.02)  # measured 0.7 %


def test_an_anisotropic_section_bends_about_the_axis_its_clamp_frame_names():
    """Start direction (1, 0.2, 0): the clamp frame's d1 is the world axis least aligned with it,
    z (Hose: bending_stiffness is EI about d1), so the U in the plane z = 0 bends about d1 and
    takes its soft EI1 = EI2 / 3.  The BVP with the section so oriented gives the end force."""
    stiffness = (EI / 3.0, EI, 2.5e5)
    problem = _u_bend(40, 0.0, stiffness, tilt=0.2)
    result = solve(problem)
    t0 = problem.start.direction
    d1 = np.array([0.0, 0.0, 1.0])
    start_frame = Rotation.from_matrix(np.column_stack([d1, np.cross(t0, d1), t0]))
    _, reference, _ = _untwisted_u_reference(problem, stiffness, start_frame)
    assert result.stable and np.max(np.abs(result.centerline[:, 2])) < 1e-9  # stays in its plane
    # measured 0.6 % at 40 segments; bending about d2 instead would triple the force
    np.testing.assert_allclose(result.end_force, reference.y[7:10, -1], atol=0.02 * np.linalg.norm(result.end_force))


def test_the_lock_angle_is_the_torque_free_roll_of_the_end_fitting():
    """Mounts out of one plane, isotropic and weightless hose, no twist.  Torque free, the hose
    carries no twisting moment, and its end frame is the start frame carried along the centreline
    without twist (discrete parallel transport, joint by joint).  The lock angle is that frame's
    roll from the nominal end frame: the start frame turned about t0 x t1 by the angle between
    the tangents (docs/model.md, placement)."""
    hose = Hose(length=300.0, outer_diameter=10.0, bending_stiffness=EI, torsional_stiffness=GJ_ISOTROPIC, segments=30)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([60.0, 120.0, 70.0], [0.2, -1.0, 0.6]))
    result = solve(problem)
    # exact up to rounding (the tolerances leave room for other machines' rounding): measured 8.8e-16
    assert np.max(np.abs(result.twisting_moment)) < 1e-12 * np.max(result.bending_moment)

    tangents = np.vstack([result.start_frame[2], result.frames[:, 2], -problem.end.direction])
    d1 = result.start_frame[0]
    for a, b in zip(tangents[:-1], tangents[1:]):
        axis = np.cross(a, b)
        d1 = Rotation.from_rotvec(axis / np.linalg.norm(axis) * math.atan2(np.linalg.norm(axis), a @ b)).apply(d1)
    np.testing.assert_allclose(result.end_frame[0], d1, atol=1e-12)  # measured 1.6e-15

    t0, t1 = problem.start.direction, -problem.end.direction
    normal = np.cross(t0, t1)
    nominal = Rotation.from_rotvec(normal / np.linalg.norm(normal) * math.atan2(np.linalg.norm(normal), t0 @ t1))
    nominal_d1 = nominal.apply(result.start_frame[0])
    roll = math.degrees(math.atan2(np.cross(nominal_d1, d1) @ t1, nominal_d1 @ d1))  # right-hand about t1
    assert abs(roll) > 20.0  # a case where the lock matters (-142 deg)
    assert result.lock_angle_deg == pytest.approx(roll, abs=1e-10)  # degrees, measured 9e-14


def test_minimum_bend_radius_of_a_quarter_circle_is_measured_to_the_inside_of_the_bend():
    """A hose of length pi R / 2 from the origin along +x to (R, R, 0) arriving along +y: the
    circular arc of radius R is its equilibrium (a pure moment EI / R, no force).  Catalogues
    give the bend radius to the inside of the bend: R - outer radius."""
    radius, outer = 60.0, 6.0
    hose = Hose(length=math.pi * radius / 2.0, outer_diameter=2.0 * outer, bending_stiffness=EI,
                torsional_stiffness=GJ_ISOTROPIC, segments=20)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([radius, radius, 0.0], [0.0, -1.0, 0.0]))
    result = solve(problem)
    on_arc = np.linalg.norm(result.centerline - [0.0, radius, 0.0], axis=1) - radius
    assert np.max(np.abs(on_arc)) < 0.09  # mm, measured 0.029
    assert np.linalg.norm(result.end_force) < 0.1 * EI / radius**2  # measured 0.031 EI / R^2
    assert result.min_bend_radius == pytest.approx(radius - outer, abs=0.65)  # mm, measured 0.21
    # the same measure at every pose of a sweep (hose_health), station by station
    clamps = Clamps(problem.start.point, result.start_frame, problem.end.point, result.end_frame, False, np.zeros(3))
    props = RodProperties(hose.stiffness_vector, hose.segment_length, hose.segments)
    health = hose_health(props, clamps, RodState(result.frames, result.end_force), outer)
    np.testing.assert_allclose(health.bend_radius, radius - outer, atol=0.8)  # mm, measured 0.27


@pytest.mark.parametrize("twist, measured", [(0.0, 0.179), (180.0, 0.281)])
def test_a_heavy_twisted_hose_matches_the_kirchhoff_solution(twist, measured):
    """The thesis hose weighing 0.3 kg/m under gravity -z, at 40 segments: shape and end force
    against the BVP (the weight's size, direction and sense, the torque-free lock and the twist)."""
    result = solve(brake_hose(segments=40, twist=twist))
    reference = heavy_thesis_hose((0.0, 180.0))[twist]
    exact = reference.sol(result.s)
    assert np.max(np.linalg.norm(result.centerline - exact[:3].T, axis=1)) < 3.0 * measured  # mm, measured beside
    force = exact[7:10, -1]
    assert np.linalg.norm(result.end_force - force) < 0.02 * np.linalg.norm(force)  # measured 0.6 / 0.7 %
