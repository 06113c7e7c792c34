"""The placement path with contact followed on a cushion (procedures/contact/cushion.py): the same equilibrium as the
path followed with the model's own barrier all along, the roll locked only after narrowing, and the fall-back.
The obstacles are present all along the path here (contact_placement "along_path"); the default brings them in
after the free placement (tests/test_contact_bring_in.py)."""

from dataclasses import replace

import numpy as np
import pytest
import trimesh

from hoseline.demos.thesis_hose import demo_problem
from hoseline.mechanics import contact_newton
from hoseline.mechanics.newton import NewtonReport
from hoseline.model.clips import Clip
from hoseline.model.obstacles import Cylinder, Mesh
from hoseline.procedures.contact import cushion
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.sequence import solve

STRUT_RADIUS = 15.0


def strut_problem(sense: float, depth: float = 1.0, placement: str = "along_path"):
    """The issue's case (bench/bench_contact_placement.py --mesh) with the strut as a cylinder: the thesis hose (100
    segments, 180 deg), a fixed clip where the free hose passes station 50, self-contact, and a strut of radius
    15 mm pressing `depth` mm into the clipped shape at station 25, its axis on the side sense (t x d1) of it;
    placement: the problem's contact_placement."""
    plain = demo_problem(180.0, segments=100)
    free = solve(plain, estimate_error=False)
    h = plain.hose.segment_length
    clipped = replace(plain, clips=(Clip("fixed", free.centerline[50], 50 * h, free.frames[49, 2] + free.frames[50, 2]),))
    placed = solve(clipped, estimate_error=False)
    tangent = placed.frames[24, 2] + placed.frames[25, 2]
    side = sense * np.cross(tangent, placed.frames[25, 0])
    side /= np.linalg.norm(side)
    centre = placed.centerline[25] + side * (plain.hose.outer_radius + STRUT_RADIUS - depth)
    axis = np.cross(tangent, side) / np.linalg.norm(np.cross(tangent, side))
    strut = Cylinder(centre - 100.0 * axis, centre + 100.0 * axis, STRUT_RADIUS, "strut")
    return replace(clipped, contact=(strut,), self_contact=True, contact_placement=placement)


@pytest.fixture(scope="module")
def strut_case():
    """The strut on the side where the hose slides along it for much of the place phase."""
    return strut_problem(-1.0)


