"""Write files so that a reader never sees half of one, and directories so that a failure leaves nothing.

write_bytes / write_text: one file, via a temporary file in the same directory,
fsync, then os.replace (atomic on POSIX and Windows).

staged_directory: collect all files of an output directory in a hidden staging
directory and move them into place only when the whole block succeeded.
"""

from __future__ import annotations

import os
import secrets
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write `data` to `path` atomically; the parent directory must exist."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    # os.open rather than mkstemp: the file gets the usual permissions (0o666 less the umask), not 0o600
    handle = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    _fsync_directory(path.parent)
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 `text` to `path` atomically; the parent directory must exist."""
    return write_bytes(path, text.encode("utf-8"))


@contextmanager
def staged_directory(out_dir: str | Path) -> Iterator[Path]:
    """Yield an empty staging directory; on success move its files into `out_dir`, on failure drop them.

    out_dir: the output directory, created (with parents) only on success.  Files
    already in it that the block did not write are left alone; files it did write
    are replaced one by one with os.replace.

        with staged_directory("out/run") as staging:
            write_text(staging / "a.csv", ...)
            write_text(staging / "b.json", ...)   # if this fails, out/run is untouched
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise NotADirectoryError(f"{out_dir} exists and is not a directory")
    anchor = _nearest_existing(out_dir.parent)
    staging = Path(tempfile.mkdtemp(dir=anchor, prefix=f".{out_dir.name}.staging-"))
    try:
        yield staging
        _move_files(staging, out_dir)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _move_files(staging: Path, out_dir: Path) -> None:
    """Move every file under `staging` to the same relative place under `out_dir`."""
    for source in sorted(p for p in staging.rglob("*") if p.is_file()):
        target = out_dir / source.relative_to(staging)
        target.parent.mkdir(parents=True, exist_ok=True)
        with source.open("rb") as stream:
            os.fsync(stream.fileno())
        os.replace(source, target)
        _fsync_directory(target.parent)


def _nearest_existing(directory: Path) -> Path:
    """`directory` or its closest existing ancestor (staging must be on the same file system)."""
    directory = directory.absolute()
    while not directory.exists():
        directory = directory.parent
    return directory


def _fsync_directory(directory: Path) -> None:
    """Make a rename durable (POSIX); a no-op where directories cannot be opened (Windows)."""
    try:
        handle = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(handle)
    finally:
        os.close(handle)
