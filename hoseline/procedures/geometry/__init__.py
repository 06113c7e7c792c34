"""Exact distances between the hose and its surroundings.

clearance.py finds the nearest triangle of an obstacle mesh for every segment with the
bounding-volume hierarchy of mechanics/bounding_volumes.py and the segment-triangle distance
of mechanics/proximity.py (there, not here, because contact with meshes uses them too);
clearance_profile.py the clearance along the hose.  Used by sweeps.  contact_shapes.py gives the
triangles of a problem's contact obstacles, for the studio and the sweep report to draw.

May import: numpy, numba and those two geometric kernels of mechanics: pure geometry in mm;
contact_shapes.py also the model (the obstacles it tessellates) and trimesh.
"""

from hoseline import compilation

compilation.install()  # Numba's cache of these kernels: hoseline/compilation.py
