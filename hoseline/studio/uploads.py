"""Files dropped on the page: names and sizes checked, then read by the command line's own readers.

    .toml                 problem file, or sweep file when it has [[bodies]] (io/problem_file, io/sweep_file)
    .igs .iges            mount points: the thesis' labels A, B, C, D (io/iges_mounts), or four labels the
                          page chose (?labels=START_TIP,START_BEHIND,END_TIP,END_AHEAD) after the studio
                          answered with the labels the file holds
    .stl .obj .ply .step .stp   an obstacle (io/obstacle_mesh), required clearance one inch
    .csv                  a pose table, kept for the sweep file dropped with it

A file is stored under its own name in the session's upload folder (never a path from the
browser: the name loses any folder part and may hold only letters, digits and . _ -), so a
sweep file finds the pose tables and meshes dropped with it.
"""

from __future__ import annotations

import re
from pathlib import Path

from hoseline.studio.session import Session

MiB = 1024 * 1024
KINDS = {
    ".toml": "problem",
    ".igs": "mounts", ".iges": "mounts",
    ".stl": "obstacle", ".obj": "obstacle", ".ply": "obstacle", ".step": "obstacle", ".stp": "obstacle",
    ".csv": "pose table",
}
SIZE_LIMITS = {"problem": 1 * MiB, "mounts": 16 * MiB, "obstacle": 64 * MiB, "pose table": 16 * MiB}
MAX_FILES = 200  # in one session's upload folder
_SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")
_SAFE_LABEL = re.compile(r"[A-Za-z0-9_.-]{1,64}")  # an IGES point label (a name property may be longer than 8)


class UploadError(ValueError):
    """A file the studio refuses; status: the HTTP status to answer with.  labels: the point labels of
    an IGES file that lacks the ones asked for (the page offers them to choose from), else None."""

    def __init__(self, message: str, status: int = 400, labels: list[str] | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.labels = labels


def mount_labels(query: str | None):
    """The (start, end) FittingLabels of a `labels` query START_TIP,START_BEHIND,END_TIP,END_AHEAD
    (the thesis' order: B,A,D,C); None for none given.  UploadError for anything else."""
    from hoseline.io.iges_mounts import FittingLabels

    if query is None:
        return None
    labels = query.split(",")
    if len(labels) != 4 or not all(_SAFE_LABEL.fullmatch(label) for label in labels):
        raise UploadError(f"labels={query!r}: give four point labels START_TIP,START_BEHIND,END_TIP,END_AHEAD, e.g. B,A,D,C")
    return FittingLabels(tip=labels[0], behind=labels[1]), FittingLabels(tip=labels[2], ahead=labels[3])


def checked_name(name: str) -> tuple[str, str]:
    """(file name, kind) of an upload; UploadError (415) for a name or type the studio does not take."""
    base = name.replace("\\", "/").rsplit("/", 1)[-1]
    if not _SAFE_NAME.fullmatch(base):
        raise UploadError(f"file name {name!r}: use letters, digits and . _ - only (at most 100 characters)", 415)
    kind = KINDS.get(Path(base).suffix.lower())
    if kind is None:
        raise UploadError(f"{base}: not a file the studio reads; drop a problem or sweep file (.toml), IGES mounts "
                          "(.igs), an obstacle mesh (.stl, .obj, .ply, .step) or a pose table (.csv)", 415)
    return base, kind


def open_upload(session: Session, path: Path, kind: str, store_only: bool, labels=None) -> str:
    """Read a stored upload into the session; returns what was done, for the page.

    store_only: keep the file for a sweep file dropped with it, do nothing else.  labels: (start,
    end) FittingLabels of IGES mounts (mount_labels), None for the thesis' A, B, C, D.
    Raises UploadError with the reader's message for a file that cannot be read.
    """
    from hoseline.io.iges_mounts import THESIS_END, THESIS_START, IgesError, mounts_from_iges, read_named_points
    from hoseline.io.obstacle_mesh import ObstacleFileError, read_mesh
    from hoseline.io.problem_file import ProblemFileError, load_problem, read_toml
    from hoseline.io.sweep_file import load_sweep

    if store_only or kind == "pose table":
        return f"kept {path.name} for the sweep file dropped with it"
    try:
        if kind == "problem":
            if "bodies" in read_toml(path, ProblemFileError):
                session.open_sweep(load_sweep(path))
                return f"opened the sweep {path.name}"
            session.open_problem(load_problem(path))
            return f"opened the problem {path.name}"
        if kind == "mounts":
            start, end = labels or (THESIS_START, THESIS_END)
            asked = [start.tip, start.axis, end.tip, end.axis]
            found = sorted(read_named_points(path))
            missing = [label for label in asked if label not in found]
            if missing:
                raise UploadError(f"{path.name}: no point labelled {', '.join(missing)}; the file's points are "
                                  f"{', '.join(found) or 'unlabelled'}: choose which make the fittings", labels=found)
            session.set_mounts(*mounts_from_iges(path, start, end))
            return f"mounts from {path.name} ({', '.join(asked)}); placed again"
        vertices, faces = read_mesh(path)
        session.add_obstacle(path.stem, vertices, faces, path.name)
        return f"obstacle {path.stem}: {len(faces)} triangles, required clearance {session.obstacles[-1].obstacle.clearance:g} mm"
    except UploadError:
        raise
    except (ProblemFileError, IgesError, ObstacleFileError, ValueError) as exc:
        raise UploadError(_without_folder(str(exc), path.parent)) from None
    except OSError as exc:
        raise UploadError(f"{path.name}: cannot be read: {exc.strerror or exc}") from None


def _without_folder(message: str, folder: Path) -> str:
    """A reader's message with the server's upload folder left out of the paths it names."""
    return message.replace(f"{folder}/", "").replace(str(folder), "upload folder")
