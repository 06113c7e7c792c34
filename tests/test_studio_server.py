"""The studio's server: the WebSocket protocol, continuation steps, coalescing of drag bursts, uploads and limits."""

import asyncio
import json
import re
import time
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from starlette.testclient import TestClient

from hoseline.demos.sweep import demo_sweep
from hoseline.demos.thesis_hose import THESIS_MOUNTS_IGES, demo_problem
from hoseline.io.problem_file import problem_from_dict, problem_to_dict, problem_to_toml
from hoseline.model.motion import axis_angle_matrix, matrix_quaternion, quaternion_matrix
from hoseline.procedures.placement.sequence import solve
from hoseline.studio.inbox import Inbox
from hoseline.studio.messages import parse_message
from hoseline.studio.server import create_app
from hoseline.studio.session import Session
from hoseline.studio.uploads import SIZE_LIMITS

HOSTS = ("testserver",)
SEGMENTS = 30


@pytest.fixture(scope="module")
def problem():
    return demo_problem(180.0, segments=SEGMENTS)


@pytest.fixture
def client(problem, tmp_path):
    app = create_app(Session(problem), tmp_path, allowed_hosts=HOSTS)
    with TestClient(app) as test_client:
        yield test_client


def opened(ws):
    """The session and state messages a page gets on connecting."""
    session, state = ws.receive_json(), ws.receive_json()
    assert (session["type"], state["type"]) == ("session", "state")
    return session, state


def next_state(ws):
    """The next state message (errors and comparisons on the way are returned with it)."""
    others = []
    while True:
        message = ws.receive_json()
        if message["type"] == "state":
            return message, others
        others.append(message)


def moved_end(state, offset):
    """A target moving the end fitting by `offset` (mm), its orientation kept."""
    end = state["fittings"]["end"]
    return {"type": "set", "end": {"point": (np.array(end["point"]) + offset).tolist(), "quaternion": end["quaternion"]}}


def test_first_state_is_the_placement_and_a_drag_is_a_reversible_continuation_path(client, problem):
    placed = solve(problem).centerline
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        assert np.max(np.abs(np.array(state["centerline"]) - placed)) < 1e-9 * problem.hose.length
        assert state["comparison"]["same"] and state["seq"] is None
        start = np.array(state["centerline"])
        for k in range(1, 11):  # drag the end fitting 10 mm up in steps of 1 mm
            ws.send_json({**moved_end(state, [0.0, 0.0, float(k)]), "seq": k})
            moved, _ = next_state(ws)
            assert moved["seq"] == k
        shape = np.array(moved["centerline"])
        assert np.allclose(shape[-1], start[-1] + [0.0, 0.0, 10.0], atol=1e-9)  # the hose ends at the dragged tip
        assert np.max(np.linalg.norm(shape - start, axis=1)) > 5.0
        assert moved["step"]["iterations"] >= 1
        assert abs(np.sum(np.linalg.norm(np.diff(shape, axis=0), axis=1)) - problem.hose.length) < 1e-9  # inextensible
        ws.send_json({**moved_end(state, [0.0, 0.0, 0.0]), "seq": 11})  # and back: the same equilibrium again
        back, _ = next_state(ws)
        assert np.max(np.abs(np.array(back["centerline"]) - start)) < 1e-6 * problem.hose.length


def test_sliders_change_the_hose_through_the_problem_file_checks(client, problem):
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        ws.send_json({"type": "set", "seq": 1, "hose": {"length": 360.0}, "twist": 90.0})
        longer, _ = next_state(ws)
        shape = np.array(longer["centerline"])
        assert abs(np.sum(np.linalg.norm(np.diff(shape, axis=0), axis=1)) - 360.0) < 1e-9
        assert longer["twist"] == 90.0 and longer["hose"]["length"] == 360.0
        ws.send_json({"type": "set", "seq": 2, "hose": {"length": 100.0}})  # shorter than the mount distance
        kept, others = next_state(ws)
        assert [m["type"] for m in others] == ["error"] and "hose.length" in others[0]["message"]
        assert kept["seq"] == 2 and kept["centerline"] == longer["centerline"]
        ws.send_json({"type": "set", "seq": 3, "hose": {"torsion_factor": -1.0}})
        _, others = next_state(ws)
        assert "torsion_factor" in others[0]["message"]  # the problem file's own message


