"""The compiled kernels' cache (hoseline/compilation.py): an edit always takes effect, kernels load
from the cache otherwise, the first run compiles everything a placement needs and says so."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import pytest
from typer.testing import CliRunner

from hoseline import cli, compilation
from hoseline.commands import common
from hoseline.procedures import compile_kernels

CALLEE = "from numba import njit\n\n\n@njit(cache=True)\ndef factor():\n    return {factor}\n"
CALLER = """from numba import njit

from hoseline.mechanics.probe_callee import factor


@njit(cache=True)
def scaled(x):
    return factor() * x
"""
PROBE = """from hoseline.mechanics.probe_caller import scaled

print(scaled(1.5), sum(scaled.stats.cache_hits.values()))
"""


def run_python(code: str, source: Path, cache: Path) -> str:
    """Run `code` in a fresh interpreter that imports hoseline from `source`, with NUMBA_CACHE_DIR=cache."""
    env = {**os.environ, "PYTHONPATH": str(source), "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", code], env=env, cwd=source, capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_an_edit_to_a_kernel_called_from_another_module_takes_effect(tmp_path):
    """Numba's own cache keeps the caller's old machine code (its file did not change); here the
    next run compiles the edit, while an unchanged run loads from the cache."""
    source = tmp_path / "src"
    package = source / "hoseline"
    shutil.copytree(compilation.PACKAGE, package, ignore=shutil.ignore_patterns("__pycache__"))
    (package / "mechanics" / "probe_callee.py").write_text(CALLEE.format(factor=2.0))
    (package / "mechanics" / "probe_caller.py").write_text(CALLER)
    cache = tmp_path / "cache"

    assert run_python(PROBE, source, cache).split() == ["3.0", "0"]  # compiled
    assert run_python(PROBE, source, cache).split() == ["3.0", "1"]  # loaded from the cache
    (package / "mechanics" / "probe_callee.py").write_text(CALLEE.format(factor=3.0))
    assert run_python(PROBE, source, cache).split() == ["4.5", "0"]  # the edit compiled, not the old code loaded


def write_package(root: Path, files: dict[str, str]) -> Path:
    """A package `hoseline` under root with the given modules (relative path: text)."""
    for name, text in files.items():
        path = root / "hoseline" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root / "hoseline"


def test_the_fingerprint_covers_kernel_modules_and_what_they_import_only(tmp_path):
    package = write_package(tmp_path, {
        "__init__.py": "",
        "kernels/__init__.py": "",
        "kernels/rod.py": "import numba\nfrom hoseline.model.limits import (\n    BANDWIDTH,\n)\n",
        "kernels/lazy.py": "def f():\n    from numba import njit\n    from hoseline.kernels import helpers\n",
        "kernels/helpers.py": "SCALE = 2.0\n",
        "model/__init__.py": "",
        "model/limits.py": "BANDWIDTH = 5\n",
        "report/table.py": "import hoseline.model\nWIDTH = 80\n",
    })
    assert [p.relative_to(package).as_posix() for p in compilation.kernel_sources(package)] == [
        "kernels/__init__.py", "kernels/helpers.py", "kernels/lazy.py", "kernels/rod.py", "model/limits.py"]
    before = compilation.fingerprint(package)
    (package / "report" / "table.py").write_text("WIDTH = 100\n")
    assert compilation.fingerprint(package) == before  # no kernel can see the report
    for name, text in [("model/limits.py", "BANDWIDTH = 6\n"), ("kernels/helpers.py", "SCALE = 3.0\n")]:
        (package / name).write_text(text)
        assert compilation.fingerprint(package) != before
        before = compilation.fingerprint(package)


def test_numba_cache_dir_is_the_first_base_and_an_unwritable_one_is_passed_over(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "mine"))
    bases = compilation.base_folders()
    assert bases[:2] == [tmp_path / "mine", compilation.PACKAGE / "__pycache__"]
    (tmp_path / "file").write_text("")
    assert not compilation._writable(tmp_path / "file" / "cache")
    assert compilation._writable(tmp_path / "mine" / "cache")
    monkeypatch.setattr(numba.config, "CACHE_DIR", "")
    assert compilation.base_folders()[0] == compilation.PACKAGE / "__pycache__"


def test_old_versions_are_pruned_most_recently_used_kept(tmp_path):
    for age in range(6):
        folder = tmp_path / f"{compilation.FOLDER_PREFIX}{age}"
        folder.mkdir()
        os.utime(folder, (1e9 - age, 1e9 - age))
    (tmp_path / "other-cache").mkdir()
    compilation.prune_versions(tmp_path, keep=4)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == [f"{compilation.FOLDER_PREFIX}{age}" for age in range(4)] + ["other-cache"]


def test_every_kernel_module_is_below_a_package_that_installs_the_cache():
    """A module that defines kernels must be imported after compilation.install(): its package,
    or one above it (not hoseline/ itself, which the command line imports for --help), calls it."""
    package = compilation.PACKAGE
    kernel_modules = [path for path in compilation.kernel_sources()
                      if compilation._USES_NUMBA.search(path.read_text()) and path != Path(compilation.__file__)]
    assert kernel_modules
    for module in kernel_modules:
        inits = [folder / "__init__.py" for folder in module.relative_to(package).parents if folder != Path(".")]
        assert any("compilation.install()" in (package / init).read_text() for init in inits), module


def test_the_kernels_live_in_the_version_folder():
    from hoseline.mechanics import newton
    from hoseline.procedures.geometry import clearance

    for kernel in (newton._track_kernel, clearance._nearest):
        assert Path(kernel.stats.cache_path).is_relative_to(compilation.version_folder())
    assert compilation.persistent()


SIGNATURES = textwrap.dedent("""
    import sys
    from numba.core.registry import CPUDispatcher

    def signatures():
        # (kernel, argument types) of every compiled or loaded kernel of hoseline in this process
        return {(f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}", str(signature))
                for name, module in list(sys.modules.items()) if name.startswith("hoseline")
                for kernel in vars(module).values() if isinstance(kernel, CPUDispatcher)
                for signature in kernel.overloads}