@pytest.fixture(scope="module")
def without_cushion(strut_case):
    """The placement with the model's own barrier (0.01 mm) all along the path."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cushion, "CUSHION_RADII", 0.0)  # no wider than d_hat: follow_contact as it is
        return solve(strut_case, estimate_error=False)


def test_the_cushioned_path_ends_at_the_equilibrium_of_the_path_with_the_model_s_barrier(strut_case, without_cushion):
    on_cushion = solve(strut_case, estimate_error=False)
    strut, = (contact for contact in on_cushion.contacts if contact.name == "strut")
    assert strut.gap.size > 0 and 0.0 < strut.min_gap < 0.01  # it rests on the strut, within d_hat
    np.testing.assert_allclose(on_cushion.centerline, without_cushion.centerline, rtol=0.0, atol=1e-9)
    assert on_cushion.lock_angle_deg == pytest.approx(without_cushion.lock_angle_deg, abs=1e-9)
    assert on_cushion.stable and on_cushion.iterations < without_cushion.iterations


def faceted(case, sections: int, longest_edge: float):
    """`case` with its cylinder as a closed faceted tube of `sections` sides, triangles at most `longest_edge` mm."""
    cylinder, = case.contact
    axis = (cylinder.end - cylinder.start) / np.linalg.norm(cylinder.end - cylinder.start)
    tube = trimesh.creation.cylinder(radius=cylinder.radius, height=float(np.linalg.norm(cylinder.end - cylinder.start)),
                                     sections=sections, transform=trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis))
    vertices, faces = trimesh.remesh.subdivide_to_size(tube.vertices + 0.5 * (cylinder.start + cylinder.end), tube.faces,
                                                       max_edge=longest_edge)
    return replace(case, contact=(Mesh(vertices, faces, cylinder.name),))


def test_a_phase_that_starts_resting_on_an_obstacle_widens_the_barrier_downhill_first(strut_case):
    # the place phase ends narrowed to d_hat on the strut (960 triangles); the twist phase then follows its path on
    # the cushion: started at once from that state, out of balance under the wider barrier, its first step failed
    # ten times and was taken for a fold (an event "twist: ... (fold); ... snaps downhill")
    result = solve(faceted(strut_case, 60, 100.0), estimate_error=False)
    strut, = (contact for contact in result.contacts if contact.name == "strut")
    assert strut.gap.size > 0 and result.stable
    assert not [event for event in result.events if event.startswith("twist:")]


def test_the_strut_as_a_faceted_mesh_is_placed_as_the_cylinder_within_its_faceting(strut_case, without_cushion):
    # 128 sides cut to triangles of 8 mm at most (62 976, with T-junctions): before the flat patches its barrier had
    # steps at vertices and the placement failed at fraction 0.905 ("no descent step found"); the shape is the
    # cylinder's to within twice the facets' sagitta (0.0045 mm; 250 sides: 0.0021 mm from it, 60 sides: 0.029)
    result = solve(faceted(strut_case, 128, 8.0), estimate_error=False)
    sagitta = STRUT_RADIUS * (1.0 - np.cos(np.pi / 128))
    assert result.stable
    assert np.max(np.linalg.norm(result.centerline - without_cushion.centerline, axis=1)) < 2.0 * sagitta


def test_a_widening_that_fails_follows_the_path_with_the_model_s_barrier(strut_case, without_cushion, monkeypatch):
    def fails(props, clamps, state, model, **options):
        return state, NewtonReport(False, 3, 1.0, -1, "no descent step found")

    monkeypatch.setattr(cushion, "minimise_with_contact", fails)
    result = solve(strut_case, estimate_error=False)
    assert any(event.startswith("twist: the contact barrier did not widen") for event in result.events)
    np.testing.assert_allclose(result.centerline, without_cushion.centerline, rtol=0.0, atol=1e-9)


def test_a_roll_locked_on_the_cushion_is_another_problem(strut_case, without_cushion, monkeypatch):
    # the mutation the module doc warns of: the place phase returned on the cushion, its roll locked there
    def not_narrowed(phase, path, props, state, model, **options):
        return cushion.follow_contact(phase, path, props, state, model.with_activation(1.0),
                                      start=options["start"], control=options["control"], log=options["log"])[0]

    monkeypatch.setattr(cushion, "follow_on_cushion", not_narrowed)  # the placement imports it where it calls it
    locked_on_cushion = solve(strut_case, estimate_error=False)
    assert np.max(np.abs(locked_on_cushion.centerline - without_cushion.centerline)) > 1e-3


def test_a_narrowing_that_fails_follows_the_path_again_with_the_model_s_barrier(strut_case, without_cushion,
                                                                                 monkeypatch):
    # Newton fails every narrowing, and so does the walk downhill (not the widening at a phase's start: its barrier
    # is the cushion's, wider than any narrowing's)
    widest = cushion.CUSHION_RADII * strut_case.hose.outer_radius
    downhill = cushion.minimise_with_contact

    def fails(props, clamps, state, model, **options):
        return state, NewtonReport(False, 3, 1.0, -1, "iteration limit reached")

    def fails_narrower(props, clamps, state, model, **options):
        if model.activation < widest:
            return fails(props, clamps, state, model)
        return downhill(props, clamps, state, model, **options)

    monkeypatch.setattr(cushion, "solve_with_contact", fails)
    monkeypatch.setattr(cushion, "minimise_with_contact", fails_narrower)
    again = solve(strut_case, estimate_error=False)
    assert any("did not narrow" in event and "followed again" in event for event in again.events)
    np.testing.assert_allclose(again.centerline, without_cushion.centerline, rtol=0.0, atol=1e-12)


@pytest.fixture(scope="module")
def drum_cases():
    """(the drum of bench/bench_contact_placement.py, its placement with the model's barrier all along): a 335 mm
    hose between two upright mounts 200 mm apart, draped over a drum of radius 30 mm lying across its plane."""
    from hoseline.io.problem_file import problem_from_dict

    drum = problem_from_dict({
        "hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "contact": {"placement": "along_path",
                    "obstacles": [{"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0],
                                   "radius": 30.0, "name": "drum"}]}})
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cushion, "CUSHION_RADII", 0.0)
        return drum, solve(drum, estimate_error=False)


def without_restoring_steps(monkeypatch):
    """Newton without its restoring steps (mechanics/contact_newton.py): with them it carries the drum's hose
    through the narrowing below (the hose drops onto the drum with nothing yet within the narrower barrier's reach),
    without them it fails there, as the fall-backs tested here need."""
    monkeypatch.setattr(contact_newton, "_restored", lambda *arguments: None)


def test_a_narrowing_newton_fails_settles_downhill_on_the_equilibrium_of_the_model_s_barrier(drum_cases, monkeypatch):
    # the hose rests on the drum's cushion (1 mm) at the end of the place phase; narrowed to 0.1 mm it drops about
    # half a millimetre, and Newton (without its restoring steps) fails ("no acceptable step found"): the place phase
    # was followed again with the model's barrier (80 Newton iterations in all, 51 of them again); the walk downhill
    # ends at the same equilibrium (53 in all)
    drum, slow = drum_cases
    without_restoring_steps(monkeypatch)
    result = solve(drum, estimate_error=False)
    assert not [event for event in result.events if "did not narrow" in event]
    assert result.stable and result.contacts[0].min_gap >= 0.0
    np.testing.assert_allclose(result.centerline, slow.centerline, rtol=0.0, atol=1e-9)


def test_a_narrowing_that_moves_the_hose_farther_than_the_settling_limit_is_not_kept(drum_cases, monkeypatch):
    # the same drum with no settling allowed: its narrowing's walk downhill (0.5 mm) is refused and the path is
    # followed again with the model's barrier, to the same equilibrium
    drum, slow = drum_cases
    without_restoring_steps(monkeypatch)
    monkeypatch.setattr(cushion, "SETTLING_DIAMETERS", 0.01)
    result = solve(drum, estimate_error=False)
    assert any("did not narrow" in event and "more than 0.01 hose diameter(s)" in event for event in result.events)
    np.testing.assert_allclose(result.centerline, slow.centerline, rtol=0.0, atol=1e-12)


def test_a_planar_loop_closes_on_itself_at_the_same_touch_with_and_without_the_cushion(monkeypatch):
    """1000 mm of hose between coaxial mounts 150 mm apart (self-contact, 50 segments): its free shape crosses
    itself; with contact the loop closes on itself and stops there (docs/model.md: one pair at s = 76 mm, gap 0.0096
    mm, push 2.48 N, stable, from the path without the cushion)."""
    from hoseline.io.problem_file import problem_from_dict

    loop = problem_from_dict({
        "hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "torsional_stiffness": 1e5,
                 "segments": 50},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
        "end": {"point": [150.0, 2.0, 0.0], "direction": [-1.0, 0.0, 0.0]}, "contact": {"self": True}})
    on_cushion = solve(loop, estimate_error=False)
    monkeypatch.setattr(cushion, "CUSHION_RADII", 0.0)
    without = solve(loop, estimate_error=False)
    for result in (on_cushion, without):
        itself, = result.contacts
        assert itself.gap.size == 1 and 0.0 < itself.min_gap < 0.01 and result.stable
        assert itself.arc_length[0] == pytest.approx(76.28, abs=0.01)
        assert np.linalg.norm(itself.total_force) == pytest.approx(2.482, abs=1e-3)
    np.testing.assert_allclose(on_cushion.centerline, without.centerline, rtol=0.0, atol=1e-9)


def test_a_clip_carried_through_the_strut_is_refused_before_the_path_naming_the_clip_and_the_obstacle():
    # the strut on the other side: the clip's straight path to its point passes 15.7 mm from the strut's axis
    # (radius 15 mm plus the hose's 5.05) between fractions 0.46 and 0.62 of the place phase (the pieces of 0.005
    # that hold the crossings: 0.455 to 0.625), so the hose at the clip would have to enter the strut: no placement
    # exists along that path
    with pytest.raises(PlacementError) as failure:
        solve(strut_problem(1.0), estimate_error=False)
    message = str(failure.value)
    assert "carries the clip at arc length 165.3 mm on a straight line" in message
    assert "passes through obstacle 'strut' between fractions 0.455 and 0.625" in message


def test_a_path_that_jams_says_where_the_hose_is_pressed_hardest(monkeypatch):
    # the same without the check of the held paths: the contact continuation follows the path until the hose at the
    # clip is crushed against the strut, and its failure says so
    monkeypatch.setattr("hoseline.procedures.contact.placement.check_held_paths", lambda *arguments: None)
    with pytest.raises(PlacementError) as failure:
        solve(strut_problem(1.0), estimate_error=False)
    message = str(failure.value)
    assert "pressed hardest against 'strut'" in message and "next to the clip at station 50" in message
    assert "straight line" in message and "Move the obstacle" in message


def test_a_path_step_whose_newton_creeps_is_halved_at_once_and_the_path_ends_where_it_did(strut_case, without_cushion,
                                                                                          monkeypatch):
    """Continuation steps whose Newton iterations are cut below STALLED_STEP three times in a row are given up
    ("stalled") and halved instead of crept through: on the issue's strut case far fewer iterations, the same
    equilibrium as a path whose Newton never stalls (and as the path without the cushion)."""
    from hoseline.procedures.contact import continuation

    messages = []

    def recorded(*arguments, **options):
        state, report = solve_with_contact(*arguments, **options)
        messages.append(report.message)
        return state, report

    solve_with_contact = continuation.solve_with_contact
    monkeypatch.setattr(continuation, "solve_with_contact", recorded)
    with_stall = solve(strut_case, estimate_error=False)
    assert "stalled" in messages
    monkeypatch.setattr(continuation, "STALLED_ITERATIONS", 0)  # never stall: Newton creeps until it fails
    creeping = solve(strut_case, estimate_error=False)
    np.testing.assert_allclose(with_stall.centerline, creeping.centerline, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(with_stall.centerline, without_cushion.centerline, rtol=0.0, atol=1e-9)
    assert with_stall.lock_angle_deg == pytest.approx(creeping.lock_angle_deg, abs=1e-9)
    assert with_stall.iterations < 0.9 * creeping.iterations