def test_a_burst_of_drag_events_is_coalesced_the_latest_target_wins(client, monkeypatch):
    session = client.app.state.studio.session
    apply = session.apply

    def slow_apply(target):  # a slow solver: a burst arrives while one step runs
        time.sleep(0.05)
        apply(target)

    monkeypatch.setattr(session, "apply", slow_apply)
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        burst = 20
        for k in range(1, burst + 1):
            ws.send_json({**moved_end(state, [0.0, 0.0, 0.5 * k]), "seq": k})
        states = []
        while not states or states[-1]["seq"] != burst:
            states.append(next_state(ws)[0])
        assert len(states) <= 4  # not one solve per event
        assert client.app.state.studio.coalesced >= burst - 4
        last = np.array(states[-1]["fittings"]["end"]["point"])
        assert np.allclose(last, np.array(state["fittings"]["end"]["point"]) + [0.0, 0.0, 0.5 * burst])


def test_a_drag_during_the_idle_comparison_abandons_it_and_gets_its_state_first(client, monkeypatch):
    """The server places the problem afresh while the page is idle; a drag arriving meanwhile does not wait for that:
    the placement is abandoned after its current continuation step, the drag's state comes first, and the comparison
    is made again once the page is idle.  Here the first fresh placement goes on for 20 s unless
    abandoned: a drag that waited for it would get its state after the comparison."""
    import threading

    import hoseline.studio.session as session_module

    until_abandoned_s = 20.0
    started, calls = threading.Event(), []

    def slow_then_real(problem, *, progress=None, **options):
        calls.append(problem)
        if len(calls) == 1:  # continuation steps that go on (progress after each) until abandoned
            started.set()
            ends = time.monotonic() + until_abandoned_s
            while time.monotonic() < ends:
                progress("place", 0.5)
                time.sleep(0.002)
        return solve(problem, progress=progress, **options)

    monkeypatch.setattr(session_module, "solve", slow_then_real)
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        ws.send_json({**moved_end(state, [0.0, 0.0, 1.0]), "seq": 1})
        assert next_state(ws)[0]["seq"] == 1
        assert started.wait(until_abandoned_s)  # the idle comparison has begun
        ws.send_json({**moved_end(state, [0.0, 0.0, 2.0]), "seq": 2})
        assert ws.receive_json()["type"] == "readouts"  # the first drag's readouts, before the comparison began
        assert ws.receive_json()["seq"] == 2  # the drag's state, before any comparison
        assert client.app.state.studio.abandoned == 1
        assert ws.receive_json()["type"] == "readouts"  # its readouts, then the comparison
        comparison = ws.receive_json()  # made again once idle, of the shape dragged to
        assert comparison["type"] == "comparison" and not comparison["comparison"]["same"]
        assert len(calls) >= 2 and np.allclose(calls[-1].end.point, np.array(state["fittings"]["end"]["point"]) + [0, 0, 2])


def test_the_inbox_merges_only_consecutive_targets():
    async def drain():
        inbox = Inbox()
        messages = [{"type": "set", "seq": 1, "twist": 10.0}, {"type": "set", "seq": 2, "hose": {"length": 340.0}},
                    {"type": "place", "seq": 3}, {"type": "set", "seq": 4, "twist": 20.0}]
        for message in messages:
            inbox.put(parse_message(json.dumps(message)))
        return [await inbox.get(0.01) for _ in range(4)], inbox.coalesced

    (first, command, last, empty), coalesced = asyncio.run(drain())
    assert (first.seq, first.twist, first.hose.length) == (2, 10.0, 340.0)  # both changes of the burst kept
    assert command.type == "place" and last.twist == 20.0 and empty is None and coalesced == 1