""")


def test_the_made_up_arrays_of_the_parallel_compile_have_a_placements_types():
    """newton_kernels() and stability_kernels() (run side by side on a first run) compile the kernels
    a placement uses with the argument types it uses: the placement then adds no signature to them."""
    code = SIGNATURES + textwrap.dedent("""
        from hoseline.procedures import compile_kernels
        from hoseline.procedures.placement.sequence import solve

        compile_kernels.newton_kernels()
        compile_kernels.stability_kernels()
        covered = signatures()
        kernels = {kernel for kernel, _ in covered}
        solve(compile_kernels.SMALL_PLACEMENT)
        print(sorted((kernel, types) for kernel, types in signatures() - covered if kernel in kernels))
        print(sorted(kernel.rsplit(".", 1)[1] for kernel in kernels if kernel.rsplit(".", 1)[1] in
                     ("_track_kernel", "_minimise_kernel", "_subspace_iteration")))
    """)
    cache = numba.config.CACHE_DIR or compilation.version_folder().parent
    assert run_python(code, compilation.PACKAGE.parent, cache).splitlines() == [
        "[]", "['_minimise_kernel', '_subspace_iteration', '_track_kernel']"]


def test_placements_after_compile_kernels_need_no_other_kernel(tmp_path):
    """compile_kernels() compiles or loads every kernel, with every argument type, that a full-size
    placement uses: the demo hose at 100 segments then adds no signature to any kernel, nor does
    the hose with stiffener springs twisted by 45 degrees after compile_kernels(stiffeners=True),
    nor, after compile_kernels(clips=True, contact=True), a hose held by clips and the heavy hose
    that snaps onto the floor at 40 segments, with its obstacles and without the large mesh among them, nor,
    after compile_kernels(preset=True, braid=True), the demo hose with a set and with a braid at 0 and 180 degrees.  (Counting signatures, not compilations: a kernel loaded from the cache would have compiled on
    a fresh installation.)"""
    code = SIGNATURES + textwrap.dedent("""
        from dataclasses import replace
        from hoseline.procedures.compile_kernels import compile_kernels, kernels_compiled
        from hoseline.demos.thesis_hose import demo_problem
        from hoseline.model.stiffeners import thesis_preset
        from hoseline.procedures.placement.sequence import solve

        compile_kernels()
        before = signatures()
        for twist in (0.0, 180.0):
            solve(demo_problem(twist))
        print(sorted(signatures() - before))
        compile_kernels(stiffeners=True)
        before = signatures()
        preset = thesis_preset(330.6)
        stiffened = demo_problem(45.0, preset.segments)
        solve(replace(stiffened, hose=replace(stiffened.hose, stiffeners=preset.stiffeners)))
        print(sorted(signatures() - before), kernels_compiled(stiffeners=True))
        compile_kernels(clips=True, contact=True)
        before = signatures()
        from hoseline.procedures.compile_kernels import SMALL_PLACEMENT, CONTACT_PLACEMENT, small_clips
        solve(replace(SMALL_PLACEMENT, clips=small_clips()), estimate_error=False)
        heavy = replace(CONTACT_PLACEMENT, hose=replace(CONTACT_PLACEMENT.hose, segments=40))
        solve(heavy, estimate_error=False)
        solve(replace(heavy, contact=heavy.contact[:-1]), estimate_error=False)  # small meshes only: no leaf lists
        print(sorted(signatures() - before), kernels_compiled(clips=True, contact=True))
        compile_kernels(preset=True, braid=True)
        before = signatures()
        from hoseline.model.braid import Braid
        from hoseline.model.preset import Preset
        for twist in (0.0, 180.0):
            plain = demo_problem(twist)
            solve(replace(plain, hose=replace(plain.hose, preset=Preset(1.0 / 300.0, 25.0))))
            solve(replace(plain, hose=replace(plain.hose, braid=Braid(30.0, 16, 2500.0, 0.01, 4.0))))
        print(sorted(signatures() - before), kernels_compiled(preset=True, braid=True))
    """)
    cache = numba.config.CACHE_DIR or compilation.version_folder().parent  # the session's: compiled once
    source = compilation.PACKAGE.parent
    assert run_python(code, source, cache).splitlines() == ["[]", "[] True", "[] True", "[] True"]


@pytest.mark.parametrize("compiled", [False, True])
def test_the_command_line_says_when_it_compiles(tmp_path, monkeypatch, compiled):
    calls = []
    monkeypatch.setattr(compile_kernels, "kernels_compiled", lambda **parts: compiled)
    monkeypatch.setattr(compile_kernels, "compile_kernels", lambda **parts: calls.append(parts))
    result = CliRunner().invoke(cli.app, ["demo", "-o", str(tmp_path / "out"), "--export", "none"])
    assert result.exit_code == 0, result.output
    assert (common.FIRST_RUN in result.output) == (not compiled)
    assert calls == ([] if compiled else [{}])


def test_a_problem_with_clips_and_contact_compiles_their_parts_first(tmp_path, monkeypatch):
    """solve compiles the parts its problem uses (its clips, its contact) before it starts, with the notice."""
    calls = []
    monkeypatch.setattr(compile_kernels, "kernels_compiled", lambda **parts: False)
    monkeypatch.setattr(compile_kernels, "compile_kernels", lambda **parts: calls.append(parts))
    problem = tmp_path / "problem.toml"
    problem.write_text(textwrap.dedent("""
        [hose]
        length = 400.0
        outer_diameter = 8.0
        bending_stiffness = 500.0
        segments = 16
        [start]
        point = [0.0, 0.0, 100.0]
        direction = [1.0, 0.0, 0.0]
        [end]
        point = [150.0, 0.0, 100.0]
        direction = [-1.0, 0.0, 0.0]
        [contact]
        self = true
    """), encoding="utf-8")
    result = CliRunner().invoke(cli.app, ["solve", str(problem), "-o", str(tmp_path / "out"), "--export", "none"])
    assert result.exit_code == 0, result.output
    assert common.FIRST_RUN in result.output
    assert calls == [{"stiffeners": False, "clips": False, "contact": True, "preset": False, "braid": False}]


def test_hoseline_compile_compiles_every_part(monkeypatch):
    calls = []
    monkeypatch.setattr(compile_kernels, "kernels_compiled", lambda **parts: False)
    monkeypatch.setattr(compile_kernels, "compile_kernels", lambda **parts: calls.append(parts))
    result = CliRunner().invoke(cli.app, ["compile"])
    assert result.exit_code == 0, result.output
    assert calls == [{"clearance": True, "stiffeners": True, "clips": True, "contact": True, "preset": True,
                      "braid": True}]
    assert "the solver is compiled" in result.output


def test_a_plain_placement_loads_only_the_placements_kernels():
    """Kernels load per part the problem uses: placing the demo hose (no clips, springs, set, braid or contact)
    loads no kernel of the clipped rod, the stiffener springs' own, the braid's or contact's, and no contact module
    is imported at all; a clipped placement then loads the clipped rod's."""
    code = SIGNATURES + textwrap.dedent("""
        from dataclasses import replace
        from hoseline.demos.thesis_hose import demo_problem
        from hoseline.procedures.compile_kernels import SMALL_PLACEMENT, small_clips
        from hoseline.procedures.placement.sequence import solve

        solve(demo_problem(180.0))
        parts = ("clipped", "bordered", "stiffeners", "braid", "contact", "proximity", "self_pairs", "leaf_lists")
        def loaded():
            return sorted({kernel.split(".")[2] for kernel, _ in signatures() if kernel.split(".")[2].startswith(parts)})
        print(loaded(), sorted(name for name in sys.modules if "contact" in name))
        solve(replace(SMALL_PLACEMENT, clips=small_clips()), estimate_error=False)
        print(loaded())
    """)
    cache = numba.config.CACHE_DIR or compilation.version_folder().parent
    assert run_python(code, compilation.PACKAGE.parent, cache).splitlines() == [
        "[] []", "['bordered', 'clipped']"]


