"""The studio's messages, typed values and warnings (issue 29, part A), driven as a user drives it, by mouse and keyboard in headless chromium: a pull the hose cannot follow
is refused once per cause in the Messages list and leaves the header once dragged back; a refused typed value
does not stay in its box; a direction 0, 0, 0 and a box without a finite number are refused with a message;
near the taut limit the readouts warn of the reactions and the bend, in colour and in words.

The hose: 185 mm between mounts 160 mm apart whose directions cross at a right angle (the start along +y, the
end along +x), so that pulling the end fitting away along -x draws it taut: 25 mm of pull reach the mount
distance, and before that the hose bends round its ends ever more tightly and pulls on them with kN.
"""

import numpy as np
import pytest

from hoseline.io.problem_file import problem_from_dict
from hoseline.studio.session import Session
from test_studio_browser import browser, drawn_after, opened_page, pytestmark  # noqa: F401 (the fixture, the skip mark)

LENGTH, SLACK = 185.0, 25.0  # mm: the hose, and the pull from the mounts to the mount distance
PULLED_TAUT = "pulled nearly taut"
TOO_SHORT = "shorter than the mount distance"

# where the mouse takes the end fitting's Z arrow (it points along -x: away from the start), and pixels per mm along it
ARROW = """(length) => {
    const studio = window.studio, object = studio.fittings.objects.end, camera = studio.scene.camera;
    const rect = studio.scene.renderer.domElement.getBoundingClientRect();
    const screen = (mm) => {
        const p = object.localToWorld(new object.position.constructor(0, 0, mm)).project(camera);
        return [rect.left + (p.x + 1) / 2 * rect.width, rect.top + (1 - p.y) / 2 * rect.height];
    };
    const [a, b] = [screen(length), screen(length + 1)];
    return [a, [b[0] - a[0], b[1] - a[1]]];
}"""


def taut_problem():
    return problem_from_dict({
        "hose": {"length": LENGTH, "outer_diameter": 10.1, "bending_stiffness": 1.5e5, "segments": 30},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [0.0, 1.0, 0.0]},
        "end": {"point": [-160.0, -7.0, 0.0], "direction": [1.0, 0.0, 0.0]},
    })


@pytest.fixture()
def page(browser, tmp_path):  # noqa: F811 (the browser fixture imported above)
    with opened_page(browser, Session(taut_problem()), tmp_path) as (opened, errors, _):
        yield opened
        assert errors == []


def take_end_arrow(page):
    """Put the Move gizmo on the end fitting and the mouse on its Z arrow, pressed; the point and pixels per mm."""
    page.click('[data-select="end"]')
    page.click('[data-mode="translate"]')
    for length in (15, 20, 25, 30, 40):
        point, per_mm = page.evaluate(ARROW, length)
        page.mouse.move(*point)
        if page.evaluate("() => window.studio.fittings.gizmo.axis") == "Z":
            page.mouse.down()
            return point, per_mm
    raise AssertionError("the mouse found no Z arrow on the end fitting")


def pull(page, grip, pulls_mm) -> dict:
    """Move the pressed mouse to each of `pulls_mm` (mm along the arrow from where it took it), waiting for each
    answer, as a slow hand drags; the last state."""
    (x, y), (dx, dy) = grip
    for mm in pulls_mm:
        state = drawn_after(page, lambda: page.mouse.move(x + mm * dx, y + mm * dy))
    return state


def moved(page, state) -> float:
    """How far (mm) the end fitting of `state` is from where the problem puts it."""
    return float(np.linalg.norm(np.array(state["fittings"]["end"]["point"]) - [-160.0, -7.0, 0.0]))


