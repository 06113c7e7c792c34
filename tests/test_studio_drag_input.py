"""How the studio takes a drag in headless chromium (software WebGL), by the mouse as a user drags:

- each move's target goes out in the move's pointerrawupdate, before chromium hands the page its pointermove (held
  for the next animation frame), and the gizmo then ignores that pointermove (one target a move);
- drawn in software, the view is drawn at half the resolution while the drag moves and at full resolution again
  once it pauses, and what is drawn is the state received.
"""

from pathlib import Path

import numpy as np
import pytest

from test_studio_browser import CHROMIUM, browser, drawn_after, drawn_centerline, opened_page  # noqa: F401 (a fixture)
from test_studio_editing import gizmo_handle, screen_point, select, thesis_problem
from hoseline.studio.session import Session

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason=f"{CHROMIUM} is not installed")

# when the page first saw each move (by its timeStamp) in a pointerrawupdate and in a pointermove, and the marks of
# the targets sent (static/js/marks.js)
RECORD = """() => {
    window.seen = { pointerrawupdate: new Map(), pointermove: new Map() };
    window.studio.marks.list = [];
    for (const type of ['pointerrawupdate', 'pointermove']) {
        window.addEventListener(type, (event) => {
            const now = performance.now(), coalesced = event.getCoalescedEvents();
            for (const move of coalesced.length ? coalesced : [event]) window.seen[type].set(move.timeStamp, now);
        }, { capture: true });
    }
}"""
TAKEN = """() => ({
    raw: [...window.seen.pointerrawupdate], move: [...window.seen.pointermove],
    sent: window.studio.marks.list.filter((m) => m[0] === 'sent').map((m) => m[2]),
})"""
RESOLUTION = """() => {
    const canvas = window.studio.scene.renderer.domElement;
    return canvas.width / (canvas.clientWidth * window.devicePixelRatio);
}"""


def pressed_on_the_end_arrow(page):
    """Select the end fitting, find its X arrow by hovering, press on it; a function of the screen point `pixels`
    along the arrow, outwards, from the point pressed."""
    select(page, "end", "translate")
    handle = np.array(gizmo_handle(page, "end", "X", "translate"))
    along = handle - np.array(screen_point(page, "end", [0.0, 0.0, 0.0]))
    page.mouse.down()
    return lambda pixels: (handle + pixels * along / np.linalg.norm(along)).tolist()


def test_each_move_of_a_drag_is_sent_in_its_pointerrawupdate_before_its_pointermove(browser, tmp_path):  # noqa: F811
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        along = pressed_on_the_end_arrow(page)
        page.evaluate(RECORD)
        for step in range(1, 9):  # one at a time: each answered and drawn before the next, none in flight
            drawn_after(page, lambda: page.mouse.move(*along(3 * step)))
        taken = page.evaluate(TAKEN)
        page.mouse.up()
        raw, move, sent = dict(taken["raw"]), dict(taken["move"]), np.array(taken["sent"])
        assert len(raw) == 8 and raw.keys() == move.keys()  # every move seen in both, by the same timeStamp
        for stamp, raw_seen in raw.items():
            carried = sent[(sent >= raw_seen) & (sent <= move[stamp])]
            assert len(carried) == 1, (raw_seen, move[stamp], sent)  # sent once, before its pointermove came
        assert len(sent) == 8
        assert errors == []


def test_a_drag_drawn_in_software_is_drawn_at_half_resolution_until_it_pauses(browser, tmp_path):  # noqa: F811
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        if not page.evaluate("() => window.studio.scene.software"):
            pytest.skip("WebGL runs on a GPU here: the view is drawn at full resolution throughout")
        assert page.evaluate(RESOLUTION) == pytest.approx(1.0, abs=0.01)
        along = pressed_on_the_end_arrow(page)
        for step in range(1, 6):
            state = drawn_after(page, lambda: page.mouse.move(*along(4 * step)))
            assert page.evaluate(RESOLUTION) == pytest.approx(0.5, abs=0.01)
            # what is drawn is the state received (the tube's rings round its centreline, in float32)
            assert np.abs(drawn_centerline(page) - np.array(state["centerline"])).max() < 1e-3
        page.wait_for_function(f"() => ({RESOLUTION})() > 0.99", timeout=2000)  # paused, the mouse still down
        page.mouse.up()
        assert page.evaluate(RESOLUTION) == pytest.approx(1.0, abs=0.01)
        assert errors == []
