"""Exact distances between the hose and its surroundings.

proximity.py holds the compiled segment-triangle and segment-plane distance kernels;
clearance.py the bounding-volume hierarchy that finds the nearest triangle of an obstacle
mesh for every segment.  Used by sweeps now, and by contact.

May import: numpy, numba only (no model, no mechanics): pure geometry in mm.
"""

from hoseline import compilation

compilation.install()  # Numba's cache of these kernels: hoseline/compilation.py