def test_a_pull_past_the_taut_hose_is_told_once_and_leaves_the_header_when_dragged_back(page):
    grip = take_end_arrow(page)
    pull(page, grip, range(1, 36))  # 35 mm: the last 10 or so beyond the mount distance
    refusals = page.locator("#messages li", has_text=TOO_SHORT)
    assert refusals.count() == 1  # one line for the cause, however many moves were refused
    times = int(refusals.inner_text().rsplit("(", 1)[1].split()[0])
    assert times >= 3
    assert TOO_SHORT in page.locator("#status").inner_text()
    state = pull(page, grip, range(34, 9, -1))  # back to 10 mm: the hose follows again
    page.mouse.up()
    assert 5.0 < moved(page, state) < 15.0
    assert TOO_SHORT not in page.locator("#status").inner_text()
    assert page.locator("#messages li", has_text=TOO_SHORT).count() == 1


def test_near_the_taut_limit_the_readouts_warn_of_the_reactions_and_the_bend(page):
    readout = lambda name: page.locator(f'#readouts tr[data-readout="{name}"] td').nth(1)  # noqa: E731
    assert PULLED_TAUT not in readout("start_reaction").inner_text()  # as placed: no warning on the reactions
    grip = take_end_arrow(page)
    state = pull(page, grip, np.arange(1.0, SLACK - 2.0, 1.0))  # to 2-3 mm short of the mount distance
    page.mouse.up()
    assert SLACK - 4.0 < moved(page, state) < SLACK  # near the taut limit, not past it
    page.wait_for_function(f"() => document.getElementById('readouts').textContent.includes('{PULLED_TAUT}')")
    force = np.linalg.norm(state["readouts"]["start_force"])
    assert force > 1000.0  # N: the hose, weightless, pulls on its mounts with over a kN
    for name in ("start_reaction", "end_reaction", "min_bend_radius"):
        assert readout(name).get_attribute("class") == "bad", name
    assert PULLED_TAUT in readout("start_reaction").inner_text()
    assert PULLED_TAUT in readout("end_reaction").inner_text()
    bend = readout("min_bend_radius").inner_text()
    assert "typical minimum 30.3" in bend and ("below 30.3 mm, 3 outer diameters" in bend or "kink" in bend)


def type_into(page, box, text: str) -> None:
    """Click into `box`, select what it holds, type `text` and press Enter, as a user gives a value."""
    box.click()
    page.keyboard.press("Control+A")
    page.keyboard.type(text)
    page.keyboard.press("Enter")


def test_a_refused_length_does_not_stay_in_its_box(page):
    box = page.locator('.slider[data-key="length"] input[type="number"]')
    state = drawn_after(page, lambda: type_into(page, box, "100"))
    assert state["hose"]["length"] == LENGTH  # refused: the hose keeps its length
    assert TOO_SHORT in page.locator("#messages li.error").first.inner_text()
    page.wait_for_function("(box) => box.value === '185'", arg=box.element_handle())  # the box shows it again
    assert page.evaluate("() => document.activeElement.closest('.slider').dataset.key") == "length"  # still typed in


def test_a_refused_segment_count_does_not_stay_in_its_box(page):
    box = page.locator("#segments")
    state = drawn_after(page, lambda: type_into(page, box, "3"))
    assert state["hose"]["segments"] == 30
    assert "hose.segments" in page.locator("#messages li.error").first.inner_text()
    page.wait_for_function("(box) => box.value === '30'", arg=box.element_handle())


def test_a_typed_direction_of_zero_is_refused_with_a_message(page):
    row = page.locator('table.fittings tr[data-fitting="end"][data-field="direction"] input')
    assert [row.nth(k).input_value() for k in range(3)] == ["1", "0", "0"]
    seq = page.evaluate("() => window.studio.seq")
    type_into(page, row.nth(0), "0")  # 0, 0, 0
    error = page.locator("#messages li.error").first
    assert "end direction: 0, 0, 0 points nowhere" in error.inner_text()
    assert page.evaluate("() => window.studio.seq") == seq  # nothing sent
    assert row.nth(0).input_value() == "1"  # the box shows the direction in force again
    assert "points nowhere" in page.locator("#status").inner_text()


