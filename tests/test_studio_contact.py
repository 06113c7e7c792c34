"""The studio with contact: a drag keeps the hose out of the problem's [contact] obstacles, which the page shows.

A heavy hose hangs between two horizontal mounts and rests on a floor ([contact] plane at z = 0);
the end mount is dragged down and sideways in small steps, as the page sends them.
"""

from dataclasses import replace

import numpy as np
import pytest

from hoseline.io.problem_file import load_problem, problem_from_dict, problem_to_dict
from hoseline.io.sweep_file import sweep_from_dict
from hoseline.procedures.sweep.quasi_static import run_sweep
from hoseline.procedures.placement.sequence import solve
from hoseline.studio.messages import Target
from hoseline.studio.session import Session
from hoseline.studio.view import state_message

LENGTH, MASS, RADIUS, HEIGHT = 400.0, 0.5, 5.0, 150.0


def resting_hose(contact: bool = True):
    """The hose of tests/test_sweep_contact.py with its end mount 100 mm lower: its middle lies on the floor."""
    data = {"hose": {"length": LENGTH, "outer_diameter": 2 * RADIUS, "bending_stiffness": 500.0,
                     "torsional_stiffness": 500.0, "mass_per_length": MASS, "segments": 30},
            "start": {"point": [-150.0, 0.0, HEIGHT], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [150.0, 0.0, HEIGHT - 100.0], "direction": [-1.0, 0.0, 0.0]},
            "environment": {"gravity": [0.0, 0.0, -9.81]}}
    if contact:
        data["contact"] = {"obstacles": [{"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0],
                                          "name": "floor"}]}
    return problem_from_dict(data)


def dragged(session: Session, offset) -> None:
    """Move the end fitting by `offset` (mm) in steps of at most 2 mm, as a drag sends them."""
    state = state_message(session)["fittings"]["end"]
    start = np.array(state["point"])
    steps = int(np.ceil(np.linalg.norm(offset) / 2.0))
    for k in range(1, steps + 1):
        point = start + np.asarray(offset) * k / steps
        session.apply(Target(type="set", seq=k, end={"point": point.tolist(), "quaternion": state["quaternion"]}))


@pytest.fixture(scope="module")
def dragged_on_the_floor():
    session = Session(resting_hose())
    before = session.result()
    dragged(session, [-20.0, 15.0, -20.0])
    return session, before


def test_the_page_shows_the_floor_and_measures_clearance_to_it(dragged_on_the_floor):
    session, _ = dragged_on_the_floor
    [floor] = session.obstacles
    assert floor.obstacle.name == "floor" and floor.obstacle.clearance == 0.0
    message = state_message(session)
    [near] = message["readouts"]["min_clearance"]
    assert 0.0 <= near["distance"] < 0.01  # touching: within the barrier's activation distance
    [contact] = message["readouts"]["contacts"]
    assert contact["name"] == "floor" and contact["length_in_contact"] > 0.0


def test_a_drag_keeps_the_hose_on_the_floor_not_through_it(dragged_on_the_floor):
    session, before = dragged_on_the_floor
    result = session.result()
    [floor] = result.contacts
    assert floor.min_gap >= 0.0
    assert np.min(result.centerline[:, 2]) >= RADIUS  # the surface stays above the floor
    assert floor.length_in_contact > before.contacts[0].length_in_contact  # the end went down: more hose lies on it
    weight = MASS * 9.81e-3 * LENGTH  # kg/m * m/s^2 -> N/mm, times mm
    np.testing.assert_allclose(result.start_force + result.end_force + floor.total_force, [0.0, 0.0, weight],
                               atol=1e-6 * weight)  # the mounts and the floor carry the weight
    assert result.stability_margin >= 0.0


def test_without_the_floor_the_same_drag_goes_through_it():
    """The check above can fail: the same hose and drag without [contact] ends below the floor."""
    session = Session(resting_hose(contact=False))
    dragged(session, [-20.0, 15.0, -20.0])
    assert np.min(session.result().centerline[:, 2]) < -10.0


def test_the_drag_ends_where_a_sweep_through_the_same_motion_ends(dragged_on_the_floor):
    """A second code path: the quasi-static sweep (procedures/sweep) moving the end body along the drag, in 7 poses
    instead of the drag's 19 steps; both keep the end fitting's roll locked at assembly."""
    session, _ = dragged_on_the_floor
    offset = np.array([-20.0, 15.0, -20.0])
    data = problem_to_dict(resting_hose())
    data["end"]["body"] = "arm"
    data["bodies"] = [{"name": "arm", "stages": [{"name": "drag", "translate": [0.0, float(np.linalg.norm(offset))],
                                                  "axis": (offset / np.linalg.norm(offset)).tolist(), "steps": 7}]}]
    data["sweep"] = {"compare_free_roll": False}
    swept = run_sweep(sweep_from_dict(data))
    shown = session.result()
    assert np.max(np.linalg.norm(swept.centerlines[-1] - shown.centerline, axis=1)) < 1e-6 * LENGTH
    np.testing.assert_allclose(swept.contacts[0].total_force[-1], shown.contacts[0].total_force, rtol=1e-6)