def test_bad_messages_get_an_answer_and_the_loop_goes_on(client):
    with client.websocket_connect("/ws") as ws:
        opened(ws)
        ws.send_text("not json")
        assert ws.receive_json()["type"] == "error"
        ws.send_json({"type": "set", "seq": 1, "end": {"point": [0, 0], "quaternion": [1, 0, 0, 0]}})
        assert "end.point" in ws.receive_json()["message"]
        ws.send_text(json.dumps({"type": "set", "seq": 2, "twist": 1.0, "pad": "x" * 70000}))
        assert "more than" in ws.receive_json()["message"]
        ws.send_json({"type": "place", "seq": 3})
        placed, _ = next_state(ws)
        assert placed["seq"] == 3 and placed["comparison"]["same"]


def test_uploads_are_limited_and_checked_by_the_command_line_readers(client, problem):
    before = client.get("/problem.toml").text
    too_large = client.post("/upload/big.stl", content=b"x" * 10, headers={"content-length": str(SIZE_LIMITS["obstacle"] + 1)})
    assert too_large.status_code == 413 and "64 MiB" in too_large.json()["error"]
    assert client.post("/upload/x.exe", content=b"MZ").status_code == 415
    for name in (".hidden.toml", "two%20words.toml", "..%2F..%2Fescape.toml"):  # no paths, no odd names
        assert client.post(f"/upload/{name}", content=b"").status_code in (404, 415)
    text = re.sub(r"length = [0-9.]+", "length = -1.0", problem_to_toml(problem), count=1)
    bad = client.post("/upload/bad.toml", content=text.encode())
    assert bad.status_code == 400 and "hose.length = -1.0" in bad.json()["error"]
    broken = client.post("/upload/broken.stl", content=b"solid nothing\nendsolid\n")
    assert broken.status_code == 400 and "broken.stl" in broken.json()["error"]
    assert client.get("/problem.toml").text == before  # the session is untouched


def test_opened_files_replace_the_problem_and_add_obstacles(client, problem, tmp_path):
    mine = replace(problem, name="uploaded", end_twist_deg=0.0)
    assert client.post("/upload/mine.toml", content=problem_to_toml(mine).encode()).status_code == 200
    assert problem_from_dict(tomllib.loads(client.get("/problem.toml").text)).end_twist_deg == 0.0
    with open(THESIS_MOUNTS_IGES, "rb") as stream:
        assert client.post("/upload/mounts.igs", content=stream.read()).status_code == 200
    strut = demo_sweep(steps_per_degree=0.1, segments=SEGMENTS).obstacles[0]
    import trimesh
    stl = trimesh.Trimesh(strut.vertices, strut.faces).export(file_type="stl")
    assert client.post("/upload/strut.stl", content=stl).status_code == 200
    with client.websocket_connect("/ws") as ws:
        session, state = opened(ws)
        assert session["name"] == "uploaded" and [o["name"] for o in session["obstacles"]] == ["strut"]
        near = state["readouts"]["min_clearance"][0]
        assert near["required"] == 25.4 and abs(near["distance"] - 26.4) < 1.0
        assert len(state["clearance_ratio"]) == SEGMENTS + 1 and min(state["clearance_ratio"]) < 2.0
    mesh = client.get("/obstacle/0").content
    vertices, faces = np.frombuffer(mesh[:8], "<u4")
    assert len(mesh) == 8 + 12 * vertices + 12 * faces and faces == len(strut.faces)


def test_the_problem_file_and_exports_are_of_the_shape_shown(client, problem, tmp_path):
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        ws.send_json({**moved_end(state, [0.0, 0.0, 5.0]), "seq": 1})
        moved, _ = next_state(ws)
    saved = problem_from_dict(tomllib.loads(client.get("/problem.toml").text))
    assert np.allclose(saved.end.point, moved["fittings"]["end"]["point"], atol=1e-12)
    cmd = client.get("/export/adams")
    assert cmd.status_code == 200 and "hose.cmd" in cmd.headers["content-disposition"]
    path = tmp_path / "hose.cmd"
    path.write_bytes(cmd.content)
    from hoseline.io.adams_cmd import hose_from_adams, read_adams_cmd
    stations, _ = hose_from_adams(read_adams_cmd(path))
    assert np.max(np.abs(stations - np.array(moved["centerline"]))) < 1e-6 * problem.hose.length
    assert client.get("/export/nonsense").status_code == 404


