"""Frictionless contact as a smooth barrier energy, with its exact gradient and Hessian (compiled).

The hose surface is the tube of the outer radius r about its centreline, a chain of straight
segments (a chain of capsules), as in procedures/geometry/clearance.py.  Contact pairs:
- station-plane: a plane's half-space; the nearest point of a segment to a plane is an end,
  so the stations give the exact distance of the chain;
- segment-ball (a sphere obstacle), segment-segment (a cylinder obstacle, a capsule about its
  axis), and segment-segment of the hose itself (self-contact, segments far enough apart
  along the hose: see self_exclusion).
The gap of a pair is its exact distance less the radii (r, plus the obstacle's radius, or 2r).

Barrier (Li et al., Incremental Potential Contact, 2020):  b(d) = -(d - d_hat)^2 ln(d / d_hat)
for 0 < d < d_hat, zero beyond: C2 at d_hat, infinite at d = 0.  Energy of a pair:
kappa h b(gap), h the segment length, so kappa (N/mm^2) is a stiffness per length of hose.

Exact derivatives of a distance.  A pair's closest points are r(z) = sum_j c_j(z) X_j over its
points X_j (segment ends, obstacle points) with coefficients affine in the parameters z (the
positions along the segments), f = |r|^2 minimised over z in [0, 1]^k.  With the set of
parameters strictly inside (0, 1) fixed (it is, away from a switch between closest features),
and for a triangle, whose parameters (u, v) range over a simplex, the free directions those
of the closest feature (two in the face, one along an edge, none at a vertex: triangle_parameters),
the envelope theorem and the implicit function theorem give
    f_X = df/dX at z*,   f_XX = d2f/dX2 - f_Xz f_zz^-1 f_zX   (over the free parameters only),
and d = sqrt(f).  No approximation; tests/test_contact_derivatives.py checks against finite
differences.  A station-triangle pair's are the closed forms of the same (station_triangle_terms:
(I - n n^T) / d at a vertex, less e e^T / d along an edge, zero over the face), in a third of the
time, for the hundreds of such pairs a fine mesh gives.

On the rotation group.  Stations are x_k = x_0 + h sum_{i<k} d3_i, so a frame rotation delta_i
moves every station beyond segment i: dx_k/d delta_i = -h [d3_i]x for i < k.  With node
gradients g_k and G_i = sum_{k>i} g_k (the contact force beyond segment i, negated), the
gradient is h d3_i x G_i, the second-order change of the stations adds the block
h (1/2 (G t^T + t G^T) - (G . t) I) (the segment-load term of energy.py), and the node Hessian
adds h^2 [t_i]x^T C_ij [t_j]x with C_ij = sum_{k>i, l>j} H_kl (a dense coupling: every station
in contact couples all segments before it).

Written by hand (Numba): no library gives these distances with exact Hessians.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hoseline.mechanics.proximity import corner_of, point_of
from hoseline.mechanics.self_pairs import near_segment_pairs

# np.int64, not int: Numba compiles a kernel again for every int constant passed to it (a Literal[int] type each);
# an np.int64 is a plain int64, so every call site shares one compiled version
STATION_PLANE, SEGMENT_BALL, SEGMENT_CAPSULE, SEGMENT_SEGMENT, STATION_TRIANGLE, SEGMENT_EDGE = np.arange(6)
PAIR_KINDS = ("station-plane", "segment-ball", "segment-capsule", "segment-segment", "station-triangle", "segment-edge")
STATION_KINDS = (STATION_PLANE, STATION_TRIANGLE)  # pairs whose hose primitive is a station, not a segment
MESH_KINDS = (STATION_TRIANGLE, SEGMENT_EDGE)  # pairs with a triangle mesh
# the closest feature of a triangle abc to a point (triangle_parameters)
FACE, EDGE_AB, EDGE_AC, EDGE_BC, VERTEX_A, VERTEX_B, VERTEX_C = 0, 1, 2, 3, 4, 5, 6
PARALLEL = 1e-12  # relative: segments closer to parallel than this keep their first end as the closest point


@njit(cache=True)
def barrier(d, d_hat):
    """b(d), b'(d), b''(d) of b = -(d - d_hat)^2 ln(d / d_hat) for 0 < d < d_hat (mm^2, mm, 1); zero beyond."""
    if d >= d_hat:
        return 0.0, 0.0, 0.0
    if d <= 0.0:
        return math.inf, -math.inf, math.inf
    x = d - d_hat
    log = math.log(d / d_hat)
    return -x * x * log, -2.0 * x * log - x * x / d, -2.0 * log - 4.0 * x / d + x * x / (d * d)