def test_after_place_again_the_saved_file_gives_the_shape_shown(tmp_path):
    session = Session(resting_hose())
    dragged(session, [10.0, -10.0, -10.0])
    session.place_again()  # a fresh assembly locks the end fitting's roll afresh (a drag keeps the old lock)
    path = tmp_path / "problem.toml"
    path.write_text(session.problem_toml())
    fresh = solve(load_problem(path), estimate_error=False)
    shown = session.result()
    assert np.max(np.linalg.norm(fresh.centerline - shown.centerline, axis=1)) < 1e-6 * LENGTH
    np.testing.assert_allclose(fresh.contacts[0].total_force, shown.contacts[0].total_force, rtol=1e-6, atol=1e-9)


def test_a_heavier_hose_from_the_slider_presses_harder_and_stays_out():
    session = Session(resting_hose())
    light = session.result().contacts[0]
    session.apply(Target(type="set", seq=1, hose={"mass_per_length": 2.0 * MASS}))
    heavy = session.result().contacts[0]
    assert heavy.min_gap >= 0.0 and np.min(session.result().centerline[:, 2]) >= RADIUS
    assert heavy.total_force[2] > 1.5 * light.total_force[2]


def test_opening_another_problem_replaces_the_contact_obstacles_shown():
    session = Session(resting_hose())
    session.open_problem(replace(resting_hose(contact=False), name="free"))
    assert session.obstacles == []


def test_a_box_under_the_hose_is_drawn_as_its_triangles_and_carries_it_as_the_floor_does(dragged_on_the_floor):
    """The floor as the top face of a [contact] box: the page draws the box's 12 triangles, and the dragged hose
    rests on it as on the analytic plane (the same push, to the barrier's accuracy)."""
    data = problem_to_dict(resting_hose(contact=False))
    data["contact"] = {"obstacles": [{"kind": "box", "center": [0.0, 0.0, -10.0], "size": [800.0, 400.0, 20.0],
                                      "name": "block"}]}
    session = Session(problem_from_dict(data))
    dragged(session, [-20.0, 15.0, -20.0])
    [block] = session.obstacles
    assert len(block.obstacle.faces) == 12 and block.obstacle.clearance == 0.0
    result = session.result()
    assert np.min(result.centerline[:, 2]) >= RADIUS
    floor = dragged_on_the_floor[0].result().contacts[0]
    np.testing.assert_allclose(result.contacts[0].total_force, floor.total_force, rtol=1e-4, atol=1e-9)


def test_a_drag_keeps_the_contact_models_search_trees_and_a_slider_its_stiffness_follows():
    """The contact model is built once per set of obstacles: a drag reuses it, a heavier hose changes only the
    barrier's stiffness (the reference pressure grows with the weight)."""
    data = problem_to_dict(resting_hose(contact=False))
    data["contact"] = {"obstacles": [{"kind": "box", "center": [0.0, 0.0, -10.0], "size": [800.0, 400.0, 20.0]}]}
    session = Session(problem_from_dict(data))
    built = session.tracker.contact
    dragged(session, [0.0, 0.0, -4.0])
    assert session.tracker.contact.mesh is built.mesh and session.tracker.contact.stiffness == built.stiffness
    session.apply(Target(type="set", seq=9, hose={"mass_per_length": 2.0 * MASS}))
    assert session.tracker.contact.mesh is built.mesh and session.tracker.contact.stiffness > built.stiffness


def test_a_drag_sends_the_costly_readouts_pending_and_completes_them_when_it_pauses(tmp_path):
    """During a drag the states leave the stability margin and the contacts' smallest gaps pending (null, named in
    "pending"); once the drag pauses a "readouts" message brings them, equal to a complete evaluation of the shape
    shown; the readouts the drag's states did send were current."""
    from starlette.testclient import TestClient

    from hoseline.studio.server import create_app

    app = create_app(Session(resting_hose()), tmp_path, allowed_hosts=("testserver",))
    session = app.state.studio.session
    with TestClient(app) as client, client.websocket_connect("/ws") as ws:
        ws.receive_json()
        state = ws.receive_json()
        assert state["readouts"]["pending"] == [] and state["readouts"]["stability_margin"] is not None
        end = state["fittings"]["end"]
        for k in range(1, 4):
            point = (np.array(end["point"]) + [0.0, 0.0, -2.0 * k]).tolist()
            ws.send_json({"type": "set", "seq": k, "end": {"point": point, "quaternion": end["quaternion"]}})
            moved = ws.receive_json()
            assert (moved["type"], moved["seq"]) == ("state", k)
            readouts = moved["readouts"]
            assert readouts["pending"] == ["stability_margin", "min_gap"]
            assert readouts["stability_margin"] is None and readouts["contacts"][0]["min_gap"] is None
        completed = ws.receive_json()  # the drag pauses: the readouts come before the idle comparison
        assert completed["type"] == "readouts"
        fresh = state_message(session)["readouts"]
        assert completed["readouts"] == fresh and fresh["pending"] == []
        result = session.result()
        assert completed["readouts"]["stability_margin"] == result.stability_margin > 0.0
        assert completed["readouts"]["contacts"][0]["min_gap"] == result.contacts[0].min_gap
        for key in ("start_force", "end_force", "end_moment", "min_bend_radius", "min_clearance"):  # the drag's: current
            assert readouts[key] == fresh[key]
        assert readouts["contacts"][0]["total_force"] == fresh["contacts"][0]["total_force"]
        assert ws.receive_json()["type"] == "comparison"


