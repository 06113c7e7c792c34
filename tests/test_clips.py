"""Clips (intermediate supports): exact derivatives, and the placement against independent references."""

from dataclasses import replace

import numpy as np
import pytest

from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_toml
from hoseline.mechanics.banded import ldlt_banded
from hoseline.mechanics.bordered import kkt_solve_bordered
from hoseline.mechanics.clipped_newton import apply_step, evaluate
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.mechanics.rotations import rotation_matrix
from hoseline.model.clips import Clip
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem
from hoseline.procedures.placement.sequence import solve
from tests.test_energy_derivatives import dense, random_frames


def _clipped_rod(rng, end_roll_free, springs=None):
    count, h = 9, 0.9  # a span of one segment only would fix |x_k - x_(k-1)| = h: J rank deficient
    frames = random_frames(rng, count)
    clips = (
        ClipHold(2, rng.normal(size=3), rotation_matrix(rng.normal(size=3)), False),  # fixed
        ClipHold(4, rng.normal(size=3), rotation_matrix(rng.normal(size=3)), True),  # rotating
        ClipHold(6, rng.normal(size=3), None, False),  # ball
    )
    clamps = Clamps(
        start_point=rng.normal(size=3), start_frame=rotation_matrix(rng.normal(size=3)),
        end_point=rng.normal(size=3), end_frame=rotation_matrix(rng.normal(size=3)), roll_free=end_roll_free,
        line_weight=rng.normal(size=3), clips=clips,
    )
    props = RodProperties(np.array([1.0, 2.5, 0.7]), h, count, springs)
    state = RodState(frames, rng.normal(size=3), 0.3, rng.normal(size=(3, 3)), np.array([0.0, 0.4, 0.0]))
    return props, clamps, state


@pytest.mark.parametrize("end_roll_free, with_springs", [(False, False), (True, False), (True, True)])
def test_clipped_gradient_hessian_and_jacobian_match_finite_differences(end_roll_free, with_springs):
    """Gradient and Hessian of the Lagrangian (joints to the clip frames, clip roll, clip forces in
    the segment loads, stiffener springs in the half joints) and the constraint Jacobian (end and
    clip positions) against central differences."""
    from tests.test_stiffeners import springs_for

    springs = springs_for(8, 0.9) if with_springs else None
    props, clamps, state = _clipped_rod(np.random.default_rng(5), end_roll_free, springs)
    system = evaluate(props, clamps, state)
    multipliers = np.concatenate([state.end_force, state.clip_forces.reshape(-1)])
    n = system.grad.size
    assert n == 3 * props.segments + 1 + int(end_roll_free)  # the rotating clip adds one unknown

    def at(delta):
        moved = evaluate(props, clamps, apply_step(props, clamps, state, delta, np.zeros(3)))
        return moved.energy - multipliers @ moved.constraint, moved.grad, moved.constraint

    eps = 1e-5
    fd_grad, fd_hess, fd_jac = np.empty(n), np.empty((n, n)), np.empty((n, multipliers.size))
    for j in range(n):
        delta = np.zeros(n)
        delta[j] = eps
        (lp, gp, cp), (lm, gm, cm) = at(delta), at(-delta)
        fd_grad[j] = (lp - lm) / (2 * eps)
        fd_hess[:, j] = (gp - gm) / (2 * eps)
        fd_jac[j] = (cp - cm) / (2 * eps)
    # measured: gradient and Jacobian agree to ~1e-10 relative, the Hessian to ~1e-9
    assert np.allclose(system.grad, fd_grad, rtol=1e-7, atol=1e-8 * np.max(np.abs(system.grad)))
    assert np.allclose(system.jac_t, fd_jac, atol=1e-8)
    hess = dense(system.band)
    assert np.allclose(hess, 0.5 * (fd_hess + fd_hess.T), rtol=1e-6, atol=1e-6 * np.max(np.abs(hess)))


