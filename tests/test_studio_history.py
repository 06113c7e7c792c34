"""Undo and redo in the studio's server (studio/history.py), over the WebSocket: the messages of one gesture are one
edit, a refused change leaves no edit behind, a file opened is an edit of its own, and undo and redo give back the
very states shown."""

import numpy as np
from starlette.testclient import TestClient

from test_studio_server import HOSTS, moved_end, next_state, opened
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_to_toml
from hoseline.studio.server import create_app
from hoseline.studio.session import Session


def test_a_gesture_is_one_edit_a_refused_change_none_and_undo_redo_give_back_the_states_shown(tmp_path):
    problem = demo_problem(180.0, segments=30)
    with TestClient(create_app(Session(problem), tmp_path, allowed_hosts=HOSTS)) as client:
        with client.websocket_connect("/ws") as ws:
            _, first = opened(ws)
            for k in range(1, 6):  # gesture 1: a drag of five steps
                ws.send_json(moved_end(first, [0.0, -2.0 * k, 0.0]) | {"seq": k, "edit": 1})
                dragged, _ = next_state(ws)
            ws.send_json({"type": "set", "seq": 6, "edit": 2, "hose": {"length": 10.0}})  # gesture 2: refused
            refused, others = next_state(ws)
            assert [m["type"] for m in others] == ["error"]
            ws.send_json({"type": "set", "seq": 7, "edit": 3, "twist": 150.0})  # gesture 3
            twisted, _ = next_state(ws)
            shown = []
            for seq, kind in enumerate(["undo", "undo", "undo", "redo", "redo", "redo"], start=8):
                ws.send_json({"type": kind, "seq": seq})
                state, _ = next_state(ws)
                shown.append(np.array(state["centerline"]))
            expected = [dragged, first, first, dragged, twisted, twisted]  # the refused gesture left no edit
            for state, wanted in zip(shown, expected):
                np.testing.assert_array_equal(state, wanted["centerline"])
            assert twisted["twist"] == 150.0


def test_a_file_opened_is_undone_with_its_session_message(tmp_path):
    problem = demo_problem(180.0, segments=30)
    other = demo_problem(90.0, segments=30)
    with TestClient(create_app(Session(problem), tmp_path, allowed_hosts=HOSTS)) as client:
        with client.websocket_connect("/ws") as ws:
            session, first = opened(ws)
            answer = client.post("/upload/other.toml", content=problem_to_toml(other).encode(),
                                 headers={"origin": "http://testserver"})
            assert answer.status_code == 200, answer.text
            opened_other = ws.receive_json()
            assert opened_other["type"] == "session" and opened_other["name"] == other.name
            state, _ = next_state(ws)
            assert state["twist"] == 90.0
            ws.send_json({"type": "undo", "seq": 1})
            told = ws.receive_json()
            assert told["type"] == "session" and told["name"] == problem.name
            state, _ = next_state(ws)
            np.testing.assert_array_equal(state["centerline"], first["centerline"])
            ws.send_json({"type": "undo", "seq": 2})  # nothing more to undo: the state as it is, no session message
            state, others = next_state(ws)
            assert others == [] or all(m["type"] == "comparison" for m in others)
            np.testing.assert_array_equal(state["centerline"], first["centerline"])
