"""The studio's editing habits (issue 29, part B), driven in headless chromium by mouse and keyboard as a user works:

- the problem file saved after each kind of edit (a drag of the end fitting in and out of the plane, a turn of
  either fitting, the twist slider, a typed value, a clip dragged, a drag onto a floor) solves by `hoseline solve`
  to the shape shown within 0.1 mm;
- undo and redo (Ctrl+Z, Ctrl+Shift+Z) step through drags, typed values, a clearance and a file opened, back to
  the very shapes shown, and the browser's own text undo does not reach the number boxes;
- snapping (S) moves and turns in whole steps, and the readout shows the distance and angle while dragging;
- a handle pulled past the reach of the hose stays at the hose's end;
- F turns the view onto the selected fitting, M measures between two points picked on the hose;
- a reload shows the last state, the camera, colour map and selection, and still undoes what was done before.
"""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from test_studio_browser import CHROMIUM, browser, drawn_after, opened_page  # noqa: F401 (browser: a fixture)
from test_studio_contact import resting_hose
from test_studio_server import clipped_thesis_problem
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_from_dict, problem_to_dict
from hoseline.studio.messages import Target
from hoseline.studio.session import Session
from hoseline.studio.view import state_message

SAVED_TO_SHOWN_MM = 0.1  # the issue's bound between the shape shown and the saved file solved

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason=f"{CHROMIUM} is not installed")


def thesis_problem():
    return demo_problem(180.0, segments=30)


# --- what the user does ---

def screen_point(page, name: str, local) -> list[float]:
    """Where on the screen the point `local` (mm, in the frame of fitting or clip `name`) is drawn."""
    return page.evaluate(
        """([name, local]) => {
            const studio = window.studio, object = studio.fittings.objects[name], camera = studio.scene.camera;
            object.updateMatrixWorld(true);
            const p = object.localToWorld(new object.position.constructor(...local)).project(camera);
            const rect = studio.scene.renderer.domElement.getBoundingClientRect();
            return [rect.left + (p.x + 1) / 2 * rect.width, rect.top + (1 - p.y) / 2 * rect.height];
        }""", [name, list(local)])


def world_point(page, point) -> list[float]:
    """Where on the screen the world point `point` (mm) is drawn."""
    return page.evaluate(
        """(point) => {
            const studio = window.studio, camera = studio.scene.camera;
            const p = camera.position.clone().set(...point).project(camera);
            const rect = studio.scene.renderer.domElement.getBoundingClientRect();
            return [rect.left + (p.x + 1) / 2 * rect.width, rect.top + (1 - p.y) / 2 * rect.height];
        }""", list(point))


def select(page, name: str, mode: str) -> None:
    """Select fitting `name` with its toolbar button ('start', 'end') or by clicking it (a clip), then the mode."""
    if name in ("start", "end"):
        page.click(f'[data-select="{name}"]')
    else:
        page.mouse.click(*screen_point(page, name, [0.0, 0.0, 0.0]))
    page.click(f'[data-mode="{mode}"]')
    assert page.evaluate("() => window.studio.fittings.selected") == name, click_diagnosis(page, name)


def click_diagnosis(page, name: str) -> dict:
    """What the page had where fitting `name` is drawn (for a click that selected something else, seen once in CI):
    the element on top there, the gizmo's axis, whether the measuring tool is on, the canvas' size."""
    x, y = screen_point(page, name, [0.0, 0.0, 0.0])
    return page.evaluate(
        """([x, y]) => {
            const top = document.elementFromPoint(x, y), canvas = window.studio.scene.renderer.domElement;
            return {point: [x, y], top: top && (top.id || top.tagName), axis: window.studio.fittings.gizmo.axis,
                    measuring: document.getElementById('measure').classList.contains('active'),
                    canvas: [canvas.clientWidth, canvas.clientHeight]};
        }""", [x, y])


