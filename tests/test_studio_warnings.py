"""The studio's warnings on the shape shown (studio/warnings.py), with and without limits in the file: the thesis
hose as placed has none; a minimum bend radius above its bend is told; the hose of tests/test_studio_editing.py
pulled towards taut gets the reactions warned of (kN against an Euler load of 44 N), then a kink."""

from dataclasses import replace

import numpy as np
import pytest

from hoseline.demos.thesis_hose import demo_problem
from hoseline.procedures.placement.sequence import solve
from hoseline.studio.messages import Target
from hoseline.studio.session import Session
from hoseline.studio.view import state_message
from hoseline.studio.warnings import bend_limit, force_scale, shape_warnings
from test_studio_messages import taut_problem


def kinds(problem, result):
    return [(w["kind"], w["readout"]) for w in shape_warnings(problem, result)]


def test_the_thesis_hose_as_placed_is_warned_of_nothing():
    problem = demo_problem(180.0, segments=30)
    result = solve(problem)
    assert result.min_bend_radius > bend_limit(problem)["radius"] == pytest.approx(3 * 10.1)
    assert kinds(problem, result) == []


def test_a_minimum_bend_radius_in_the_file_is_the_limit():
    problem = demo_problem(180.0, segments=30)
    result = solve(problem)
    strict = replace(problem, hose=replace(problem.hose, min_bend_radius=result.min_bend_radius + 1.0))
    assert bend_limit(strict) == {"radius": result.min_bend_radius + 1.0, "given": True}
    [warning] = shape_warnings(strict, result)
    assert warning["kind"] == "bend" and "the hose's minimum (hose.min_bend_radius)" in warning["text"]


def test_the_force_scales_are_the_weight_and_the_euler_load():
    problem = taut_problem()
    heavy = replace(problem, hose=replace(problem.hose, mass_per_length=0.5), gravity=np.array([0.0, 0.0, -9.81]))
    scales = force_scale(heavy)
    assert scales["weight"] == pytest.approx(0.5 * 9.81 * 0.185)  # kg/m * m/s^2 * m
    assert scales["euler"] == pytest.approx(np.pi ** 2 * 1.5e5 / 185.0 ** 2)  # 43.3 N
    assert force_scale(problem)["weight"] == 0.0


def test_a_hose_pulled_towards_taut_gets_its_reactions_warned_of_and_then_a_kink():
    session = Session(taut_problem())
    end = state_message(session)["fittings"]["end"]
    seen = {}
    for pull in range(1, 25):  # mm along -x, away from the start; the mount distance is reached at 25
        point = np.array(end["point"]) - [pull, 0.0, 0.0]
        session.apply(Target(type="set", seq=pull, end={"point": point.tolist(), "quaternion": end["quaternion"]}))
        result = session.result()
        force = max(np.linalg.norm(result.start_force), np.linalg.norm(result.end_force))
        seen[pull] = (force, result.min_bend_radius, kinds(session.problem, result))
    euler = force_scale(session.problem)["euler"]
    for force, radius, found in seen.values():
        assert (("reaction", "start_reaction") in found) == (np.linalg.norm(force) > 10 * euler)
        assert (("kink", "min_bend_radius") in found) == (radius <= 0.0)
        assert (("bend", "min_bend_radius") in found) == (0.0 < radius < 30.3)
    assert seen[1][0] < 10 * euler < seen[21][0]  # the reactions cross the threshold on the way
    assert seen[24][1] < 0.0  # and the bend radius goes below zero: the kink is told
