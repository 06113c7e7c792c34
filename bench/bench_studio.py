"""Benchmark: a drag in the studio by real pointer events, from the pointer move to the state received and drawn.

    python bench/bench_studio.py [--moves 150] [--no-contact]

The thesis hose (100 segments, 180 degrees of twist) in the studio, served on 127.0.0.1 and open in Debian's
headless chromium (software WebGL, no GPU) through Playwright (its async API, so that the moves at 60 Hz go out
on their ticks).  The mouse (page.mouse: input events that go through the browser as a user's do) takes the end
fitting's gizmo by one of its arrows and drags it to and fro along it, 1 mm a move, first one move at a time
(the next 100 ms after the last one's frame) and then at 60 Hz (a move every 1/60 s, as a steady hand drags).
Timed in the page with performance.now(): each move, timed from when the browser took it in (the event's
timeStamp), and when the page first saw it (capture listeners on the window, before the gizmo's): in a
pointerrawupdate, dispatched as the browser takes the move in, which the studio's drag follows where the browser
has it, or in a pointermove (chromium hands the page at most one a frame, holding the moves since the last in its
coalesced events, some 4 ms after they came at 60 Hz); and the page's marks (static/js/marks.js) of every target
sent, state received and frame drawn.  A move's position goes out with the first target sent after the page saw it
(at once, or merged into the next while one is in flight), so for each move:

    state received  the first state answering that target or a later one, less the move's time;
    shape drawn     the drawing of the view that shows it (its render call returned: at an animation frame, or at
                    once when the state comes, static/js/scene.js), less the move's time;
    lag at 60 Hz    at every frame drawn during the 60 Hz drag, its time less the time of the latest move whose
                    position it shows; and the last move's time to the frame that shows it.

Then the same with contact: the case of bench_contact_placement.py --mesh (a fixed clip at station 50, a strut
of 100 000 triangles pushing the hose 1 mm aside, self-contact on), so every step is a contact solve and every
frame draws the strut.  Prints medians and 95th percentiles, the solver thread's share, an empty round trip on a
second WebSocket (the transport alone), and the machine's load.
Targets (issue 29): state received median <= 10 ms; shape drawn median <= 33 ms, 95th percentile <= 50 ms;
lag at 60 Hz <= 50 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import tempfile
import time
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from hoseline.demos.thesis_hose import demo_problem  # noqa: E402
from hoseline.studio.launch import in_background  # noqa: E402
from hoseline.studio.session import Session  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]
AMPLITUDE_MM = 8  # the drag runs to and fro between -8 and +8 mm from where it took the arrow
PAUSE_S = 0.1  # between the moves made one at a time

# the timestamps: every mouse move the browser took in, when it took it in (the event's timeStamp) and when the page
# first saw it, in a pointerrawupdate (dispatched as the browser takes the move in; the studio's drag follows those
# where the browser has them) or in a pointermove (chromium hands the page at most one a frame, the moves since the
# last one in its coalesced events), before the gizmo does; and the page's own marks
RECORD = """() => {
    window.benchMoves = [];
    window.studio.marks.list = [];
    for (const type of ['pointerrawupdate', 'pointermove']) {
        window.addEventListener(type, (event) => {
            const seen = performance.now(), coalesced = event.getCoalescedEvents();
            for (const move of coalesced.length ? coalesced : [event]) {
                window.benchMoves.push([move.timeStamp, seen, type]);
            }
        }, { capture: true });
    }
}"""
FORGET = "() => { window.benchMoves.length = 0; window.studio.marks.list.length = 0; }"
TAKE = "() => ({ moves: window.benchMoves.slice(), marks: window.studio.marks.list.slice() })"

# resolves once a target was sent after the `sent`-th one and a frame has drawn its answer
DRAWN_AFTER = """(sent) => new Promise((resolve) => {
    const check = () => {
        const marks = window.studio.marks.list, targets = marks.filter((m) => m[0] === 'sent');
        const last = targets.length > sent ? targets[targets.length - 1][1] : Infinity;
        if (marks.some((m) => m[0] === 'drawn' && m[1] >= last)) resolve(); else setTimeout(check, 1);
    };
    check();
})"""

# a screen point on the end fitting's arrow along its own `axis` at `length` mm, and the pixels a mm along it
ARROW = """([axis, length]) => {
    const studio = window.studio, object = studio.fittings.objects.end, camera = studio.scene.camera;
    const rect = studio.scene.renderer.domElement.getBoundingClientRect();
    const screen = (mm) => {
        const local = [0, 0, 0]; local[axis] = mm;
        const p = object.localToWorld(new object.position.constructor(...local)).project(camera);
        return [rect.left + (p.x + 1) / 2 * rect.width, rect.top + (1 - p.y) / 2 * rect.height];
    };
    const [a, b] = [screen(length), screen(length + 1)];
    return [a, [b[0] - a[0], b[1] - a[1]]];
}"""

# the same round trip with nothing to solve: a second socket sends a message the server refuses at once
EMPTY = """async (events) => {
    const socket = new WebSocket(`ws://${location.host}/ws`);
    let answer = null;
    await new Promise((resolve) => { let count = 0; socket.onmessage = () => { if (++count === 2) resolve(); }; });
    socket.onmessage = () => answer && answer(performance.now());
    const times = [];
    for (let k = 0; k < events; k++) {
        const start = performance.now();
        const at = await new Promise((resolve) => { answer = resolve; socket.send('{"type": "none"}'); });
        times.push(at - start);
    }
    socket.close();
    return times;
}"""


async def gizmo_arrow(page) -> tuple[list[float], list[float]]:
    """A screen point where the mouse takes one of the end fitting's arrows, and the pixels per mm along it."""
    await page.click('[data-select="end"]')
    await page.click('[data-mode="translate"]')
    for axis in (0, 1):
        for length in (15, 20, 25, 30, 35, 40, 50):
            point, per_mm = await page.evaluate(ARROW, [axis, length])
            await page.mouse.move(*point)
            if await page.evaluate("() => window.studio.fittings.gizmo.axis") in ("X", "Y"):
                return point, per_mm
    raise RuntimeError("the mouse found no gizmo arrow on the end fitting")


