"""Contact obstacles carried rigidly by moving bodies, and whether a move keeps the hose out of them.

Carrying (moved_model).  An obstacle on a body moves with the body's pose (model/motion.Pose):
plane points, ball centres, capsule axes and mesh corners as points, plane and triangle normals as
directions.  A mesh keeps what was worked out from its triangles (contact_mesh.pack_meshes: its kept
edges, flat patches, its edges' corners), since a rigid motion keeps every distance and side, and
the topology of its bounding-volume trees, whose boxes are refitted to the moved items
(bounding_volumes.refit_boxes: O(items), no rebuild).  Points are carried element by element, so a
point stored twice (a joint for each of its two edges) stays the same bits, as their tests need.

The move check (move_is_clear).  The contact Newton starts from a state that penetrates nothing, and
its step filter keeps every later state on the same side of every obstacle.  Between two solves (a
step of a sweep) the obstacles move as well: a thin one could jump across the hose within one step
and leave it clear, on the wrong side.  So the move is judged as the obstacles see it: for a group
of obstacles carried rigidly by `carry`, the hose goes, relative to them, from `before` to `after`
carried back by carry^-1.  Along a virtual path between the two (the start point on a straight
line, each segment's tangent on a great circle through the angle phi_i between its two tangents)
station k moves by at most |start move| + h sum_(i<k) phi_i and strays from its chord by at most
(h/8) sum_(i<k) phi_i^2: the bounds of a Newton step, so the step filter of the contact Newton
(contact_newton.motion_filter) decides as for a step: every gap the move could close stays above
SAFE_FRACTION of its value, and no primitive can pass through the body it faces (its thickness; a
plane is infinitely thick), meshes by the exact gaps of the stations' chords and the swept
segment-edge check.  The relative configurations at both ends are the real ones, so an admitted
move takes the hose and the obstacles from the old positions to the new without the hose ever
crossing one, whatever path each really took.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import replace

import numpy as np
from numba import njit

from hoseline.mechanics.bounding_volumes import refit_boxes
from hoseline.mechanics.contact_mesh import MeshArrays
from hoseline.mechanics.contact_newton import ContactModel, hose_move_clear
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.motion import Pose


def carried(points: np.ndarray, pose: Pose) -> np.ndarray:
    """Points (..., 3) mm carried by `pose` (R x + p), element by element: equal points give equal bits."""
    flat = np.ascontiguousarray(points, dtype=float).reshape(-1, 3)
    return _affine(flat, pose.rotation, np.asarray(pose.position, dtype=float)).reshape(np.shape(points))


def turned(directions: np.ndarray, pose: Pose) -> np.ndarray:
    """Directions (..., 3) (or frames, rows d1, d2, d3) turned by `pose`'s rotation (R v), element by element."""
    flat = np.ascontiguousarray(directions, dtype=float).reshape(-1, 3)
    return _affine(flat, pose.rotation, np.zeros(3)).reshape(np.shape(directions))


@njit(cache=True)
def _affine(points, rotation, translation):
    """(n, 3): R x + t for each row x of points (n, 3), written out (no temporaries, the same bits for equal rows)."""
    out = np.empty_like(points)
    for i in range(points.shape[0]):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        for k in range(3):
            out[i, k] = rotation[k, 0] * x + rotation[k, 1] * y + rotation[k, 2] * z + translation[k]
    return out


def moved_model(model: ContactModel, poses: Sequence[Pose | None]) -> ContactModel:
    """`model` with obstacle j (model.names[j]) carried rigidly by poses[j] from where it is (None: it stays)."""
    if all(pose is None for pose in poses):  # nothing moves (a sweep's fixed obstacles): no copy
        return model
    planes, balls, capsules = model.planes.copy(), model.balls.copy(), model.capsules.copy()
    for i, owner in enumerate(model.owners_planes):
        if poses[owner] is not None:
            planes[i, :3], planes[i, 3:] = carried(planes[i, :3], poses[owner]), turned(planes[i, 3:], poses[owner])
    for i, owner in enumerate(model.owners_balls):
        if poses[owner] is not None:
            balls[i, :3] = carried(balls[i, :3], poses[owner])
    for i, owner in enumerate(model.owners_capsules):
        if poses[owner] is not None:
            capsules[i, :6] = carried(capsules[i, :6].reshape(2, 3), poses[owner]).reshape(6)
    mesh = _moved_meshes(model.mesh, [poses[owner] for owner in model.mesh.owners])
    return replace(model, planes=planes, balls=balls, capsules=capsules, mesh=mesh)


