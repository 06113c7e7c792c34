"""Exact distances between a straight segment and a triangle (compiled with Numba).

Used by the clearance search: the hose is a chain of straight segments (its centreline)
and an obstacle a triangle mesh.  For a segment that does not cross the triangle, the
closest pair of points has an end of the segment or an edge of the triangle in it, so
the distance is the smallest of: each end of the segment to the triangle, and the segment
to each of the three edges.  A segment that crosses the triangle has distance zero.
Algorithms after C. Ericson, Real-Time Collision Detection (2005), 5.1.5 and 5.1.9.

All lengths in mm.  Points are 3-tuples of floats: in compiled code, tuples live on the
stack, where small arrays would cost a heap allocation each.
"""

from __future__ import annotations

import math

from numba import njit

EPSILON = 1e-12


@njit(cache=True, inline="always")
def point_of(points, i):
    """Row i of an (n, 3) array as a tuple (a view of the row would cost more than the arithmetic on it: its
    reference count is taken and dropped by atomic operations)."""
    return (points[i, 0], points[i, 1], points[i, 2])


@njit(cache=True, inline="always")
def corner_of(items, i, k):
    """Point k of item i of an (n, m, 3) array (a triangle's corner, an edge's end) as a tuple."""
    return (items[i, k, 0], items[i, k, 1], items[i, k, 2])


@njit(cache=True, inline="always")
def point_between(p, q, t):
    """p + t (q - p) for points p, q (3-tuples or rows, mm), as a tuple."""
    return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), p[2] + t * (q[2] - p[2]))


@njit(cache=True, inline="always")
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, inline="always")
def _along(a, scale, d):
    """a + scale * d."""
    return (a[0] + scale * d[0], a[1] + scale * d[1], a[2] + scale * d[2])


@njit(cache=True, inline="always")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, inline="always")
def _distance(a, b):
    d = _sub(a, b)
    return math.sqrt(_dot(d, d))


@njit(cache=True)
def closest_point_on_triangle(p, a, b, c):
    """The point of triangle abc nearest to p (Voronoi regions of the vertices, edges and face)."""
    ab = _sub(b, a)
    ac = _sub(c, a)
    ap = _sub(p, a)
    d1 = _dot(ab, ap)
    d2 = _dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return a
    bp = _sub(p, b)
    d3 = _dot(ab, bp)
    d4 = _dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return _along(a, d1 / (d1 - d3), ab)
    cp = _sub(p, c)
    d5 = _dot(ab, cp)
    d6 = _dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return _along(a, d2 / (d2 - d6), ac)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        return _along(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), _sub(c, b))
    denominator = 1.0 / (va + vb + vc)
    return _along(_along(a, vb * denominator, ab), vc * denominator, ac)


@njit(cache=True)
def closest_points_of_segments(p1, q1, p2, q2):
    """Closest points (on p1q1, on p2q2) of two segments; either may have zero length."""
    d1 = _sub(q1, p1)
    d2 = _sub(q2, p2)
    r = _sub(p1, p2)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    if a <= EPSILON and e <= EPSILON:
        return p1, p2
    if a <= EPSILON:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = _dot(d1, r)
        if e <= EPSILON:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = _dot(d1, d2)
            denominator = a * e - b * b
            s = min(max((b * f - c * e) / denominator, 0.0), 1.0) if denominator > EPSILON * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    return _along(p1, s, d1), _along(p2, t, d2)


@njit(cache=True)
def _crossing(p, q, a, b, c, normal):
    """Whether segment pq crosses triangle abc (normal: (b - a) x (c - a)), and where."""
    dp = _dot(normal, _sub(p, a))
    dq = _dot(normal, _sub(q, a))
    if (dp > 0.0 and dq > 0.0) or (dp < 0.0 and dq < 0.0) or dp == dq:
        return False, p
    x = _along(p, dp / (dp - dq), _sub(q, p))
    inside = (
        _dot(_cross(_sub(b, a), _sub(x, a)), normal) >= 0.0
        and _dot(_cross(_sub(c, b), _sub(x, b)), normal) >= 0.0
        and _dot(_cross(_sub(a, c), _sub(x, c)), normal) >= 0.0
    )
    return inside, x


@njit(cache=True)
def segment_triangle_distance(p, q, a, b, c):
    """Distance (mm) between segment pq and triangle abc, and the closest points (on pq, on abc).

    p, q, a, b, c: 3-tuples, mm.
    """
    ab = _sub(b, a)
    ac = _sub(c, a)
    normal = _cross(ab, ac)
    scale = _dot(ab, ab) + _dot(ac, ac)
    degenerate = _dot(normal, normal) <= EPSILON * scale * scale  # a degenerate triangle is its edges
    if not degenerate:
        crosses, x = _crossing(p, q, a, b, c, normal)
        if crosses:
            return 0.0, x, x
    best = math.inf
    on_segment = p
    on_triangle = a
    if not degenerate:
        for end in (p, q):
            y = closest_point_on_triangle(end, a, b, c)
            distance = _distance(end, y)
            if distance < best:
                best, on_segment, on_triangle = distance, end, y
    for u, v in ((a, b), (b, c), (c, a)):
        x, y = closest_points_of_segments(p, q, u, v)
        distance = _distance(x, y)
        if distance < best:
            best, on_segment, on_triangle = distance, x, y
    return best, on_segment, on_triangle


@njit(cache=True)
def segment_plane_gap(p, q, a, normal):
    """Distance (mm) from segment pq to the plane through a with unit `normal`; zero if pq crosses it.

    A lower bound of the distance to any triangle in that plane.
    """
    dp = _dot(normal, _sub(p, a))
    dq = _dot(normal, _sub(q, a))
    if (dp > 0.0) != (dq > 0.0):
        return 0.0
    return min(abs(dp), abs(dq))
