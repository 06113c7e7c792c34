"""Each command loads only the heavy libraries its run uses (issue 31: most of a warm `hoseline solve` was start-up).

Every command runs once in a fresh interpreter, which lists the modules it has loaded when it exits.  A plain solve
loads no mesh, CAD, plotting, image, cluster or web library and no SciPy module it does not call (scipy.linalg is
loaded by Numba itself, for its BLAS and LAPACK bindings, when it loads the first kernel); a sweep without meshes
loads no mesh or CAD library (it writes its envelope's STL itself) and, without contact, none of the contact
solver's SciPy modules; a compare no mesh, CAD or image library.
A module-level import anywhere on a command's way breaks this unseen, hence the test.
"""

import json
import subprocess
import sys

import numpy as np
from cases import THESIS_TOML, write
from test_degenerate_scans import hose_scan
from test_sweep import KNUCKLE_CSV
from validation_cases import brake_hose

from hoseline.io.problem_file import problem_to_toml
from hoseline.io.scans import write_ply

MESH_CAD_IMAGE = ["trimesh", "networkx", "OCP", "skimage"]
CLUSTER_WEB = ["dask", "distributed", "fastapi", "uvicorn", "starlette"]
PLOTS = ["plotly", "matplotlib"]
FITTING = ["scipy.interpolate", "scipy.optimize", "scipy.sparse", "scipy.spatial", "scipy.special", "scipy.stats",
           "scipy.ndimage"]

# {modules} of the watched list that the command loaded, written when the interpreter exits (after typer's exit)
RUNNER = """
import atexit, json, sys
watched, report = json.loads(sys.argv[1]), sys.argv[2]
atexit.register(lambda: open(report, "w").write(json.dumps([m for m in watched if m in sys.modules])))
from hoseline.cli import app
app(sys.argv[3:])
"""


def loaded(tmp_path, watched: list[str], *args) -> list[str]:
    """Run `hoseline *args` in a fresh interpreter, warm (run once before, so that its kernels are compiled: a
    compile, in a fresh cache, loads modules of its own); the modules of `watched` it loaded."""
    report = tmp_path / "loaded.json"
    command = [sys.executable, "-c", RUNNER, json.dumps(watched), str(report), *map(str, args)]
    for _ in range(2):
        run = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
        assert run.returncode == 0, run.stdout + run.stderr
    return json.loads(report.read_text())


def test_a_plain_solve_loads_no_heavy_library(tmp_path):
    problem = write(tmp_path / "brake.toml", THESIS_TOML)
    watched = MESH_CAD_IMAGE + CLUSTER_WEB + PLOTS + FITTING
    assert loaded(tmp_path, watched, "solve", problem, "-o", tmp_path / "out", "--quiet") == []
    assert (tmp_path / "out" / "result.json").is_file()


def test_a_sweep_without_meshes_loads_no_mesh_or_cad_library(tmp_path):
    bodies = '[[bodies]]\nname = "knuckle"\nposes = "knuckle.csv"\n'
    toml = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + bodies
    write(tmp_path / "knuckle.csv", KNUCKLE_CSV)
    sweep = write(tmp_path / "sweep.toml", toml)
    watched = MESH_CAD_IMAGE[:3] + CLUSTER_WEB + FITTING[:4]  # SciPy's interpolate, optimize, sparse, spatial
    assert loaded(tmp_path, watched, "sweep", sweep, "-o", tmp_path / "out", "--quiet") == []
    assert (tmp_path / "out" / "envelope.stl").read_bytes()[:6] != b"solid "  # binary, written without trimesh


def test_a_compare_loads_no_mesh_cad_or_image_library(tmp_path):
    problem = write(tmp_path / "hose.toml", problem_to_toml(brake_hose(segments=24)))
    scan = write_ply(tmp_path / "scan.ply", hose_scan())
    watched = MESH_CAD_IMAGE + CLUSTER_WEB
    assert loaded(tmp_path, watched, "compare", problem, scan, "-o", tmp_path / "out", "--quiet") == []
    assert np.isfinite(json.loads((tmp_path / "out" / "validation.json").read_text())["comparisons"][0]
                       ["deviation"]["mean_mm"])
