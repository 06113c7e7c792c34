"""Export a solved hose to CAD, mesh and multibody files: all that were asked for, or none.

    name    file        what
    iges    hose.igs    segment centres, polyline, profile circle, B-spline: the thesis' CAD sweep input
    step    hose.step   solid tube and centreline B-spline (STEP AP214)
    stl     hose.stl    closed triangle mesh of the tube (binary STL)
    ply     hose.ply    the same mesh (binary PLY)
    gltf    hose.glb    the same mesh (binary glTF 2.0)
    adams   hose.cmd    ADAMS/View command file of the discrete beam model

Each writer is imported only when its format is asked for (OpenCASCADE takes about a second to load).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from hoseline.io.atomic import staged_directory, write_bytes
from hoseline.io.export_names import FILE_NAMES
from hoseline.procedures.placement.result import Result

class ExportError(RuntimeError):
    """An export could not be made (e.g. the tube cannot be swept); nothing was written."""


@dataclass(frozen=True)
class ExportedFile:
    """One written export: its file name, size in bytes and the seconds it took to make and write."""

    name: str
    size: int
    seconds: float



def write_exports(result: Result, out_dir: str | Path, formats: list[str], beam_section=None) -> list[ExportedFile]:
    """Write the files of `formats` into `out_dir`, all or none.

    beam_section: an adams_cmd.BeamSection for the ADAMS model (default: from the hose).
    Raises ExportError when a shape cannot be made; OSError when the files cannot be written.
    """
    written = []
    with staged_directory(out_dir) as staging:
        for name in formats:
            began = time.perf_counter()
            data = export_bytes(name, result, beam_section)
            write_bytes(staging / FILE_NAMES[name], data)
            written.append(ExportedFile(FILE_NAMES[name], len(data), time.perf_counter() - began))
    return written


def export_bytes(name: str, result: Result, beam_section=None) -> bytes:
    """The content of one export file (see the module docstring for the names)."""
    try:
        if name == "iges":
            from hoseline.io.iges_shape import iges_bytes

            return iges_bytes(result, FILE_NAMES[name])
        if name == "step":
            from hoseline.io.step_shape import step_bytes

            return step_bytes(result)
        if name in ("stl", "ply", "gltf"):
            from hoseline.io.mesh import mesh_bytes

            return mesh_bytes(result, "glb" if name == "gltf" else name)
        if name == "adams":
            from hoseline.io.adams_cmd import adams_cmd_text

            return adams_cmd_text(result, beam_section).encode("utf-8")
    except RuntimeError as exc:  # OpenCASCADE could not build or write a shape
        raise ExportError(f"{FILE_NAMES[name]}: {exc}") from exc
    raise ValueError(f"unknown export format {name!r}: choose from {', '.join(FILE_NAMES)}")
