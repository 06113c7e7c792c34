"""Where a contact carries its force: the arcs the hose lies on an obstacle, their touch-down (lift-off) points,
and the concentrated forces there.

A frictionless elastica on a smooth obstacle (docs/model.md, Contact: Contact extent) lies on it over an arc
[s_a, s_b]: there its curvature normal to the surface is the surface's (0 on a plane, -1/(R + r) over a drum
of radius R, the centreline on the circle of R + r), and the obstacle pushes a distributed pressure (the
weight per length on a floor, T/(R + r) under a tension T on a drum).  At each end the moment (so the
curvature) is continuous and the shear jumps: the obstacle pushes a point force P there, along its normal.
The discrete solver spreads that point force over the few stations within the barrier's reach d_hat, so
the stations in reach overstate the arc (the floor of tests/test_contact_floor.py: 450 mm of stations in
reach, 434.6 mm lying).  Read from the converged discrete solution instead:
- a touch-down: where the free hose next to the contact, continued as a planar elastica in the plane of its
  tangent and the obstacle's normal (from the last station with no contact on the way, with the internal
  force and the weight it carries there), reaches the surface's normal curvature.  Under a tension T the
  free hose's curvature changes over a boundary layer sqrt(EI / T) (13.5 mm, 4 segments, on the drum of
  tests/test_contact_cylinder.py), too fast for a straight line through the curvature of the last stations:
  it is integrated (RK4);
- its point force: the free side's shear there, EI theta'' (the surface side's is EI times the change of
  the surface curvature along the hose, taken as zero);
- the surface's normal curvature: -t . dn/ds from the normals n of the barrier pairs along the contact;
- the distributed part: the contact's total force less its point forces.
A contact too short for a lying part (the two touch-downs cross, or the free side never reaches the
surface's curvature: a touch on a sphere, a drum's side or an edge) is one point force: the contact's total
at the force-weighted arc of its pairs.  A contact that reaches a mount has no touch-down there.
The curvature model uses the hose's bending stiffness (stiffener springs and a preset are not in it).
Units: mm, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.procedures.placement.result import CarriedArc, Touchdown

STEPS_PER_SEGMENT = 8  # RK4 steps per segment length along the free side


@dataclass(frozen=True)
class FreeHose:
    """What the touch-down search reads of an equilibrium.

    h: segment length, mm.  nodes: (N+1, 3) stations, mm.  frames: (N, 3, 3) segment frames (rows d1, d2, d3).
    tangents: (N+2, 3) the start fitting's tangent, the segments', the end fitting's.
    internal_force: (N+1, 3) N, of the part beyond each station on the part before it.
    line_weight: (3,) N/mm.  bending: (EI1, EI2) N*mm^2.
    """

    h: float
    nodes: np.ndarray
    frames: np.ndarray
    tangents: np.ndarray
    internal_force: np.ndarray
    line_weight: np.ndarray
    bending: np.ndarray

    @property
    def segments(self) -> int:
        return self.frames.shape[0]

    def joint_tangent(self, station: int) -> np.ndarray:
        """The unit tangent (3,) at a station: the mean of the segments' (or fittings') next to it."""
        tangent = self.tangents[station] + self.tangents[station + 1]
        return tangent / math.sqrt(tangent @ tangent)

    def curvature(self, station: int) -> np.ndarray:
        """The curvature binormal (3,) 1/mm at a station: the turn from the tangent before it to the one beyond,
        2 (t_a x t_b) / (h (1 + t_a . t_b))."""
        before, after = self.tangents[station], self.tangents[station + 1]
        return 2.0 * _cross(before, after) / (self.h * (1.0 + before @ after))

    def point_at(self, arc: float) -> np.ndarray:
        """The centreline point (3,) mm at arc length `arc` mm (linear between stations)."""
        k = min(max(int(arc // self.h), 0), self.segments - 1)
        return self.nodes[k] + (arc - k * self.h) * self.frames[k, 2]


def free_hose(h: float, nodes: np.ndarray, frames: np.ndarray, start_tangent: np.ndarray, end_tangent: np.ndarray,
              internal_force: np.ndarray, line_weight: np.ndarray, bending: np.ndarray) -> FreeHose:
    """The FreeHose of an equilibrium: h mm, nodes (N+1, 3) mm, frames (N, 3, 3), the fittings' tangents (3,),
    internal_force (N+1, 3) N, line_weight (3,) N/mm, bending (EI1, EI2) N*mm^2."""
    tangents = np.vstack([start_tangent, frames[:, 2], end_tangent])
    return FreeHose(h, nodes, frames, tangents, internal_force, line_weight, np.asarray(bending, dtype=float))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (np.cross is slow on small arrays)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def carried_extent(hose: FreeHose, arc: np.ndarray, force: np.ndarray, normal: np.ndarray, first_station: np.ndarray,
                   last_station: np.ndarray) -> tuple[list[CarriedArc], list[Touchdown]]:
    """The arcs one obstacle carries and its touch-downs, from its barrier pairs (sorted by arc).

    arc: (k,) mm of each pair's hose point.  force: (k, 3) N, the obstacle's push.  normal: (k, 3) the
    obstacle's outward unit normal at each pair.  first_station, last_station: (k,) the stations each pair
    touches (a station pair one, a segment pair its two ends).
    """
    carried, touchdowns = [], []
    for pairs in _contacts(first_station, last_station):
        lying = _lying(hose, arc[pairs], normal[pairs], int(first_station[pairs].min()), int(last_station[pairs].max()))
        total = force[pairs].sum(axis=0)
        if lying is None:  # a point contact
            weights = np.linalg.norm(force[pairs], axis=1)
            at = float(np.average(arc[pairs], weights=weights)) if weights.sum() > 0.0 else float(arc[pairs].mean())
            touchdowns.append(Touchdown(at, hose.point_at(at), total))
            continue
        start, end, ends = lying
        point_forces = [Touchdown(s, hose.point_at(s), push) for s, push in ends]
        touchdowns += point_forces
        carried.append(CarriedArc(start, end, total - sum((t.force for t in point_forces), np.zeros(3))))
    return carried, touchdowns


def _contacts(first_station: np.ndarray, last_station: np.ndarray) -> list[np.ndarray]:
    """The pairs grouped into contacts: runs of stations touched with no untouched station between."""
    if first_station.size == 0:
        return []
    order = np.argsort(first_station, kind="stable")
    groups, current, reach = [], [order[0]], last_station[order[0]]
    for p in order[1:]:
        if first_station[p] > reach + 1:
            groups.append(np.array(current))
            current, reach = [], last_station[p]
        current.append(p)
        reach = max(reach, last_station[p])
    groups.append(np.array(current))
    return [np.sort(group) for group in groups]


def _lying(hose: FreeHose, arc, normal, first: int, last: int):
    """(start, end, [(arc, point force (3,))...]) of one contact's lying part, mm and N, from its pairs' arcs and
    normals and the stations first to last it touches; None if it is a point contact."""
    inner_start, inner_end = _surface_curvature(hose, arc, normal, 1), _surface_curvature(hose, arc, normal, -1)
    if inner_start is None or inner_end is None:
        return None
    ends = []
    if first - 1 >= 1:  # a free hose before the contact
        found = _touchdown(hose, first - 1, +1, arc, normal, inner_start, arc[-1] - (first - 1) * hose.h)
        if found is None:
            return None
        ends.append(found)
        start = found[0]
    else:
        start = float(arc[0])
    if last + 1 <= hose.segments - 1:  # a free hose beyond it
        found = _touchdown(hose, last + 1, -1, arc, normal, inner_end, (last + 1) * hose.h - arc[0])
        if found is None:
            return None
        ends.append(found)
        end = found[0]
    else:
        end = float(arc[-1])
    if end <= start:
        return None
    return start, end, ends


def _surface_curvature(hose: FreeHose, arc, normal, side: int) -> float | None:
    """The obstacle's normal curvature along the hose at one end of a contact (side +1: its start, -1: its
    end), 1/mm: -t . dn/ds between the end pair and the first pair at least h/2 further in; None if none is."""
    ordered = range(len(arc)) if side > 0 else range(len(arc) - 1, -1, -1)
    end = next(iter(ordered))
    inner = next((p for p in ordered if abs(arc[p] - arc[end]) >= 0.5 * hose.h), None)
    if inner is None:
        return None
    tangent = hose.joint_tangent(min(max(int(round(0.5 * (arc[end] + arc[inner]) / hose.h)), 0), hose.segments))
    return -float(tangent @ (normal[inner] - normal[end])) / (arc[inner] - arc[end])


def _touchdown(hose: FreeHose, station: int, direction: int, arc, normals, surface: float, reach: float):
    """(arc mm, point force (3,) N) where the free hose from `station` towards a contact (direction +1: on
    along the hose, -1: back) reaches the surface's normal curvature `surface` (1/mm) within `reach` mm;
    None if it does not.  arc, normals: the contact's pairs (arc lengths, the obstacle's outward normals)."""
    h = hose.h
    normal = normals[0] if direction > 0 else normals[-1]
    tangent = hose.joint_tangent(station)
    across = normal - (normal @ tangent) * tangent  # the bending plane: the tangent and the obstacle's normal
    if np.linalg.norm(across) < 1e-6:
        return None
    across /= np.linalg.norm(across)
    binormal = _cross(tangent, across)
    frame = hose.frames[station if direction > 0 else station - 1]
    stiffness = float(hose.bending[0] * (binormal @ frame[0]) ** 2 + hose.bending[1] * (binormal @ frame[1]) ** 2)
    force = hose.internal_force[station]
    n_across, n_along = float(force @ across), float(force @ tangent)
    w_across, w_along = float(hose.line_weight @ across), float(hose.line_weight @ tangent)

    def bend_rate(sigma: float, theta: float) -> float:
        # EI theta'' = -(n . nu) with nu = cos(theta) across - sin(theta) tangent, n = n_k - w sigma (n' = -w)
        across_force, along_force = n_across - w_across * sigma, n_along - w_along * sigma
        return (math.sin(theta) * along_force - math.cos(theta) * across_force) / stiffness

    step = direction * h / STEPS_PER_SEGMENT
    sigma, theta, rate = 0.0, 0.0, float(hose.curvature(station) @ binormal)
    miss = rate - surface
    if miss == 0.0:
        return station * h, -direction * stiffness * bend_rate(0.0, 0.0) * _normal_at(station * h, arc, normals)
    while abs(sigma) < reach:
        k1t, k1r = rate, bend_rate(sigma, theta)
        k2t, k2r = rate + 0.5 * step * k1r, bend_rate(sigma + 0.5 * step, theta + 0.5 * step * k1t)
        k3t, k3r = rate + 0.5 * step * k2r, bend_rate(sigma + 0.5 * step, theta + 0.5 * step * k2t)
        k4t, k4r = rate + step * k3r, bend_rate(sigma + step, theta + step * k3t)
        theta_next = theta + step / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
        rate_next = rate + step / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r)
        miss_next = rate_next - surface
        if (miss_next > 0.0) != (miss > 0.0):  # crossed within this step: interpolate
            part = miss / (miss - miss_next)
            sigma_at, theta_at = sigma + part * step, theta + part * (theta_next - theta)
            shear = stiffness * bend_rate(sigma_at, theta_at)
            return station * h + sigma_at, -direction * shear * _normal_at(station * h + sigma_at, arc, normals)
        sigma, theta, rate, miss = sigma + step, theta_next, rate_next, miss_next
    return None


def _normal_at(at: float, arc, normals) -> np.ndarray:
    """The obstacle's outward unit normal (3,) at arc length `at` mm: interpolated between the pairs' (the
    nearest pair's outside them, or where the two next to it face apart)."""
    normal = np.array([np.interp(at, arc, normals[:, axis]) for axis in range(3)])
    size = math.sqrt(normal @ normal)
    return normal / size if size > 0.5 else normals[int(np.argmin(np.abs(arc - at)))]
