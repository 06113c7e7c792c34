"""A placement problem: a hose between two mounts, a twist at assembly, gravity."""

from __future__ import annotations

import math

from dataclasses import dataclass, field

import numpy as np

from hoseline.model.clips import Clip, clip_node, off_station_message
from hoseline.model.fittings import EndFittings, Fitting
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount, mount_distance, unit_vector
from hoseline.model.obstacles import Obstacle

STRAIGHT_MARGIN = 1e-9  # relative: a hose pulled straight between its mounts has no equilibrium to solve for


def reaches(length: float, distance: float) -> bool:
    """Whether a hose of `length` mm spans mounts `distance` mm apart without being pulled straight (False for NaN)."""
    return distance < length * (1.0 - STRAIGHT_MARGIN)


@dataclass(frozen=True)
class Problem:
    """Everything the solver needs, in user units.

    hose: the hose (mm, N*mm^2, kg/m).
    start, end: mounts (mm); directions from the fitting into the hose.
    end_twist_deg: degrees, rotation of the end fitting about end.direction
        (right-hand rule) applied after the torque-free lock angle.
    gravity: m/s^2 vector (e.g. [0, 0, -9.81]); zero for a weightless study.
    name: free text for reports.
    clips: intermediate supports (model/clips.py), in order of arc length; each on a station of the hose.
    fittings: the ports and rigid end fittings (model/fittings.py) when the user gave them; start and end
        are then the fitting outlets (what the solver clamps) and hose.length is the free length.
    contact: obstacles the hose touches without entering (model/obstacles.py: plane, sphere, cylinder, box, mesh; mm),
        frictionless; each with its own name.
    self_contact: keep the hose out of itself (segments far enough apart along it).
    contact_sides: per obstacle of `contact`, the side of it the hose is to end on (a world direction, unit) or
        None for the side of least penetration (procedures/contact/bring_in.py); empty (as kept when every one is
        None): None for every one.
    contact_placement: "bring_in" (default: the published sequence without the obstacles, then each obstacle the
        free hose touches brought in from a clear position) or "along_path" (the sequence with the obstacles
        present all along; the straight start and the end fitting's path must clear them).
    force_accuracy: with obstacles, the relative accuracy (a fraction, e.g. 0.005) of each obstacle's total force and
        the mounts' reactions that `hoseline solve` refines the segments for (procedures/placement/force_accuracy.py);
        None: the segment count as given.  A problem file sets DEFAULT_FORCE_ACCURACY when it gives obstacles and no
        hose.segments.
    """

    hose: Hose
    start: Mount
    end: Mount
    end_twist_deg: float = 0.0
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = "hose"
    clips: tuple[Clip, ...] = ()
    fittings: EndFittings | None = None
    contact: tuple[Obstacle, ...] = ()
    self_contact: bool = False
    contact_sides: tuple[np.ndarray | None, ...] = ()
    contact_placement: str = "bring_in"
    force_accuracy: float | None = None

    def __post_init__(self) -> None:
        g = np.asarray(self.gravity, dtype=float).reshape(-1)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(f"environment.gravity = {list(g)}: must be three finite numbers in m/s^2")
        object.__setattr__(self, "gravity", g)
        if not np.isfinite(self.end_twist_deg):
            raise ValueError(f"end.twist = {self.end_twist_deg!r}: must be a finite angle in degrees")
        distance = mount_distance(self.start, self.end)
        if not reaches(self.hose.length, distance):
            raise ValueError(
                f"hose.length = {self.hose.length:g} mm is not longer than the mount distance "
                f"{distance:g} mm: an inextensible hose cannot reach; use a hose longer than {distance:g} mm"
            )
        object.__setattr__(self, "clips", tuple(self.clips))
        self._check_clips()
        self._check_fittings()
        object.__setattr__(self, "contact", tuple(self.contact))
        self._check_contact()

    @property
    def has_contact(self) -> bool:
        """Whether the placement keeps the hose out of obstacles or itself."""
        return bool(self.contact) or self.self_contact

    def _check_contact(self) -> None:
        """Obstacle names unique (they label the report) and not "self"; no contact with what it does not take yet."""
        names = [obstacle.name for obstacle in self.contact]
        for index, name in enumerate(names):
            if name == "self" or name in names[:index]:
                reason = "is reserved for self-contact" if name == "self" else "is used by an earlier obstacle"
                raise ValueError(f"contact.obstacles[{index}].name = {name!r} {reason}: give each obstacle its own name")
        sides = tuple(self.contact_sides) or (None,) * len(self.contact)
        if len(sides) != len(self.contact):
            raise ValueError(f"contact_sides: {len(sides)} given for {len(self.contact)} obstacles: give one per "
                             "obstacle (None for the side of least penetration)")
        sides = tuple(None if side is None else _side(side, obstacle) for side, obstacle in zip(sides, self.contact))
        # none given: kept empty, so that a copy with other obstacles (dataclasses.replace) needs no new list
        object.__setattr__(self, "contact_sides", () if all(side is None for side in sides) else sides)
        if self.contact_placement not in CONTACT_PLACEMENTS:
            raise ValueError(f"contact.placement = {self.contact_placement!r}: must be one of "
                             f"{', '.join(repr(name) for name in CONTACT_PLACEMENTS)}")
        if self.force_accuracy is not None and not (math.isfinite(self.force_accuracy) and 0.0 < self.force_accuracy < 1.0):
            raise ValueError(f"contact.force_accuracy_percent = {100 * self.force_accuracy!r}: give a percentage between "
                             "0 and 100 (e.g. 0.5)")
        if self.force_accuracy is not None and not self.contact:
            raise ValueError("contact.force_accuracy_percent without obstacles: it refines the obstacles' forces; "
                             "remove it or add [[contact.obstacles]]")
        if not self.has_contact:
            return
        if self.hose.stiffeners is not None:
            raise ValueError("[contact] with [hose.stiffeners]: contact on a hose with stiffener springs is not "
                             "implemented yet; remove the stiffeners or the contact")
        if any(clip.slides for clip in self.clips):
            raise ValueError("[contact] with a sliding clip: not implemented yet (the hose's segments stretch next "
                             "to the clip); use a rotating clip at a chosen arc_length or remove the contact")

    def side_of(self, name: str) -> np.ndarray | None:
        """The hose_side given for the obstacle `name` (unit world direction), None if none."""
        return dict(zip((obstacle.name for obstacle in self.contact), self.contact_sides)).get(name)

    def _check_fittings(self) -> None:
        """With fittings, start and end must be their outlets (a moved port needs its fittings moved too)."""
        if self.fittings is None:
            return
        for name, mount, outlet in zip(("start", "end"), (self.start, self.end), self.fittings.outlets()):
            off = float(np.linalg.norm(mount.point - outlet.point)) / self.hose.length
            turned = float(np.linalg.norm(mount.direction - outlet.direction))
            if off > 1e-9 or turned > 1e-9:
                raise ValueError(f"{name}: the mount is not the outlet of its fitting (off by {off * self.hose.length:g} mm, "
                                 f"{turned:g} in direction): build the problem with model.problem.fitted_problem")

    def _check_clips(self) -> None:
        """Each clip strictly inside the hose, on a station, after the previous one, and reachable; none on a braided hose."""
        hose = self.hose
        if self.clips and hose.braid is not None:
            raise ValueError("[hose.braid] with [[clips]]: a braided hose with clips is not implemented yet (the clipped "
                             "rod has no braid term); remove the braid or the clips")
        previous_s, previous_point, previous_label = 0.0, self.start.point, "the start mount"
        for index, clip in enumerate(self.clips):
            label = f"clips[{index}]" + (f" ({clip.name})" if clip.name else "")
            if not previous_s < clip.arc_length < hose.length:
                raise ValueError(
                    f"{label}: arc_length = {clip.arc_length:g} mm: must lie between {previous_s:g} mm "
                    f"({previous_label}) and the hose length {hose.length:g} mm; list clips in order of arc length"
                )
            if not clip.slides and clip_node(clip.arc_length, hose.length, int(hose.segments)) is None:
                raise ValueError(off_station_message(label, clip.arc_length, hose.length, int(hose.segments)))
            self._check_span(label, clip.arc_length - previous_s, previous_label)
            self._check_reach(label, clip.arc_length - previous_s, previous_point, clip.point, previous_label)
            previous_s, previous_point, previous_label = clip.arc_length, clip.point, label
        if self.clips:
            self._check_span("end mount", hose.length - previous_s, previous_label)
            self._check_reach("end mount", hose.length - previous_s, previous_point, self.end.point, previous_label)

    def _check_span(self, label: str, span: float, from_label: str) -> None:
        # one segment between two held stations is a rigid link: it cannot take up any distance
        segments = span / self.hose.segment_length
        if segments < 2.0 - 1e-9:
            raise ValueError(
                f"{label}: only {segments:.0f} segment of hose from {from_label}: a span between held stations "
                f"needs at least two; raise hose.segments or move the clip"
            )

    @staticmethod
    def _check_reach(label: str, span: float, from_point: np.ndarray, to_point: np.ndarray, from_label: str) -> None:
        distance = float(np.linalg.norm(to_point - from_point))
        if not reaches(span, distance):
            raise ValueError(
                f"{label}: the {span:g} mm of hose from {from_label} cannot reach {distance:g} mm; move the clip "
                "point or change its arc_length"
            )