def test_the_remembered_fingerprint_is_the_fingerprint_and_follows_every_edit(tmp_path):
    """The fingerprint is noted with the modules' stamp (names, sizes, modification times): the note is read while
    no module changed, and an edit, or a file only touched, makes it computed again."""
    package = write_package(tmp_path, {"__init__.py": "", "kernels/rod.py": "import numba\nSCALE = 2.0\n",
                                       "report/table.py": "WIDTH = 80\n"})
    first = compilation.remembered_fingerprint(package)
    assert first == compilation.fingerprint(package)
    stamp = compilation.source_stamp(package)
    (package / "kernels" / "__pycache__").mkdir()
    (package / "kernels" / "__pycache__" / "cached.py").write_text("")  # the cache folders are not walked
    assert compilation.source_stamp(package) == stamp
    note = package / "__pycache__" / compilation.FINGERPRINT_NOTE
    stamp = note.read_text().split()[0]
    note.write_text(f"{stamp} noted\n")  # what is noted is what is read back, sources unread
    assert compilation.remembered_fingerprint(package) == "noted"
    os.utime(package / "report" / "table.py", ns=(0, 0))  # touched, not changed: computed again
    assert compilation.remembered_fingerprint(package) == first
    (package / "kernels" / "rod.py").write_text("import numba\nSCALE = 3.0\n")
    assert compilation.remembered_fingerprint(package) == compilation.fingerprint(package) != first
    note.unlink()
    note.mkdir()  # a note that cannot be written: computed every time
    assert compilation.remembered_fingerprint(package) == compilation.fingerprint(package)


def test_the_fingerprint_note_is_not_taken_for_a_version_folder(tmp_path):
    for k in range(compilation.KEEP_VERSIONS):
        (tmp_path / f"{compilation.FOLDER_PREFIX}{k}").mkdir()
    (tmp_path / compilation.FINGERPRINT_NOTE).write_text("stamp fingerprint\n")
    compilation.prune_versions(tmp_path)
    assert len(list(tmp_path.iterdir())) == compilation.KEEP_VERSIONS + 1
