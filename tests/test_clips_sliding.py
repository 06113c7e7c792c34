"""Sliding clips (guide rings): exact derivatives along the arc-length unknowns, and the placement."""

import numpy as np
import pytest

from hoseline.mechanics.clipped_newton import SlidingSystem, _step, apply_step, evaluate
from hoseline.mechanics.newton import RodProperties, solve_equilibrium
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.mechanics.rotations import rotation_matrix, rotation_vector
from hoseline.model.clips import Clip
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem
from hoseline.procedures.placement.path import weight_vector
from hoseline.procedures.placement.sequence import rod_properties, solve
from tests.test_energy_derivatives import dense, random_frames


def _sliding_rod(rng, end_roll_free):
    count, h = 11, 0.9
    frames = random_frames(rng, count)
    clips = (
        ClipHold(2, rng.normal(size=3), rotation_matrix(rng.normal(size=3)), False),  # fixed
        ClipHold(4, rng.normal(size=3), rotation_matrix(rng.normal(size=3)), True, True),  # sliding
        ClipHold(6, rng.normal(size=3), None, False),  # ball
        ClipHold(8, rng.normal(size=3), rotation_matrix(rng.normal(size=3)), True, True),  # sliding
    )
    clamps = Clamps(
        start_point=rng.normal(size=3), start_frame=rotation_matrix(rng.normal(size=3)),
        end_point=rng.normal(size=3), end_frame=rotation_matrix(rng.normal(size=3)), roll_free=end_roll_free,
        line_weight=rng.normal(size=3), clips=clips,
    )
    props = RodProperties(np.array([1.0, 2.5, 0.7]), h, count)
    arc = np.array([2.0, 4.3, 6.0, 7.8]) * h  # the sliding clips off their stations: spans stretched
    state = RodState(frames, rng.normal(size=3), 0.3, rng.normal(size=(4, 3)), np.array([0.0, 0.4, 0.0, -0.2]), arc)
    return props, clamps, state


@pytest.mark.parametrize("end_roll_free", [False, True])
def test_arc_length_derivatives_match_finite_differences(end_roll_free):
    """Gradient and Hessian of the Lagrangian in all unknowns (rotations, rolls, the two sliding
    arc lengths), and the constraint Jacobian along the arc lengths, against central differences."""
    props, clamps, state = _sliding_rod(np.random.default_rng(7), end_roll_free)
    system = evaluate(props, clamps, state)
    assert isinstance(system, SlidingSystem)
    multipliers = np.concatenate([state.end_force, state.clip_forces.reshape(-1)])
    n, s = system.grad.size, system.stretch_grad.size
    assert s == 2

    def at(delta):
        moved = evaluate(props, clamps, apply_step(props, clamps, state, delta, np.zeros(3)))
        return (moved.energy - multipliers @ moved.constraint, np.concatenate([moved.grad, moved.stretch_grad]),
                moved.constraint)

    eps = 1e-5
    fd_grad, fd_hess, fd_jac = np.empty(n + s), np.empty((n + s, n + s)), np.empty((multipliers.size, n + s))
    for j in range(n + s):
        delta = np.zeros(n + s)
        delta[j] = eps
        (lp, gp, cp), (lm, gm, cm) = at(delta), at(-delta)
        fd_grad[j] = (lp - lm) / (2 * eps)
        fd_hess[:, j] = (gp - gm) / (2 * eps)
        fd_jac[:, j] = (cp - cm) / (2 * eps)
    grad = np.concatenate([system.grad, system.stretch_grad])
    hess = np.block([[dense(system.band), system.mixed], [system.mixed.T, system.stretch_hessian]])
    assert np.allclose(grad, fd_grad, rtol=1e-7, atol=1e-8 * np.max(np.abs(grad)))
    assert np.allclose(system.jac_t.T, fd_jac[:, :n], atol=1e-8)
    assert np.allclose(system.stretch_jac, fd_jac[:, n:], atol=1e-8)
    assert np.allclose(hess, 0.5 * (fd_hess + fd_hess.T), rtol=1e-6, atol=1e-6 * np.max(np.abs(hess)))