# --- placement with clips ---


GRAVITY = np.array([0.0, 0.0, -9.81])
CLIP_POINT, CLIP_DIRECTION = np.array([-60.0, 120.0, 10.0]), np.array([-1.0, 0.3, 0.0])


def _hose(length, segments):
    # isotropic bending: with a free roll the centreline does not depend on the roll of the frames
    return Hose(length=length, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=1.0e5,
                segments=segments, mass_per_length=0.3)


def _clipped_problem(kind, twist=90.0):
    clip = Clip(kind, CLIP_POINT, 200.0, None if kind == "ball" else CLIP_DIRECTION)
    return Problem(_hose(400.0, 40), Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 30], [1, 0, 0]),
                   end_twist_deg=twist, gravity=GRAVITY, clips=(clip,))


@pytest.fixture(scope="module")
def placed():
    return {kind: solve(_clipped_problem(kind), estimate_error=False) for kind in ("fixed", "rotating", "ball")}


def test_fixed_clip_splits_the_hose_into_two_independent_solves(placed):
    """A fixed clip at mid-length: the same shape as start -> clip and clip -> end solved apart
    (each placed by its own continuation; the clip is the second one's start fitting)."""
    whole = placed["fixed"]
    problem = _clipped_problem("fixed")
    first = solve(Problem(_hose(200.0, 20), problem.start, Mount(CLIP_POINT, -CLIP_DIRECTION), gravity=GRAVITY),
                  estimate_error=False)
    second = solve(Problem(_hose(200.0, 20), Mount(CLIP_POINT, CLIP_DIRECTION), problem.end, end_twist_deg=90.0,
                           gravity=GRAVITY), estimate_error=False)
    apart = np.vstack([first.centerline, second.centerline[1:]])
    # measured 2e-12 L (both converged to 1e-11); the issue asks for 1e-6 L
    assert np.max(np.linalg.norm(whole.centerline - apart, axis=1)) < 1e-6 * 400.0
    # the clip carries what the two fittings at its point carry apart (measured 1e-10 relative)
    clip_force = first.end_force + second.start_force
    assert np.linalg.norm(whole.clips[0].force - clip_force) < 1e-7 * np.linalg.norm(clip_force)


@pytest.mark.parametrize("clip_twist", [40.0, -130.0])
def test_a_fixed_clips_twist_turns_it_from_its_lock_as_an_end_fitting_would_be(clip_twist):
    """A fixed clip at mid-length turned by its twist (right-handed about the clip direction) from the roll it is
    locked at: the same shape as the two halves solved apart, the first ending at the clip turned by -twist about
    its end direction (the clip direction reversed), the second turned by the end's twist plus the clip's (its
    start, the clip, turned the same way).  The held roll is the lock's plus the twist."""
    problem = _clipped_problem("fixed")
    (clip,) = problem.clips
    whole = solve(replace(problem, clips=(replace(clip, twist_deg=clip_twist),)), estimate_error=False)
    first = solve(Problem(_hose(200.0, 20), problem.start, Mount(CLIP_POINT, -CLIP_DIRECTION), end_twist_deg=-clip_twist,
                          gravity=GRAVITY), estimate_error=False)
    second = solve(Problem(_hose(200.0, 20), Mount(CLIP_POINT, CLIP_DIRECTION), problem.end,
                           end_twist_deg=90.0 + clip_twist, gravity=GRAVITY), estimate_error=False)
    apart = np.vstack([first.centerline, second.centerline[1:]])
    assert np.max(np.linalg.norm(whole.centerline - apart, axis=1)) < 1e-6 * 400.0
    untwisted = solve(problem, estimate_error=False)
    assert np.max(np.linalg.norm(whole.centerline - untwisted.centerline, axis=1)) > 1.0  # the twist does something
    turned = whole.clips[0].locked_roll_deg - untwisted.clips[0].locked_roll_deg
    assert abs(np.remainder(turned - clip_twist + 180.0, 360.0) - 180.0) < 1e-6


