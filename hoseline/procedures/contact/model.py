"""The contact model of a set of obstacles for the solver: primitives, barrier distance and stiffness.

Barrier stiffness.  A pair pushes with kappa h |b'(gap)| (N); per length of hose that is a
pressure kappa |b'(gap)| (N/mm), and |b'(d_hat / 2)| = 1.19 d_hat.  kappa = p_ref / d_hat puts
the gap near d_hat / 2 where the hose presses with about p_ref, below it where it presses
harder (gap ~ d_hat p_ref / p for p >> p_ref), so every gap at rest lies in (0, d_hat).  The
reference pressure is the hose's weight per length plus EI / L^3, the pressure that bends it
visibly over the length l: the hose length, or R + r for a round obstacle of radius R it may
wrap (bend_length), where a pressed hose pushes much harder.  A p_ref far below the pressure
that acts makes the gaps tiny and the barrier stiff (Newton then needs many more iterations:
30x more for a hose pulled over a drum with l = L than with l = R + r).  See docs/model.md, Contact.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hoseline.mechanics.contact_mesh import pack_meshes
from hoseline.mechanics.contact_newton import ContactModel, self_exclusion
from hoseline.model.obstacles import Box, Cylinder, Mesh, Obstacle, Plane, Sphere

DEFAULT_ACTIVATION = 0.01  # mm: d_hat, the largest gap at which contact pushes (the accuracy of a touch)


def reference_pressure(weight_per_length: float, bending_stiffness: float, length: float) -> float:
    """p_ref, N/mm: the hose's weight per length (N/mm) plus EI / l^3 (EI in N*mm^2, l in mm: bend_length)."""
    return float(weight_per_length) + float(bending_stiffness) / float(length) ** 3


def bend_length(hose_length: float, obstacles: Sequence[Obstacle], hose_radius: float) -> float:
    """l, mm: the shortest of the hose length and R + r over the round obstacles (spheres, cylinders).

    Boxes and meshes do not shorten it: their edges are sharp (R = 0), and a hose pressed over an
    edge is bent over the length between its supports, not over the edge's radius."""
    radii = [obstacle.radius + hose_radius for obstacle in obstacles if isinstance(obstacle, (Sphere, Cylinder))]
    return float(min([hose_length, *radii]))


def contact_model(
    obstacles: Sequence[Obstacle],
    hose_radius: float,
    segment_length: float,
    pressure: float,
    *,
    self_contact: bool = False,
    activation: float = DEFAULT_ACTIVATION,
) -> ContactModel:
    """The ContactModel of `obstacles` for a hose of outer radius `hose_radius` (mm) and segment length (mm).

    pressure: reference pressure p_ref (N/mm, reference_pressure); kappa = p_ref / activation.
    self_contact: also keep the hose out of itself.  activation: d_hat, mm.
    """
    if not activation > 0.0:
        raise ValueError(f"contact activation distance = {activation!r}: must be a positive distance in mm")
    planes, balls, capsules, meshes = [], [], [], []
    owners: tuple[list[int], list[int], list[int], list[int]] = ([], [], [], [])
    for index, obstacle in enumerate(obstacles):
        if isinstance(obstacle, Plane):
            planes.append(np.concatenate([obstacle.point, obstacle.normal]))
            owners[0].append(index)
        elif isinstance(obstacle, Sphere):
            balls.append(np.concatenate([obstacle.centre, [obstacle.radius]]))
            owners[1].append(index)
        elif isinstance(obstacle, Cylinder):
            capsules.append(np.concatenate([obstacle.start, obstacle.end, [obstacle.radius]]))
            owners[2].append(index)
        elif isinstance(obstacle, (Box, Mesh)):
            meshes.append(obstacle.triangles())
            owners[3].append(index)
        else:
            raise TypeError(f"obstacle {index}: {type(obstacle).__name__} is not a contact obstacle")
    return ContactModel(
        hose_radius=float(hose_radius),
        activation=float(activation),
        stiffness=float(pressure) / float(activation),
        planes=np.array(planes, dtype=float).reshape(-1, 6),
        balls=np.array(balls, dtype=float).reshape(-1, 4),
        capsules=np.array(capsules, dtype=float).reshape(-1, 7),
        owners_planes=np.array(owners[0], dtype=np.int64),
        owners_balls=np.array(owners[1], dtype=np.int64),
        owners_capsules=np.array(owners[2], dtype=np.int64),
        mesh=pack_meshes(meshes, owners[3]),
        names=tuple(obstacle.name for obstacle in obstacles),
        self_exclusion=self_exclusion(hose_radius, segment_length) if self_contact else -1,
    )