@njit(cache=True)
def _dot3(a, b):
    # a . b for 3-vectors of any layout (row slices of the primitive tables)
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _clamp01(value):
    return min(max(value, 0.0), 1.0)


@njit(cache=True)
def triangle_parameters(x, a, b, c):
    """(u, v, feature) of the point (1 - u - v) a + u b + v c of triangle abc nearest to x.

    Ericson, Real-Time Collision Detection (2005) 5.1.5 (the Voronoi regions of the vertices,
    edges and face, as mechanics/proximity.py's closest_point_on_triangle), returning the
    barycentric parameters and the region: FACE (u, v free), EDGE_AB (v = 0), EDGE_AC (u = 0),
    EDGE_BC (u + v = 1), or a vertex.  abc must have a positive area (contact_mesh.py leaves
    zero-area triangles out).
    """
    # in scalars: the mesh pairs take it for every triangle near every station, where the small arrays of vector
    # expressions (allocated per call) cost more than the arithmetic
    abx, aby, abz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    acx, acy, acz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    xax, xay, xaz = x[0] - a[0], x[1] - a[1], x[2] - a[2]
    d1 = abx * xax + aby * xay + abz * xaz
    d2 = acx * xax + acy * xay + acz * xaz
    if d1 <= 0.0 and d2 <= 0.0:
        return 0.0, 0.0, VERTEX_A
    xbx, xby, xbz = x[0] - b[0], x[1] - b[1], x[2] - b[2]
    d3 = abx * xbx + aby * xby + abz * xbz
    d4 = acx * xbx + acy * xby + acz * xbz
    if d3 >= 0.0 and d4 <= d3:
        return 1.0, 0.0, VERTEX_B
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return d1 / (d1 - d3), 0.0, EDGE_AB
    xcx, xcy, xcz = x[0] - c[0], x[1] - c[1], x[2] - c[2]
    d5 = abx * xcx + aby * xcy + abz * xcz
    d6 = acx * xcx + acy * xcy + acz * xcz
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 1.0, VERTEX_C
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return 0.0, d2 / (d2 - d6), EDGE_AC
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 1.0 - w, w, EDGE_BC
    scale = 1.0 / (va + vb + vc)
    return vb * scale, vc * scale, FACE