def test_rotating_clip_carries_no_axial_moment_a_fixed_clip_does(placed):
    axis = CLIP_DIRECTION / np.linalg.norm(CLIP_DIRECTION)
    rotating, fixed = placed["rotating"].clips[0], placed["fixed"].clips[0]
    scale = np.linalg.norm(fixed.moment)
    assert abs(rotating.moment @ axis) < 1e-9 * scale  # measured ~1e-13 of the moment
    assert abs(fixed.moment @ axis) > 1e-2 * scale  # the end twist is carried by the fixed clip
    assert np.allclose(placed["ball"].clips[0].moment, 0.0)


@pytest.mark.parametrize("kind", ["fixed", "rotating", "ball"])
def test_loads_on_a_clipped_hose_balance(placed, kind):
    """Mounts, clip and weight: the forces and the moments about the origin sum to zero."""
    result = placed[kind]
    clip = result.clips[0]
    problem = result.problem
    weight = problem.hose.mass_per_length * 1e-3 * GRAVITY * problem.hose.length
    centroid = 0.5 * (result.centerline[1:] + result.centerline[:-1]).mean(axis=0)
    force = result.start_force + result.end_force + clip.force + weight
    moment = (result.start_moment + np.cross(problem.start.point, result.start_force) + result.end_moment
              + np.cross(problem.end.point, result.end_force) + clip.moment + np.cross(clip.point, clip.force)
              + np.cross(centroid, weight))
    assert np.linalg.norm(force) < 1e-8 * np.linalg.norm(weight)  # measured ~1e-13
    assert np.linalg.norm(moment) < 1e-8 * np.linalg.norm(weight) * 400.0
    assert result.stability_margin > 0.0
    assert np.linalg.norm(result.centerline[20] - CLIP_POINT) < 1e-9 * 400.0


@pytest.mark.parametrize("kind", ["rotating", "fixed"])
def test_a_clip_on_the_start_axis_over_a_nearly_straight_span_places_stable(kind):
    """A clip 19 mm above the start mount on its axis, 20.1 mm of hose (3 segments) between them: the
    span is pushed into a buckle carrying kN, and the factor of its Hessian grows by 1e11 at the
    first segment (tests/test_bordered_inertia.py).  The pivot count used to drop the negative
    pivots under the grown one and report -3 unstable directions, so the placement found no
    stable state after the buckle.  The span may turn about the common axis of mount and clip at
    no cost: the placed hose is neutral, not unstable, and the rotating clip carries no axial moment."""
    problem = problem_from_dict({
        "hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "clips": [{"type": kind, "point": [-100.0, 0.0, -61.0], "direction": [0.0, 0.0, 1.0], "arc_length": 20.1}],
    })
    result = solve(problem, estimate_error=False)
    assert result.stable and result.stability_margin == 0.0  # neutral: the span turns about the axis
    assert any("neutral stability" in event for event in result.events)
    assert np.linalg.norm(result.centerline[3] - [-100.0, 0.0, -61.0]) < 1e-9 * 335.0
    clip = result.clips[0]
    assert abs(clip.moment[2]) < 1e-9 * np.linalg.norm(clip.moment)  # measured 0 (the hose stays in the x-z plane)
    # the buckled span pushes the clip up and the mount down: 7.27 kN at 50 segments (three in the span;
    # the clamped-clamped Euler load of 20.1 mm is 9.8 kN)
    assert 5e3 < -clip.force[2] < 1e4 and abs(clip.force[2] + result.start_force[2]) < 2.0


