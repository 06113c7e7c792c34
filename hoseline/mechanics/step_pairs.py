"""Which pairs a move of the hose could bring into contact, and whether a trial kept them clear (compiled).

The step filter of contact_newton.py (StepFilter) bounds how far each pair can approach along a
move: a station k by reach_k (mm), a segment pair i < j relative to each other by
reach_{j+1} - reach_i.  A pair whose gap that bound cannot shrink to SAFE_FRACTION of it is never
refused, and its fraction of the move is above 1: it is left out.  On a long hose with
self-contact that is nearly every pair, and a long Newton step made the filter list hundreds of
them by their exact distance (contact.pair_gaps at the largest reach); here each segment pair is
first bounded by its midpoints (two segments' surfaces are at least the midpoints' distance, less
half of each length, less a diameter, apart), and only the pairs that bound cannot clear are
measured exactly.  The watched pairs, their gaps and the limit are those of listing every pair
below the cutoff and filtering them (the test compares both).

Written by hand (Numba): the filter runs at every Newton step and every pose of a sweep, and the
pairs are the contact kernels' own (contact.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hoseline.mechanics.contact import (
    SEGMENT_BALL,
    SEGMENT_CAPSULE,
    SEGMENT_SEGMENT,
    STATION_PLANE,
    _pair_distance,
)
from hoseline.mechanics.self_pairs import near_segment_pairs

ROUNDING = 1e-9  # mm, and relative: a midpoint bound must clear a pair by this much before it is not measured


@njit(cache=True)
def _midpoints_and_halves(nodes):
    # each segment's midpoint (N, 3) and half its length (N,), mm
    n_seg = nodes.shape[0] - 1
    midpoints = np.empty((n_seg, 3))
    halves = np.empty(n_seg)
    for i in range(n_seg):
        length = 0.0
        for x in range(3):
            midpoints[i, x] = 0.5 * (nodes[i, x] + nodes[i + 1, x])
            length += (nodes[i + 1, x] - nodes[i, x]) ** 2
        halves[i] = 0.5 * math.sqrt(length)
    return midpoints, halves


@njit(cache=True)
def _midpoint_bound(midpoints, halves, i, j, hose_radius):
    # a lower bound of the gap (mm) of segments i and j: midpoints' distance less half of each length and a diameter
    d = 0.0
    for x in range(3):
        d += (midpoints[i, x] - midpoints[j, x]) ** 2
    return math.sqrt(d) - halves[i] - halves[j] - 2.0 * hose_radius


@njit(cache=True)
def _self_candidates(nodes, self_exclusion, reach):
    # (first, second): the segment pairs that may touch (j - i > self_exclusion) closer than `reach` (mm, centreline
    # to centreline) among others; every such pair when the reach spans the hose's box (a long Newton step), where
    # the sort and sweep of near_segment_pairs would find them all at a higher cost
    n_seg = nodes.shape[0] - 1
    if self_exclusion < 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    diagonal = 0.0
    for x in range(3):
        diagonal += (np.max(nodes[:, x]) - np.min(nodes[:, x])) ** 2
    if reach < math.sqrt(diagonal):
        return near_segment_pairs(nodes, self_exclusion, reach)
    count = max(n_seg - self_exclusion - 1, 0) * max(n_seg - self_exclusion, 0) // 2
    first = np.empty(count, np.int64)
    second = np.empty(count, np.int64)
    p = 0
    for i in range(n_seg):
        for j in range(i + self_exclusion + 1, n_seg):
            first[p], second[p] = i, j
            p += 1
    return first, second


@njit(cache=True)
def watched_pairs(nodes, hose_radius, planes, balls, capsules, self_exclusion, reach, cutoff, shrink):
    """The pairs a move could bring within `shrink` of their gap: (kinds, first, second, gaps, limit).

    nodes (N+1, 3), mm; reach (N+1,), mm: a bound of each station's move; cutoff, mm: no pair with a
    larger gap is listed; shrink = 1 - SAFE_FRACTION.  limit: the largest fraction of the move (at most 1)
    that lets no primitive pass through the body it faces, the smallest (gap + thickness) / bound over the
    pairs below the cutoff (contact_newton.motion_filter).  No trial goes beyond the limit, so a pair is
    watched where shrink * gap is below limit * bound: a long Newton step cut to a small limit watches only
    the pairs its cut step can bring near.
    """
    n_seg = nodes.shape[0] - 1
    last = n_seg
    span = reach[last] - reach[0]  # the largest relative move of two segments
    near_first, near_second = _self_candidates(nodes, self_exclusion, min(cutoff, span / shrink) + 2.0 * hose_radius)
    no_triangles, no_edges = np.zeros((0, 3, 3)), np.zeros((0, 2, 3))
    midpoints, halves = _midpoints_and_halves(nodes)
    # first pass: the limit (a self pair whose midpoint bound cannot lower it is not measured)
    limit = 1.0
    radii = np.concatenate((balls[:, 3], capsules[:, 6]))
    solid_gaps = np.empty((n_seg, radii.shape[0]))  # of every segment to each ball and capsule
    for i in range(n_seg):
        bound = reach[min(i + 1, last)]
        for j in range(radii.shape[0]):
            kind, index = (SEGMENT_BALL, j) if j < balls.shape[0] else (SEGMENT_CAPSULE, j - balls.shape[0])
            d = _pair_distance(kind, i, index, nodes, planes, balls, capsules, no_triangles, no_edges)[0]
            solid_gaps[i, j] = d - hose_radius - radii[j]
            if solid_gaps[i, j] < cutoff and bound > 0.0:
                limit = min(limit, (solid_gaps[i, j] + 2.0 * radii[j]) / bound)
    self_gaps = np.full(near_first.shape[0], np.nan)  # nan: not measured
    for p in range(near_first.shape[0]):
        i, j = near_first[p], near_second[p]
        bound = reach[min(j + 1, last)] - reach[i]
        if bound <= 0.0:
            continue
        least = _midpoint_bound(midpoints, halves, i, j, hose_radius) + 2.0 * hose_radius  # of gap + thickness
        if least > limit * bound + ROUNDING * (1.0 + limit * bound):
            continue
        self_gaps[p] = _pair_distance(SEGMENT_SEGMENT, i, j, nodes, planes, balls, capsules, no_triangles,
                                      no_edges)[0] - 2.0 * hose_radius
        if self_gaps[p] < cutoff:
            limit = min(limit, (self_gaps[p] + 2.0 * hose_radius) / bound)
    # second pass: the watched pairs
    capacity = n_seg * (planes.shape[0] + radii.shape[0]) + near_first.shape[0]
    kinds = np.empty(capacity, np.int64)
    first = np.empty(capacity, np.int64)
    second = np.empty(capacity, np.int64)
    gaps = np.empty(capacity)
    count = 0
    for k in range(1, n_seg + 1):
        for j in range(planes.shape[0]):
            gap = _pair_distance(STATION_PLANE, k, j, nodes, planes, balls, capsules, no_triangles, no_edges)[0]
            gap -= hose_radius
            if gap < cutoff and shrink * gap < limit * reach[k]:  # a plane is infinitely thick: it limits nothing
                kinds[count], first[count], second[count], gaps[count] = STATION_PLANE, k, j, gap
                count += 1
    for i in range(n_seg):
        bound = reach[min(i + 1, last)]
        for j in range(radii.shape[0]):
            gap = solid_gaps[i, j]
            if gap < cutoff and shrink * gap < limit * bound:
                kind, index = (SEGMENT_BALL, j) if j < balls.shape[0] else (SEGMENT_CAPSULE, j - balls.shape[0])
                kinds[count], first[count], second[count], gaps[count] = kind, i, index, gap
                count += 1
    for p in range(near_first.shape[0]):
        i, j = near_first[p], near_second[p]
        bound = limit * (reach[min(j + 1, last)] - reach[i])
        gap = self_gaps[p]
        if np.isnan(gap):
            most = min(cutoff, bound / shrink)  # no watched pair has a larger gap
            if _midpoint_bound(midpoints, halves, i, j, hose_radius) > most + ROUNDING * (1.0 + abs(most)):
                continue
            gap = _pair_distance(SEGMENT_SEGMENT, i, j, nodes, planes, balls, capsules, no_triangles,
                                 no_edges)[0] - 2.0 * hose_radius
        if gap < cutoff and shrink * gap < bound:
            kinds[count], first[count], second[count], gaps[count] = SEGMENT_SEGMENT, i, j, gap
            count += 1
    return kinds[:count].copy(), first[:count].copy(), second[:count].copy(), gaps[:count].copy(), limit


@njit(cache=True)
def pairs_clear(nodes, hose_radius, planes, balls, capsules, triangles, edges, kinds, first, second, floors):
    """Whether every listed pair's gap (mm) is above its floor (mm): a self pair cleared by its midpoint bound is
    not measured exactly (most of them, on a long hose)."""
    midpoints, halves = _midpoints_and_halves(nodes)
    for p in range(kinds.shape[0]):
        kind, i, j = kinds[p], first[p], second[p]
        if kind == SEGMENT_SEGMENT and _midpoint_bound(midpoints, halves, i, j, hose_radius) > floors[p]:
            continue
        d, radius = _pair_distance(kind, i, j, nodes, planes, balls, capsules, triangles, edges)
        if not d - hose_radius - (hose_radius if kind == SEGMENT_SEGMENT else radius) > floors[p]:
            return False
    return True