def test_the_timeline_moves_the_fittings_with_the_sweep_bodies_and_runs_the_sweep(tmp_path):
    sweep = demo_sweep(steps_per_degree=0.1, segments=SEGMENTS)
    sweep = replace(sweep, compare_free_roll=False)
    app = create_app(Session(sweep=sweep), tmp_path, allowed_hosts=HOSTS)
    with TestClient(app) as client, client.websocket_connect("/ws") as ws:
        session, state = opened(ws)
        assert session["sweep"]["poses"] == sweep.pose_count
        k = 3
        ws.send_json({"type": "set", "seq": 1, "pose": k})
        posed, _ = next_state(ws)
        expected = sweep.pose(sweep.end_body, k).point(sweep.problem.end.point)
        assert posed["pose"] == k and np.allclose(posed["fittings"]["end"]["point"], expected, atol=1e-9)
        assert np.allclose(posed["centerline"][-1], expected, atol=1e-9)
        ran = client.post("/sweep")
        assert ran.status_code == 200
        report = client.get(ran.json()["report"])
        assert report.status_code == 200 and "<html" in report.text.lower()
        assert client.get("/reports/0/../../etc/passwd").status_code == 404


def test_requests_from_other_origins_and_hosts_are_refused(client):
    refused = client.post("/upload/a.toml", content=b"", headers={"origin": "http://evil.example"})
    assert refused.status_code == 403
    assert client.get("/", headers={"host": "evil.example"}).status_code == 400
    with pytest.raises(Exception):
        with client.websocket_connect("/ws", headers={"origin": "http://evil.example"}) as ws:
            ws.receive_json()
    page = client.get("/")
    assert "connect-src 'self'" in page.headers["content-security-policy"]


def test_the_command_refuses_bad_input_and_serves_until_interrupted(problem, tmp_path):
    import signal
    import socket
    import subprocess
    import sys
    import urllib.request
    from pathlib import Path

    from typer.testing import CliRunner

    from hoseline.cli import app

    bad = tmp_path / "bad.toml"
    bad.write_text("[hose]\nlength = -1\n")
    runner = CliRunner()
    assert runner.invoke(app, ["studio", str(bad), "--no-browser"]).exit_code == 2
    assert runner.invoke(app, ["studio", "--port", "70000", "--no-browser"]).exit_code == 2
    assert runner.invoke(app, ["studio", str(tmp_path / "none.toml"), "--no-browser"]).exit_code == 2
    good = tmp_path / "problem.toml"
    good.write_text(problem_to_toml(problem))
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        busy = runner.invoke(app, ["studio", str(good), "--port", str(taken.getsockname()[1]), "--no-browser"])
        assert busy.exit_code == 2 and "cannot listen" in busy.output
    command = [str(Path(sys.executable).with_name("hoseline")), "studio", str(good), "--port", "0", "--no-browser"]
    server = subprocess.Popen(command, stderr=subprocess.PIPE, text=True)
    try:
        line = server.stderr.readline()
        url = line.split(" at ", 1)[1].split()[0]
        assert url.startswith("http://127.0.0.1:")
        for _ in range(100):  # uvicorn starts serving just after the announcement
            try:
                page = urllib.request.urlopen(url, timeout=5).read().decode()
                break
            except OSError:
                time.sleep(0.1)
        assert "hoseline studio" in page
    finally:
        server.send_signal(signal.SIGINT)
        assert server.wait(timeout=20) == 0


def test_a_failure_inside_a_step_is_told_and_the_loop_goes_on(client, monkeypatch):
    session = client.app.state.studio.session

    def broken(target):
        raise ZeroDivisionError("a bug")

    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        with monkeypatch.context() as patch:
            patch.setattr(session, "apply", broken)
            ws.send_json({"type": "set", "seq": 1, "twist": 10.0})
            kept, others = next_state(ws)
        assert "internal error" in others[0]["message"] and kept["centerline"] == state["centerline"]
        ws.send_json({"type": "set", "seq": 2, "twist": 10.0})
        assert next_state(ws)[0]["twist"] == 10.0