def test_bordered_inertia_matches_the_dense_reduced_hessian():
    """The unstable count of the bordered solve (neg(D) + pos(S) - m) equals the number of negative
    eigenvalues of the Hessian on the null space of the clip and end constraints."""
    import scipy.linalg

    for seed in range(6):
        props, clamps, state = _clipped_rod(np.random.default_rng(seed), seed % 2 == 0)
        system = evaluate(props, clamps, state)
        lower, diag, negative, _ = ldlt_banded(system.band, 0.0)
        unstable = kkt_solve_bordered(lower, diag, negative, system.jac_t, system.grad, system.constraint)[2]
        basis = scipy.linalg.null_space(system.jac_t.T)
        values = np.linalg.eigvalsh(basis.T @ dense(system.band) @ basis)
        assert unstable == int(np.sum(values < -1e-10 * np.max(np.abs(values))))


# --- the problem file ---


def _file(**clip):
    return {"hose": {"length": 400.0, "outer_diameter": 10.0, "bending_stiffness": 1.5e5, "segments": 40},
            "start": {"point": [0, 0, 0], "direction": [0, 1, 0]}, "end": {"point": [-200, 0, 30], "direction": [1, 0, 0]},
            "clips": [{"type": "fixed", "arc_length": 200.0, "point": [-60, 120, 10], "direction": [-1, 0.3, 0]} | clip]}


def test_clips_round_trip_through_the_problem_file():
    import tomllib

    problem = problem_from_dict(_file(name="bracket", twist=-12.5))
    again = problem_from_dict(tomllib.loads(problem_to_toml(problem)))
    (clip,), (read,) = problem.clips, again.clips
    assert (read.kind, read.name, read.arc_length, read.twist_deg) == ("fixed", "bracket", 200.0, -12.5)
    assert np.array_equal(read.point, clip.point) and np.array_equal(read.direction, clip.direction)


@pytest.mark.parametrize("clip, message", [
    ({"type": "hinge"}, "must be one of fixed, rotating, sliding, ball"),
    ({"arc_length": 201.0}, "use arc_length = 200 or 210 mm"),
    ({"arc_length": 395.0}, "use arc_length = 390 mm, or hose.segments = 80"),
    ({"arc_length": 390.0}, "needs at least two"),
    ({"point": [-300, 100, 0]}, "cannot reach"),
    ({"type": "ball"}, "remove direction"),
    ({"colour": "red"}, "unknown key 'clips[0].colour'"),
    ({"type": "rotating", "twist": 10.0}, "twist = 10: only a fixed clip holds the hose's roll"),
    ({"twist": float("nan")}, "clips[0].twist"),
])
def test_bad_clips_are_refused_naming_the_fix(clip, message):
    with pytest.raises(ProblemFileError, match="clips\\[0\\]") as error:
        problem_from_dict(_file(**clip), "p.toml")
    assert message in str(error.value)


def test_clipped_placement_estimates_its_discretisation_error(placed):
    """The Richardson estimate with clips (coarse solve on the even stations) against a solve at
    twice the segments: the estimate is the error of the 40-segment shape at its stations."""
    problem = _clipped_problem("rotating")
    coarse = solve(problem)  # 40 segments, estimate from 20
    fine = solve(Problem(_hose(400.0, 160), problem.start, problem.end, end_twist_deg=90.0, gravity=GRAVITY,
                         clips=problem.clips), estimate_error=False)
    true_error = np.max(np.linalg.norm(coarse.centerline - fine.centerline[::4], axis=1)) * 16.0 / 15.0
    assert coarse.discretisation_error is not None
    # measured 0.5 % here (2 % with a fixed or a ball clip): the order-2 law holds with clips
    assert abs(coarse.discretisation_error - true_error) < 0.02 * true_error