def test_bordered_step_with_arc_lengths_solves_the_dense_kkt_system():
    """The step of the border with arc-length columns and its inertia against the dense KKT system."""
    import scipy.linalg

    for seed in range(4):
        props, clamps, state = _sliding_rod(np.random.default_rng(seed), seed % 2 == 0)
        system = evaluate(props, clamps, state)
        step, force_step, unstable = _step(system, 0.0)
        n, m = system.grad.size, system.constraint.size
        hess = np.block([[dense(system.band), system.mixed], [system.mixed.T, system.stretch_hessian]])
        jac = np.hstack([system.jac_t.T, system.stretch_jac])
        kkt = np.block([[hess, -jac.T], [-jac, np.zeros((m, m))]])
        rhs = -np.concatenate([system.grad, system.stretch_grad, -system.constraint])
        dense_solution = np.linalg.solve(kkt, rhs)
        assert np.allclose(step, dense_solution[: step.size], rtol=1e-8, atol=1e-10 * np.max(np.abs(step)))
        assert np.allclose(force_step, dense_solution[step.size:], rtol=1e-8, atol=1e-10 * np.max(np.abs(force_step)))
        basis = scipy.linalg.null_space(jac)
        values = np.linalg.eigvalsh(basis.T @ hess @ basis)
        assert unstable == int(np.sum(values < -1e-10 * np.max(np.abs(values))))
        assert n == 3 * props.segments + 2 + int(seed % 2 == 0)


# --- equilibria with a sliding clip ---



GRAVITY = np.array([0.0, 0.0, -9.81])


def _hose(segments, length=400.0):
    return Hose(length=length, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=1.0e5,
                segments=segments, mass_per_length=0.3)


def _ring_where_the_free_hose_passes(segments):
    # the free hose, and Newton from it with a sliding clip at its point and tangent at 170 mm (the
    # ring frame halfway between the two segments there), the ring started 0.4 segment further on
    free = solve(Problem(_hose(segments), Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 30], [1, 0, 0]), end_twist_deg=90.0,
                         gravity=GRAVITY), estimate_error=False)
    problem, h = free.problem, 400.0 / segments
    k = round(170.0 / h)
    frames = free.frames
    ring = frames[k - 1] @ rotation_matrix(0.5 * rotation_vector(frames[k].T @ frames[k - 1])).T
    clamps = Clamps(problem.start.point, free.start_frame, problem.end.point, free.end_frame, False,
                    weight_vector(problem), clips=(ClipHold(k, free.centerline[k], ring, True, True),))
    start = RodState(frames.copy(), free.end_force.copy(), 0.0, np.zeros((1, 3)), np.zeros(1), np.array([(k + 0.4) * h]))
    state, report = solve_equilibrium(rod_properties(problem), clamps, start)
    assert report.converged and report.unstable_directions == 0
    return (abs(state.clip_arc_lengths[0] - 170.0), np.linalg.norm(state.clip_forces[0]) / np.linalg.norm(free.end_force),
            np.max(np.abs(state.frames[:, 2] - frames[:, 2])))


def test_a_ring_where_the_free_hose_passes_finds_its_arc_length_and_leaves_the_shape():
    """A sliding clip at the point and tangent of the free hose: Newton slides the hose back to the
    free hose's arc length there, the ring carries next to nothing and the shape stays.  Not exactly:
    at the ring the hose's joint is two half joints to the ring frame where the free hose has one
    full joint; the differences vanish under refinement (measured from 40 to 80 segments: arc
    length 0.0124 -> 0.0025 mm, ring force 6.8e-3 -> 7.7e-4 of the end force, tangents 5.8e-4 -> 9.1e-5)."""
    coarse, fine = _ring_where_the_free_hose_passes(40), _ring_where_the_free_hose_passes(80)
    assert coarse[0] < 2e-3 * 10.0 and coarse[1] < 1e-2 and coarse[2] < 1e-3
    for before, after in zip(coarse, fine):
        assert after < before / 4.0  # at least second order


@pytest.fixture(scope="module")
def ring_placed():
    """A guide ring at (0, 120, 0) mm, axis x, over mounts mirror-symmetric about x = 0: the ring
    started at 170 mm, 30 mm before the middle of the 400 mm hose."""
    ring = Clip("sliding", np.array([0.0, 120.0, 0.0]), 170.0, np.array([1.0, 0.0, 0.0]), "ring")
    problem = Problem(_hose(40), Mount([-100, 0, 0], [0.3, 1, 0]), Mount([100, 0, 0], [-0.3, 1, 0]), gravity=GRAVITY,
                      clips=(ring,))
    return solve(problem, estimate_error=False)