def gizmo_handle(page, name: str, axis: str, mode: str) -> list[float]:
    """A screen point on the gizmo's `axis` ('X', 'Y', 'Z') handle at fitting `name`, found by hovering: along the
    axis for a move, round the ring about it for a turn."""
    if mode == "translate":
        index = "XYZ".index(axis)
        tries = [screen_point(page, name, [length if k == index else 0.0 for k in range(3)])
                 for length in (12, 16, 20, 25, 30, 35, 40, 50, 60, 75, 90, 110, 130, 160, 200)]
    else:  # circles round the fitting on the screen
        centre = screen_point(page, name, [0.0, 0.0, 0.0])
        tries = [[centre[0] + radius * math.cos(math.radians(angle)), centre[1] + radius * math.sin(math.radians(angle))]
                 for radius in range(40, 200, 8) for angle in range(5, 360, 15)]
    for point in tries:
        page.mouse.move(*point)
        if page.evaluate("() => window.studio.fittings.gizmo.axis") == axis:
            return point
    raise AssertionError(f"the mouse found no {axis} handle of the {mode} gizmo at {name}")


def drag_handle(page, name: str, axis: str, mode: str, pixels, steps: int = 15, release: bool = True) -> dict:
    """Press on the gizmo's `axis` handle at `name`, move the mouse by `pixels` (dx, dy; or a number: along the arrow,
    outwards, or along the ring, the way round that it is positive) in `steps`, release; the state drawn after it."""
    select(page, name, mode)
    handle = gizmo_handle(page, name, axis, mode)
    if np.ndim(pixels) == 0:  # from the fitting to the handle on the screen, or across that for a turn
        radial = np.array(handle) - np.array(screen_point(page, name, [0.0, 0.0, 0.0]))
        along = radial if mode == "translate" else np.array([-radial[1], radial[0]])
        pixels = pixels * along / np.linalg.norm(along)

    def drag():
        page.mouse.down()
        for step in range(1, steps + 1):
            page.mouse.move(handle[0] + pixels[0] * step / steps, handle[1] + pixels[1] * step / steps)
        if release:
            page.mouse.up()

    return drawn_after(page, drag)


def type_into(page, selector: str, value: str) -> dict:
    """Type `value` into the box `selector` as a user does (click, select all, type, Enter); the state drawn after."""
    box = page.locator(selector)

    def typed():
        box.click()
        page.keyboard.press("Control+A")
        page.keyboard.type(value)
        page.keyboard.press("Enter")

    return drawn_after(page, typed)


def shown(page) -> np.ndarray:
    return np.array(page.evaluate("() => window.studio.state.centerline"))


def press(page, keys: str) -> dict:
    """Press `keys` with the view focused (clicked on empty sky first); the state drawn after."""
    return drawn_after(page, lambda: page.keyboard.press(keys))


# --- save = shown ---

