"""Contact in the placement of a problem: its contact model, the clear start, and what the result reports.

The placement sequence (procedures/placement/sequence.py) calls these when the problem has
contact (Problem.contact or Problem.self_contact): the model of its obstacles, a check that the
state the contact continuation starts from clears every obstacle (else a PlacementError naming
the obstacle and what to do), and, on the converged shape, per obstacle the barrier's pairs and where
the force is carried (the lying arcs, the touch-downs and their point forces: contact/extent.py), the
internal force with the contact loads, the stability margin with the barrier's Hessian, and a last
check that nothing penetrates.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from hoseline.mechanics.blas_threads import one_blas_thread
from hoseline.mechanics.banded import NEUTRAL
from hoseline.mechanics.clipped_newton import clip_forces
from hoseline.mechanics.contact import SEGMENT_SEGMENT, STATION_KINDS
from hoseline.mechanics.contact_newton import (
    ContactModel,
    evaluate_contact,
    self_exclusion,
    spectrum_ends,
    tangent_hessian,
    tridiagonal_form,
)
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.model.problem import Problem
from hoseline.procedures.contact.extent import carried_extent, free_hose
from hoseline.procedures.contact.model import bend_length, contact_model, reference_pressure
from hoseline.procedures.contact.nearest import nearest_gaps
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.result import ObstacleContact, Result


def problem_contact_model(problem: Problem, reuse: ContactModel | None = None) -> ContactModel:
    """The ContactModel of the problem's obstacles (and self-contact) with the reference pressure of its hose.

    The bend length (model.bend_length) is the shortest of the hose length and R + r over round
    obstacles; with self-contact also pi r, the tightest U-turn of two touching passes.
    reuse: a model of the same obstacles, self-contact and hose radius (its primitives and meshes' search
    trees are kept; only the barrier stiffness and the self-contact exclusion follow the hose).
    """
    hose = problem.hose
    weight = hose.mass_per_length * float(np.linalg.norm(problem.gravity)) * 1e-3  # kg/m * m/s^2 = N/m -> N/mm
    length = bend_length(hose.length, problem.contact, hose.outer_radius)
    if problem.self_contact:
        length = min(length, math.pi * hose.outer_radius)
    pressure = reference_pressure(weight, float(np.max(hose.stiffness_vector[:2])), length)
    if reuse is not None:
        exclusion = self_exclusion(hose.outer_radius, hose.segment_length) if problem.self_contact else -1
        return replace(reuse, stiffness=pressure / reuse.activation, self_exclusion=exclusion)
    return contact_model(problem.contact, hose.outer_radius, hose.segment_length, pressure,
                         self_contact=problem.self_contact)


def is_clear(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> bool:
    """Whether `state` keeps a positive gap to every obstacle (and itself, with self-contact)."""
    return model.penetration(centerline(state.frames, clamps.start_point, props.segment_length)) is None


def check_clear(where: str, props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> None:
    """Raise PlacementError naming the obstacle, the station or segment and the depth if `state` touches or
    enters anything; where: what the state is, for the message (e.g. "the straight hose the placement starts from")."""
    inside = model.penetration(centerline(state.frames, clamps.start_point, props.segment_length))
    if inside is None:
        return
    raise PlacementError(
        f"placement with contact: {where} is not clear: {inside}. "
        "The placement carries the hose from a straight line out of the start fitting (along start.direction, the "
        "hose length long) to the end fitting, and needs that start clear of every obstacle: move or shorten the "
        "obstacle so that it does not meet that line, or remove it from [contact]")


HELD_PATH_SAMPLES = 201  # points along a held station's path that crosses an obstacle: where, in fractions


def check_held_paths(place: Callable[[float], Clamps], clip_arcs: Sequence[float], model: ContactModel) -> None:
    """Raise PlacementError if the place phase carries the end fitting or a clip (each on a straight line, from where
    it sits on the straight hose to its mount or clip point) through an obstacle: the station held there, with the
    hose's radius about it, would have to enter the obstacle, so no placement exists along that path.

    place: the clamps at each fraction of the place phase.  clip_arcs: each clip's arc length (mm), for the message.
    """
    first, last = place(0.0), place(1.0)
    held = [("the end fitting", lambda clamps: clamps.end_point, first.end_point, last.end_point)]
    held += [(f"the clip at arc length {arc:g} mm", lambda clamps, j=j: clamps.clips[j].point, first.clips[j].point,
              last.clips[j].point) for j, arc in enumerate(clip_arcs)]
    obstacles = replace(model, self_exclusion=-1)  # the path of one station: no self-contact
    for what, point_of, start, end in held:
        if np.array_equal(start, end):  # it stays where it sits on the straight hose, which is clear
            continue
        crossed = _entered(obstacles, np.array([start, end]))
        if not crossed:
            continue
        fractions = np.linspace(0.0, 1.0, HELD_PATH_SAMPLES)
        points = [point_of(place(t)) for t in fractions]
        inside = [(t0, t1) for t0, t1, p, q in zip(fractions[:-1], fractions[1:], points[:-1], points[1:])
                  if _entered(obstacles, np.array([p, q]))]  # pieces of the path that enter it
        between = f"between fractions {inside[0][0]:.3f} and {inside[-1][1]:.3f}" if inside else "(grazing)"
        raise PlacementError(
            f"placement with contact: the place phase carries {what} on a straight line from "
            f"{np.round(start, 3).tolist()} to {np.round(end, 3).tolist()} mm (from where it sits on the straight hose), "
            f"and that line passes through obstacle {crossed[0]!r} {between}, nearer to it than the hose radius: the "
            "hose held there would have to enter it, so no placement exists along that path. Move the obstacle, or the "
            "clip or mount, or place without the obstacle and read its clearance")


def _entered(model: ContactModel, nodes: np.ndarray) -> list[str]:
    """The obstacles that the capsule of the hose radius about the segment nodes[0] to nodes[1] (mm, apart) enters."""
    return [name for name, gap in model.smallest_gaps(nodes).items() if gap < 0.0]


def contact_reports(problem: Problem, props: RodProperties, clamps: Clamps, state: RodState,
                    model: ContactModel, smallest_gaps: bool = True) -> tuple[list[ObstacleContact], np.ndarray]:
    """(reports, forces beyond): one ObstacleContact per obstacle of the problem (and "self" with self-contact) at
    `state` (mm, N), its barrier pairs and where it carries its force (procedures/contact/extent.py); and the
    (N+1, 3) N sum of the contact forces on the part of the hose beyond each station (forces_beyond), from the
    same pairs.  A station's force (station-plane, station-triangle) at station k acts beyond the stations before
    k; a segment's force (on segment i, between stations i and i + 1) beyond stations 0..i; a self-contact pair
    pushes its first segment and pulls the second the other way.
    smallest_gaps: False leaves each report's min_gap NaN (the search of every obstacle for its smallest gap saved, for
    a result whose gaps are read later: a studio drag)."""
    h = props.segment_length
    nodes = centerline(state.frames, clamps.start_point, h)
    a_kinds, a_first, a_second, _ = model.pairs(nodes, model.activation)
    forces, on_hose, on_other, active_gaps = model.terms(nodes, model.stiffness * h, a_kinds, a_first, a_second)[3:]
    active_owners = np.array([model.owner(kind, j) for kind, j in zip(a_kinds, a_second)], dtype=object)
    at_station = np.isin(a_kinds, STATION_KINDS)
    arc = np.where(at_station, a_first * h,
                   a_first * h + np.linalg.norm(on_hose - nodes[np.minimum(a_first, props.segments)], axis=1))
    normal = on_hose - on_other  # from the obstacle's surface to the hose's centreline: its outward normal
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    last_station = np.where(at_station, a_first, a_first + 1)  # a segment pair touches both its ends
    beyond = _forces_beyond(props.segments, a_kinds, a_first, a_second, forces)
    hose = free_hose(h, nodes, state.frames, clamps.start_frame[2],
                     state.frames[-1, 2] if clamps.end_frame is None else clamps.end_frame[2],
                     _internal_force(props, clamps, state) + beyond, clamps.line_weight, props.stiffness[:2])
    smallest = model.smallest_gaps(nodes) if smallest_gaps else None
    names = [obstacle.name for obstacle in problem.contact] + (["self"] if problem.self_contact else [])
    kind_of = {obstacle.name: obstacle.kind for obstacle in problem.contact} | {"self": "self"}
    reports = []
    for name in names:
        mine = np.flatnonzero(active_owners == name)
        mine = mine[np.argsort(arc[mine], kind="stable")]
        force = forces[mine]
        carried, touchdowns = carried_extent(hose, arc[mine], force, normal[mine], a_first[mine], last_station[mine])
        reports.append(ObstacleContact(
            name=name, kind=kind_of[name], min_gap=smallest[name] if smallest_gaps else math.nan,
            arc_length=arc[mine], point=on_hose[mine], surface_point=on_other[mine],
            gap=active_gaps[mine], force=force, total_force=force.sum(axis=0),
            length_in_contact=float(sum(part.length for part in carried)), carried=tuple(carried),
            touchdowns=tuple(touchdowns)))
    return reports, beyond


def _internal_force(props: RodProperties, clamps: Clamps, state: RodState) -> np.ndarray:
    """(N+1, 3) N: the force of the part beyond each station on the part before it, without the contact loads:
    the end mount's reaction, the weight and the clips beyond the station."""
    s = props.segment_length * np.arange(props.segments + 1)
    force = state.end_force[None, :] + (props.length - s)[:, None] * clamps.line_weight[None, :]
    for clip, push in zip(clamps.clips, clip_forces(clamps, state)):
        force[:clip.node] += push
    return force