def to_and_fro(moves: int) -> list[float]:
    """The offsets (mm) of `moves` moves of 1 mm along the arrow, to and fro between -AMPLITUDE_MM and +AMPLITUDE_MM."""
    period = 4 * AMPLITUDE_MM
    phases = np.arange(1, moves + 1) % period
    return np.where(phases <= AMPLITUDE_MM, phases, np.where(phases <= 3 * AMPLITUDE_MM, 2 * AMPLITUDE_MM - phases,
                                                              phases - period)).tolist()


async def drag(page, moves: int, rate_hz: float | None) -> dict:
    """Drag the end fitting by the mouse: `moves` moves at `rate_hz` (None: one at a time); the page's timestamps.

    At a rate, each move is sent on its tick without waiting for the browser to take the last one (chromium answers
    an input event once it has handled it, at its next frame: waiting would pace the moves by the frames)."""
    point, per_mm = await gizmo_arrow(page)
    await page.wait_for_function("() => window.studio.state.comparison", timeout=60000)  # the idle comparison done
    await page.mouse.down()
    await page.evaluate(FORGET)
    started, moving = time.perf_counter(), []
    for k, offset in enumerate(to_and_fro(moves)):
        target = (point[0] + offset * per_mm[0], point[1] + offset * per_mm[1])
        if rate_hz is None:
            sent = await page.evaluate("() => window.studio.marks.list.filter((m) => m[0] === 'sent').length")
            await page.mouse.move(*target)
            await page.evaluate(DRAWN_AFTER, sent)
            await asyncio.sleep(PAUSE_S)
        else:
            await asyncio.sleep(max(0.0, started + k / rate_hz - time.perf_counter()))
            moving.append(asyncio.ensure_future(page.mouse.move(*target)))
    await asyncio.gather(*moving)
    await page.evaluate(DRAWN_AFTER, 0)
    taken = await page.evaluate(TAKE)
    await page.mouse.up()
    return taken


