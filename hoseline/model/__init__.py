"""Model layer: plain data for hoses, mounts, clips and problems (no solver, no files)."""

from hoseline.model.clips import Clip
from hoseline.model.hose import Hose, bending_stiffness_from_modulus, isotropic_torsional_stiffness
from hoseline.model.mounts import Mount, single_plane_offset, mount_distance
from hoseline.model.problem import Problem

__all__ = [
    "Clip",
    "Hose",
    "Mount",
    "Problem",
    "bending_stiffness_from_modulus",
    "isotropic_torsional_stiffness",
    "mount_distance",
    "single_plane_offset",
]