def _forces_beyond(segments: int, kinds, first, second, forces) -> np.ndarray:
    """(N+1, 3) N: the sum of the contact forces (of the pairs kinds, first, second) on the part of the hose
    beyond each station (see contact_reports)."""
    acting = np.zeros((segments + 2, 3))  # at index m: the forces that act beyond the stations before m
    np.add.at(acting, np.where(np.isin(kinds, STATION_KINDS), first, first + 1), forces)
    self_pairs = kinds == SEGMENT_SEGMENT
    np.add.at(acting, second[self_pairs] + 1, -forces[self_pairs])
    return np.cumsum(acting[::-1], axis=0)[::-1][1:]


def _solver_error(what: str) -> None:
    """Raise the PlacementError of a converged shape that is not clear (`what` it does): the solver's guarantee failed."""
    raise PlacementError(f"placement with contact: the converged shape {what}; this is a solver error, please report it "
                         "with the problem file")


def stability_margin_with_contact(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> float:
    """Smallest eigenvalue of the Hessian with the barrier, on the tangent space of the constraints, per length
    (N/rad^2, as Result.stability_margin); zero (neutral) when it is within NEUTRAL of the largest magnitude
    (rounding: the barrier's curvature makes that largest eigenvalue big)."""
    system = evaluate_contact(props, clamps, state, model)
    with one_blas_thread():  # small dense matrices: threads only contend (4x slower)
        values, scale = spectrum_ends(tridiagonal_form(tangent_hessian(system)), 1)
    if abs(values[0]) <= NEUTRAL * scale:
        return 0.0
    return float(values[0]) / props.segment_length


def with_contact(result: Result, props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel,
                 stability: bool = True, locate_gaps: bool = True) -> Result:
    """The Result of a placement with contact completed: contacts per obstacle, the internal force (and the start
    mount's reaction) with the contact loads, the stability margin with the barrier, each obstacle's smallest gap
    to the whole assembly and where it is (contact/nearest.py).  Raises PlacementError if the hose enters anything
    (a smallest gap below zero): the solver's guarantee failed.
    stability: False leaves the rod's margin without the barrier in place (a dense eigenvalue problem saved), for a
    result whose forces only are read (the error estimates' other solves).
    locate_gaps: False leaves each obstacle's smallest gap to the whole assembly unlocated (min_gap NaN, its place None; the
    search saved, and the search of each obstacle for its smallest gap to the hose too: whether the hose enters anything
    is then the cheaper ContactModel.penetration's), for a result whose gaps are read later (a studio drag)."""
    problem = result.problem
    result.contacts, beyond = contact_reports(problem, props, clamps, state, model, smallest_gaps=locate_gaps)
    nodes = centerline(state.frames, clamps.start_point, props.segment_length)
    if not locate_gaps and (inside := model.penetration(nodes)) is not None:
        _solver_error(f"is not clear: {inside}")
    gaps = [contact.min_gap for contact in result.contacts]
    if locate_gaps and gaps and min(gaps) < 0.0:
        worst = result.contacts[int(np.argmin(gaps))]
        _solver_error(f"enters {worst.name!r} by {-worst.min_gap:.3g} mm")
    if locate_gaps:
        nearest = nearest_gaps(problem, model, nodes)  # the whole assembly: fittings and the start station too
        result.contacts = [contact if contact.name not in nearest else
                           replace(contact, min_gap=min(contact.min_gap, nearest[contact.name].gap),
                                   min_gap_on=nearest[contact.name].on,
                                   min_gap_arc_length=nearest[contact.name].arc_length)
                           for contact in result.contacts]
    result.internal_force = result.internal_force + beyond
    result.start_force = -result.internal_force[0]
    if stability:
        result.stability_margin = stability_margin_with_contact(props, clamps, state, model)
    return result