@njit(cache=True)
def distance_terms(points, m, c, dc, free, used, r, rz, f_x, f_xx, f_xz):
    """Distance d = |sum_j c_j X_j| at the closest parameters, its gradient and Hessian in the first `used` points.

    points: (4, 3), the first m used.  c: (4,) coefficients at z*.  dc: (4, 2), dc[j, k] = dc_j/dz_k.
    free: (2,) bool, the parameters strictly inside their range (the others stay on their bound).
    used: the points whose derivatives are wanted (the hose's, which come first: an obstacle's points are
    fixed; the blocks of the full gradient (3m,) and Hessian (3m, 3m) they are, to the bit).
    r (3,), rz (3, 2), f_x (12,), f_xx (12, 12), f_xz (12, 2): scratch, allocated once by the caller (a pair's
    own arrays cost more than its arithmetic).  Returns d; the gradient is left in f_x[:3 used], the Hessian
    in f_xx[:3 used, :3 used].
    """
    n = 3 * used
    for x in range(3):
        r[x] = 0.0
        for k in range(2):
            rz[x, k] = 0.0
    for j in range(m):
        for x in range(3):
            r[x] += c[j] * points[j, x]
            for k in range(2):
                rz[x, k] += dc[j, k] * points[j, x]
    f = _dot3(r, r)
    for p in range(n):
        for q in range(n):
            f_xx[p, q] = 0.0
    for j in range(used):
        for x in range(3):
            f_x[3 * j + x] = 2.0 * c[j] * r[x]
            for l in range(used):
                f_xx[3 * j + x, 3 * l + x] = 2.0 * c[j] * c[l]
    nf = 0
    k0 = k1 = 0  # the free parameters
    for k in range(2):
        if free[k]:
            if nf == 0:
                k0 = k
            else:
                k1 = k
            nf += 1
    if nf > 0:
        # f_xx -= f_xz f_zz^-1 f_xz^T, by hand: at most 12 x 2, where a BLAS call per pair cost more than the sums
        for a, ka in enumerate((k0, k1)):
            if a < nf:
                for j in range(used):
                    for x in range(3):
                        f_xz[3 * j + x, a] = 2.0 * (dc[j, ka] * r[x] + c[j] * rz[x, ka])
        f_00 = 2.0 * (rz[0, k0] * rz[0, k0] + rz[1, k0] * rz[1, k0] + rz[2, k0] * rz[2, k0])  # f_zz
        if nf == 1:
            for p in range(n):
                t0 = f_xz[p, 0] / f_00
                for q in range(n):
                    f_xx[p, q] -= t0 * f_xz[q, 0]
        else:
            f_01 = 2.0 * (rz[0, k0] * rz[0, k1] + rz[1, k0] * rz[1, k1] + rz[2, k0] * rz[2, k1])
            f_11 = 2.0 * (rz[0, k1] * rz[0, k1] + rz[1, k1] * rz[1, k1] + rz[2, k1] * rz[2, k1])
            det = f_00 * f_11 - f_01 * f_01
            for p in range(n):  # (f_xz f_zz^-1)[p] with f_zz^-1 = [[f_11, -f_01], [-f_01, f_00]] / det
                t0 = (f_xz[p, 0] * f_11 - f_xz[p, 1] * f_01) / det
                t1 = (f_xz[p, 1] * f_00 - f_xz[p, 0] * f_01) / det
                for q in range(n):
                    f_xx[p, q] -= t0 * f_xz[q, 0] + t1 * f_xz[q, 1]
    d = math.sqrt(f)
    twice = 2.0 * d
    cubed = 4.0 * d * d * d
    for p in range(n):  # the Hessian first: it needs f_x
        for q in range(n):
            f_xx[p, q] = f_xx[p, q] / twice - f_x[p] * f_x[q] / cubed
    for p in range(n):
        f_x[p] = f_x[p] / twice
    return d


@njit(cache=True)
def pair_geometry(kind, i, j, nodes, balls, capsules, points, c, dc, free, node):
    """The points, coefficients and free parameters of pair (kind, hose primitive i, obstacle primitive j).

    Fills points (4, 3), c (4,), dc (4, 2), free (2,) and node (4,), the station of each point or -1 for
    an obstacle point (the caller's arrays, reused from pair to pair); returns (m, the points used, the
    radius of the obstacle primitive (mm)); for the segment pairs but SEGMENT_EDGE (segment_edge_terms; and
    station_triangle_terms gives STATION_TRIANGLE's, STATION_PLANE's is node_terms' own).  For SEGMENT_SEGMENT, j
    is the second hose segment.
    """
    for a in range(4):
        c[a] = 0.0
        node[a] = -1
        for x in range(3):
            points[a, x] = 0.0
        for k in range(2):
            dc[a, k] = 0.0
    free[0] = free[1] = False
    p, q = point_of(nodes, i), point_of(nodes, i + 1)
    _set_point(points, 0, p)
    _set_point(points, 1, q)
    node[0], node[1] = i, i + 1
    if kind == SEGMENT_BALL:
        centre = point_of(balls, j)
        e = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
        s = _clamp01(_dot3((centre[0] - p[0], centre[1] - p[1], centre[2] - p[2]), e) / _dot3(e, e))
        _set_point(points, 2, centre)
        c[0], c[1], c[2] = 1.0 - s, s, -1.0
        dc[0, 0], dc[1, 0] = -1.0, 1.0
        free[0] = 0.0 < s < 1.0
        return 3, balls[j, 3]
    if kind == SEGMENT_CAPSULE:
        a, b = point_of(capsules, j), (capsules[j, 3], capsules[j, 4], capsules[j, 5])
        radius = capsules[j, 6]
    else:
        a, b = point_of(nodes, j), point_of(nodes, j + 1)
        node[2], node[3] = j, j + 1
        radius = 0.0
    _, s, t = segment_closest(p, q, a, b)
    _set_point(points, 2, a)
    _set_point(points, 3, b)
    c[0], c[1], c[2], c[3] = 1.0 - s, s, -(1.0 - t), -t
    dc[0, 0], dc[1, 0], dc[2, 1], dc[3, 1] = -1.0, 1.0, 1.0, -1.0
    free[0] = 0.0 < s < 1.0
    free[1] = 0.0 < t < 1.0
    return 4, radius


