"""The discrete beam model of the solved hose as an ADAMS/View command file (.cmd), and reading one back.

What the thesis' generator wrote (Thomas 2004, chapter II and appendix D), at the solved shape:
- one rigid part per segment (.MODEL.seg_001 ...), placed at the segment centre with the
  segment's frame: orientation = body-fixed Z-X-Z Euler angles (ADAMS "body313"), so its
  z axis runs along the hose (d3) and its x, y axes are the section axes d1, d2;
- on each part: marker cm (the centre, the part's own frame), marker base at the
  segment's start (the cylinder's reference: ADAMS extrudes a cylinder along the z axis of
  its centre marker), marker beam at the centre with x along the hose (an ADAMS beam runs
  along the x axis of its J marker), and a cylinder of the outer radius and segment length;
- a beam between the centres of adjacent parts (I marker on the outboard part, J on the
  inboard one, undeformed length = segment length) with the section properties of
  BeamSection; the beams are pre-bent and pre-twisted: their markers carry the solved frames;
- fixed joints from the first part (at the start tip) and the last part (at the end tip) to
  markers on ground; gravity when the problem has it; mass properties when the hose has mass;
- a joint per clip (CLIP_JOINTS: fixed, revolute for a rotating clip, cylindrical for a sliding
  clip, spherical for a ball clip) from the base marker of the part that starts at the clip
  station to a ground marker clip_<n> there, with the part's axes (so the joint is assembled at
  the solved shape; the revolute or cylindrical axis is then the part's z, within half a joint
  angle of the clip direction).  A cylindrical joint lets that one part slide along the axis: the
  guide ring for small motions (the material passing through the ring is not modelled; the parts
  keep the hose's nominal segment length where a sliding clip stretched its spans);
- a rigid part per end fitting (model/fittings.py), fitting_start / fitting_end: placed at the
  port with z along the port direction, its centreline as a polyline, fixed to a ground marker
  at the port (fix_fitting_start / _end); the hose's end part is then fixed to the fitting's
  outlet marker instead of ground.  Fitting parts carry no cylinder, so read_adams_cmd and
  hose_from_adams still find the hose parts alone;
- with stiffeners (model/stiffeners.py), the thesis' off-axis springs between adjacent parts
  as its line forces (Figure 27): one spline of force against marker distance and a
  single_component_force AKISPL(DM(I, J), 0, spline, 0) per spring (_stiffener_springs).
  A braid (model/braid.py) is not written: a comment says the beams carry EI and GJ only.

Units mm, kg, N, s, degrees.  The commands and parameter names follow the ADAMS/View command
language as ADAMS/View itself writes .cmd files; the file was checked against that
documentation and read back here, never run in ADAMS.

read_adams_cmd() reads the parts, markers and cylinders of such a file (ours, or one saved by
ADAMS/View after a simulation) and hose_from_adams() turns them back into stations and frames;
stiffeners_from_adams() gives back the stiffener springs (count, angle, table).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.model.hose import DEFAULT_POISSON_RATIO, Hose
from hoseline.model.stiffeners import SpringTable, Stiffeners
from hoseline.procedures.placement.result import Result

LENGTH_UNITS_MM = {"mm": 1.0, "cm": 10.0, "meter": 1000.0, "km": 1.0e6, "inch": 25.4, "foot": 304.8}
ANGLE_UNITS_RAD = {"deg": math.pi / 180.0, "rad": 1.0}
CYLINDER_SIDES = 20
# the beam marker's axes in the part frame: x along the hose (part z), y = part x, z = part y
BEAM_AXES_IN_PART = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).T


@dataclass(frozen=True)
class BeamSection:
    """Section of the ADAMS beams that realises the hose's stiffness.

    area: mm^2.  youngs_modulus, shear_modulus: N/mm^2.  ixx: torsion constant, iyy, izz:
    second moments of area about the beam's y (hose d1) and z (hose d2) axes, mm^4.
    """

    area: float
    youngs_modulus: float
    shear_modulus: float
    ixx: float
    iyy: float
    izz: float

    @classmethod
    def from_hose(
        cls,
        hose: Hose,
        youngs_modulus: float | None = None,
        shear_modulus: float | None = None,
        poisson_ratio: float = DEFAULT_POISSON_RATIO,
    ) -> "BeamSection":
        """The section of a solid round bar of the hose's outer radius with E*I and G*J equal to the hose's.

        youngs_modulus: E in N/mm^2; default EI / (pi r^4 / 4).  shear_modulus: G in N/mm^2;
        default E / (2 (1 + poisson_ratio)).  Then iyy = EI1 / E, izz = EI2 / E and
        ixx = GJ / G: the torsion constant is whatever realises the hose's torsional stiffness
        (the thesis' 25540.26 mm^4 for G = 96.12 N/mm^2).
        """
        radius = hose.outer_radius
        bending_1, bending_2, torsion = (float(value) for value in hose.stiffness_vector)
        youngs = bending_1 / (math.pi * radius**4 / 4.0) if youngs_modulus is None else youngs_modulus
        shear = youngs / (2.0 * (1.0 + poisson_ratio)) if shear_modulus is None else shear_modulus
        return cls(
            area=math.pi * radius**2,
            youngs_modulus=youngs,
            shear_modulus=shear,
            ixx=torsion / shear,
            iyy=bending_1 / youngs,
            izz=bending_2 / youngs,
        )


# --- Z-X-Z body-fixed Euler angles (ADAMS body313) ---


def body313_angles(frame: np.ndarray) -> np.ndarray:
    """Body-fixed Z-X-Z angles (psi, theta, phi) in degrees of a rotation matrix.

    frame: 3x3 matrix whose columns are the body's x, y, z axes in world components, so that
    frame = Rz(psi) Rx(theta) Rz(phi): rotate about z by psi, about the new x by theta, about
    the newest z by phi.  theta is in [0, 180]; where it is 0 or 180 only psi + phi (or
    psi - phi) is defined and phi is set to 0.  The body z axis is
    (sin psi sin theta, -cos psi sin theta, cos theta): the thesis' equations 5 and 6 for a
    vector (a, b, c) give tan psi = -a/b and tan theta = sqrt(a^2 + b^2)/c.
    """
    theta = math.atan2(math.hypot(frame[0, 2], frame[1, 2]), frame[2, 2])
    if math.sin(theta) > 1e-12:
        psi = math.atan2(frame[0, 2], -frame[1, 2])
        phi = math.atan2(frame[2, 0], frame[2, 1])
    else:
        psi, phi = math.atan2(frame[1, 0], frame[0, 0]), 0.0
    return np.degrees([psi, theta, phi])


def body313_matrix(angles_deg) -> np.ndarray:
    """The rotation matrix (columns: body axes in world components) of body-fixed Z-X-Z angles in degrees."""
    psi, theta, phi = np.radians(angles_deg)
    return _about_z(psi) @ _about_x(theta) @ _about_z(phi)


def _about_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _about_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


# --- writing ---


CLIP_JOINTS = {"fixed": "fixed", "rotating": "revolute", "sliding": "cylindrical", "ball": "spherical"}  # clip type -> ADAMS joint


def adams_cmd_text(result: Result, section: BeamSection | None = None) -> str:
    """The ADAMS/View command file of the solved hose (see the module docstring).

    section: the beams' section; default BeamSection.from_hose(hose).
    """
    problem, hose = result.problem, result.problem.hose
    section = section or BeamSection.from_hose(hose)
    model = "." + _adams_name(problem.name)
    count, h = hose.segments, hose.segment_length
    parts = [f"{model}.seg_{index + 1:0{len(str(count))}d}" for index in range(count)]
    centres = 0.5 * (result.centerline[1:] + result.centerline[:-1])
    frames = np.transpose(result.frames, (0, 2, 1))  # columns d1, d2, d3
    ids = _Ids()

    out = _Commands()
    out.comment(
        f"hoseline: discrete beam model of {problem.name!r} at its solved shape",
        f"{count} rigid parts (one per segment), {count - 1} beams between the centres of adjacent parts,",
        "the first and last part fixed to ground.  Units mm, kg, N, s, degrees; orientations body-fixed",
        "Z-X-Z (body313).  Written from the ADAMS/View command documentation; not run in ADAMS by hoseline.",
        f"Beam section: E = {section.youngs_modulus:.6g} N/mm^2, G = {section.shear_modulus:.6g} N/mm^2, "
        f"A = {section.area:.6g} mm^2, Ixx = {section.ixx:.6g}, Iyy = {section.iyy:.6g}, Izz = {section.izz:.6g} mm^4",
    )
    if hose.braid is not None:
        out.comment("The hose's braid ([hose.braid], tension-only strands) has no ADAMS element here: the beams carry "
                    "EI and GJ only,", "so this model lacks the stiffening of taut strands.")
    out.command("defaults units", length="mm", angle="deg", force="newton", mass="kg", time="sec")
    out.command("defaults units", coordinate_system_type="cartesian", orientation_type="body313")
    out.command("model create", model_name=model[1:])

    out.comment("ground: where the fittings hold the hose")
    out.command("defaults coordinate_system", default_coordinate_system=f"{model}.ground")
    _place(out, ids, "marker", f"{model}.ground.start_fitting", result.centerline[0], frames[0])
    _place(out, ids, "marker", f"{model}.ground.end_fitting", result.centerline[-1], frames[-1])

    mass = hose.mass_per_length * 1e-3 * h  # kg/m * mm -> kg
    for index, (part, centre, frame) in enumerate(zip(parts, centres, frames)):
        out.comment(f"segment {index + 1} of {count}")
        out.command("defaults coordinate_system", default_coordinate_system=f"{model}.ground")
        _place(out, ids, "part", part, centre, frame)
        out.command("defaults coordinate_system", default_coordinate_system=part)  # markers in the part's frame
        _place(out, ids, "marker", f"{part}.cm", (0.0, 0.0, 0.0), np.eye(3))
        _place(out, ids, "marker", f"{part}.base", (0.0, 0.0, -0.5 * h), np.eye(3))
        _place(out, ids, "marker", f"{part}.beam", (0.0, 0.0, 0.0), BEAM_AXES_IN_PART)
        if index == count - 1:
            _place(out, ids, "marker", f"{part}.tip", (0.0, 0.0, 0.5 * h), np.eye(3))
        if mass > 0.0:
            radius = hose.outer_radius
            across = mass * (3.0 * radius**2 + h**2) / 12.0  # solid cylinder about its centre, kg*mm^2
            out.command(
                "part create rigid_body mass_properties",
                part_name=part,
                mass=_number(mass),
                center_of_mass_marker=f"{part}.cm",
                inertia_marker=f"{part}.cm",
                ixx=_number(across),
                iyy=_number(across),
                izz=_number(0.5 * mass * radius**2),
                ixy="0.0",
                izx="0.0",
                iyz="0.0",
            )
        out.command(
            "geometry create shape cylinder",
            cylinder_name=f"{part}.tube",
            adams_id=ids.next("geometry"),
            center_marker=f"{part}.base",
            angle_extent="360.0",
            length=_number(h),
            radius=_number(hose.outer_radius),
            side_count_for_body=CYLINDER_SIDES,
            segment_count_for_ends=CYLINDER_SIDES,
        )

    out.comment("beams between the centres of adjacent parts (I outboard, J inboard)")
    for index in range(count - 1):
        out.command(
            "force create element_like beam",
            beam_name=f"{model}.beam_{index + 1:0{len(str(count))}d}",
            adams_id=ids.next("force"),
            i_marker_name=f"{parts[index + 1]}.beam",
            j_marker_name=f"{parts[index]}.beam",
            length=_number(h),
            area_of_cross_section=_number(section.area),
            y_shear_area_ratio="0.0",
            z_shear_area_ratio="0.0",
            youngs_modulus=_number(section.youngs_modulus),
            shear_modulus=_number(section.shear_modulus),
            ixx=_number(section.ixx),
            iyy=_number(section.iyy),
            izz=_number(section.izz),
        )

    _stiffener_springs(out, ids, model, parts, hose)
    holders = _fitting_parts(out, ids, model, result, frames)
    out.comment("the end parts held by the fittings")
    for joint, marker, ground in (
        ("fix_start", f"{parts[0]}.base", "start_fitting"),
        ("fix_end", f"{parts[-1]}.tip", "end_fitting"),
    ):
        out.command(
            "constraint create joint fixed",
            joint_name=f"{model}.{joint}",
            adams_id=ids.next("joint"),
            i_marker_name=marker,
            j_marker_name=holders.get(ground, f"{model}.ground.{ground}"),
        )
    _clip_joints(out, ids, model, parts, result, frames)
    if np.any(problem.gravity != 0.0):
        gravity = problem.gravity * 1e3  # m/s^2 -> mm/s^2
        out.command(
            "force create body gravitational",
            gravity_field_name=f"{model}.gravity",
            x_component_gravity=_number(gravity[0]),
            y_component_gravity=_number(gravity[1]),
            z_component_gravity=_number(gravity[2]),
        )
    return out.text()


def _stiffener_springs(out: "_Commands", ids: "_Ids", model: str, parts: list[str], hose: Hose) -> None:
    """The thesis' off-axis springs between adjacent parts (Thomas 2004, equations 9-16), as its line forces.

    The thesis' Figure 27 form: one spline for all springs (data_element create spline, linear
    extrapolation) giving the force in N against the distance of the spring's two markers in mm,
    the table's zero deformation moved to the free length and tension negative (ADAMS counts a
    positive single-component force as pushing the markers apart); each spring a
    single_component_force with function AKISPL(DM(I, J), 0, spline, 0) between a marker on
    each part, at the anchors of Stiffeners.anchors in the part's section plane through its
    centre.  The thesis reports this form identical to its spring elements, whose commands the
    OCR does not show.  ADAMS interpolates the spline by Akima's method, hoseline's solver
    linearly between the same points.  The joints at the fittings carry no springs here (the
    end parts are fixed to the fittings), as in the thesis' model.
    """
    stiffeners = hose.stiffeners
    if stiffeners is None:
        return
    h = hose.segment_length
    anchors = stiffeners.anchors(hose.outer_radius, h, h)  # relative to the node between two parts
    free = float(np.linalg.norm(anchors[0, 1] - anchors[0, 0]))  # element / sin(angle), the same for every spring
    spline = f"{model}.spring_table"
    out.comment(
        f"stiffener springs: {stiffeners.springs} between each two adjacent parts at {stiffeners.angle_deg:g} deg "
        "to the section plane,",
        f"line forces along a spline of force (N, tension negative) against marker distance (mm); free length {free:.9g} mm",
    )
    out.command(
        "data_element create spline",
        spline_name=spline,
        adams_id=ids.next("spline"),
        x=_vector(free + np.asarray(stiffeners.table.deformation)),
        y=_vector(0.0 - np.asarray(stiffeners.table.force)),  # 0.0 - : no "-0.0"
        linear_extrapolate="yes",
    )
    centre = np.array([0.0, 0.0, 0.5 * h])  # from the node to the part centres: anchors -> part frames
    for index, part in enumerate(parts):
        out.command("defaults coordinate_system", default_coordinate_system=part)
        for j in range(stiffeners.springs):
            if index + 1 < len(parts):
                _place(out, ids, "marker", f"{part}.spring_{j + 1:02d}_next", anchors[j, 0] + centre, np.eye(3))
            if index > 0:
                _place(out, ids, "marker", f"{part}.spring_{j + 1:02d}_prev", anchors[j, 1] - centre, np.eye(3))
    out.command("defaults coordinate_system", default_coordinate_system=f"{model}.ground")
    digits = len(str(len(parts)))
    for index in range(len(parts) - 1):
        for j in range(stiffeners.springs):
            i_marker, j_marker = f"{parts[index + 1]}.spring_{j + 1:02d}_prev", f"{parts[index]}.spring_{j + 1:02d}_next"
            out.command(
                "force create direct single_component_force",
                single_component_force_name=f"{model}.spring_{index + 1:0{digits}d}_{j + 1:02d}",
                adams_id=ids.next("force"),
                type_of_freedom="translational",
                i_marker_name=i_marker,
                j_marker_name=j_marker,
                action_only="off",
                function=f'"AKISPL(DM({i_marker}, {j_marker}), 0, {spline}, 0)"',
            )


def _fitting_parts(out: "_Commands", ids: "_Ids", model: str, result: Result, frames: np.ndarray) -> dict[str, str]:
    """One rigid part per end fitting, fixed to ground at its port; returns {ground marker name of the hose end:
    the fitting's outlet marker that holds the hose instead}."""
    fittings = result.problem.fittings
    if fittings is None:
        return {}
    holders = {}
    for name, port, fitting in fittings.pieces():
        part = f"{model}.fitting_{name}"
        axes = frame_from_tangent(port.direction).T  # columns x, y, z; z along the port direction
        if fitting.bend_angle_deg:
            bend = fitting.bend_direction(port)
            axes = np.column_stack([bend, np.cross(port.direction, bend), port.direction])
        hose_end = frames[0] if name == "start" else frames[-1]
        outlet = fitting.outlet(port).point
        out.comment(f"the {name} fitting: a rigid part fixed to ground at its port")
        out.command("defaults coordinate_system", default_coordinate_system=f"{model}.ground")
        _place(out, ids, "marker", f"{model}.ground.{name}_port", port.point, axes)
        _place(out, ids, "part", part, port.point, axes)
        _place(out, ids, "marker", f"{part}.port", port.point, axes)
        _place(out, ids, "marker", f"{part}.outlet", outlet, hose_end)
        local = (fitting.centreline(port) - port.point) @ axes  # in the part's frame
        out.command(
            "geometry create curve polyline",
            polyline_name=f"{part}.centreline",
            adams_id=ids.next("geometry"),
            location=", ".join(_vector(point) for point in local),
            relative_to=part,
            close="no",
        )
        out.command(
            "constraint create joint fixed",
            joint_name=f"{model}.fix_fitting_{name}",
            adams_id=ids.next("joint"),
            i_marker_name=f"{part}.port",
            j_marker_name=f"{model}.ground.{name}_port",
        )
        holders[f"{name}_fitting"] = f"{part}.outlet"
    return holders


def _clip_joints(out: "_Commands", ids: "_Ids", model: str, parts: list[str], result: Result, frames: np.ndarray) -> None:
    """One joint per clip, from the base of the part starting at the clip station to a ground marker there."""
    if not result.clips:
        return
    out.comment("the clips: one joint each at its station")
    for number, clip in enumerate(result.clips, start=1):
        node = int(np.argmin(np.abs(result.s - clip.arc_length)))  # the station (a sliding clip's is where it came to rest)
        out.command("defaults coordinate_system", default_coordinate_system=f"{model}.ground")
        _place(out, ids, "marker", f"{model}.ground.clip_{number}", result.centerline[node], frames[node])
        out.command(
            f"constraint create joint {CLIP_JOINTS[clip.kind]}",
            joint_name=f"{model}.clip_{number}",
            adams_id=ids.next("joint"),
            i_marker_name=f"{parts[node]}.base",
            j_marker_name=f"{model}.ground.clip_{number}",
        )


def _place(out: "_Commands", ids: "_Ids", kind: str, name: str, location, axes: np.ndarray) -> None:
    """Create a part or a marker at `location` (mm) with `axes` (columns x, y, z) in the current coordinate system."""
    command, key = {
        "part": ("part create rigid_body name_and_position", "part_name"),
        "marker": ("marker create", "marker_name"),
    }[kind]
    out.command(
        command,
        **{key: name},
        adams_id=ids.next(kind),
        location=_vector(location),
        orientation=_angles(body313_angles(axes)),
    )


class _Commands:
    """Collects commands in the layout ADAMS/View writes: one parameter per line, '&' continues."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def comment(self, *lines: str) -> None:
        self.lines += ([] if self.lines else ["!"]) + [f"! {line}" for line in lines] + ["!"]

    def command(self, name: str, **parameters) -> None:
        items = [f"   {key} = {value}" for key, value in parameters.items()]
        self.lines += [name + "  &"] + [item + "  &" for item in items[:-1]] + [items[-1], "!"]

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


class _Ids:
    """Consecutive adams_id numbers, counted separately per kind of object."""

    def __init__(self) -> None:
        self.last: dict[str, int] = {}

    def next(self, kind: str) -> int:
        self.last[kind] = self.last.get(kind, 0) + 1
        return self.last[kind]


def _adams_name(text: str) -> str:
    """A model name ADAMS accepts: letters, digits and underscores, starting with a letter."""
    name = re.sub(r"\W+", "_", text).strip("_") or "hose"
    return name if name[0].isalpha() else "hose_" + name


def _number(value: float) -> str:
    """A real as ADAMS writes it: always with a decimal point, exponent as E+nn, 15 significant digits."""
    text = f"{value:.15g}"
    if "e" in text:
        return f"{value:.14E}"
    return text if "." in text else text + ".0"


def _vector(values) -> str:
    return ", ".join(_number(float(v)) for v in values)


def _angles(values) -> str:
    return ", ".join(_number(float(v)) + "d" for v in values)


# --- reading ---


class AdamsFileError(ValueError):
    """An ADAMS/View command file that cannot give the hose's parts; the message names the line."""


@dataclass
class AdamsModel:
    """Positions (mm) and orientations (3x3, columns = body axes) of the parts and markers of a .cmd file.

    parts, markers: full name -> (position, rotation), in the world (ground) frame, in file order.
    cylinders: part name -> (centre marker name, length in mm).
    splines: name -> (x, y) of each data_element spline, x in the length unit (mm), y as written.
    spline_forces: single-component force name -> (I marker, J marker, spline name) of the forces
    whose function is AKISPL(DM(I, J), 0, spline[, 0]) (the stiffener springs).
    """

    parts: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    markers: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    cylinders: dict[str, tuple[str, float]] = field(default_factory=dict)
    splines: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    spline_forces: dict[str, tuple[str, str, str]] = field(default_factory=dict)


def read_adams_cmd(path: str | Path) -> AdamsModel:
    """Read the parts, markers and cylinders of an ADAMS/View command file.

    Understands what it needs of the commands ADAMS/View writes: defaults units (length,
    angle, orientation_type body313), defaults coordinate_system, part create rigid_body
    name_and_position, marker create (with relative_to or the default coordinate system) and
    geometry create shape cylinder; other commands are skipped.  Keywords must be written in
    full, as ADAMS/View writes them.  Raises AdamsFileError naming the line for what it cannot read.
    """
    path = Path(path)
    model = AdamsModel()
    length_mm, angle_rad = 1.0, math.pi / 180.0
    reference = "ground"
    for line, words, parameters in _commands(path.read_text(encoding="utf-8", errors="replace")):
        where = f"{path}: line {line}"
        command = " ".join(words)
        if command == "defaults units":
            length_mm = _unit(where, parameters, "length", LENGTH_UNITS_MM, length_mm)
            angle_rad = _unit(where, parameters, "angle", ANGLE_UNITS_RAD, angle_rad)
            kind = parameters.get("orientation_type", ["body313"])[0].lower()
            if kind != "body313":
                raise AdamsFileError(f"{where}: orientation_type = {kind}: only body313 (Z-X-Z) orientations are read")
        elif command == "defaults coordinate_system":
            reference = _name(where, parameters, "default_coordinate_system")
        elif command in ("part create rigid_body name_and_position", "marker create"):
            name = _name(where, parameters, "part_name" if command.startswith("part") else "marker_name")
            base = _pose(where, model, parameters["relative_to"][0] if "relative_to" in parameters else reference)
            position = _reals(where, parameters, "location", 3, length_mm, default=(0.0, 0.0, 0.0))
            pose = (
                base[0] + base[1] @ position,
                base[1] @ body313_matrix(_orientation_deg(where, parameters, angle_rad)),
            )
            (model.parts if command.startswith("part") else model.markers)[name] = pose
        elif command == "geometry create shape cylinder":
            name = _name(where, parameters, "cylinder_name")
            length = _reals(where, parameters, "length", 1, length_mm)[0]
            model.cylinders[name.rsplit(".", 1)[0]] = (_name(where, parameters, "center_marker"), length)
        elif command == "data_element create spline":
            name = _name(where, parameters, "spline_name")
            x = _reals(where, parameters, "x", len(parameters.get("x", [])), length_mm)
            y = _reals(where, parameters, "y", len(x), 1.0)
            model.splines[name] = (x, y)
        elif command == "force create direct single_component_force":
            found = _SPLINE_FORCE.fullmatch(re.sub(r"\s+", "", " ".join(parameters.get("function", [])).strip('"')))
            if found:
                model.spline_forces[_name(where, parameters, "single_component_force_name")] = tuple(
                    name.lstrip(".") for name in found.groups())
    return model


_SPLINE_FORCE = re.compile(r"AKISPL\(DM\(([^,()]+),([^,()]+)\),0(?:\.0*)?,([^,()]+?)(?:,0(?:\.0*)?)?\)", re.IGNORECASE)


def stiffeners_from_adams(model: AdamsModel) -> Stiffeners | None:
    """The stiffener springs of a model read by read_adams_cmd (as _stiffener_springs writes them), or None.

    The count is the springs between each pair of adjacent parts; the free length L0 is the
    distance of a spring's markers with the two parts' frames laid end to end along z (the
    straight hose), the angle asin(h / L0) with h the parts' cylinder length; the table is
    the spline with the free length taken off the distances and the sign turned back to
    tension positive.  Raises AdamsFileError for springs that do not share one spline or one count.
    """
    if not model.spline_forces:
        return None
    pairs: dict[tuple[str, str], list[tuple[str, str]]] = {}
    splines = set()
    for i_marker, j_marker, spline in model.spline_forces.values():
        parts = (j_marker.rsplit(".", 1)[0], i_marker.rsplit(".", 1)[0])
        pairs.setdefault(parts, []).append((j_marker, i_marker))
        splines.add(spline)
    counts = {len(springs) for springs in pairs.values()}
    if len(splines) != 1 or len(counts) != 1:
        raise AdamsFileError(f"stiffener springs: found {len(splines)} splines and counts {sorted(counts)} per pair of "
                             "parts: hoseline reads one spline and one count for all")
    (inboard, outboard), springs = next(iter(pairs.items()))
    missing = [name for name in (inboard, outboard, *(m for pair in springs for m in pair))
               if name not in model.parts and name not in model.markers]
    if missing or inboard not in model.cylinders or splines.pop() not in model.splines:
        raise AdamsFileError(f"stiffener springs: parts, markers or the spline of {inboard} - {outboard} are not defined")
    h = model.cylinders[inboard][1]

    def in_part(marker: str, part: str) -> np.ndarray:
        (origin, axes), (position, _) = model.parts[part], model.markers[marker]
        return axes.T @ (position - origin)

    j_marker, i_marker = springs[0]
    free = float(np.linalg.norm(in_part(i_marker, outboard) + np.array([0.0, 0.0, h]) - in_part(j_marker, inboard)))
    x, y = model.splines[next(iter(model.spline_forces.values()))[2]]
    table = SpringTable(tuple(x - free), tuple(-y))
    return Stiffeners(len(springs), math.degrees(math.asin(min(1.0, h / free))), table)


def hose_from_adams(model: AdamsModel) -> tuple[np.ndarray, np.ndarray]:
    """(stations (N+1, 3) in mm, frames (N, 3, 3) with rows d1, d2, d3) of the hose parts of a model.

    The hose parts are those carrying a cylinder, in file order.  Each part's cm marker (or
    the part itself) gives the segment centre and frame (z along the hose); its cylinder gives
    the segment length.  A station between two parts is the mean of the end of the one and
    the start of the next (they coincide in a file hoseline wrote; in a simulated model the
    beams let them drift apart slightly).
    """
    names = [name for name in model.parts if name in model.cylinders]
    if len(names) < 2:
        raise AdamsFileError(f"found {len(names)} parts with a cylinder: a hose needs at least two")
    centres, rotations, lengths = [], [], []
    for name in names:
        position, rotation = model.markers.get(f"{name}.cm", model.parts[name])
        centres.append(position)
        rotations.append(rotation)
        lengths.append(model.cylinders[name][1])
    centres, rotations, half = np.array(centres), np.array(rotations), 0.5 * np.array(lengths)[:, None]
    axes = rotations[:, :, 2]
    starts, ends = centres - half * axes, centres + half * axes
    stations = np.vstack([starts[:1], 0.5 * (ends[:-1] + starts[1:]), ends[-1:]])
    return stations, np.transpose(rotations, (0, 2, 1))


_TOKEN = re.compile(r'"[^"]*"|[^\s=,"]+|=|,')


def _commands(text: str):
    """(first line number, command words, {parameter: [value tokens]}) for each command of a .cmd text."""
    pending, start = "", 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = re.sub(r'!(?=(?:[^"]*"[^"]*")*[^"]*$).*', "", raw).rstrip()  # drop a comment outside quotes
        if not pending:
            start = number
        if line.endswith("&"):
            pending += line[:-1] + " "
            continue
        pending += line
        if pending.strip():
            yield start, *_split_command(start, pending)
        pending = ""


def _split_command(line: int, text: str) -> tuple[list[str], dict[str, list[str]]]:
    """Command words and parameters of one joined command."""
    tokens = _TOKEN.findall(text)
    keys = [index - 1 for index, token in enumerate(tokens) if token == "=" and index > 0]
    words = [token.lower() for token in tokens[: keys[0] if keys else len(tokens)]]
    parameters = {}
    for position, key in enumerate(keys):
        stop = keys[position + 1] if position + 1 < len(keys) else len(tokens)
        parameters[tokens[key].lower()] = [token for token in tokens[key + 2 : stop] if token != ","]
    return words, parameters


def _name(where: str, parameters: dict, key: str) -> str:
    """An object name, without its leading dot."""
    if not parameters.get(key):
        raise AdamsFileError(f"{where}: missing {key}")
    return parameters[key][0].lstrip(".")


def _unit(where: str, parameters: dict, key: str, table: dict[str, float], current: float) -> float:
    if key not in parameters:
        return current
    unit = parameters[key][0].lower()
    if unit not in table:
        raise AdamsFileError(f"{where}: {key} = {unit}: hoseline reads {', '.join(table)}")
    return table[unit]


def _reals(where: str, parameters: dict, key: str, count: int, scale: float, default=None) -> np.ndarray:
    """`count` reals of a parameter, times `scale`."""
    values = parameters.get(key)
    if values is None and default is not None:
        return np.array(default, dtype=float)
    try:
        numbers = [float(value) for value in values or []]
    except ValueError:
        raise AdamsFileError(f"{where}: {key} = {', '.join(values)}: expected {count} plain numbers") from None
    if len(numbers) != count:
        raise AdamsFileError(f"{where}: {key} has {len(numbers)} values, expected {count}")
    return np.array(numbers) * scale


def _orientation_deg(where: str, parameters: dict, angle_rad: float) -> np.ndarray:
    """The orientation angles in degrees ('90.0d' is in degrees, a plain number in the default angle unit)."""
    values = parameters.get("orientation", ["0", "0", "0"])
    if len(values) != 3:
        raise AdamsFileError(f"{where}: orientation has {len(values)} values, expected 3 (body313 angles)")
    angles = []
    for value in values:
        degrees = value.lower().endswith("d")
        try:
            number = float(value[:-1] if degrees else value)
        except ValueError:
            raise AdamsFileError(f"{where}: orientation value {value!r} is not a plain angle") from None
        angles.append(number if degrees else math.degrees(number * angle_rad))
    return np.array(angles)


def _pose(where: str, model: AdamsModel, name: str) -> tuple[np.ndarray, np.ndarray]:
    """World pose of a reference frame: ground, a part or a marker read before."""
    name = name.lstrip(".")
    if name.split(".")[-1] == "ground":
        return np.zeros(3), np.eye(3)
    for table in (model.parts, model.markers):
        if name in table:
            return table[name]
    raise AdamsFileError(f"{where}: coordinate system {name!r} is not defined before it is used")
