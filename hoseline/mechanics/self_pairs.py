"""Which segments of the hose may touch each other: the broad phase of self-contact (compiled).

Every pair of segments far enough apart along the hose (more than `exclusion` apart in index)
may touch; checking all of them is N^2 / 2 exact distances per evaluation, which made a 50-segment
placement with self-contact ten times slower than with a drum alone.  Sort and sweep instead:
each segment's axis-aligned box (its two stations) grown by half the reach, sorted by its lower x;
a pair is a candidate only where the boxes overlap on all three axes, which every pair closer
than the reach does.  O(N log N + candidates); the exact distances are then taken for the
candidates only (mechanics/contact.py).

Written by hand (Numba): the pairs are needed inside the contact kernels' loop, where a Python
spatial index (SciPy's cKDTree on segment midpoints would need the longest segment as slack) would
cost more than the distances it saves on a hose of a hundred segments.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def near_segment_pairs(nodes, exclusion, reach):
    """(first, second) arrays of the segment pairs i < j with j - i > exclusion whose boxes, grown by reach / 2
    each (mm), overlap: every pair of segments closer than `reach` (mm, centreline to centreline) is among them.

    nodes: (N+1, 3) stations, mm.  exclusion: >= 0.
    """
    n_seg = nodes.shape[0] - 1
    low = np.empty((n_seg, 3))
    high = np.empty((n_seg, 3))
    for i in range(n_seg):
        for k in range(3):
            a, b = nodes[i, k], nodes[i + 1, k]
            low[i, k] = min(a, b) - 0.5 * reach
            high[i, k] = max(a, b) + 0.5 * reach
    order = np.argsort(low[:, 0])
    capacity = 4 * n_seg + 16
    first = np.empty(capacity, np.int64)
    second = np.empty(capacity, np.int64)
    count = 0
    for a in range(n_seg):
        i = order[a]
        for b in range(a + 1, n_seg):
            j = order[b]
            if low[j, 0] > high[i, 0]:
                break  # sorted by the lower x: no later box reaches back to segment i
            if abs(i - j) <= exclusion:
                continue
            if low[j, 1] > high[i, 1] or low[i, 1] > high[j, 1] or low[j, 2] > high[i, 2] or low[i, 2] > high[j, 2]:
                continue
            if count == capacity:  # grow: a hose folded onto itself has many near pairs
                capacity *= 2
                grown_first = np.empty(capacity, np.int64)
                grown_second = np.empty(capacity, np.int64)
                grown_first[:count] = first[:count]
                grown_second[:count] = second[:count]
                first, second = grown_first, grown_second
            first[count], second[count] = min(i, j), max(i, j)
            count += 1
    return first[:count].copy(), second[:count].copy()
