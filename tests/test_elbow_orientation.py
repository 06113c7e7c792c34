"""The SAE J517 orientation angle of a two-elbow assembly from a placed hose (procedures/placement/orientation.py):
exact on a nearly straight hose whose legs are set by hand, and the law that ties it to hoseline's twist."""

import numpy as np
import pytest

from hoseline import solve
from hoseline.model.fittings import Fitting
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.problem import fitted_problem
from hoseline.procedures.placement.orientation import orientation_angle_deg

HOSE = Hose(length=300.3, outer_diameter=10.0, bending_stiffness=1e5, torsional_stiffness=5e5, segments=40)


def elbow(toward):
    return Fitting(20.0, bend_angle_deg=90.0, outlet_length=20.0, reference=np.array(toward, dtype=float))


def assembly(far_port_direction, twist=0.0):
    """Start elbow: port 20 mm below the hose's line, pointing up, bending towards +x (its leg points down, -z).  End
    elbow 340 mm along x, its port 20 mm from the line on the side opposite far_port_direction, pointing along it,
    bending towards -x.  The outlets are 300 mm apart: the hose (300.3 mm) runs nearly straight along +x."""
    up = np.array(far_port_direction, dtype=float)
    return fitted_problem(HOSE, Mount([0.0, 0.0, -20.0], [0.0, 0.0, 1.0]), Mount(np.array([340.0, 0.0, 0.0]) - 20.0 * up, up),
                          elbow([1.0, 0.0, 0.0]), elbow([-1.0, 0.0, 0.0]), end_twist_deg=twist)


@pytest.mark.parametrize("far_port, expected", [((0.0, 0.0, 1.0), 0.0), ((0.0, 1.0, 0.0), 90.0),
                                               ((0.0, 0.0, -1.0), 180.0), ((0.0, -1.0, 0.0), 270.0)])
def test_the_orientation_of_legs_set_by_hand(far_port, expected):
    # viewed from the start fitting along +x (z up, y to the left), the near leg at six o'clock (-z); a far leg along
    # -y points to three o'clock: 90 deg counter-clockwise
    result = solve(assembly(far_port), estimate_error=False)
    angle = orientation_angle_deg(result.problem, result.start_frame, result.end_frame)
    assert abs((angle - expected + 180.0) % 360.0 - 180.0) < 0.5  # the hose is nearly, not exactly, straight
    assert result.summary()["elbow_orientation_angle_deg"] == pytest.approx(angle)


def test_a_twist_lowers_the_orientation_by_itself():
    # orientation(twist) = orientation(0) - twist: to install an assembly crimped at theta, twist = orientation(0) - theta
    base = solve(assembly((0.0, 1.0, 0.0)), estimate_error=False)
    base_angle = orientation_angle_deg(base.problem, base.start_frame, base.end_frame)
    for twist in (30.0, -75.0):
        twisted = solve(assembly((0.0, 1.0, 0.0), twist), estimate_error=False)
        angle = orientation_angle_deg(twisted.problem, twisted.start_frame, twisted.end_frame)
        assert (angle - (base_angle - twist) + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-6)


def test_no_angle_without_two_elbows():
    problem = fitted_problem(HOSE, Mount([-20.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([320.0, 0.0, -20.0], [0.0, 0.0, 1.0]),
                             Fitting(20.0), elbow([-1.0, 0.0, 0.0]))
    result = solve(problem, estimate_error=False)
    assert orientation_angle_deg(problem, result.start_frame, result.end_frame) is None
    assert "elbow_orientation_angle_deg" not in result.summary()