def test_a_ring_carries_the_jump_of_the_bending_energy_along_its_axis(ring_placed):
    """The axial force of a frictionless guide ring that holds the hose's direction is not zero: it
    is the jump of the bending energy density M^2 / (2 EI) across the ring, the Eshelby-like force of
    a sliding sleeve (Bigoni et al. 2015, "Eshelby-like forces acting on elastic structures"; for
    each span e + n . t is constant without weight, and sliding balances it across the ring).  Here
    the ring's moment makes the two sides bend differently and the hose slides out of the middle to
    175.8 mm (the mirror shape, at 224.2 mm, is as good: the fittings' mirror symmetry swaps them)."""
    clip, result = ring_placed.clips[0], ring_placed
    axis = np.array([1.0, 0.0, 0.0])
    k = int(np.argmin(np.abs(result.s - clip.arc_length)))
    assert abs(result.s[k] - clip.arc_length) < 1e-9 and np.linalg.norm(result.centerline[k] - clip.point) < 1e-8
    after = result.internal_moment[k]  # the half joint from the ring frame on
    before = after + clip.moment  # the half joint up to the ring: the ring's moment is the jump

    def energy_density(moment):
        bending = moment - (moment @ axis) * axis
        return bending @ bending / (2.0 * 1.5e5)

    jump = energy_density(after) - energy_density(before)
    axial = clip.force @ axis
    assert axial > 0.1 * np.linalg.norm(clip.force)  # far from zero
    # measured: 14.35 N against a jump of 14.26 N (40 segments; 14.390 and 14.386 N at 160)
    assert abs(axial - jump) < 1e-2 * axial
    assert abs(clip.moment @ axis) < 1e-9 * np.linalg.norm(clip.moment)  # the hose rolls freely in the ring
    assert 170.0 < clip.arc_length < 190.0 and result.stability_margin > 0.0


def test_a_sliding_clip_from_the_problem_file_starts_off_station_and_round_trips():
    import tomllib

    from hoseline.io.problem_file import problem_from_dict, problem_to_toml

    data = {"hose": {"length": 400.0, "outer_diameter": 10.0, "bending_stiffness": 1.5e5, "segments": 40},
            "start": {"point": [-100, 0, 0], "direction": [0.3, 1, 0]},
            "end": {"point": [100, 0, 0], "direction": [-0.3, 1, 0]},
            "clips": [{"type": "sliding", "arc_length": 173.0, "point": [0, 120, 0], "direction": [1, 0, 0]}]}
    problem = problem_from_dict(data)  # 173 mm is between stations: only a guess for a sliding clip
    (clip,) = problem_from_dict(tomllib.loads(problem_to_toml(problem))).clips
    assert (clip.kind, clip.arc_length, clip.slides) == ("sliding", 173.0, True)


def test_the_adams_export_holds_a_sliding_clip_by_a_cylindrical_joint(ring_placed, tmp_path):
    from hoseline.io.adams_cmd import adams_cmd_text, read_adams_cmd
    from tests.test_adams_cmd import commands

    path = tmp_path / "hose.cmd"
    path.write_text(adams_cmd_text(ring_placed))
    joints = [(command, p) for _, command, p in commands(path) if p.get("joint_name", [""])[0].endswith("clip_1")]
    assert [command for command, _ in joints] == ["constraint create joint cylindrical"]
    model = read_adams_cmd(path)
    ground = model.markers[joints[0][1]["j_marker_name"][0].lstrip(".")]
    np.testing.assert_allclose(ground[0], ring_placed.clips[0].point, atol=1e-9)  # at the ring, where it came to rest


def test_loads_on_a_hose_in_a_ring_balance(ring_placed):
    """Mounts, ring and weight: forces and moments about the origin sum to zero (the stations at
    their stretched arc lengths)."""
    result = ring_placed
    clip, problem = result.clips[0], result.problem
    h = np.diff(result.s)
    weights = problem.hose.mass_per_length * 1e-3 * GRAVITY[None, :] * h[:, None]
    centres = 0.5 * (result.centerline[1:] + result.centerline[:-1])
    force = result.start_force + result.end_force + clip.force + weights.sum(axis=0)
    moment = (result.start_moment + np.cross(problem.start.point, result.start_force) + result.end_moment
              + np.cross(problem.end.point, result.end_force) + clip.moment + np.cross(clip.point, clip.force)
              + np.cross(centres, weights).sum(axis=0))
    scale = np.linalg.norm(clip.force)
    assert np.linalg.norm(force) < 1e-9 * scale and np.linalg.norm(moment) < 1e-9 * scale * 400.0
    assert abs(result.s[-1] - 400.0) < 1e-9 and result.length_error < 1e-12
