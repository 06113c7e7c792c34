"""Exact distances between the hose and its surroundings.

proximity.py holds the compiled segment-triangle and segment-plane distance kernels;
clearance.py the bounding-volume hierarchy that finds the nearest triangle of an obstacle
mesh for every segment.  Used by sweeps now, and by contact.  contact_shapes.py tessellates the
analytic contact obstacles of a problem, for the studio and the sweep report to draw.

May import: numpy, numba only (no mechanics): pure geometry in mm; contact_shapes.py also the
model (the obstacles it tessellates) and trimesh.
"""

from hoseline import compilation

compilation.install()  # Numba's cache of these kernels: hoseline/compilation.py