@pytest.mark.parametrize("kind, joint", [("fixed", "fixed"), ("rotating", "revolute"), ("ball", "spherical")])
def test_adams_export_holds_each_clip_by_a_joint_of_its_kind(placed, kind, joint, tmp_path):
    from hoseline.io.adams_cmd import adams_cmd_text, hose_from_adams, read_adams_cmd
    from tests.test_adams_cmd import commands

    path = tmp_path / "hose.cmd"
    path.write_text(adams_cmd_text(placed[kind]))
    clip_joints = [p for _, command, p in commands(path) if command.startswith("constraint create joint")
                   and p["joint_name"][0].endswith("clip_1")]
    kinds = [command for _, command, p in commands(path) if p.get("joint_name", [""])[0].endswith("clip_1")]
    assert kinds == [f"constraint create joint {joint}"]
    model = read_adams_cmd(path)
    i_pose, j_pose = (model.markers[clip_joints[0][key][0].lstrip(".")] for key in ("i_marker_name", "j_marker_name"))
    np.testing.assert_allclose(i_pose[0], CLIP_POINT, atol=1e-9)  # both markers at the clip, axes alike
    np.testing.assert_allclose(j_pose[0], CLIP_POINT, atol=1e-9)
    np.testing.assert_allclose(i_pose[1], j_pose[1], atol=1e-12)
    stations, _ = hose_from_adams(model)
    np.testing.assert_allclose(stations, placed[kind].centerline, atol=1e-6)


def test_clip_points_from_the_iges_file_of_the_mounts(tmp_path):
    """[[clips]] naming IGES points (tip and behind, or a ball clip's tip) read as the typed points."""
    import io

    from OCP.gp import gp_XYZ
    from OCP.IGESControl import IGESControl_Writer
    from OCP.IGESGeom import IGESGeom_Point
    from OCP.TCollection import TCollection_HAsciiString

    from hoseline.io.problem_file import load_problem

    named = {"A": (-13.0, -16.0, -11.25), "B": (-13.0, 0.0, -11.25), "C": (-160.0, -7.0, -11.25),
             "D": (-173.064, -7.0, -11.25), "E": (-60.0, 60.0, -11.25), "F": (-50.0, 65.0, -11.25),
             "G": (-130.0, 20.0, -11.25)}
    writer = IGESControl_Writer("MM", 0)
    for label, xyz in named.items():
        point = IGESGeom_Point()
        point.Init(gp_XYZ(*xyz), None)
        point.SetLabel(TCollection_HAsciiString(label))
        writer.AddEntity(point)
    writer.ComputeModel()
    stream = io.BytesIO()
    assert writer.Write(stream)
    (tmp_path / "mounts.igs").write_bytes(stream.getvalue())
    hose = ('[hose]\nlength = 330.6\nouter_diameter = 10.1\nbending_stiffness = 149563.0\nsegments = 10\n'
            '[end]\ntwist = 0.0\n')
    from_iges = tmp_path / "iges.toml"
    from_iges.write_text(hose + '[mounts]\niges = "mounts.igs"\n[[clips]]\ntype = "fixed"\narc_length = 165.3\n'
                         'tip = "E"\nbehind = "F"\n[[clips]]\ntype = "ball"\narc_length = 264.48\ntip = "G"\n')
    problem = load_problem(from_iges)
    fixed, ball = problem.clips
    np.testing.assert_allclose(fixed.point, named["E"], atol=1e-9)
    np.testing.assert_allclose(fixed.direction, np.array([-10.0, -5.0, 0.0]) / np.sqrt(125.0), atol=1e-12)
    np.testing.assert_allclose(ball.point, named["G"], atol=1e-9)
    assert ball.direction is None
    typed = tmp_path / "typed.toml"
    typed.write_text(hose + '[start]\npoint = [0, 0, 0]\ndirection = [0, 1, 0]\n'
                     '[[clips]]\ntype = "ball"\narc_length = 165.3\ntip = "E"\n'.replace("[end]\ntwist = 0.0\n", ""))
    with pytest.raises(ProblemFileError, match="needs the IGES file of \\[mounts\\]"):
        load_problem(typed)


