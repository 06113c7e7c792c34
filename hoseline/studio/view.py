"""What the page is sent: the shape, the fittings and clips, the colour-map data along the hose and the readouts.

With end fittings, "fittings" are the ports (what the page drags) and "pieces" the fittings'
centrelines in their ports' frames (drawn as rigid tubes carried by the ports); "centerline" is
the flexible hose between the outlets.  A clip is sent with the frame it holds the hose by (what the page drags back: a rotating or
sliding clip's roll found by the solve is not in it) and its load on the hose.

Units as everywhere at the user boundary: mm, N, N*mm, degrees, kg/m.  Numbers that are not
finite (the bend radius of a straight station) are sent as null, since JSON has no infinity.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hoseline.model.motion import matrix_quaternion
from hoseline.procedures.geometry.profile_nearest import profile_and_nearest
from hoseline.procedures.placement.result import Result
from hoseline.studio.warnings import bend_limit, shape_warnings

if TYPE_CHECKING:
    from hoseline.studio.session import Session

PENDING_READOUTS = ("stability_margin", "min_gap")  # left out of a drag's states (null): the margin, the contacts' gaps
CLEARANCE_SCALE = 2.0  # the clearance colour map runs from 0 to this many times the required clearance
# decimals of the arrays a drag's state sends only to be drawn (the lay line's unit vectors, 0.006 degrees; the colour
# maps, far finer than a colour's 256 levels: clearance / required, mm of bend radius, N*mm of twisting moment): fewer
# digits are written to JSON the sooner (a drag's state with the strut: 0.42 -> 0.32 ms, 21.8 -> 15.8 kB); the shape
# and the readouts keep every digit
DRAWN_DECIMALS = {"lay_line": 4, "clearance_ratio": 4, "bend_radius": 3, "twisting_moment": 3}


def state_message(session: "Session", complete: bool = True) -> dict:
    """The "state" message: everything the page draws after a change.

    complete: False (a drag's step) sends the readouts that cost most as pending (PENDING_READOUTS: null, named in
    the readouts' "pending"), for readouts_message to send when the drag pauses, and the arrays that are only drawn
    to DRAWN_DECIMALS.
    """
    result = session.result(complete)
    problem = session.problem
    radius = problem.hose.outer_radius
    clearance, nearest = _clearances(session, result.centerline, radius)
    with np.errstate(divide="ignore"):
        bend_radius = 1.0 / result.curvature - radius
    step = session.last_step

    def drawn(name: str, values: np.ndarray) -> np.ndarray:
        return values if complete else np.round(values, DRAWN_DECIMALS[name])

    fittings = session.handles()  # the ports with end fittings
    return {
        "type": "state",
        "centerline": result.centerline.tolist(),
        "lay_line": drawn("lay_line", _station_d1(result)).tolist(),
        "s": result.s.tolist(),
        "bend_radius": _finite_or_none(drawn("bend_radius", bend_radius)),
        "twisting_moment": drawn("twisting_moment", result.twisting_moment).tolist(),
        "clearance_ratio": None if clearance is None else drawn("clearance_ratio", clearance).tolist(),
        "fittings": {
            "start": {"point": fittings.start_point.tolist(), "quaternion": _quaternion(fittings.start_frame)},
            "end": {"point": fittings.end_point.tolist(), "quaternion": _quaternion(fittings.end_frame)},
        },
        "pieces": session.pieces(),
        "clips": [
            {"kind": clip.kind, "name": clip.name, "point": point.tolist(), "quaternion": _quaternion(frame),
             "arc_length": reaction.arc_length, "force": reaction.force.tolist(), "moment": reaction.moment.tolist()}
            for clip, reaction, point, frame in zip(problem.clips, result.clips, fittings.clip_points, fittings.clip_frames)
        ],
        "twist": problem.end_twist_deg,
        "hose": {
            "length": problem.hose.length,
            "outer_diameter": problem.hose.outer_diameter,
            "bending_stiffness": problem.hose.bending_stiffness,
            "torsion_factor": problem.hose.torsion_factor,
            "mass_per_length": problem.hose.mass_per_length,
            "min_bend_radius": problem.hose.min_bend_radius,
            "segments": problem.hose.segments,
        },
        "obstacle_poses": [_matrix(session.obstacle_pose(shown)) for shown in session.obstacles],
        "pose": session.pose_index,
        "readouts": _readouts(session, result, nearest, complete),
        "step": None if step is None else {
            "iterations": step.iterations, "seconds": step.seconds, "events": step.events, "movement": step.movement,
        },
        "comparison": session.comparison,
    }


def readouts_message(session: "Session") -> dict:
    """The "readouts" message: the complete readouts of the shape shown, for a page sent them pending (state_message
    with complete=False)."""
    result = session.result()
    nearest = _clearances(session, result.centerline, session.problem.hose.outer_radius)[1]
    return {"type": "readouts", "readouts": _readouts(session, result, nearest, True)}


def _readouts(session: "Session", result: Result, nearest: list[dict], complete: bool) -> dict:
    """The readouts of `result` (session.result(complete)); nearest: each shown obstacle's nearest approach."""
    problem = session.problem
    return {
        "min_clearance": nearest,
        "min_bend_radius": _finite_or_none(result.min_bend_radius),
        "bend_limit": bend_limit(problem),
        "warnings": shape_warnings(problem, result),
        "start_force": result.start_force.tolist(),
        "start_moment": result.start_moment.tolist(),
        "end_force": result.end_force.tolist(),
        "end_moment": result.end_moment.tolist(),
        "lock_angle": session.placement.lock_angle_deg,
        "single_plane_offset": result.single_plane_offset,
        "stability_margin": result.stability_margin,
        "max_twisting_moment": result.max_twisting_moment,
        "free_length": problem.hose.length,
        "overall_length": None if problem.fittings is None else problem.fittings.overall_length(problem.hose.length),
        "contacts": [
            {"name": c.name, "kind": c.kind, "min_gap": _finite_or_none(c.min_gap),
             "total_force": c.total_force.tolist(), "length_in_contact": c.length_in_contact}
            for c in result.contacts
        ],
        "pending": [] if complete else list(PENDING_READOUTS),
    }


def session_message(session: "Session") -> dict:
    """The "session" message: what changes only when a file is opened (names, obstacles, the sweep's timeline)."""
    sweep = session.sweep
    return {
        "type": "session",
        "revision": session.revision,
        "name": session.problem.name,
        "obstacles": [
            {"id": k, "name": s.obstacle.name, "required": s.obstacle.clearance, "triangles": int(len(s.obstacle.faces)),
             "body": s.obstacle.body}
            for k, s in enumerate(session.obstacles)
        ],
        "sweep": None if sweep is None else {
            "poses": sweep.pose_count,
            "travel": sweep.travel.tolist(),
            "stages": [{"name": st.name, "unit": st.unit, "first": st.first, "count": st.count} for st in sweep.stages],
        },
    }


def _clearances(session: "Session", nodes: np.ndarray, radius: float):
    """Per station the least clearance ratio over the obstacles (distance / required, up to CLEARANCE_SCALE),
    and per obstacle its nearest approach; (None, []) without obstacles."""
    if not session.obstacles:
        return None, []
    ratio = np.full(len(nodes), CLEARANCE_SCALE)
    nearest = []
    for shown in session.obstacles:
        pose = session.obstacle_pose(shown)
        local = pose.inverse().points(nodes)
        required = shown.obstacle.clearance
        scale = max(required, 1e-3 * session.problem.hose.length)  # a zero requirement: colour by distance
        profile, found = profile_and_nearest(shown.index, local, radius, CLEARANCE_SCALE * scale)
        segments = profile / scale
        stations = np.minimum(np.append(segments, segments[-1]), np.insert(segments, 0, segments[0]))
        ratio = np.minimum(ratio, stations)
        nearest.append({"name": shown.obstacle.name, "distance": found.distance, "required": required, "s": found.s})
    return ratio, nearest


def _station_d1(result: Result) -> np.ndarray:
    """(N+1, 3) the section axis d1 at the stations (fitting frames at the ends, the mean of the two
    segments' elsewhere, made normal to the tangent): the lay line that shows the twist."""
    d1 = np.vstack([result.start_frame[0][None], result.frames[:, 0], result.end_frame[0][None]])
    tangents = np.vstack([result.start_frame[2][None], result.frames[:, 2], result.end_frame[2][None]])
    axis = d1[:-1] + d1[1:]
    tangent = tangents[:-1] + tangents[1:]
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    axis -= np.einsum("ij,ij->i", axis, tangent)[:, None] * tangent
    return axis / np.linalg.norm(axis, axis=1)[:, None]


def _quaternion(frame: np.ndarray) -> list[float]:
    """Unit quaternion (w, x, y, z) turning the world axes onto a fitting frame's d1, d2, d3."""
    return matrix_quaternion(np.asarray(frame).T).tolist()


def _matrix(pose) -> list[float]:
    """A pose as a 4x4 matrix, row by row (mm)."""
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = pose.rotation, pose.position
    return matrix.ravel().tolist()


def _finite_or_none(values):
    """Numbers, with inf and NaN as None (JSON has neither)."""
    if np.ndim(values) == 0:
        return float(values) if math.isfinite(values) else None
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, dtype=float)]