@njit(cache=True, inline="always")
def _set_point(points, row, x):
    # points[row] = x for a tuple x
    points[row, 0], points[row, 1], points[row, 2] = x[0], x[1], x[2]


@njit(cache=True)
def segment_closest(p, q, a, b):
    """(distance mm, s, t) of the closest points p + s (q - p), a + t (b - a), s and t in [0, 1], of the segments pq
    and ab (a point when a = b).

    Ericson, Real-Time Collision Detection (2005) 5.1.9, as mechanics/proximity.py's
    closest_points_of_segments, which returns the points; the contact terms need the parameters.  In
    scalars: the pair lists and the step filters take it for thousands of pairs per Newton iteration,
    where small arrays (allocated per pair) cost ten times the arithmetic.
    """
    d1x, d1y, d1z = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    d2x, d2y, d2z = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    rx, ry, rz = p[0] - a[0], p[1] - a[1], p[2] - a[2]
    aa = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    c = d1x * rx + d1y * ry + d1z * rz
    if e == 0.0:  # a point: the segment's point nearest to it
        s, t = _clamp01(-c / aa), 0.0
    else:
        bb = d1x * d2x + d1y * d2y + d1z * d2z
        denominator = aa * e - bb * bb
        s = _clamp01((bb * f - c * e) / denominator) if denominator > PARALLEL * aa * e else 0.0
        t = (bb * s + f) / e
        if t < 0.0:
            t = 0.0
            s = _clamp01(-c / aa)
        elif t > 1.0:
            t = 1.0
            s = _clamp01((bb - c) / aa)
    x, y, z = rx + s * d1x - t * d2x, ry + s * d1y - t * d2y, rz + s * d1z - t * d2z
    return math.sqrt(x * x + y * y + z * z), s, t


@njit(cache=True)
def _segment_distance(p, q, a, b):
    # distance (mm) of the segments pq and ab (segment_closest)
    return segment_closest(p, q, a, b)[0]


@njit(cache=True)
def _pair_distance(kind, i, j, nodes, planes, balls, capsules, triangles, edges):
    # distance of one pair (mm; the obstacle primitive's radius not subtracted) and that radius
    # the points as tuples (proximity.point_of): a row's view costs more than the distance
    if kind == STATION_PLANE:
        x = point_of(nodes, i)
        return (planes[j, 3] * (x[0] - planes[j, 0]) + planes[j, 4] * (x[1] - planes[j, 1])
                + planes[j, 5] * (x[2] - planes[j, 2])), 0.0
    if kind == SEGMENT_BALL:
        centre = point_of(balls, j)
        return _segment_distance(point_of(nodes, i), point_of(nodes, i + 1), centre, centre), balls[j, 3]
    if kind == SEGMENT_CAPSULE:
        a, b = point_of(capsules, j), (capsules[j, 3], capsules[j, 4], capsules[j, 5])
        return _segment_distance(point_of(nodes, i), point_of(nodes, i + 1), a, b), capsules[j, 6]
    if kind == SEGMENT_EDGE:
        return _segment_distance(point_of(nodes, i), point_of(nodes, i + 1), corner_of(edges, j, 0),
                                 corner_of(edges, j, 1)), 0.0
    if kind == SEGMENT_SEGMENT:
        return _segment_distance(point_of(nodes, i), point_of(nodes, i + 1), point_of(nodes, j),
                                 point_of(nodes, j + 1)), 0.0
    x = point_of(nodes, i)  # STATION_TRIANGLE: as contact_mesh.mesh_pairs measures it, to the bit
    a, b, c = corner_of(triangles, j, 0), corner_of(triangles, j, 1), corner_of(triangles, j, 2)
    u, v, _ = triangle_parameters(x, a, b, c)
    distance = 0.0
    for k in range(3):
        distance += (x[k] - ((1.0 - u - v) * a[k] + u * b[k] + v * c[k])) ** 2
    return math.sqrt(distance), 0.0