def test_a_sweep_file_dropped_with_its_pose_table_opens_with_its_motion(client, problem, tmp_path):
    from hoseline.io.pose_table import pose_table_text

    motion = demo_sweep(steps_per_degree=0.1, segments=SEGMENTS).motions[0]
    table = pose_table_text("steer [deg]", motion.travel, motion.poses)
    sweep_text = problem_to_toml(replace(problem, name="dropped sweep")).replace(
        "[end]\n", '[end]\nbody = "knuckle"\n', 1) + '\n[[bodies]]\nname = "knuckle"\nposes = "knuckle.csv"\n'
    alone = client.post("/upload/alone.toml", content=sweep_text.replace("knuckle.csv", "missing.csv").encode())
    assert alone.status_code == 400 and "missing.csv" in alone.json()["error"]
    assert str(tmp_path) not in alone.json()["error"]  # the server's folders are not told to the page
    assert client.post("/upload/knuckle.csv?store=1", content=table.encode()).status_code == 200
    assert client.post("/upload/sweep.toml", content=sweep_text.encode()).status_code == 200
    with client.websocket_connect("/ws") as ws:
        session, _ = opened(ws)
        assert session["name"] == "dropped sweep" and session["sweep"]["poses"] == len(motion.poses)


def test_the_segment_count_places_again_and_each_obstacle_takes_its_own_clearance(client, problem):
    strut = demo_sweep(steps_per_degree=0.1, segments=SEGMENTS).obstacles[0]
    import trimesh
    stl = trimesh.Trimesh(strut.vertices, strut.faces).export(file_type="stl")
    assert client.post("/upload/strut.stl", content=stl).status_code == 200
    with client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        ratio = np.array(state["clearance_ratio"])
        ws.send_json({"type": "clearance", "seq": 1, "obstacle": 0, "required": 50.8})
        stricter, _ = next_state(ws)
        near = stricter["readouts"]["min_clearance"][0]
        assert near["required"] == 50.8 and near["distance"] == state["readouts"]["min_clearance"][0]["distance"]
        assert np.all(np.array(stricter["clearance_ratio"]) <= ratio + 1e-12)  # judged against twice the distance
        assert np.min(stricter["clearance_ratio"]) == pytest.approx(min(near["distance"] / 50.8, 2.0), rel=1e-6)
        ws.send_json({"type": "clearance", "seq": 2, "obstacle": 3, "required": 1.0})
        _, others = next_state(ws)
        assert "obstacle 3 does not exist" in others[0]["message"]
        ws.send_json({"type": "clearance", "seq": 3, "obstacle": 0, "required": -1.0})
        _, others = next_state(ws)
        assert "0 to 100000 mm" in others[0]["message"]
        ws.send_json({"type": "segments", "seq": 4, "segments": 2 * SEGMENTS})
        finer, _ = next_state(ws)
        assert finer["hose"]["segments"] == 2 * SEGMENTS and len(finer["centerline"]) == 2 * SEGMENTS + 1
        coarse, fine = np.array(state["centerline"]), np.array(finer["centerline"])[::2]
        assert np.max(np.linalg.norm(fine - coarse, axis=1)) < 0.01 * problem.hose.length  # the same shape, refined
        assert finer["readouts"]["min_clearance"][0]["required"] == 50.8  # kept across the new placement
        ws.send_json({"type": "segments", "seq": 5, "segments": 2})
        kept, others = next_state(ws)
        assert "hose.segments" in others[0]["message"] and kept["centerline"] == finer["centerline"]


@pytest.mark.parametrize("message, fragment", [
    ({"type": "segments", "seq": 1}, "give 'segments'"),
    ({"type": "place", "seq": 1, "segments": 20}, "remove 'segments'"),
    ({"type": "clearance", "seq": 1, "obstacle": 0}, "give 'required'"),
])
def test_commands_carry_exactly_the_fields_of_their_type(message, fragment):
    with pytest.raises(ValueError, match=fragment):
        parse_message(json.dumps(message))