@pytest.mark.parametrize("text", ["nan", "inf", "1e999"])
def test_a_box_without_a_finite_number_says_so(page, text):
    box = page.locator('.slider[data-key="length"] input[type="number"]')
    seq = page.evaluate("() => window.studio.seq")
    type_into(page, box, text)
    assert page.locator("#messages li.error").first.inner_text() == "Length, mm: must be a finite number"
    assert page.evaluate("() => window.studio.seq") == seq  # nothing sent
    assert box.input_value() == "185"


def test_the_bending_stiffness_box_shows_its_whole_value(page):
    box = page.locator('.slider[data-key="bending_stiffness"] input[type="number"]')
    state = drawn_after(page, lambda: type_into(page, box, "149563.02563205"))  # the thesis hose's EI, N*mm^2
    assert state["hose"]["bending_stiffness"] == 149563.02563205
    page.locator("#segments").click()  # away from the box
    assert box.input_value() == "149563.025632"
    width, room = box.evaluate("(box) => [box.scrollWidth, box.clientWidth]")
    assert width <= room  # nothing cut off


def test_the_fittings_boxes_show_their_whole_values(browser, tmp_path):  # noqa: F811 (the browser fixture)
    """The thesis hose's end tip x (-173.064 mm) and the clips' values to six decimals fit their boxes."""
    from hoseline.demos.thesis_hose import demo_problem
    from test_studio_server import clipped_thesis_problem

    with opened_page(browser, Session(clipped_thesis_problem(demo_problem(180.0, segments=30))), tmp_path) as (page, errors, _):
        page.wait_for_function("() => document.querySelector('tr[data-clip] input').value !== ''")
        boxes = page.evaluate("""() => [...document.querySelectorAll('table.fittings input')]
            .map((box) => [box.value, box.scrollWidth, box.clientWidth])""")
        assert len(boxes) == 24 and "-173.064" in [value for value, _, _ in boxes]
        assert min(len(value) for value, _, _ in boxes[12:]) >= 8  # the clips' values: 8 characters and more
        assert [value for value, width, room in boxes if width > room] == []  # nothing cut off
        assert errors == []


def test_place_again_shows_that_the_page_is_busy_until_the_hose_is_placed(page):
    busy = page.locator("#busy")
    assert busy.is_hidden()
    shown = page.evaluate("""() => { document.getElementById('place-again').click();  // as the mouse clicks it
        const busy = document.getElementById('busy'); return [busy.hidden, busy.textContent]; }""")
    assert shown == [False, "placing the hose again"]
    busy.wait_for(state="hidden", timeout=20000)
    assert page.evaluate("() => window.studio.state.seq === window.studio.seq")


def test_fit_and_iso_frame_the_hose_not_the_contact_plane(browser, tmp_path):  # noqa: F811
    from tests.test_studio_contact import resting_hose

    with opened_page(browser, Session(resting_hose()), tmp_path) as (page, errors, _):
        page.wait_for_function("() => window.studio.scene.bounds")
        for view in ("iso", "fit"):
            page.click(f'[data-view="{view}"]')
            width, height = page.evaluate("""() => {  // the hose's extent on the screen, as fractions of the view
                const studio = window.studio, box = studio.hose.bounds(), camera = studio.scene.camera;
                const xs = [], ys = [];
                for (const x of [box.min.x, box.max.x]) for (const y of [box.min.y, box.max.y]) for (const z of [box.min.z, box.max.z]) {
                    const p = box.min.clone().set(x, y, z).project(camera); xs.push(p.x); ys.push(p.y);
                }
                return [(Math.max(...xs) - Math.min(...xs)) / 2, (Math.max(...ys) - Math.min(...ys)) / 2];
            }""")
            assert max(width, height) > 0.45, (view, width, height)  # the floor is 1600 mm wide, the hose 300 mm
        assert errors == []
