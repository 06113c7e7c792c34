"""A built-in sweep: the thesis brake hose between the chassis and a steered, sprung knuckle, past a strut.

The start fitting (B) is on the chassis, fixed.  The end fitting (D) is on the knuckle,
which steers 25 degrees each way about an inclined kingpin axis and then moves 40 mm up
(jounce) and down (rebound).  A cylinder of 25 mm radius stands for the strut, fixed to
the chassis; it is made here rather than read from a file, so the report writes it beside
itself as obstacle_strut.stl (to check the clearance against).  `hoseline sweep --demo -o
out/sweep` runs it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import trimesh

from hoseline.demos.thesis_hose import GOODYEAR_5052, demo_problem
from hoseline.model.motion import Rotation, Translation, generated_motion
from hoseline.model.sweep import Obstacle, SweepProblem

KINGPIN_POINT = (-190.0, -7.0, -11.25)  # mm, where the kingpin axis passes near the end fitting D
KINGPIN_INCLINATION_DEG = 10.0  # the axis leans inboard from vertical
STEER_DEG = 25.0
JOUNCE_MM = 40.0
STRUT_CENTRE = (-60.0, 175.0, 0.0)  # mm, axis vertical
STRUT_RADIUS = 25.0  # mm
STRUT_HEIGHT = 300.0  # mm
ASSUMED_MIN_BEND_RADIUS = 35.0  # mm, not from the thesis: a typical catalogue value, so the report shows a margin


def strut_obstacle(sections: int = 64) -> Obstacle:
    """The strut: a closed cylinder mesh (trimesh), `sections` facets round; no source file."""
    mesh = trimesh.creation.cylinder(radius=STRUT_RADIUS, height=STRUT_HEIGHT, sections=sections)
    mesh.apply_translation(STRUT_CENTRE)
    return Obstacle("strut", np.asarray(mesh.vertices), np.asarray(mesh.faces))


def demo_sweep(steps_per_degree: float = 0.5, segments: int = GOODYEAR_5052.segments) -> SweepProblem:
    """The demo sweep; `steps_per_degree` sets the pose spacing (the jounce uses the same count per mm).

    steps_per_degree: poses per degree of steer and per mm of jounce.  segments: of the hose model.
    """
    tilt = math.radians(KINGPIN_INCLINATION_DEG)
    kingpin = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    up = np.array([0.0, 0.0, 1.0])

    def steer(start: float, end: float) -> Rotation:
        steps = max(1, round(abs(end - start) * steps_per_degree))
        return Rotation(kingpin, np.array(KINGPIN_POINT), (start, end), steps, "steer")

    def jounce(start: float, end: float) -> Translation:
        return Translation(up, (start, end), max(1, round(abs(end - start) * steps_per_degree)), "jounce")

    motion = generated_motion("knuckle", [
        steer(0.0, STEER_DEG), steer(STEER_DEG, -STEER_DEG), steer(-STEER_DEG, 0.0),
        jounce(0.0, JOUNCE_MM), jounce(JOUNCE_MM, -JOUNCE_MM), jounce(-JOUNCE_MM, 0.0),
    ])
    problem = replace(demo_problem(0.0, segments), name="thesis brake hose: steer, jounce and rebound")
    problem = replace(problem, hose=replace(problem.hose, min_bend_radius=ASSUMED_MIN_BEND_RADIUS))
    return SweepProblem(problem, start_body=None, end_body="knuckle", motions=(motion,), obstacles=(strut_obstacle(),))