def timings(taken: dict) -> dict:
    """Per move (ms): to the state received and to the frame drawn; per frame: the lag of the position drawn."""
    marks = taken["marks"]
    sent = [(at, seq) for what, seq, at, _ in marks if what == "sent"]
    received = [(at, seq) for what, seq, at, _ in marks if what == "received" and seq is not None]
    drawn = [(at, seq) for what, seq, at, _ in marks if what == "drawn"]

    def first(events, seq):
        return next((at for at, s in events if s >= seq), None)

    first_seen = {}  # when the browser took the move in -> when the page first saw it
    for moved, seen, _ in taken["moves"]:
        first_seen[moved] = min(seen, first_seen.get(moved, seen))
    carried = []  # (when the browser took the move in, seq of the first target sent after the page saw it)
    for moved, seen in sorted(first_seen.items()):
        seq = next((s for at, s in sent if at >= seen), None)
        if seq is not None:
            carried.append((moved, seq))
    to_sent = [first(sent, seq) - moved for moved, seq in carried]
    to_received = [first(received, seq) - moved for moved, seq in carried if first(received, seq) is not None]
    to_drawn = [first(drawn, seq) - moved for moved, seq in carried if first(drawn, seq) is not None]
    lags = []
    for at, seq in drawn:
        shown = [moved for moved, s in carried if s <= seq]
        if shown:
            lags.append(at - max(shown))
    last_moved, last_seq = carried[-1]
    server = [1000 * detail for what, _, _, detail in marks if what == "received" and detail is not None]
    moves = sorted(first_seen)
    return {"sent": to_sent, "received": to_received, "drawn": to_drawn, "lag": lags, "last": first(drawn, last_seq) - last_moved,
            "server": server, "moves": len(carried), "targets": len(sent), "frames": len(drawn),
            "rate": 1000.0 * (len(moves) - 1) / (moves[-1] - moves[0]),
            "events": {kind: len({seen for _, seen, type in taken["moves"] if type == kind})
                       for kind in ("pointerrawupdate", "pointermove")}}


def figures(values: list[float]) -> str:
    values = np.array(values)
    return f"median {np.median(values):6.1f} ms, 95th percentile {np.percentile(values, 95):6.1f} ms"


async def measure(session: Session, work: Path, moves: int, playwright) -> None:
    """Print the figures of the drags one at a time and at 60 Hz on `session`, in a fresh browser."""
    browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
    try:
        with in_background(session, work) as url:
            page = await browser.new_page(viewport={"width": 1400, "height": 900})
            await page.goto(url)
            await page.wait_for_function("() => window.studio && window.studio.state !== null", timeout=60000)
            await page.wait_for_timeout(1000)  # the obstacles fetched and drawn
            await page.evaluate(RECORD)
            await drag(page, 20, 60.0)  # warm-up: compiled paths, shaders
            load_before = os.getloadavg()[0]
            single = timings(await drag(page, moves, None))
            steady = timings(await drag(page, 3 * moves, 60.0))
            empty = await page.evaluate(EMPTY, 100)
            load_after = os.getloadavg()[0]
    finally:
        await browser.close()
    print(f"  one move at a time ({single['moves']} moves):")
    print(f"    pointermove to target sent     {figures(single['sent'])}")
    print(f"    pointermove to state received  {figures(single['received'])}")
    print(f"    pointermove to shape drawn     {figures(single['drawn'])}")
    print(f"    in the solver thread           {figures(single['server'])}")
    events = steady["events"]
    print(f"  at 60 Hz ({steady['moves']} moves, {steady['rate']:.0f} a second as the browser took them in, in "
          f"{events['pointerrawupdate']} pointerrawupdate and {events['pointermove']} pointermove events; "
          f"{steady['targets']} targets sent, {steady['frames']} frames drawn):")
    print(f"    pointermove to state received  {figures(steady['received'])}")
    print(f"    pointermove to shape drawn     {figures(steady['drawn'])}")
    print(f"    lag of the position drawn      {figures(steady['lag'])}; the last move drawn after {steady['last']:.1f} ms")
    print(f"    in the solver thread           {figures(steady['server'])}, longest {max(steady['server']):.0f} ms")
    print(f"  empty round trip (transport)     {figures(empty)}")
    print(f"  load average (1 min) {load_before:.2f} before, {load_after:.2f} after, on {os.cpu_count()} cores")


async def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=150, help="moves one at a time; three times as many at 60 Hz")
    parser.add_argument("--no-contact", action="store_true", help="skip the case with the strut in contact")
    options = parser.parse_args()
    from playwright.async_api import async_playwright

    cases = [("thesis hose, 100 segments, 180 deg of twist, no obstacle", lambda: demo_problem(180.0))]
    if not options.no_contact:
        from bench_contact_placement import strut_cases

        cases.append(("the same with a fixed clip at station 50 and a strut of 100 000 triangles in contact, "
                      "self-contact on", lambda: strut_cases()[1]))
    async with async_playwright() as playwright:
        with tempfile.TemporaryDirectory() as work:
            for number, (label, problem) in enumerate(cases):
                print(f"\n{label}:", flush=True)
                await measure(Session(problem()), Path(work) / str(number), options.moves, playwright)
    print("\ntargets: state received median <= 10 ms; shape drawn median <= 33 ms, 95th percentile <= 50 ms; "
          "lag at 60 Hz <= 50 ms")


if __name__ == "__main__":
    asyncio.run(main())
