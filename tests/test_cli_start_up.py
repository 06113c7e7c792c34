"""The command line's start-up setting (issue 31): one OpenBLAS thread unless the user sets another count.

Each check runs in a fresh interpreter, since the setting is made when `hoseline.cli` is first imported.
"""

import os
import subprocess
import sys

PROBE = """
import os
import hoseline.cli
import numpy, scipy.linalg
from threadpoolctl import threadpool_info
blas = [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]
print(os.environ["OPENBLAS_NUM_THREADS"], len(blas), min(blas), max(blas))
"""


def probe(env_extra: dict) -> list[str]:
    env = {key: value for key, value in os.environ.items() if key != "OPENBLAS_NUM_THREADS"}
    output = subprocess.run([sys.executable, "-c", PROBE], env={**env, **env_extra}, capture_output=True,
                            text=True, check=True).stdout
    return output.split()


def test_one_blas_thread_in_numpy_and_scipy():
    threads, pools, fewest, most = probe({})
    assert threads == "1" and int(pools) >= 2 and fewest == most == "1"  # NumPy's OpenBLAS and SciPy's own


def test_a_thread_count_the_user_set_is_kept():
    threads, _, _, most = probe({"OPENBLAS_NUM_THREADS": "2"})
    assert threads == "2" and most == "2"