def test_an_iges_file_without_the_thesis_labels_offers_its_labels_and_takes_the_chosen_ones(client, problem):
    text = open(THESIS_MOUNTS_IGES).read()
    for old, new in (("A", "P1"), ("B", "P2"), ("C", "P3"), ("D", "P4")):
        text = text.replace(f" {old}       0D", f"{new}       0D")  # the label is right-aligned in columns 57-64
    asked = client.post("/upload/fixture.igs", content=text.encode())
    assert asked.status_code == 400 and asked.json()["labels"] == ["P1", "P2", "P3", "P4"]
    assert "no point labelled B, A, D, C" in asked.json()["error"]
    bad = client.post("/upload/fixture.igs?labels=P2,P1", content=text.encode())
    assert bad.status_code == 400 and "four point labels" in bad.json()["error"] and "labels" not in bad.json()
    chosen = client.post("/upload/fixture.igs?labels=P2,P1,P4,P3", content=text.encode())
    assert chosen.status_code == 200 and "P2, P1, P4, P3" in chosen.json()["message"]
    placed = problem_from_dict(tomllib.loads(client.get("/problem.toml").text))
    from hoseline.io.iges_mounts import mounts_from_iges
    start, end = mounts_from_iges(THESIS_MOUNTS_IGES)  # the same points under the thesis' labels
    np.testing.assert_allclose(placed.start.point, start.point)
    np.testing.assert_allclose(placed.end.direction, end.direction)


def fitted_thesis_problem(problem):
    """`problem` (the thesis hose) with a straight fitting at the start and a clocked 90 degree elbow at the end,
    its mounts now the ports and its length the free length."""
    data = problem_to_dict(problem)
    data["fittings"] = {"start": {"length": 20.0},
                        "end": {"length": 25.0, "bend_angle": 90.0, "outlet_length": 25.0, "bend_radius": 10.0,
                                "clocking": 30.0, "reference": [0.0, 0.0, 1.0]}}
    return problem_from_dict(data)


def turned_port(port, rotation, offset):
    """A target for a port (state["fittings"][...]) turned by the world `rotation` about its point and moved by `offset`."""
    frame = quaternion_matrix(port["quaternion"]).T @ rotation.T
    return {"point": (np.array(port["point"]) + offset).tolist(), "quaternion": matrix_quaternion(frame.T).tolist()}


