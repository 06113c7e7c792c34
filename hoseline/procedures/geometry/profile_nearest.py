"""The clearance profile along the hose and the hose's nearest approach to an obstacle, found together.

clearance_profile searches every segment down to a cut-off; where a segment comes within it, the
hose's nearest approach (TriangleIndex.nearest) lies on the segment nearest in the profile, so
only that segment is searched again for the points and the arc length, not the whole hose.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hoseline.procedures.geometry.clearance import Proximity, TriangleIndex
from hoseline.procedures.geometry.clearance_profile import clearance_profile


def profile_and_nearest(index: TriangleIndex, nodes: np.ndarray, outer_radius: float,
                        cutoff: float) -> tuple[np.ndarray, Proximity]:
    """(clearance_profile, TriangleIndex.nearest) of the hose with centreline `nodes` ((N+1, 3) mm).

    index: the obstacle's triangles.  outer_radius: mm.  cutoff: mm, that of the profile.
    """
    profile = clearance_profile(index, nodes, outer_radius, cutoff)
    segment = int(np.argmin(profile))
    if not profile[segment] < cutoff:
        return profile, index.nearest(nodes, outer_radius)
    nodes = np.ascontiguousarray(nodes, dtype=float)
    found = index.nearest(nodes[segment:segment + 2], outer_radius)
    before = float(np.sum(np.linalg.norm(np.diff(nodes, axis=0), axis=1)[:segment]))  # as TriangleIndex.nearest sums
    return profile, replace(found, s=before + found.s)