@njit(cache=True)
def pair_gaps(nodes, hose_radius, planes, balls, capsules, self_exclusion, cutoff):
    """Every pair with an analytic obstacle or the hose itself whose gap (mm, surface to surface) is below `cutoff` mm.

    Returns (kinds, first (hose station or segment), second (obstacle primitive or second
    segment), gaps), arrays of one entry per pair.  self_exclusion: segments i < j pair up when
    j - i > self_exclusion; negative: no self-contact.
    """
    n_seg = nodes.shape[0] - 1
    if self_exclusion >= 0:  # the broad phase: only segments whose boxes come within the reach (self_pairs.py)
        near_first, near_second = near_segment_pairs(nodes, self_exclusion, cutoff + 2.0 * hose_radius)
    else:
        near_first, near_second = np.zeros(0, np.int64), np.zeros(0, np.int64)
    capacity = n_seg * (planes.shape[0] + balls.shape[0] + capsules.shape[0]) + near_first.shape[0]
    kinds = np.empty(capacity, np.int64)
    first = np.empty(capacity, np.int64)
    second = np.empty(capacity, np.int64)
    gaps = np.empty(capacity)
    no_triangles, no_edges = np.zeros((0, 3, 3)), np.zeros((0, 2, 3))  # meshes: contact_mesh.mesh_pairs
    count = 0
    for k in range(1, n_seg + 1):
        for j in range(planes.shape[0]):
            d, _ = _pair_distance(STATION_PLANE, k, j, nodes, planes, balls, capsules, no_triangles, no_edges)
            if d - hose_radius < cutoff:
                kinds[count], first[count], second[count], gaps[count] = STATION_PLANE, k, j, d - hose_radius
                count += 1
    for i in range(n_seg):
        for j in range(balls.shape[0]):
            d, radius = _pair_distance(SEGMENT_BALL, i, j, nodes, planes, balls, capsules, no_triangles, no_edges)
            if d - hose_radius - radius < cutoff:
                kinds[count], first[count], second[count], gaps[count] = SEGMENT_BALL, i, j, d - hose_radius - radius
                count += 1
        for j in range(capsules.shape[0]):
            d, radius = _pair_distance(SEGMENT_CAPSULE, i, j, nodes, planes, balls, capsules, no_triangles, no_edges)
            if d - hose_radius - radius < cutoff:
                kinds[count], first[count], second[count], gaps[count] = SEGMENT_CAPSULE, i, j, d - hose_radius - radius
                count += 1
    for p in range(near_first.shape[0]):
        i, j = near_first[p], near_second[p]
        d, _ = _pair_distance(SEGMENT_SEGMENT, i, j, nodes, planes, balls, capsules, no_triangles, no_edges)
        if d - 2.0 * hose_radius < cutoff:
            kinds[count], first[count], second[count], gaps[count] = SEGMENT_SEGMENT, i, j, d - 2.0 * hose_radius
            count += 1
    return kinds[:count].copy(), first[:count].copy(), second[:count].copy(), gaps[:count].copy()


@njit(cache=True)
def plane_terms(x, j, planes, normal, curvature, nearest):
    """Signed distance (mm) of the point x (3,) from plane j of planes (P, 6), its gradient (normal (3,), the plane's
    unit normal) and Hessian (curvature (3, 3), zero) in x, and the nearest point of the plane (nearest (3,)), written
    into the caller's arrays as station_triangle_terms does."""
    d = 0.0
    for k in range(3):
        normal[k] = planes[j, 3 + k]
        d += normal[k] * (x[k] - planes[j, k])
    for k in range(3):
        nearest[k] = x[k] - d * normal[k]
        for m in range(3):
            curvature[k, m] = 0.0
    return d


@njit(cache=True)
def station_triangle_terms(x, j, triangles, planar, normal, curvature, nearest):
    """Distance (mm) of the point x (3,) to triangle j of triangles (F, 3, 3), its gradient (normal (3,)) and Hessian
    (curvature (3, 3)) in x, and the nearest point (nearest (3,)), written into the caller's arrays.

    The closed forms of distance_terms' envelope formulas for a point and a triangle (the same derivatives in a
    third of the time: a mesh near the hose gives hundreds of such pairs per evaluation):
    with n the unit vector from the nearest point, (I - n n^T) / d at a vertex, (I - n n^T - e e^T) / d on an
    edge of unit direction e, zero on the face or a feature inside the flat patch (bit 1 << feature of planar).
    """
    a, b, c = corner_of(triangles, j, 0), corner_of(triangles, j, 1), corner_of(triangles, j, 2)
    u, v, feature = triangle_parameters(x, a, b, c)
    if (planar >> feature) & 1:
        feature = FACE
    for k in range(3):
        nearest[k] = (1.0 - u - v) * a[k] + u * b[k] + v * c[k]
        normal[k] = x[k] - nearest[k]
    d = math.sqrt(_dot3(normal, normal))
    for k in range(3):
        normal[k] /= d
    for k in range(3):
        for m in range(3):
            curvature[k, m] = 0.0
    if feature == FACE:
        return d
    if feature == EDGE_AB or feature == EDGE_AC or feature == EDGE_BC:
        p, q = (a, b) if feature == EDGE_AB else (a, c) if feature == EDGE_AC else (b, c)
        e = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
        length = math.sqrt(_dot3(e, e))
        e = (e[0] / length, e[1] / length, e[2] / length)
    else:
        e = (0.0, 0.0, 0.0)
    for k in range(3):
        for m in range(3):
            curvature[k, m] = ((1.0 if k == m else 0.0) - normal[k] * normal[m] - e[k] * e[m]) / d
    return d