def test_end_fittings_are_dragged_by_their_ports_and_carry_the_outlets_rigidly(problem, tmp_path):
    fitted = fitted_thesis_problem(problem)
    length = fitted.hose.length
    session = Session(fitted)
    clamped = session.fittings_at_zero_twist().end_frame  # the end outlet's frame as the flexible hose is held there
    app = create_app(session, tmp_path, allowed_hosts=HOSTS)
    with TestClient(app) as client, client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        assert np.max(np.abs(np.array(state["centerline"]) - solve(fitted).centerline)) < 1e-9 * length
        port = state["fittings"]["end"]  # the page is given the ports and the fittings as rigid pieces
        np.testing.assert_allclose(port["point"], fitted.fittings.end_port.point)
        np.testing.assert_allclose(quaternion_matrix(port["quaternion"])[:, 2], -fitted.fittings.end_port.direction,
                                   atol=1e-12)
        np.testing.assert_allclose(state["fittings"]["start"]["point"], fitted.fittings.start_port.point)
        assert set(state["pieces"]) == {"start", "end"}
        assert state["readouts"]["overall_length"] == pytest.approx(length + 20.0 + 25.0)
        assert state["readouts"]["free_length"] == length

        # the end port turned by 12 degrees about a tilted axis and moved 6 mm, in 6 drag events
        axis, offset = np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0]), np.array([0.0, 3.0, -5.2])
        for k in range(1, 7):
            ws.send_json({"type": "set", "seq": k, "end": turned_port(port, axis_angle_matrix(axis, np.radians(2.0 * k)),
                                                                      offset * k / 6)})
            moved, _ = next_state(ws)
        turn = axis_angle_matrix(axis, np.radians(12.0))
        outlet = fitted.end.point - fitted.fittings.end_port.point
        shape = np.array(moved["centerline"])
        np.testing.assert_allclose(shape[-1], fitted.fittings.end_port.point + offset + turn @ outlet, atol=1e-9)
        np.testing.assert_allclose(shape[0], fitted.start.point, atol=1e-9)  # the start fitting stays
        assert np.max(np.linalg.norm(shape - np.array(state["centerline"]), axis=1)) > 5.0  # the hose follows
        assert abs(np.sum(np.linalg.norm(np.diff(shape, axis=0), axis=1)) - length) < 1e-9
        saved = problem_from_dict(tomllib.loads(client.get("/problem.toml").text))
        np.testing.assert_allclose(saved.fittings.end_port.point, fitted.fittings.end_port.point + offset, atol=1e-12)
        np.testing.assert_allclose(saved.end.point, shape[-1], atol=1e-9)  # the file's outlet is the one shown
        np.testing.assert_allclose(saved.end.direction, turn @ fitted.end.direction, atol=1e-9)
        np.testing.assert_allclose(saved.fittings.end.reference, turn @ fitted.fittings.end.reference, atol=1e-12)
        np.testing.assert_allclose(session.fittings_at_zero_twist().end_frame, clamped @ turn.T, atol=1e-9)  # rigidly

        ws.send_json({"type": "set", "seq": 7, "end": port})  # and back: the same equilibrium again
        back, _ = next_state(ws)
        assert np.max(np.abs(np.array(back["centerline"]) - np.array(state["centerline"]))) < 1e-6 * length

        ws.send_json({"type": "set", "seq": 8, "end": turned_port(port, turn, offset)})  # there again, then place again
        next_state(ws)
        ws.send_json({"type": "place", "seq": 9})
        shown, _ = next_state(ws)
        saved = problem_from_dict(tomllib.loads(client.get("/problem.toml").text))
    assert saved.fittings.end.clocking_deg == 30.0 and saved.fittings.start.length == 20.0
    assert np.max(np.linalg.norm(solve(saved).centerline - np.array(shown["centerline"]), axis=1)) < 1e-6 * length


def clipped_thesis_problem(problem):
    """`problem` (the thesis hose, 30 segments) held by a fixed clip (station 10) and a rotating clip (station 20),
    each a few mm off the unclipped shape, its tangent there as the clip direction."""
    from hoseline.model.clips import Clip
    shape, h = solve(problem, estimate_error=False).centerline, problem.hose.segment_length

    def tangent(k):
        t = shape[k + 1] - shape[k - 1]
        return t / np.linalg.norm(t)

    return replace(problem, clips=(Clip("fixed", shape[10] + [0.0, 0.0, 3.0], 10 * h, tangent(10), "bracket"),
                                   Clip("rotating", shape[20] + [0.0, 2.0, 0.0], 20 * h, tangent(20), "sleeve")))


@pytest.fixture(scope="module")
def clipped(problem):
    return clipped_thesis_problem(problem)


def moved_clip(state, index, offset):
    """A target moving clip `index` by `offset` (mm), the other clips and all orientations kept."""
    clips = [{"point": c["point"], "quaternion": c["quaternion"]} for c in state["clips"]]
    clips[index]["point"] = (np.array(clips[index]["point"]) + offset).tolist()
    return {"type": "set", "clips": clips}


