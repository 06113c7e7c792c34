"""The command line's start-up settings (issue 31): one OpenBLAS thread unless the user sets another count, and
the garbage collector off for the command's first second only (a longer command collects as usual).

Each check runs in a fresh interpreter, since both settings are made when `hoseline.cli` is first imported.
"""

import subprocess
import sys

PROBE = """
import gc, os, time
from hoseline.cli import START_UP_SECONDS
import numpy
from threadpoolctl import threadpool_info
blas = [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]
off_at_start = not gc.isenabled()
time.sleep(START_UP_SECONDS + 0.5)
print(os.environ["OPENBLAS_NUM_THREADS"], min(blas), max(blas), off_at_start, gc.isenabled())
"""


def probe(env_extra: dict) -> list[str]:
    env = {key: value for key, value in __import__("os").environ.items() if key != "OPENBLAS_NUM_THREADS"}
    output = subprocess.run([sys.executable, "-c", PROBE], env={**env, **env_extra}, capture_output=True,
                            text=True, check=True).stdout
    return output.split()


def test_one_blas_thread_and_the_collector_back_on_after_start_up():
    threads, fewest, most, off_at_start, on_after = probe({})
    assert threads == "1" and fewest == most == "1"
    assert off_at_start == "True" and on_after == "True"


def test_a_thread_count_the_user_set_is_kept():
    threads, fewest, most, _, _ = probe({"OPENBLAS_NUM_THREADS": "2"})
    assert threads == "2" and most == "2"