CONTACT_PLACEMENTS = ("bring_in", "along_path")
DEFAULT_FORCE_ACCURACY = 0.005  # relative: forces and reactions of a contact problem whose file gives no hose.segments


def _side(side, obstacle: Obstacle) -> np.ndarray:
    """A hose_side checked: a finite nonzero direction (made unit), not for a plane (whose side is its normal)."""
    label = f"contact.obstacles {obstacle.name!r} hose_side"
    if obstacle.kind == "plane":
        raise ValueError(f"{label}: a plane keeps the hose on the side its normal points to; leave hose_side out "
                         "(turn the normal to choose the side)")
    return unit_vector(side, label)


def fitted_problem(hose: Hose, start_port: Mount, end_port: Mount, start: Fitting | None, end: Fitting | None, **problem_fields):
    """The Problem of the flexible hose between the fitting outlets, carrying the fittings for reports and exports.

    hose: the hose; its length is the free length (mm) between the fittings.
    start_port, end_port: the ports as the user gives them (mm; directions from the port into the hose).
    start, end: the fittings (None: crimped at the port).
    problem_fields: the other Problem fields (end_twist_deg: degrees about the end outlet's direction, gravity, name, clips).
    Raises ValueError naming the length to change when the free hose cannot span the outlets.
    """
    fittings = EndFittings(start_port, end_port, start, end)
    first, last = fittings.outlets()
    gap = float(np.linalg.norm(last.point - first.point))
    if not reaches(hose.length, gap):
        allowance = fittings.length_allowance
        raise ValueError(
            f"hose: the free length {hose.length:g} mm (overall length {fittings.overall_length(hose.length):g} mm less "
            f"{allowance:g} mm of fittings) is not longer than the {gap:g} mm between the fitting outlets: give an "
            f"overall_length above {gap + allowance:g} mm (a length above {gap:g} mm), or shorter fittings"
        )
    return Problem(hose=hose, start=first, end=last, fittings=fittings, **problem_fields)
