"""Where Numba caches hoseline's compiled kernels: kept between runs, never stale.

Numba's own cache (cache=True) checks only the source file of the kernel it loads: after an
edit to a function that the kernel calls from another module, it loads the old machine code
(numba/numba#1833, open since 2016; no library fills the gap, hence this module).  Here every
kernel defined in hoseline's sources is cached in a folder named after a fingerprint of all
kernel sources,

    <base>/hoseline-kernels-<fingerprint>/<package folder, e.g. mechanics>/<Numba's cache files>

The fingerprint hashes Numba's version, this module and every module that imports numba,
with the hoseline modules those import (whose constants compiled code holds), so an edit to
any of them sends the next run to a fresh folder, which compiles once.  The fingerprint is
also the source stamp of every cache index, so a folder copied from another version is not used.
Reading every source for it takes 15-20 ms of each start-up, so it is noted in the package's __pycache__
(remembered_fingerprint) with the modules' names, sizes and modification times, which Python's own
bytecode cache trusts too, and read back while they are unchanged.

base: NUMBA_CACHE_DIR when set (numba.config.CACHE_DIR), else hoseline/__pycache__ (one
cache per installation, shared by every process that uses it), else ~/.cache/hoseline
($XDG_CACHE_HOME), the first that is writable; with none writable, a temporary folder of this
process (compiled on every run).  The KEEP_VERSIONS most recently used folders of a base stay.

install() registers KernelCacheLocator with Numba (through NUMBA_CACHE_LOCATOR_CLASSES, ahead of
Numba's own locators, which keep serving every other package); the __init__ of each subpackage
with kernels (mechanics, procedures/geometry, procedures/sweep) calls it before any kernel is
defined.  compiling(part) and is_compiled(part) let a part be compiled once per installation
and CPU: the first process holds a lock while it compiles, the others wait for it and then load
the kernels from the cache.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numba
from llvmlite import binding
from numba import config
from numba.core.caching import CacheImpl, UserProvidedCacheLocator

PACKAGE = Path(__file__).resolve().parent
FOLDER_PREFIX = "hoseline-kernels-"
KEEP_VERSIONS = 4  # version folders kept in a base (the most recently used)
LOCATOR = f"{__name__}.KernelCacheLocator"
FINGERPRINT_NOTE = "hoseline-fingerprint"  # in the package's __pycache__ (not a version folder): stamp, fingerprint

# a module with kernels imports numba; a from-import may name submodules (from hoseline.x import y)
_USES_NUMBA = re.compile(r"^[ \t]*(?:from|import)[ \t]+numba\b", re.MULTILINE)
_HOSELINE_IMPORT = re.compile(
    r"^[ \t]*(?:from[ \t]+(hoseline[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+(hoseline[\w.]*))",
    re.MULTILINE,
)


def kernel_sources(package: Path = PACKAGE) -> list[Path]:
    """The source files compiled code can depend on: every module of `package` that imports
    numba and, recursively, every module of `package` that those import."""
    found = {path for path in package.rglob("*.py") if _USES_NUMBA.search(path.read_text(encoding="utf-8"))}
    pending = list(found)
    while pending:
        for module, names, plain in _HOSELINE_IMPORT.findall(pending.pop().read_text(encoding="utf-8")):
            modules = [plain or module]
            if module:
                modules += [f"{module}.{name.split()[0]}" for name in names.strip("()").split(",") if name.strip()]
            for path in (path for name in modules for path in _module_files(package, name)):
                if path not in found:
                    found.add(path)
                    pending.append(path)
    return sorted(found)


def _module_files(package: Path, module: str) -> list[Path]:
    # the source file of a dotted module name whose first part is the package, if it has one
    parts = module.split(".")[1:]
    stem = package.joinpath(*parts)
    return [path for path in (stem.with_suffix(".py"), stem / "__init__.py") if parts and path.is_file()]


def fingerprint(package: Path = PACKAGE) -> str:
    """Hex SHA-256 of Numba's version, this module, and the kernel sources of `package` (names and contents)."""
    digest = hashlib.sha256(f"numba {numba.__version__}\n".encode())
    digest.update(Path(__file__).read_bytes())
    for path in kernel_sources(package):
        digest.update(f"\n{path.relative_to(package).as_posix()}\n".encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def source_stamp(package: Path = PACKAGE) -> str:
    """Hex SHA-256 of Numba's version and the name, size and modification time (ns) of every module of `package`:
    what Python's own bytecode cache trusts to tell an edited file (about 1 ms; reading the sources takes 15-20)."""
    modules = []
    for folder, subfolders, files in os.walk(package):
        subfolders[:] = [name for name in subfolders if name != "__pycache__"]  # not the kernels' cache folders
        modules += [os.path.join(folder, name) for name in files if name.endswith(".py")]
    digest = hashlib.sha256(f"numba {numba.__version__}\n".encode())
    for path in sorted(modules):
        status = os.stat(path)
        digest.update(f"{os.path.relpath(path, package)} {status.st_size} {status.st_mtime_ns}\n".encode())
    return digest.hexdigest()


def remembered_fingerprint(package: Path = PACKAGE) -> str:
    """fingerprint(package), from the note FINGERPRINT_NOTE in its __pycache__ when no module of the package has
    changed since the note was written (source_stamp), else computed and noted (a note that cannot be written is
    left out: the fingerprint is then computed in every process)."""
    stamp = source_stamp(package)
    note = package / "__pycache__" / FINGERPRINT_NOTE
    try:
        noted_stamp, noted = note.read_text(encoding="ascii").split()
        if noted_stamp == stamp:
            return noted
    except (OSError, ValueError):
        pass
    value = fingerprint(package)
    staged = None
    try:
        note.parent.mkdir(exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=note.parent, prefix=note.name, delete=False) as staged:
            staged.write(f"{stamp} {value}\n")
        os.replace(staged.name, note)  # whole or not at all: another process may read it meanwhile
    except OSError:
        if staged is not None:
            Path(staged.name).unlink(missing_ok=True)
    return value


@functools.cache
def _fingerprint() -> str:
    return remembered_fingerprint()


def base_folders() -> list[Path]:
    """Where version folders may go, in order of preference (see the module doc)."""
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "hoseline"
    return ([Path(config.CACHE_DIR)] if config.CACHE_DIR else []) + [PACKAGE / "__pycache__", user]


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


@functools.cache
def version_folder() -> Path:
    """The cache folder of this version of the kernel sources (created), or a temporary one."""
    name = FOLDER_PREFIX + _fingerprint()[:16]
    for base in base_folders():
        folder = base / name
        fresh = not folder.exists()
        if _writable(folder):
            os.utime(folder)  # marks it as used, for prune_versions
            if fresh:
                prune_versions(base)
            return folder
    return _temporary_folder()


def persistent() -> bool:
    """Whether compiled kernels outlive this process (a writable cache folder was found)."""
    return version_folder().name == FOLDER_PREFIX + _fingerprint()[:16]


@functools.cache
def _temporary_folder() -> Path:
    folder = Path(tempfile.mkdtemp(prefix=FOLDER_PREFIX))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def prune_versions(base: Path, keep: int = KEEP_VERSIONS) -> None:
    """Remove all but the `keep` most recently used version folders of `base` (another process
    still using a removed one compiles again; it never loads a partial folder as valid)."""
    folders = sorted(base.glob(FOLDER_PREFIX + "*"), key=_last_used, reverse=True)
    for folder in folders[keep:]:
        shutil.rmtree(folder, ignore_errors=True)


def _last_used(folder: Path) -> float:
    try:
        return folder.stat().st_mtime
    except OSError:  # removed meanwhile by another process
        return 0.0


def _cpu() -> str:
    # the host CPU as Numba compiles for it: cached machine code is only valid on the same kind
    features = hashlib.sha256(binding.get_host_cpu_features().flatten().encode()).hexdigest()[:8]
    return f"{binding.get_host_cpu_name()}-{features}"


def _marker(part: str) -> Path:
    return version_folder() / f"compiled-{part}-{_cpu()}"


def is_compiled(part: str) -> bool:
    """Whether `part` (a name such as "placement") has been compiled into the cache for this CPU."""
    return _marker(part).exists()


@contextmanager
def compiling(part: str) -> Iterator[None]:
    """Hold the compile lock of `part` in the version folder while the body compiles it, then mark it compiled.

    Processes that start together (the workers of a cluster) compile a part once: the others wait
    for its lock and then find the kernels in the cache.  Each part has its own lock, so two processes
    can compile two parts side by side (`hoseline compile` does, procedures/compile_kernels.py).
    """
    with open(version_folder() / f"compile-{part}.lock", "a") as lock:
        _lock(lock)
        yield
        _marker(part).touch()


def _lock(file) -> None:
    # an exclusive lock released when the file closes; without fcntl (Windows) no lock: the
    # processes then compile side by side, and Numba's cache writes stay atomic
    try:
        import fcntl
    except ImportError:
        return
    fcntl.flock(file.fileno(), fcntl.LOCK_EX)


def install() -> None:
    """Make Numba cache every kernel defined in hoseline's sources in version_folder(); other
    code keeps Numba's usual locations.  Idempotent; must run before the first kernel is defined."""
    if LOCATOR in config.CACHE_LOCATOR_CLASSES:
        return
    others = config.CACHE_LOCATOR_CLASSES or ",".join(cls.__name__ for cls in CacheImpl._locator_classes)
    config.CACHE_LOCATOR_CLASSES = f"{LOCATOR},{others}"


class KernelCacheLocator(UserProvidedCacheLocator):
    """Numba's cache locator for the kernels of hoseline's sources: the version folder, with the
    fingerprint as the source stamp of every index (see the module doc)."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(version_folder() / _package_folder(py_file))

    def get_source_stamp(self):
        return _fingerprint()

    @classmethod
    def from_function(cls, py_func, py_file):
        return None if _package_folder(py_file) is None else cls(py_func, py_file)


@functools.cache
def _package_folder(py_file: str) -> Path | None:
    # the folder of a source file relative to the package, None outside it; resolved once a file (each of its
    # kernels asks, and a start-up defines over a hundred)
    folder = Path(py_file).resolve().parent
    return folder.relative_to(PACKAGE) if folder.is_relative_to(PACKAGE) else None
