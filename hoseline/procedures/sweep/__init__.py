"""Quasi-static sweeps: the placed hose carried through the motion of its mounts' bodies.

quasi_static.py steps through the poses with both fittings clamped and the twist locked,
continuation where the shape changes fast, snap-throughs reported; result.py holds the
SweepResult (clearance, bend radius, moments per pose and station, worst cases);
envelope.py meshes the swept envelope within a memory budget.

May import: model/, mechanics/, placement/, geometry/.  Not: scans/, io/, report/.
"""

from hoseline import compilation

compilation.install()  # Numba's cache of the envelope kernel: hoseline/compilation.py
