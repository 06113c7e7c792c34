"""Benchmark: the studio server's step of a drag with the strut in contact, in Python, without a browser.

    python bench/bench_studio_step.py [--moves 64]

The case of bench_studio.py with contact (bench_contact_placement.strut_cases: the thesis hose, 100 segments, 180
degrees of twist, a fixed clip at station 50, a strut of 100 000 triangles pushing it 1 mm aside, self-contact on)
in a studio server object (studio/server.Studio) without its web server: the end fitting's target moved 1 mm a
message along z, to and fro between -8 and +8 mm, each handled as the solver thread handles a drag's message
(Studio._solve: the step of continuation and the state message as JSON, readouts pending).  Prints the CPU time
(time.process_time: the machine's load changes it less than the wall time) of the step, median over `moves` messages
after 16 to warm up, and of its parts measured again on the state reached (the drag's result, the state message with
the clearance colour map, the JSON), the state message's size, and the machine's load.
"""

from __future__ import annotations

import argparse
import json
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

from bench_contact_placement import strut_cases  # noqa: E402
from hoseline.studio import view  # noqa: E402
from hoseline.studio.messages import parse_message  # noqa: E402
from hoseline.studio.server import Studio  # noqa: E402
from hoseline.studio.session import Session  # noqa: E402

WARM_UP = 16  # messages before the timing: compiled paths, the contact searches' lists
AMPLITUDE_MM = 8  # the drag runs to and fro between -8 and +8 mm


def cpu_ms(call) -> tuple[float, object]:
    """(CPU milliseconds of call(), its value)."""
    started = time.process_time()
    value = call()
    return 1000.0 * (time.process_time() - started), value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=64, help="messages timed (after 16 to warm up)")
    options = parser.parse_args()
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as work:
        studio = Studio(Session(strut_cases()[1]), Path(work))
        end = json.loads(studio.state_text(None))["fittings"]["end"]
        session = studio.session
        times: dict[str, list[float]] = {"step": [], "result": [], "state": [], "clearances": [], "json": []}
        for k in range(WARM_UP + options.moves):
            offset = AMPLITUDE_MM - abs(k % (4 * AMPLITUDE_MM) - 2 * AMPLITUDE_MM)
            point = (np.array(end["point"]) + [0.0, 0.0, float(offset)]).tolist()
            message = parse_message(json.dumps({"type": "set", "seq": k + 1,
                                                "end": {"point": point, "quaternion": end["quaternion"]}}))
            step, _ = cpu_ms(lambda: studio._solve(message))
            result_ms, result = cpu_ms(lambda: session.result(complete=False))
            state_ms, state = cpu_ms(lambda: view.state_message(session, complete=False))
            clearance_ms, _ = cpu_ms(lambda: view._clearances(session, result.centerline, session.problem.hose.outer_radius))
            json_ms, text = cpu_ms(lambda: json.dumps(state, allow_nan=False))
            if k >= WARM_UP:
                for name, value in zip(times, (step, result_ms, state_ms, clearance_ms, json_ms)):
                    times[name].append(value)
    median = {name: float(np.median(values)) for name, values in times.items()}
    print(f"the studio's step of a drag with the strut in contact, CPU medians of {options.moves} messages:")
    print(f"  the step (Studio._solve: continuation and the state as JSON)  {median['step']:.2f} ms")
    print(f"    the drag's result (Session.result(complete=False))          {median['result']:.2f} ms")
    print(f"    the state message (with the result and clearances)          {median['state']:.2f} ms")
    print(f"      the clearance colour map and nearest approaches           {median['clearances']:.2f} ms")
    print(f"    its JSON ({len(text)} characters)                              {median['json']:.2f} ms")
    print(f"    the rest (the step of continuation, the message checked)    "
          f"{median['step'] - median['state'] - median['json']:.2f} ms")
    print(f"load average (1 min) {load_before:.2f} before, {os.getloadavg()[0]:.2f} after, on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