@njit(cache=True)
def segment_edge_terms(p, q, a, b, d_x, d_xx):
    """Distance (mm) of the hose segment pq to the fixed segment ab (a mesh edge), its gradient (d_x[:6]) and Hessian
    (d_xx[:6, :6]) in (p, q), written into the caller's arrays, and the parameters (s, t) of the closest points
    p + s (q - p), a + t (b - a).

    distance_terms' envelope formulas for this pair, written out (a fine curved mesh gives thousands of such pairs
    per evaluation): with w = the closest points' difference, c = (1 - s, s), e1 = q - p, e2 = b - a and the
    parameters strictly inside [0, 1] free, the gradient is (c0 n, c1 n) with n = w / d, and the Hessian
    ((c c^T) x I - G A^-1 G^T) / d - d_x d_x^T / d, with G's columns (-w + c0 e1, w + c1 e1) for s and
    (-c0 e2, -c1 e2) for t, and A = [[e1.e1, -e1.e2], [-e1.e2, e2.e2]] over the free ones.
    """
    d, s, t = segment_closest(p, q, a, b)
    c = (1.0 - s, s)
    e1 = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
    e2 = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    w = (p[0] + s * e1[0] - a[0] - t * e2[0], p[1] + s * e1[1] - a[1] - t * e2[1],
         p[2] + s * e1[2] - a[2] - t * e2[2])
    for j in range(2):
        for x in range(3):
            d_x[3 * j + x] = c[j] * w[x] / d
    for j in range(2):
        for x in range(3):
            for l in range(2):
                for y in range(3):
                    d_xx[3 * j + x, 3 * l + y] = (c[j] * c[l] if x == y else 0.0) - d_x[3 * j + x] * d_x[3 * l + y]
    free_s, free_t = 0.0 < s < 1.0, 0.0 < t < 1.0
    if free_s or free_t:  # less G A^-1 G^T, G's entries formed where used (an array per pair costs more)
        a_ss, a_st, a_tt = _dot3(e1, e1), -_dot3(e1, e2), _dot3(e2, e2)
        det = a_ss * a_tt - a_st * a_st
        for j in range(2):
            sign_j = -1.0 if j == 0 else 1.0
            for x in range(3):
                g_s, g_t = sign_j * w[x] + c[j] * e1[x], -c[j] * e2[x]
                if free_s and free_t:  # (G A^-1) of this row
                    k_s, k_t = (g_s * a_tt - g_t * a_st) / det, (g_t * a_ss - g_s * a_st) / det
                else:
                    k_s, k_t = (g_s / a_ss, 0.0) if free_s else (0.0, g_t / a_tt)
                for l in range(2):
                    sign_l = -1.0 if l == 0 else 1.0
                    for y in range(3):
                        d_xx[3 * j + x, 3 * l + y] -= k_s * (sign_l * w[y] + c[l] * e1[y]) - k_t * c[l] * e2[y]
    for u in range(6):
        for v in range(6):
            d_xx[u, v] /= d
    return d, s, t


