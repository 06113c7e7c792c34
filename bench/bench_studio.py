"""Benchmark: the studio's round trip from a drag event to the new shape drawn, measured in the browser.

    python bench/bench_studio.py [--events 200] [--triangles 100000]

The thesis hose (100 segments, 180 degrees of twist) in the studio, served on 127.0.0.1, open in
Debian's headless chromium (Playwright).  The end fitting is dragged in steps of 1 mm (up and
down along z) and then turned in steps of 2 degrees (about its own x axis, back and forth), one
event at a time, through the same code path as the gizmo (the page's fittings.drag, which sends
the target over the WebSocket).  Each round trip is timed in the page with performance.now():
from the event to the return of the render call that draws the answer ("drawn"), and to a
one-pixel readPixels after it, which waits until the GPU (here chromium's software renderer) has
finished the frame ("finished").  Run without obstacles, then with a strut of about --triangles
triangles shown (clearance and its colour map computed at every step).  Prints medians and 95th
percentiles, the page's share (from the answer's arrival to the render call's return), the solver
thread's share (the continuation step, the readouts and the state message) and the step's own, an
empty round trip over the same WebSocket (a message the server answers at once: the transport and
the scheduling of the processes alone), and the machine's load.
Target: median <= 16 ms, 95th percentile <= 33 ms.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_sweep import cylinder_mesh  # noqa: E402

from hoseline.demos.thesis_hose import demo_problem  # noqa: E402
from hoseline.studio.launch import in_background  # noqa: E402
from hoseline.studio.session import Session  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]

# one event at a time: move (or turn) the end fitting, wait for the answer to be drawn, then for the GPU
MEASURE = """async ([events, offset, axis, degrees, period]) => {
    const studio = window.studio, gl = studio.scene.renderer.getContext(), pixel = new Uint8Array(4);
    const drawn = [], finished = [], solve = [], server = [], page = [];
    for (let k = 0; k < events; k++) {
        const sign = Math.floor(k / period) % 2 === 0 ? 1 : -1;
        const start = performance.now();
        let done = 0;
        const answered = new Promise((resolve) => {
            studio.drawn(studio.seq + 1).then((at) => {
                gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
                done = performance.now();
                resolve(at);
            });
        });
        studio.fittings.drag('end', offset.map((x) => sign * x), axis, sign * degrees);
        const at = await answered;
        drawn.push(at - start);
        page.push(at - studio.receivedAt);
        finished.push(done - start);
        if (studio.state.step) { solve.push(1000 * studio.state.step.seconds); server.push(1000 * studio.state.server_seconds); }
    }
    return { drawn, finished, solve, server, page };
}"""


# the same round trip with nothing to solve: a second socket sends a message the server answers at once
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


def run(url: str, events: int, playwright) -> dict:
    """Round trips (ms) of `events` translation steps and as many rotation steps, in a fresh page."""
    browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
    try:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        page.wait_for_function("() => window.studio && window.studio.state !== null", timeout=60000)
        page.evaluate(MEASURE, [20, [0, 0, 1.0], 0, 0, 10])  # warm-up: compiled paths, shaders
        moves = page.evaluate(MEASURE, [events, [0, 0, 1.0], 0, 0, 25])  # 1 mm steps, 25 up then 25 down
        turns = page.evaluate(MEASURE, [events, [0, 0, 0], 0, 2.0, 10])  # 2 degree steps, 10 one way then back
        empty = page.evaluate(EMPTY, events)
    finally:
        browser.close()
    return {**{key: moves[key] + turns[key] for key in moves}, "empty": empty}


def figures(values: list[float]) -> str:
    values = np.array(values)
    return f"median {np.median(values):6.2f} ms, 95th percentile {np.percentile(values, 95):6.2f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--events", type=int, default=200, help="drag events of each kind (moves, turns)")
    parser.add_argument("--triangles", type=int, default=100_000)
    options = parser.parse_args()
    from playwright.sync_api import sync_playwright

    problem = demo_problem(180.0)
    strut = cylinder_mesh(options.triangles)
    print(f"thesis hose, {problem.hose.segments} segments, twist {problem.end_twist_deg:g} deg; "
          f"{options.events} steps of 1 mm and {options.events} of 2 deg, one at a time")
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as work:
        for label, obstacles in (("no obstacle", []), (f"strut of {len(strut.faces)} triangles", [strut])):
            session = Session(problem)
            for obstacle in obstacles:
                session.add_obstacle(obstacle.name, obstacle.vertices, obstacle.faces, "benchmark")
            with in_background(session, Path(work) / label.replace(" ", "_")) as url:
                load_before = os.getloadavg()
                times = run(url, options.events, playwright)
                load_after = os.getloadavg()
            print(f"\n{label}:")
            print(f"  event to shape drawn     {figures(times['drawn'])}")
            print(f"  event to frame finished  {figures(times['finished'])}")
            print(f"  in the page, answer to drawn {figures(times['page'])}")
            print(f"  in the solver thread     {figures(times['server'])}")
            print(f"  of which the step itself {figures(times['solve'])}")
            print(f"  empty round trip         {figures(times['empty'])}  (no solving: the transport alone)")
            print(f"  load average (1 min) {load_before[0]:.2f} before, {load_after[0]:.2f} after, on {os.cpu_count()} cores")
    print("\ntarget: median <= 16 ms, 95th percentile <= 33 ms")


if __name__ == "__main__":
    main()