def test_a_clip_drag_is_a_reversible_continuation_path_and_the_saved_file_holds_it(clipped, tmp_path):
    placed = solve(clipped)
    app = create_app(Session(clipped), tmp_path, allowed_hosts=HOSTS)
    with TestClient(app) as client, client.websocket_connect("/ws") as ws:
        _, state = opened(ws)
        assert np.max(np.abs(np.array(state["centerline"]) - placed.centerline)) < 1e-9 * clipped.hose.length
        assert [c["kind"] for c in state["clips"]] == ["fixed", "rotating"]
        for shown, clip in zip(state["clips"], placed.clips):  # the clips' loads as the placement has them
            np.testing.assert_allclose(shown["force"], clip.force, atol=1e-9 * np.linalg.norm(clip.force))
            np.testing.assert_allclose(shown["moment"], clip.moment, atol=1e-9 * np.linalg.norm(clip.moment))
        start = np.array(state["centerline"])
        for k in range(1, 9):  # drag the fixed clip 8 mm up in steps of 1 mm
            ws.send_json({**moved_clip(state, 0, [0.0, 0.0, float(k)]), "seq": k})
            moved, _ = next_state(ws)
            assert moved["seq"] == k
        shape = np.array(moved["centerline"])
        assert np.allclose(shape[10], np.array(state["clips"][0]["point"]) + [0.0, 0.0, 8.0], atol=1e-9)  # held there
        assert np.allclose(shape[20], state["clips"][1]["point"], atol=1e-9)
        assert np.max(np.linalg.norm(shape - start, axis=1)) > 4.0
        assert abs(np.sum(np.linalg.norm(np.diff(shape, axis=0), axis=1)) - clipped.hose.length) < 1e-9
        ws.send_json({**moved_clip(state, 0, [0.0, 0.0, 0.0]), "seq": 9})  # and back: the same equilibrium again
        back, _ = next_state(ws)
        assert np.max(np.abs(np.array(back["centerline"]) - start)) < 1e-6 * clipped.hose.length

        ws.send_json({**moved_clip(state, 1, [0.0, 0.0, 5.0]), "seq": 10})  # the rotating clip, then place again
        next_state(ws)
        ws.send_json({"type": "place", "seq": 11})
        shown, _ = next_state(ws)
        assert shown["comparison"]["same"]
        ws.send_json({"type": "set", "seq": 12, "clips": moved_clip(shown, 0, [0.0, 0.0, 0.0])["clips"][:1]})
        refused, others = next_state(ws)  # not every clip: refused, the shape kept
        assert "clips: 1 given" in others[0]["message"] and refused["centerline"] == shown["centerline"]
        saved = problem_from_dict(tomllib.loads(client.get("/problem.toml").text))
    np.testing.assert_allclose(saved.clips[1].point, np.array(state["clips"][1]["point"]) + [0.0, 0.0, 5.0], atol=1e-12)
    assert [clip.arc_length for clip in saved.clips] == pytest.approx([clip.arc_length for clip in clipped.clips])
    assert np.max(np.linalg.norm(solve(saved).centerline - np.array(shown["centerline"]), axis=1)) \
        < 1e-6 * clipped.hose.length


def test_clip_targets_are_checked_and_coalesce():
    quaternion = [1.0, 0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="clips.0.quaternion"):
        parse_message(json.dumps({"type": "set", "seq": 1, "clips": [{"point": [0, 0, 0], "quaternion": [0, 0, 0, 0]}]}))
    with pytest.raises(ValueError, match="clips.0.point"):
        parse_message(json.dumps({"type": "set", "seq": 1, "clips": [{"point": [0, 0], "quaternion": quaternion}]}))
    inbox = Inbox()
    for k in range(3):
        inbox.put(parse_message(json.dumps({"type": "set", "seq": k, "pose": 3} if k == 0 else
                                           {"type": "set", "seq": k, "clips": [{"point": [k, 0, 0], "quaternion": quaternion}]})))
    merged = asyncio.run(inbox.get(0.0))
    assert merged.clips[0].point == [2.0, 0.0, 0.0] and merged.pose is None and inbox.coalesced == 2


def test_a_message_nested_too_deeply_is_refused():
    """json.loads recurses once per level: a message of nested arrays within the size limit is a MessageError,
    not a RecursionError."""
    from hoseline.studio.messages import MessageError

    with pytest.raises(MessageError, match="nested too deeply"):
        parse_message('{"type": "set", "seq": 1, "clips": ' + "[" * 30_000 + "]" * 30_000 + "}")