@njit(cache=True)
def node_terms(nodes, hose_radius, weight, d_hat, planes, balls, capsules, triangles, edges, planar, kinds, first,
               second):
    """Barrier energy of the given pairs (N*mm), its gradient (N+1, 3) and Hessian (N+1, N+1, 3, 3) in the stations.

    weight: kappa h, N/mm (energy per mm^2 of barrier).  triangles (F, 3, 3), edges (E, 2, 3): the
    corners of the mesh primitives (mm) that STATION_TRIANGLE and SEGMENT_EDGE pairs index; planar (F,): each
    triangle's features inside its flat patch (station_triangle_terms).  Also per pair: the force on the hose
    (N; for a self-contact pair, on the first segment), the closest points on the hose and on the
    other body (mm) and the gap (mm).
    """
    count = nodes.shape[0]
    grad = np.zeros((count, 3))
    hess = np.zeros((count, count, 3, 3))
    forces = np.zeros((kinds.shape[0], 3))
    on_hose = np.zeros((kinds.shape[0], 3))
    on_other = np.zeros((kinds.shape[0], 3))
    gaps = np.zeros(kinds.shape[0])
    energy = 0.0
    # one pair's arrays, reused (pair_geometry, distance_terms)
    points, c, dc = np.zeros((4, 3)), np.zeros(4), np.zeros((4, 2))
    free, node = np.zeros(2, np.bool_), np.zeros(4, np.int64)
    r, rz, d_x, d_xx, f_xz = np.zeros(3), np.zeros((3, 2)), np.zeros(12), np.zeros((12, 12)), np.zeros((12, 2))
    hose_point, axis_point = np.zeros(3), np.zeros(3)  # axis_point: on the other body's axis (or centre, or surface)
    normal, curvature, nearest = np.zeros(3), np.zeros((3, 3)), np.zeros(3)  # a station pair's (plane, triangle)
    for p in range(kinds.shape[0]):
        kind, i, j = kinds[p], first[p], second[p]
        if kind == STATION_PLANE or kind == STATION_TRIANGLE:  # a station's distance: its gradient is a unit vector
            if kind == STATION_PLANE:
                d = plane_terms(point_of(nodes, i), j, planes, normal, curvature, nearest)
            else:
                d = station_triangle_terms(point_of(nodes, i), j, triangles, planar[j], normal, curvature, nearest)
            gap = d - hose_radius
            b, b1, b2 = barrier(gap, d_hat)
            energy += weight * b
            for x in range(3):
                grad[i, x] += weight * b1 * normal[x]
                forces[p, x] = -weight * b1 * normal[x]
                for y in range(3):
                    hess[i, i, x, y] += weight * (b2 * normal[x] * normal[y] + b1 * curvature[x, y])
                on_hose[p, x] = nodes[i, x]
                on_other[p, x] = nearest[x]
            gaps[p] = gap
            continue
        on_first = 2  # the points of the (first) hose segment
        if kind == SEGMENT_EDGE:
            p_, q_, a_, b_ = point_of(nodes, i), point_of(nodes, i + 1), corner_of(edges, j, 0), corner_of(edges, j, 1)
            d, s, t = segment_edge_terms(p_, q_, a_, b_, d_x, d_xx)
            node[0], node[1] = i, i + 1
            used, other_radius = on_first, 0.0
            for x in range(3):
                hose_point[x] = p_[x] + s * (q_[x] - p_[x])
                axis_point[x] = a_[x] + t * (b_[x] - a_[x])
        else:
            m, radius = pair_geometry(kind, i, j, nodes, balls, capsules, points, c, dc, free, node)
            used = 4 if kind == SEGMENT_SEGMENT else on_first  # the hose's points: the others are fixed
            d = distance_terms(points, m, c, dc, free, used, r, rz, d_x, d_xx, f_xz)
            other_radius = hose_radius if kind == SEGMENT_SEGMENT else radius
            hose_point[:] = 0.0
            axis_point[:] = 0.0
            for a in range(m):
                for x in range(3):
                    if a < on_first:
                        hose_point[x] += c[a] * points[a, x]
                    else:
                        axis_point[x] -= c[a] * points[a, x]
        gap = d - hose_radius - other_radius
        b, b1, b2 = barrier(gap, d_hat)
        energy += weight * b
        for a in range(used):
            ka = node[a]
            for x in range(3):
                grad[ka, x] += weight * b1 * d_x[3 * a + x]
                if a < on_first:
                    forces[p, x] -= weight * b1 * d_x[3 * a + x]
            for bb in range(used):
                kb = node[bb]
                for x in range(3):
                    for y in range(3):
                        hess[ka, kb, x, y] += weight * (
                            b2 * d_x[3 * a + x] * d_x[3 * bb + y] + b1 * d_xx[3 * a + x, 3 * bb + y]
                        )
        for x in range(3):
            on_hose[p, x] = hose_point[x]
            on_other[p, x] = axis_point[x] + other_radius / d * (hose_point[x] - axis_point[x])
        gaps[p] = gap
    return energy, grad, hess, forces, on_hose, on_other, gaps