def test_a_drags_result_leaves_the_gaps_unsearched_and_still_refuses_a_shape_inside_an_obstacle():
    """A drag's result (Session.result(complete=False)) leaves each obstacle's smallest gap unsearched (NaN), with the
    contact forces and gaps of the pairs as the complete result has them; it still checks that the hose enters
    nothing (the solver's guarantee), by the cheaper penetration search: with the floor raised into the hose lying on
    it, both results refuse the shape."""
    from hoseline.procedures.placement.continuation import PlacementError

    session = Session(resting_hose())
    dragged(session, [0.0, 0.0, -4.0])
    drag, complete = session.result(complete=False).contacts[0], session.result().contacts[0]
    assert np.isnan(drag.min_gap) and 0.0 < complete.min_gap < np.inf
    np.testing.assert_array_equal(drag.total_force, complete.total_force)
    np.testing.assert_array_equal(drag.gap, complete.gap)
    model = session.tracker.contact
    raised = model.planes.copy()
    raised[:, 2] += 2.0 * RADIUS  # the floor's point up by the hose's diameter: through the hose resting on it
    session.tracker.contact = replace(model, planes=raised)
    for complete in (False, True):
        with pytest.raises(PlacementError, match="solver error"):
            session.result(complete)


def test_a_drag_of_the_end_skips_the_search_for_penetration_at_its_start_and_a_drag_of_the_start_does_not(
        monkeypatch):
    """The solve of a drag's step starts from the equilibrium tracked, which clears the obstacles; moving the end
    fitting leaves it where it was, so it is not searched for penetration again, but moving the start fitting carries
    the whole hose along with it (the solve's start under the new clamps), so that start is searched."""
    from hoseline.mechanics.contact_newton import ContactModel

    session = Session(resting_hose())
    searched = []
    original = ContactModel.penetration
    monkeypatch.setattr(ContactModel, "penetration", lambda model, nodes: searched.append(nodes) or original(model, nodes))
    dragged(session, [0.0, 0.0, -4.0])
    assert searched == []
    fittings = state_message(session)["fittings"]["start"]
    aside = (np.array(fittings["point"]) + [0.0, 1.0, 0.0]).tolist()  # along the floor: one Newton solve
    session.apply(Target(type="set", seq=9, start={"point": aside, "quaternion": fittings["quaternion"]}))
    assert session.last_step.events == [] and len(searched) == 1 and np.allclose(searched[0][0], aside)


def test_a_drags_state_sends_what_is_only_drawn_to_fewer_decimals_and_the_shape_in_full():
    """A drag's state rounds the lay line and the colour maps to view.DRAWN_DECIMALS (their JSON is the shorter); the
    centreline, the arc lengths and the readouts are the complete state's to the bit."""
    from hoseline.studio.view import DRAWN_DECIMALS

    session = Session(resting_hose())
    session.add_obstacle("block", np.array([[0.0, 60.0, 0.0], [50.0, 60.0, 0.0], [0.0, 60.0, 50.0]]),
                         np.array([[0, 1, 2]]), "test")  # a clearance colour map
    dragged(session, [0.0, 10.0, -4.0])  # out of the plane: the lay line turns
    drag, complete = state_message(session, complete=False), state_message(session)
    for name, decimals in DRAWN_DECIMALS.items():
        full = np.array(complete[name], dtype=float)
        sent = np.array(drag[name], dtype=float)
        assert np.all(np.isfinite(full) == np.isfinite(sent))
        np.testing.assert_array_equal(sent, np.round(full, decimals))
        assert not np.array_equal(sent, full)  # the complete state keeps every digit
        assert len(repr(drag[name])) < 0.7 * len(repr(complete[name]))
    for name in ("centerline", "s", "fittings"):
        assert drag[name] == complete[name]
    assert drag["readouts"]["min_clearance"] == complete["readouts"]["min_clearance"]