def test_summary_table_lists_the_clip_loads(placed):
    from rich.console import Console

    from hoseline.report.table import summary_table

    console = Console(width=200, record=True)
    console.print(summary_table([placed["fixed"], placed["ball"]], ["fixed", "ball"]))
    text = console.export_text()
    force = np.linalg.norm(placed["fixed"].clips[0].force)
    assert "clip 1 force" in text and f"{force:.4g} (fixed)" in text and "(ball)" in text


def test_stability_margin_with_clips_matches_the_dense_projected_eigenvalue(placed):
    """The shift-invert subspace iteration with the 6-row border of a clipped hose (80 segments:
    past the dense shortcut of small rods) against the dense eigenvalue on the null space of J."""
    import scipy.linalg

    from hoseline.mechanics.newton import evaluate as evaluate_any
    from hoseline.mechanics.stability import smallest_eigenpairs
    from hoseline.procedures.placement.path import PlacementPath
    from hoseline.procedures.placement.sequence import rod_properties

    problem = _clipped_problem("rotating")
    problem = Problem(_hose(400.0, 80), problem.start, problem.end, end_twist_deg=90.0, gravity=GRAVITY,
                      clips=problem.clips)
    result = solve(problem, estimate_error=False)
    path = PlacementPath(problem)
    clamps = path.twisted(result.end_frame, 0.0, path.locked_clips(RodState(result.frames, result.end_force))[0])
    system = evaluate_any(rod_properties(problem), clamps, RodState(result.frames, result.end_force))
    assert system.jac_t.shape[1] == 6
    values, vectors = smallest_eigenpairs(system.band, system.jac_t, count=2)
    basis = scipy.linalg.null_space(system.jac_t.T)
    dense_values = np.linalg.eigvalsh(basis.T @ dense(system.band) @ basis)[:2]
    np.testing.assert_allclose(values, dense_values, rtol=1e-8)  # measured ~1e-12
    assert np.max(np.abs(system.jac_t.T @ vectors)) < 1e-10  # the modes keep the clip and the end in place


def test_solve_command_writes_the_clip_loads_and_refines_to_an_accuracy(tmp_path):
    import json

    from typer.testing import CliRunner

    from hoseline import cli

    problem_file = tmp_path / "clipped.toml"
    problem_file.write_text(problem_to_toml(_clipped_problem("rotating")))
    runner = CliRunner()
    done = runner.invoke(cli.app, ["solve", str(problem_file), "-o", str(tmp_path / "out"), "--quiet"])
    assert done.exit_code == 0, done.output
    document = json.loads((tmp_path / "out" / "result.json").read_text())
    (clip,) = document["summary"]["clips"]
    assert clip["type"] == "rotating" and clip["arc_length_mm"] == 200.0 and len(clip["force_N"]) == 3
    assert document["problem"]["clips"][0]["type"] == "rotating"
    # --accuracy with a clip: segment counts that keep the clip (at half the length) on an even station
    refined = runner.invoke(cli.app, ["solve", str(problem_file), "-o", str(tmp_path / "fine"), "--accuracy", "0.1",
                                      "--quiet"])
    assert refined.exit_code == 0, refined.output
    document = json.loads((tmp_path / "fine" / "result.json").read_text())
    segments = document["problem"]["hose"]["segments"]
    assert segments > 40 and segments % 4 == 0 and document["summary"]["clips"][0]["arc_length_mm"] == 200.0
    assert document["summary"]["discretisation_error_mm"] <= 0.1