def saved_and_solved(page, folder: Path, link: str = "#save") -> np.ndarray:
    """Save the problem file with the page's link `link`, solve it with `hoseline solve` as a user does; the stations."""
    with page.expect_download(timeout=120000) as download:
        page.click(link)
    path = folder / "saved.toml"
    download.value.save_as(path)
    cli = Path(sys.executable).with_name("hoseline")
    run = subprocess.run([str(cli), "solve", str(path), "-o", str(folder / "out"), "-q"], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    return np.loadtxt(folder / "out" / "centerline.csv", delimiter=",", skiprows=1)[:, 1:]


def end_out_of_plane(page):
    return drag_handle(page, "end", "Y", "translate", (0, 60))


def end_in_plane(page):
    return drag_handle(page, "end", "X", "translate", (-50, 20))


def end_turned(page):
    return drag_handle(page, "end", "X", "rotate", 80)


def end_rolled(page):
    return drag_handle(page, "end", "Z", "rotate", 80)


def start_rolled(page):
    return drag_handle(page, "start", "Z", "rotate", 120)


def start_turned(page):
    return drag_handle(page, "start", "X", "rotate", 80)


def end_dragged_then_twist_typed(page):
    end_out_of_plane(page)
    return type_into(page, '.slider[data-key="twist"] input[type="number"]', "120")


def end_turned_then_twist_slider(page):
    end_turned(page)
    box = page.locator('.slider[data-key="twist"] input[type="range"]').bounding_box()
    return drawn_after(page, lambda: page.mouse.click(box["x"] + 0.3 * box["width"], box["y"] + box["height"] / 2))


def end_tip_typed(page):
    return type_into(page, 'tr[data-fitting="end"][data-field="point"] td:nth-child(3) input', "-20")


EDITS = [end_out_of_plane, end_in_plane, end_turned, end_rolled, start_rolled, start_turned,
         end_dragged_then_twist_typed, end_turned_then_twist_slider, end_tip_typed]


@pytest.mark.parametrize("edit", EDITS, ids=[edit.__name__ for edit in EDITS])
def test_the_file_saved_after_an_edit_solves_to_the_shape_shown(browser, tmp_path, edit):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        before = shown(page)
        state = edit(page)
        assert np.max(np.linalg.norm(np.array(state["centerline"]) - before, axis=1)) > 2.0  # the edit moved the hose
        solved = saved_and_solved(page, tmp_path)
        assert np.max(np.linalg.norm(solved - shown(page), axis=1)) <= SAVED_TO_SHOWN_MM
        assert errors == []


def test_after_the_issue_s_drag_the_badge_gives_the_signed_twist_the_file_is_saved_with(browser, tmp_path):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        end_out_of_plane(page)
        page.wait_for_function("() => window.studio.state.comparison && window.studio.state.comparison.saved",
                               timeout=60000)
        comparison = page.evaluate("() => window.studio.state.comparison")
        assert comparison["distance"] > 10.0 and comparison["saved"]["same"]
        change = comparison["saved"]["twist_change"]
        sign = "+" if change >= 0 else "−"
        page.wait_for_function(f"() => document.getElementById('badge').title.includes('{sign}{abs(change):.4g}°')")
        assert f"saved as shown (twist {sign}" in page.locator("#badge").inner_text()
        assert errors == []


@pytest.mark.parametrize("clip, pixels", [("clip1", (0, 30)), ("clip0", (0, -20))], ids=["rotating", "fixed"])
def test_a_dragged_clip_saves_as_shown(browser, tmp_path, clip, pixels):
    """Save writes the shape shown without asking (a click on Save downloads the file); a fixed clip dragged keeps the
    roll it was locked at, clocked against the roll a fresh placement locks, and the file holds that as its twist."""
    with opened_page(browser, Session(clipped_thesis_problem(thesis_problem())), tmp_path) as (page, errors, _):
        before = shown(page)
        state = drag_handle(page, clip, "Y", "translate", pixels)
        assert np.max(np.linalg.norm(np.array(state["centerline"]) - before, axis=1)) > 2.0  # the drag moved the hose
        solved = saved_and_solved(page, tmp_path)
        assert np.max(np.linalg.norm(solved - shown(page), axis=1)) <= SAVED_TO_SHOWN_MM
        assert errors == []


def test_a_click_right_after_the_view_changes_picks_what_the_new_view_shows(browser, tmp_path):
    """A click that comes before the first drawing of a new view (the page just opened, a preset view pressed) picks
    with that view: the camera's matrices are made current when the page moves it, not at its next drawing.  Seen in
    CI: a clip clicked right after the page opened was missed 3 times in 8 (the raycast used the camera's first
    pose)."""
    with opened_page(browser, Session(clipped_thesis_problem(thesis_problem())), tmp_path) as (page, _, _):
        page.keyboard.press("Escape")
        for view in ("top", "front", "iso"):
            # the button pressed and the pick made in one task of the page, before any frame can be drawn
            picked = page.evaluate(
                """(view) => {
                    document.querySelector(`[data-view="${view}"]`).click();
                    const studio = window.studio, camera = studio.scene.camera, clip = studio.fittings.objects.clip1;
                    const drawnAt = studio.scene.drawCount;
                    const p = clip.getWorldPosition(clip.position.clone()).project(camera);
                    const rect = studio.scene.renderer.domElement.getBoundingClientRect();
                    const x = rect.left + (p.x + 1) / 2 * rect.width, y = rect.top + (1 - p.y) / 2 * rect.height;
                    const options = {clientX: x, clientY: y, bubbles: true, pointerType: 'mouse', button: 0};
                    studio.scene.renderer.domElement.dispatchEvent(new PointerEvent('pointerdown', options));
                    studio.scene.renderer.domElement.dispatchEvent(new PointerEvent('pointerup', options));
                    return [studio.fittings.selected, studio.scene.drawCount === drawnAt];
                }""", view)
            assert picked == ["clip1", True]
            page.keyboard.press("Escape")
        # (the page's errors are not checked: the orbit controls cannot capture a synthetic event's pointer)


def snapped_drag(page, name: str, axis: str, readout: str) -> dict:
    """With snapping on, drag the `axis` arrow of `name` as a user does, watching the readout, until it reads `readout`
    (turning back at the first step if that went the other way); the state drawn after the release."""
    page.mouse.click(700, 880)
    page.keyboard.press("s")
    select(page, name, "translate")
    handle = np.array(gizmo_handle(page, name, axis, "translate"))
    radial = handle - np.array(screen_point(page, name, [0.0, 0.0, 0.0]))
    step = 0.7 * radial / np.linalg.norm(radial)  # less than a snapping step on the screen
    components = lambda text: np.array([float(x) for x in text.split("[")[1].rstrip("]").split(",")])

    wanted = components(readout)

    def settled() -> str:
        # the readout once it stops changing: on a loaded machine the page may take the moves in late
        last = page.locator("#drag-readout").inner_text()
        for _ in range(10):
            page.wait_for_timeout(15)
            now = page.locator("#drag-readout").inner_text()
            if now == last:
                return now
            last = now
        return last

    def drag():
        page.mouse.down()
        position, increasing = handle.copy(), None  # increasing: the screen direction (+1, -1) that moves towards it
        for _ in range(600):
            progress = 0.0
            text = settled()
            if text == readout:
                page.mouse.up()
                return
            if text.startswith("moved"):
                progress = float(components(text) @ wanted) / float(wanted @ wanted)
                if increasing is None and progress != 0.0:
                    increasing = 1.0 if progress > 0.0 else -1.0
            position += (increasing or 1.0) * (1.0 if progress < 1.0 else -1.0) * step
            page.mouse.move(*position)
        raise AssertionError(f"the readout never read {readout!r}")

    return drawn_after(page, drag)


# every time the readouts table is shown: the stability margin's row (its text and colour class) and whether the
# state shown had that readout pending
MARGIN_ROWS = """() => {
    window.marginRows = [];
    new MutationObserver(() => {
        const cell = document.querySelector('#readouts tr[data-readout="stability_margin"] td:nth-child(2)');
        window.marginRows.push({ text: cell.textContent, cls: cell.className,
                                 pending: window.studio.state.readouts.pending.includes('stability_margin') });
    }).observe(document.getElementById('readouts'), { childList: true });
}"""


def test_a_drag_shows_the_stability_margin_pending_until_it_pauses_never_a_stale_value(browser, tmp_path):
    """During a drag on the floor the states leave the stability margin and the floor's smallest gap pending: the page
    shows them greyed as pending, never the last value; once the drag pauses the server's readouts come and the page
    shows the margin of the shape shown."""
    with opened_page(browser, Session(resting_hose()), tmp_path) as (page, errors, _):
        page.evaluate(MARGIN_ROWS)
        drag_handle(page, "end", "Z", "translate", 25)
        page.wait_for_function("() => window.studio.state.readouts.pending.length === 0", timeout=20000)
        page.wait_for_function("() => window.marginRows.length && !window.marginRows.at(-1).pending")
        rows = page.evaluate("() => window.marginRows")
        readouts = page.evaluate("() => window.studio.state.readouts")
        assert any(row["pending"] for row in rows)  # the drag's states were shown
        assert all(row["text"].startswith("…") and row["cls"] == "pending" for row in rows if row["pending"])
        assert all(not row["text"].startswith("…") for row in rows if not row["pending"])
        value, unit = rows[-1]["text"].split(" ")
        assert unit == "N/rad²" and float(value) == pytest.approx(readouts["stability_margin"], rel=1e-3)
        assert rows[-1]["cls"] == "good" and readouts["stability_margin"] > 0.0
        [floor] = readouts["contacts"]
        assert floor["min_gap"] is not None and "…" not in page.locator("#readouts").text_content()
        assert not errors


def test_a_drag_along_the_floor_then_a_turn_saves_as_shown_or_says_how_far_off(browser, tmp_path):
    """On the frictionless floor the hose dragged along and rolled may lie on a branch that a fresh placement reaches
    at some twist, or on one none reaches (which one depends on the states the drag passed through: moves made while
    the server steps are merged, issue 29).  Either Save writes the shape shown, or it asks and the file "as moved"
    solves as far off as it says."""
    with opened_page(browser, Session(resting_hose()), tmp_path) as (page, errors, _):
        snapped_drag(page, "end", "Z", "moved 30 mm [-30, 0, 0]")  # towards the start: more of it on the floor
        page.keyboard.press("s")  # snapping off
        drag_handle(page, "end", "Z", "rotate", -60)  # rolled on the floor
        page.wait_for_function("() => window.studio.state.readouts.pending.length === 0")  # the gaps, once it pauses
        contacts = page.evaluate("() => window.studio.state.readouts.contacts")
        assert min(c["min_gap"] for c in contacts) < 0.05  # lying on the floor
        page.wait_for_function("() => window.studio.state.comparison && window.studio.state.comparison.saved",
                               timeout=120000)
        saved = page.evaluate("() => window.studio.state.comparison.saved")
        if saved["same"]:
            solved = saved_and_solved(page, tmp_path)
            assert np.max(np.linalg.norm(solved - shown(page), axis=1)) <= SAVED_TO_SHOWN_MM
        else:
            page.click("#save")
            page.wait_for_selector("#save-choice a.save-moved", timeout=60000)
            solved = saved_and_solved(page, tmp_path / "moved", "#save-choice a.save-moved")
            distance = np.max(np.linalg.norm(solved - shown(page), axis=1))
            assert distance == pytest.approx(saved["distance"], abs=SAVED_TO_SHOWN_MM)
        assert errors == []


def moved_along_the_floor(steps: int = 10) -> Session:
    """The resting hose's end fitting dragged 10 mm along the floor towards the start in `steps` equal steps, by the
    server as a drag would: in 10 steps the hose ends on a branch no fresh placement reaches at any twist (15.7 mm off
    at best), in 20 on one it reaches (which branch depends on the states the drag passes through)."""
    session = Session(resting_hose())
    end = state_message(session)["fittings"]["end"]
    for k in range(1, steps + 1):
        point = np.array(end["point"]) - [10.0 * k / steps, 0.0, 0.0]
        session.apply(Target(type="set", seq=k, end={"point": point.tolist(), "quaternion": end["quaternion"]}))
    return session


def test_where_no_file_gives_the_shape_shown_save_asks_and_each_choice_solves_as_it_says(browser, tmp_path):
    """10 mm along the floor in 10 steps the hose lies on a branch no fresh placement reaches, whatever the twist."""
    with opened_page(browser, moved_along_the_floor(), tmp_path) as (page, errors, _):
        page.click("#save")
        page.wait_for_selector("#save-choice a.save-moved", timeout=60000)
        comparison = page.evaluate("() => window.studio.state.comparison")
        assert not comparison["saved"]["same"] and comparison["saved"]["distance"] > 1.0
        assert f"{comparison['saved']['distance']:.4g} mm off" in page.locator("#save-choice").inner_text()
        as_moved = saved_and_solved(page, tmp_path / "moved", "#save-choice a.save-moved")
        distance = np.max(np.linalg.norm(as_moved - shown(page), axis=1))
        assert distance == pytest.approx(comparison["saved"]["distance"], abs=SAVED_TO_SHOWN_MM)
        page.click("#save")
        assembled = saved_and_solved(page, tmp_path / "assembled", "#save-choice a.save-assembled")
        placed = drawn_after(page, lambda: page.click("#place-again"))
        assert np.max(np.linalg.norm(assembled - np.array(placed["centerline"]), axis=1)) <= SAVED_TO_SHOWN_MM
        assert errors == []


# --- undo and redo ---

def test_undo_and_redo_step_through_every_kind_of_edit_to_the_shapes_shown(browser, tmp_path):
    other = tmp_path / "other.toml"
    data = problem_to_dict(thesis_problem())
    longer = data["hose"]["length"] = 1.05 * data["hose"]["length"]
    data["name"] = "longer"
    from hoseline.io.problem_file import problem_to_toml
    other.write_text(problem_to_toml(problem_from_dict(data)))
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        shapes = [shown(page)]
        shapes.append(np.array(end_out_of_plane(page)["centerline"]))
        shapes.append(np.array(type_into(page, '.slider[data-key="length"] input[type="number"]', "340")["centerline"]))
        shapes.append(np.array(end_turned(page)["centerline"]))
        page.set_input_files("#open", str(other))
        page.wait_for_function("() => document.getElementById('problem-name').textContent === 'longer'", timeout=60000)
        page.wait_for_function(f"() => Math.abs(window.studio.state.hose.length - {longer!r}) < 1e-9", timeout=60000)
        shapes.append(shown(page))
        page.mouse.click(700, 880)  # on the view, below the hose
        for shape in reversed(shapes[:-1]):  # Ctrl+Z back to the first shape, each exactly as it was shown
            np.testing.assert_array_equal(np.array(press(page, "Control+z")["centerline"]), shape)
        page.wait_for_function("() => document.getElementById('problem-name').textContent !== 'longer'")
        for shape in shapes[1:-1]:  # and forward again, the last with the toolbar's button
            np.testing.assert_array_equal(np.array(press(page, "Control+Shift+z")["centerline"]), shape)
        np.testing.assert_array_equal(drawn_after(page, lambda: page.click("#redo"))["centerline"], shapes[-1])
        page.wait_for_function("() => document.getElementById('problem-name').textContent === 'longer'")
        assert errors == []


def test_the_browser_s_text_undo_does_not_reach_the_boxes(browser, tmp_path):
    """The issue's case: a value typed, a drag, Ctrl+Z in the view, then a click into the box and out of it."""
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        box = 'tr[data-fitting="end"][data-field="point"] td:nth-child(2) input'
        typed = type_into(page, box, "-250")
        end_out_of_plane(page)
        page.mouse.click(700, 880)
        undone = press(page, "Control+z")
        np.testing.assert_array_equal(undone["centerline"], typed["centerline"])  # the drag undone, the typed kept
        seq = page.evaluate("() => window.studio.seq")
        page.click(box)
        page.click("#problem-name")
        page.wait_for_timeout(500)
        assert page.evaluate("() => window.studio.seq") == seq  # nothing sent: the box kept its value
        assert page.locator(box).input_value() == "-250"
        np.testing.assert_array_equal(shown(page), typed["centerline"])
        assert errors == []


# --- snapping, readout, the taut limit, focus, measuring ---

def test_snapping_moves_and_turns_in_whole_steps_with_a_live_readout(browser, tmp_path):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        page.mouse.click(700, 880)
        page.keyboard.press("s")
        assert "active" in page.locator("#snap").get_attribute("class")
        start = np.array(page.evaluate("() => window.studio.state.fittings.end.point"))
        state = drag_handle(page, "end", "X", "translate", (-47, 13), release=False)
        readout = page.locator("#drag-readout")
        assert readout.is_visible()
        moved = np.array(state["fittings"]["end"]["point"]) - start
        distance = float(np.linalg.norm(moved))
        assert distance >= 5.0 and distance / 5.0 == pytest.approx(round(distance / 5.0), abs=1e-9)
        assert readout.inner_text().startswith(f"moved {round(distance, 3):g} mm")
        page.mouse.up()
        assert readout.is_hidden()
        before = page.evaluate("() => window.studio.state.fittings.end.quaternion")
        state = drag_handle(page, "end", "Z", "rotate", 80)
        dot = abs(float(np.dot(before, state["fittings"]["end"]["quaternion"])))
        angle = math.degrees(2 * math.acos(min(1.0, dot)))
        assert angle >= 15.0 - 1e-6 and angle / 15.0 == pytest.approx(round(angle / 15.0), abs=1e-6)
        assert errors == []


def test_a_handle_pulled_past_the_reach_of_the_hose_stays_at_its_end(browser, tmp_path):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        select(page, "end", "translate")
        handle = gizmo_handle(page, "end", "Z", "translate")
        page.mouse.down()
        for step in range(1, 41):  # the end fitting pulled away from the start by far more than the hose allows
            page.mouse.move(handle[0] - 12 * step, handle[1] + 3 * step)
            page.wait_for_timeout(30)
        page.wait_for_function("() => !window.studio.latencies || window.studio.state.seq === window.studio.seq",
                               timeout=20000)
        page.wait_for_timeout(300)
        held = np.array(page.evaluate("() => window.studio.fittings.objects.end.position.toArray()"))
        state = page.evaluate("() => window.studio.state")
        page.mouse.up()
        assert page.locator("#messages li.error").count() > 0  # the pull went past the reach
        assert np.linalg.norm(held - np.array(state["centerline"][-1])) < 1e-6  # the handle at the hose's end
        assert errors == [] or all("refused" not in e for e in errors)


def test_f_focuses_on_the_selected_fitting_and_m_measures_between_two_points_of_the_hose(browser, tmp_path):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        select(page, "end", "translate")
        page.mouse.click(700, 880)
        page.click('[data-select="end"]')
        page.keyboard.press("f")
        target = page.evaluate("() => window.studio.scene.orbit.target.toArray()")
        end = page.evaluate("() => window.studio.state.fittings.end.point")
        np.testing.assert_allclose(target, end, atol=1e-6)
        page.keyboard.press("Escape")
        page.click('[data-view="iso"]')
        page.keyboard.press("m")
        centerline = shown(page)
        for station in (9, 21):
            page.mouse.click(*world_point(page, centerline[station]))
        text = page.locator("#measure-readout").inner_text()
        assert "from hose" in text and "to hose" in text
        measured = float(text.split(" mm")[0])
        expected = float(np.linalg.norm(centerline[21] - centerline[9]))
        outer = page.evaluate("() => window.studio.state.hose.outer_diameter")
        assert abs(measured - expected) < outer  # points on the hose's surface near those stations
        assert errors == []


# --- a reload ---

def test_a_reload_restores_the_last_state_the_view_and_the_undo_history(browser, tmp_path):
    with opened_page(browser, Session(thesis_problem()), tmp_path) as (page, errors, _):
        first = shown(page)
        dragged = np.array(end_out_of_plane(page)["centerline"])
        page.select_option("#colour-map", "bend")
        page.mouse.move(700, 850)
        page.mouse.down()
        page.mouse.move(760, 800, steps=5)  # orbit the view
        page.mouse.up()
        page.click('[data-select="end"]')
        page.click('[data-mode="rotate"]')
        camera = page.evaluate("() => window.studio.scene.camera.position.toArray()")
        page.wait_for_timeout(400)  # what is kept is written within 200 ms
        page.reload()
        page.wait_for_function("() => window.studio && window.studio.state !== null", timeout=30000)
        page.wait_for_timeout(500)  # the obstacles loaded and the view fitted
        np.testing.assert_array_equal(shown(page), dragged)
        assert page.locator("#colour-map").input_value() == "bend"
        np.testing.assert_allclose(page.evaluate("() => window.studio.scene.camera.position.toArray()"), camera, atol=1e-6)
        assert page.evaluate("() => [window.studio.fittings.selected, window.studio.fittings.gizmo.mode]") == ["end", "rotate"]
        page.mouse.click(700, 880)
        np.testing.assert_array_equal(np.array(press(page, "Control+z")["centerline"]), first)
        assert errors == []