def _moved_meshes(mesh: MeshArrays, poses: Sequence[Pose | None]) -> MeshArrays:
    """`mesh` with mesh m carried rigidly by poses[m] (None: it stays), its trees refitted."""
    if all(pose is None for pose in poses):
        return mesh
    triangles, normals = mesh.triangles.copy(), mesh.normals.copy()
    edges, joints = mesh.edges.copy(), mesh.joints.copy()
    triangle_boxes = (mesh.triangle_tree[0].copy(), mesh.triangle_tree[1].copy())
    edge_boxes = (mesh.edge_tree[0].copy(), mesh.edge_tree[1].copy())
    for m, pose in enumerate(poses):
        if pose is None:
            continue
        t, e = _items_of(mesh.triangle_mesh, m), _items_of(mesh.edge_mesh, m)
        triangles[t], normals[t] = carried(triangles[t], pose), turned(normals[t], pose)
        edges[e], joints[e] = carried(edges[e], pose), carried(joints[e], pose)
        _refit(triangles, triangle_boxes, mesh.triangle_tree, mesh.triangle_roots, m)
        _refit(edges, edge_boxes, mesh.edge_tree, mesh.edge_roots, m)
    return replace(mesh, triangles=triangles, normals=normals, edges=edges, joints=joints,
                   triangle_tree=(*triangle_boxes, *mesh.triangle_tree[2:]), edge_tree=(*edge_boxes, *mesh.edge_tree[2:]))


def _items_of(owner_mesh: np.ndarray, m: int) -> slice:
    """The items (triangles or edges, stored mesh after mesh) of mesh m, given each item's mesh (sorted)."""
    return slice(int(np.searchsorted(owner_mesh, m, "left")), int(np.searchsorted(owner_mesh, m, "right")))


def _refit(items: np.ndarray, boxes: tuple, tree: tuple, roots: np.ndarray, m: int) -> None:
    """Refit, in place, the boxes (lower, upper: copies of tree's) of mesh m's tree to its moved items; the trees are
    stored mesh after mesh, each from its root (-1: none)."""
    if roots[m] < 0:
        return
    later = roots[m + 1:]
    later = later[later >= 0]
    refit_boxes(items, *boxes, tree[2], tree[3], int(roots[m]), int(later[0]) if later.size else len(boxes[0]))


def only(model: ContactModel, obstacles: Collection[int], *, self_contact: bool) -> ContactModel:
    """The part of `model` with only the obstacles of index in `obstacles` (model.names), and self-contact if asked
    (and the model has it); the meshes left out keep their arrays, their trees' roots set to -1."""
    if len(obstacles) == len(model.names) and (self_contact or model.self_exclusion < 0):
        return model  # all of it (a sweep whose obstacles are all fixed)
    keep = np.array(sorted(obstacles), dtype=np.int64)
    planes, balls, capsules = (np.isin(owners, keep) for owners in
                               (model.owners_planes, model.owners_balls, model.owners_capsules))
    meshes = np.isin(model.mesh.owners, keep)
    mesh = replace(model.mesh, triangle_roots=np.where(meshes, model.mesh.triangle_roots, -1),
                   edge_roots=np.where(meshes, model.mesh.edge_roots, -1))
    return replace(model, planes=model.planes[planes], owners_planes=model.owners_planes[planes],
                   balls=model.balls[balls], owners_balls=model.owners_balls[balls],
                   capsules=model.capsules[capsules], owners_capsules=model.owners_capsules[capsules], mesh=mesh,
                   self_exclusion=model.self_exclusion if self_contact else -1)


def move_is_clear(props: RodProperties, before: tuple[Clamps, RodState], after: tuple[Clamps, RodState],
                  model: ContactModel, carry: Pose | None) -> bool:
    """Whether the hose can go from `before` to `after` (each a state under its clamps; only the start point
    counts) while the obstacles of `model`, where they are before, are carried rigidly by `carry` (None: they
    stay), without crossing any of them (see the module doc).  `before` must not penetrate them."""
    (clamps_before, state_before), (clamps_after, state_after) = before, after
    start, frames = np.asarray(clamps_after.start_point, dtype=float), state_after.frames
    if carry is not None:  # the move as the obstacles see it: the hose carried back by their motion
        back = carry.inverse()
        start, frames = carried(start, back), turned(frames, back)
    return hose_move_clear(np.asarray(clamps_before.start_point, dtype=float), state_before.frames, start, frames,
                           props.segment_length, model)
