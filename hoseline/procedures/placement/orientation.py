"""The orientation angle of a two-elbow assembly (SAE J517), from a placed hose: the relative clocking of the two
elbows as the assembly would be crimped to install with the placement's twist.

Catalogues give a two-elbow assembly's orientation (displacement) angle as crimped: the hose laid out straight and
free of twist, viewed from the near (start) fitting along the hose, the angle counter-clockwise from the near
elbow's leg to the far elbow's leg (SAE J517; MIL-DTL-83796 the same way; some makers measure clockwise from the
far fitting, which gives 360 deg less this one).  An elbow's leg is the direction from its bend to its port,
across the hose's axis at its outlet.  hoseline instead clocks each elbow in the world at its port and twists the
hose's end relative to the torque-free lock.  The two meet in the hose's material frames: laid straight and free of
twist, the frames at both ends coincide, so each leg's angle in its end's material frame (result.start_frame,
result.end_frame) gives the crimped orientation.  The twist turns the end's material frame by the twist about the
end direction, so the orientation falls by the twist:

    orientation(twist) = orientation(0) - twist,   so   twist = orientation(0) - crimped orientation   (mod 360)

(tests/test_elbow_orientation.py checks it).  At twist 0 it is the orientation an assembly must be crimped at to
install free of torsion.
"""

from __future__ import annotations

import math

import numpy as np

from hoseline.model.fittings import Fitting
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem


def leg_angle(fitting: Fitting, port: Mount, frame: np.ndarray) -> float:
    """Angle (rad) of the elbow's leg in the material frame `frame` (rows d1, d2, d3) at its outlet: about d3, from
    d1 towards d2.  The leg: from the bend back to the port (-port direction), made normal to the outlet axis."""
    outlet = fitting.outlet(port).direction
    leg = -port.direction - float(-port.direction @ outlet) * outlet
    return math.atan2(float(leg @ frame[1]), float(leg @ frame[0]))


def orientation_angle_deg(problem: Problem, start_frame: np.ndarray, end_frame: np.ndarray) -> float | None:
    """The SAE J517 orientation angle (degrees, [0, 360)) of the assembly as crimped to install with the placed
    hose's frames (start_frame, end_frame: rows d1, d2, d3, d3 along the hose), or None unless both ends are
    elbows.  Viewed from the start fitting along d3, counter-clockwise is a negative angle about d3."""
    fittings = problem.fittings
    if fittings is None or not all(f is not None and f.bend_angle_deg > 0.0 for f in (fittings.start, fittings.end)):
        return None
    near = leg_angle(fittings.start, fittings.start_port, start_frame)
    far = leg_angle(fittings.end, fittings.end_port, end_frame)
    return math.degrees(near - far) % 360.0
