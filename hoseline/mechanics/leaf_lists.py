"""Leaf lists: the tree leaves near the hose, kept while it moves little, so nearby searches filter a short list.

The contact searches of a mesh (contact_mesh.MeshArrays.pairs) ask, for each station or segment
of the hose, which leaves of a mesh's tree come within its reach: one walk down two trees
(bounding_volumes.leaves_within).  Newton's trial states and a sweep's poses ask it again and
again about a hose that has moved a fraction of a millimetre.  As a molecular dynamics code keeps
a Verlet list, a walk is made with every reach grown by a margin, and the leaves it finds are
kept with the chain it was made for; a later search is answered from that list while every
station or segment has moved less than half the margin (less the growth of its own reach), by
the same leaf test the walk makes at its leaves.  No list is made for reaches beyond REACH_RADII hose
radii (a long Newton step's: its list would cost more to filter than the walks it saves).  The
nearest triangle of each station (contact_mesh.MeshArrays.station_gaps, the step filter's) is
taken from the same list.

Why the answer is the walk's, to the bit.  The walk keeps a (segment, leaf) pair where the
segment's box grown by its reach meets the leaf's box and bounding_volumes.leaf_within holds (the
boxes of both trees' inner nodes hold their children's, so the leaf test decides alone).  Its
bounds, box_gap of the segment and of its pieces, change by at most twice the larger move of the
segment's ends (a box's gap by sqrt(2) times it, the midpoint's distance and the half length by
once each), so a leaf that passes the test now passed it, with the grown reach, where the list was
made: the list holds every pair the walk would find, in the walk's order
(contact_mesh._leaves_in_order), and filtering keeps that order.  A small slack covers rounding.
The list is made afresh when any station or segment has moved too far, when its reach has grown
past the list's, or for another tree (a mesh moved by a body, meshes left out).

Written by hand: the leaf test must be the walk's own, which no library's neighbour list offers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from hoseline.mechanics.bounding_volumes import leaf_bounds, leaf_within
from hoseline.mechanics.proximity import point_of

MARGIN_RADII = 0.2  # how far each reach is grown for a list, in hose radii (1 mm for the thesis hose)
REACH_RADII = 1.5  # the longest reach a list is made for, in hose radii: the barrier's and a short step's
MOST_WAITING = 16  # plain walks before a list is tried again, at most (LeafLists)
SLACK = 1e-9  # relative: the reach a list must exceed beyond the moves, for rounding


@dataclass
class _List:
    """The leaves found for a chain (starts, ends (n, 3) mm) with its reaches (n,) mm grown, in one tree, and how
    many later searches it has answered."""

    lower: np.ndarray  # the tree's boxes it was made in (by identity)
    roots: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    reaches: np.ndarray
    segments: np.ndarray
    leaves: np.ndarray
    bounds: np.ndarray  # each pair's leaf bound where the list was made (bounding_volumes.leaf_bounds), mm
    served: int = 0


class LeafLists:
    """The leaf lists of one set of meshes, by search ("stations", "segments"); see the module doc.

    A list that answers no later search (the hose moved on by more than the margin at once: a long
    Newton step, a placement path) cost a wider walk for nothing: after k such lists of a search in
    a row, the next one is made only after 2^k - 1 plain walks (1, 3, 7, 15, then MOST_WAITING), so
    that a placement pays little for lists and a sweep keeps them.
    """

    def __init__(self) -> None:
        self._lists: dict[str, _List] = {}
        self._waiting: dict[str, int] = {}  # plain walks left before the next list of a search
        self._failed: dict[str, int] = {}  # lists of a search in a row that answered nothing

    def __reduce__(self):  # a copy sent elsewhere (a Dask worker) starts without lists
        return (LeafLists, ())

    def leaves(self, search: str, starts: np.ndarray, ends: np.ndarray, reaches: np.ndarray, tree: tuple,
               roots: np.ndarray, margin: float, walk, largest: float) -> tuple[np.ndarray, np.ndarray] | None:
        """(segments, leaves) of the chain starts[i] to ends[i] ((n, 3) mm) within reaches (n,) mm of the tree's leaves
        (tree: lower, upper, children, ranges; roots: each mesh's root), as walk(starts, ends, reaches, *tree, roots)
        finds them: from the list of `search` where it holds them, else from a new list with the reaches grown by
        `margin` mm if none is above `largest` mm; None for a search reaching farther (a list of every leaf within a
        long Newton step's reach would cost more to filter than the walks it saves)."""
        if not np.any(reaches > 0.0):  # nothing within reach: the list is left for the searches that need it
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        kept = self._lists.get(search)
        if (kept is not None and kept.lower is tree[0] and kept.starts.shape == starts.shape
                and np.array_equal(kept.roots, roots)):
            holds, segments, leaves = filtered(starts, ends, reaches, kept.starts, kept.ends, kept.reaches,
                                               kept.segments, kept.leaves, kept.bounds, tree[0], tree[1])
            if holds:
                kept.served += 1
                return segments, leaves
        if not np.max(reaches) <= largest:
            return None
        if kept is not None:  # it holds no more: judge it
            self._lists.pop(search, None)
            failed = 0 if kept.served else self._failed.get(search, 0) + 1
            self._failed[search] = failed
            self._waiting[search] = min(2 ** failed - 1, MOST_WAITING)
        if self._waiting.get(search, 0) > 0:
            self._waiting[search] -= 1
            return None
        grown = np.where(reaches > 0.0, reaches + margin, reaches)
        segments, leaves = walk(starts, ends, grown, *tree, roots)
        bounds = leaf_bounds(starts, ends, segments, leaves, tree[0], tree[1])
        self._lists[search] = _List(tree[0], roots.copy(), starts.copy(), ends.copy(), grown, segments, leaves,
                                    bounds)
        return filtered(starts, ends, reaches, starts, ends, grown, segments, leaves, bounds, tree[0], tree[1])[1:]


@njit(cache=True)
def filtered(starts, ends, reaches, list_starts, list_ends, list_reaches, segments, leaves, bounds, lower, upper):
    """(holds, segments, leaves): whether the list (made for list_starts, list_ends with list_reaches, mm) holds every
    leaf within reaches (mm) of the chain starts, ends, and if so those of its pairs that are (the walk's leaf test).
    bounds: each pair's leaf bound (mm) where the list was made; it has fallen by at most twice the move since, so a
    pair whose bound less that is still at or above the reach fails the leaf test without it being evaluated."""
    moves = np.zeros(starts.shape[0])
    for i in range(starts.shape[0]):
        if reaches[i] > 0.0:
            start_move = (starts[i, 0] - list_starts[i, 0]) ** 2 + (starts[i, 1] - list_starts[i, 1]) ** 2 + (
                starts[i, 2] - list_starts[i, 2]) ** 2
            end_move = (ends[i, 0] - list_ends[i, 0]) ** 2 + (ends[i, 1] - list_ends[i, 1]) ** 2 + (
                ends[i, 2] - list_ends[i, 2]) ** 2
            moves[i] = 2.0 * math.sqrt(max(start_move, end_move))
            needed = reaches[i] + moves[i]
            if not needed + SLACK * (1.0 + needed) <= list_reaches[i]:
                return False, segments[:0], leaves[:0]
    keep = np.zeros(segments.shape[0], np.bool_)
    for p in range(segments.shape[0]):
        i, node = segments[p], leaves[p]
        reach = reaches[i]
        if not reach > 0.0 or bounds[p] - moves[i] >= reach + SLACK * (1.0 + reach + bounds[p]):
            continue
        apart = False  # the walk's box test (bounding_volumes.chain_tree, leaves_within), in its own arithmetic
        for k in range(3):
            if (lower[node, k] > max(starts[i, k], ends[i, k]) + reach
                    or upper[node, k] < min(starts[i, k], ends[i, k]) - reach):
                apart = True
        keep[p] = not apart and leaf_within(point_of(starts, i), point_of(ends, i), point_of(lower, node),
                                            point_of(upper, node), reach)
    return True, segments[keep], leaves[keep]