@njit(cache=True)
def rotation_terms(frames, h, node_grad, node_hess):
    """Gradient (3N,) and dense Hessian (3N, 3N) in the segment rotations of an energy of the stations.

    node_grad: (N+1, 3), node_hess: (N+1, N+1, 3, 3) in the stations x_0..x_N (x_0 is held).
    See the module doc for the chain rule through x_k = x_0 + h sum_{i<k} d3_i.
    """
    n = frames.shape[0]
    grad = np.zeros(3 * n)
    hess = np.zeros((3 * n, 3 * n))
    beyond = np.zeros(3)
    last = 0  # the last station with a Hessian entry: no segment beyond it is coupled
    for k in range(n + 1):
        for l in range(n + 1):
            for x in range(3):
                for y in range(3):
                    if node_hess[k, l, x, y] != 0.0:
                        last = max(last, k)
    for i in range(n - 1, -1, -1):
        beyond += node_grad[i + 1]
        t = frames[i, 2]
        grad[3 * i] = h * (t[1] * beyond[2] - t[2] * beyond[1])
        grad[3 * i + 1] = h * (t[2] * beyond[0] - t[0] * beyond[2])
        grad[3 * i + 2] = h * (t[0] * beyond[1] - t[1] * beyond[0])
        along = _dot3(beyond, t)
        for x in range(3):
            for y in range(3):
                hess[3 * i + x, 3 * i + y] += h * (0.5 * (beyond[x] * t[y] + t[x] * beyond[y]) - (along if x == y else 0.0))
    if last == 0:
        return grad, hess
    # C_ij = sum_{k>i, l>j} H_kl: suffix sums over l, then over k
    rows = np.zeros((last + 1, last + 1, 3, 3))  # rows[k, j] = sum_{l>j} H_kl (zero for j = last)
    for k in range(1, last + 1):
        for j in range(last - 1, -1, -1):
            rows[k, j] = node_hess[k, j + 1] + rows[k, j + 1]
    suffix = np.zeros((last, 3, 3))
    skew_i = np.zeros((3, 3))
    skew_j = np.zeros((3, 3))
    half = np.zeros((3, 3))
    for i in range(last - 1, -1, -1):
        for j in range(last):
            suffix[j] += rows[i + 1, j]  # now suffix[j] = C_ij
        _skew_into(frames[i, 2], skew_i)
        for j in range(last):
            _skew_into(frames[j, 2], skew_j)
            for x in range(3):  # half = C_ij [t_j]x, then -h^2 [t_i]x half = h^2 [t_i]x^T C_ij [t_j]x
                for y in range(3):
                    half[x, y] = suffix[j, x, 0] * skew_j[0, y] + suffix[j, x, 1] * skew_j[1, y] + suffix[j, x, 2] * skew_j[2, y]
            for x in range(3):
                for y in range(3):
                    hess[3 * i + x, 3 * j + y] -= (h * h) * (
                        skew_i[x, 0] * half[0, y] + skew_i[x, 1] * half[1, y] + skew_i[x, 2] * half[2, y]
                    )
    return grad, hess


@njit(cache=True)
def _skew_into(t, out):
    # [t]x: the matrix of v -> t x v
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -t[2], t[1]
    out[1, 0], out[1, 1], out[1, 2] = t[2], 0.0, -t[0]
    out[2, 0], out[2, 1], out[2, 2] = -t[1], t[0], 0.0


@njit(cache=True)
def listed_gaps(nodes, hose_radius, planes, balls, capsules, triangles, edges, kinds, first, second):
    """The gap (mm, surface to surface) of each listed pair (as returned by pair_gaps or contact_mesh.mesh_pairs)."""
    gaps = np.empty(kinds.shape[0])
    for p in range(kinds.shape[0]):
        d, radius = _pair_distance(kinds[p], first[p], second[p], nodes, planes, balls, capsules, triangles, edges)
        gaps[p] = d - hose_radius - (hose_radius if kinds[p] == SEGMENT_SEGMENT else radius)
    return gaps