def test_minimising_newton_walks_a_disturbed_clipped_hose_back_to_a_stable_equilibrium(placed):
    """The minimising mode (used to leave unstable branches) with clips: from the placed hose with every
    frame turned at random by up to ~0.2 rad, it ends converged, stable, at lower energy than it started."""
    from hoseline.mechanics.newton import solve_equilibrium, total_energy
    from hoseline.mechanics.rotations import rotate_frames
    from hoseline.procedures.placement.path import PlacementPath
    from hoseline.procedures.placement.sequence import rod_properties

    problem = _clipped_problem("fixed")
    result = placed["fixed"]
    props = rod_properties(problem)
    path = PlacementPath(problem)
    clamps = path.place(1.0)  # clip and end roll free: the minimiser has the rolls to find too
    disturbed = RodState(rotate_frames(result.frames, np.random.default_rng(2).normal(scale=0.1, size=(40, 3))),
                         np.zeros(3))
    state, report = solve_equilibrium(props, clamps, disturbed, minimise=True, max_iterations=200)
    assert report.converged and report.unstable_directions == 0, report
    assert total_energy(props, clamps, state) < total_energy(props, clamps, disturbed)
    nodes = evaluate(props, clamps, state).constraint
    assert np.max(np.abs(nodes)) < 1e-9 * 400.0  # the clip and the end are where they belong


@pytest.mark.parametrize("kind", ["fixed", "rotating"])
def test_the_mirror_image_with_a_clip_in_the_mounts_plane_is_found(kind):
    """Mounts, clip and weight in one plane, the end turned 180 deg: the mirror image in that plane
    is another stable equilibrium of equal energy (the clip maps onto itself; a fixed clip's locked
    frame too); measured 21.6 mm (fixed) and 13.3 mm (rotating) from the shape taken."""
    clip = Clip(kind, np.array([-60.0, 120.0, 0.0]), 200.0, np.array([-1.0, 0.3, 0.0]))
    problem = Problem(_hose(400.0, 40), Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 0], [1, 0, 0]),
                      end_twist_deg=180.0, gravity=np.array([0.0, -9.81, 0.0]), clips=(clip,))
    result = solve(problem, estimate_error=False)
    mirrors = [other for other in result.other_equilibria if other.origin.startswith("the mirror image")]
    assert not result.unique and len(mirrors) == 1
    assert mirrors[0].max_distance > 1.0 and mirrors[0].energy_gap == 0.0


def test_a_clip_off_the_mounts_plane_breaks_the_mirror_symmetry():
    clip = Clip("rotating", np.array([-60.0, 120.0, 5.0]), 200.0, np.array([-1.0, 0.3, 0.0]))
    problem = Problem(_hose(400.0, 40), Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 0], [1, 0, 0]),
                      end_twist_deg=180.0, gravity=np.array([0.0, -9.81, 0.0]), clips=(clip,))
    result = solve(problem, estimate_error=False)
    assert not any(other.origin.startswith("the mirror image") for other in result.other_equilibria)


def test_a_coarse_clipped_hose_finds_its_first_buckle_at_a_smaller_step_and_converges_at_order_two():
    """Found by a study: with 20 segments this clip, moved 1.7 mm and tilted 2.6 degrees, pulls the hose so far in
    the first step (a tenth of the place phase) that no buckled side relaxes to a stable shape there; the step is
    halved until one does.  The answer is the branch the finer hoses reach: 20, 40 and 80 segments converge at order
    two (distances to the 80-segment shape in the ratio of about 4)."""
    from hoseline.procedures.variation.tolerances import perturbed

    deviation = np.zeros(20)
    deviation[15:] = [0.2167888, 0.26963828, -1.6452474, -0.27455183, -2.5746823]  # clips[0].x .. .tilt_b
    s = np.linspace(0.0, 400.0, 81)
    shapes = {}
    for segments in (20, 40, 80):
        problem = _clipped_problem("fixed")
        problem = perturbed(replace(problem, hose=replace(problem.hose, segments=segments)), deviation)
        result = solve(problem, estimate_error=False)
        shapes[segments] = np.column_stack([np.interp(s, result.s, result.centerline[:, k]) for k in range(3)])
        if segments == 20:
            assert any("found at 0.025" in event for event in result.events)
    coarse, middle = (np.max(np.linalg.norm(shapes[n] - shapes[80], axis=1)) for n in (20, 40))
    assert 3.0 < coarse / middle < 5.0  # measured 1.36 mm and 0.36 mm: 3.8
