"""MuJoCo peer: the brake-hose placement solved with a 1D elastic flex (discrete elastic rod).

Units: mm, N, s; mass in tonnes (t = N s^2 / mm). MuJoCo itself is unit-free.

MuJoCo 4.0 removed the ``cable`` plugin and the ``composite`` element; rods are 1D
flexes with ``<elasticity>`` (discrete elastic rods: bending stiffness
k = E I / (l0 + l1) per interior vertex, torsion k_t = G J / (l0 + l1), circular
section I = pi r^4 / 4, J = pi r^4 / 2). With E = EI / I and G = GJ / J the flex
reproduces EI and GJ exactly. Stretching is not part of rod elasticity: the edge
lengths are held by the flex equality constraint. It is soft: its static violation
grows like h^2, which is what limits the time step here (STEPS_PER_PERIOD = 500 keeps
the total length error near 0.003 mm; 200 gives 0.05 mm, 100 gives 0.18 mm).

Model (written as a raw ``<flex dim="1">`` with the bodies ``flexcomp`` would create:
``flexcomp`` pins points only to its own parent body, and here the start must be
clamped to the world and the end to a moving body):

* vertices 0, 1 belong to the world body: the first edge and its material frame are
  clamped (position and full orientation of the start fixed);
* vertices 2 .. N-2 are point-mass bodies with three slide joints;
* vertices N-1, N belong to the body ``end_fitting``: the last edge is clamped to it.
  ``end_fitting`` hangs from the mocap body ``end_mount`` by the hinge ``end_roll``
  about the end tangent. The mocap body carries the prescribed path pose.

  - place phase: the hinge is free, so the end is free to spin about its tangent
    (zero torque about it) while position and tangent follow the mocap body;
  - twist phase: the hinge is locked by a stiff joint spring whose rest angle is the
    settled roll angle plus the twist (rotation about the end mount direction
    (1,0,0) = -tangent, hence a negative roll about the tangent).

* each interior edge has its twist hinge ``H_twist_<e>`` as MuJoCo requires.
* integrator ``discrete`` (implicit in position for flex elasticity and joint springs)
  with the Newton solver; mass-proportional damping on all degrees of freedom.

The mocap pose is moved along the path with a smooth (cosine) ramp, then the model
is run to rest: rest = largest node displacement over one check interval below
``tol_mm`` after the boundary reached its final value.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

try:
    from . import common
except ImportError:  # run as a script from bench/peers
    import common

# Dynamics parameters (they do not change the equilibrium, only how fast it is reached).
DENSITY = 1.3e-9  # t/mm^3 (rubber hose ~1.3 g/cm^3)
STEPS_PER_PERIOD = 500  # time step = lowest bending period / this
DAMPING_PER_OMEGA1 = 2.0  # damping rate (damping / mass) / lowest bending eigenfrequency (critical for that mode)
RAMP_PERIODS = 1.0  # duration of each boundary ramp, in lowest bending periods
CHECK_PERIODS = 0.1  # rest-check interval, in lowest bending periods
EDGE_TIMECONST_PER_STEP = 0.25  # edge-length constraint solref timeconst / h (dampratio 1)
EDGE_SOLIMP = (0.99, 0.999, 0.001)  # impedance of the edge-length constraints
ROLL_LOCK_STIFFNESS_PER_GJ_L = 1e5  # twist-phase roll lock spring / (GJ / L)


def _fmt(values) -> str:
    return " ".join(f"{v:.12g}" for v in np.ravel(values))


def _quat(frame: np.ndarray) -> np.ndarray:
    """MuJoCo quaternion (w, x, y, z) of a rotation matrix whose columns are the body axes."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(frame).ravel())
    return q


def build_model_xml(
    p: common.HoseProblem, segments: int, density: float, timestep: float, driven_end: bool = True
) -> str:
    """MJCF text of the hose, straight along t0 from P0, first edge clamped to the world.

    ``driven_end=True``: the last edge is clamped to ``end_fitting``, which hangs from the
    mocap body ``end_mount`` by the hinge ``end_roll`` about the tangent (local z).
    ``driven_end=False``: the end is free (last node body ``H_<n>``, last edge twist ``H_twist``).
    """
    n = segments
    dl = p.length / n
    s = np.linspace(0.0, p.length, n + 1)
    points = p.start_point + s[:, None] * common.unit(p.start_tangent)
    mass = density * np.pi * p.outer_radius**2 * p.length
    node_mass = mass / (n + 1)
    edge_mass = mass / n
    edge_polar = 0.5 * edge_mass * p.outer_radius**2  # polar rotary inertia of one edge [t mm^2]

    last_node = n - 2 if driven_end else n
    nodes = [
        f'<body name="H_{i}" pos="{_fmt(points[i])}">'
        f'<inertial pos="0 0 0" mass="{node_mass:.12g}" diaginertia="{_fmt([node_mass] * 3)}"/>'
        '<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/>'
        '<joint type="slide" axis="0 0 1"/></body>'
        for i in range(2, last_node + 1)
    ]
    # One twist hinge per unclamped edge, named as MuJoCo expects (the last edge is "H_twist").
    twist_names = [f"H_twist_{e}" for e in range(1, n - 1)] + ([] if driven_end else ["H_twist"])
    twists = [
        f'<body name="{name}"><inertial pos="0 0 0" mass="{edge_mass:.12g}" '
        f'diaginertia="{_fmt([edge_polar] * 3)}"/><joint name="{name}" axis="1 0 0"/></body>'
        for name in twist_names
    ]
    vertex_bodies = ["world", "world"] + [f"H_{i}" for i in range(2, last_node + 1)]
    # Vertex coordinates in their body frames: world for the first two, body origin for the nodes.
    vertices = [points[0], points[1], np.zeros(3 * (last_node - 1))]
    end_bodies = ""
    if driven_end:
        # The end fitting's z axis is the end tangent: the last two vertices sit at
        # (0, 0, -dl) and (0, 0, 0) in it. Torsion between the clamped last edge and its
        # neighbour acts on the fitting explicitly; its rotary inertia is raised to
        # 4 k_t h^2 (omega h = 0.5; it diverges near omega h = 1). Rotary inertia does
        # not change the equilibrium.
        k_twist = p.torsional_stiffness / (2.0 * dl)
        fitting_polar = max(edge_polar, 4.0 * k_twist * timestep**2)
        vertex_bodies += ["end_fitting", "end_fitting"]
        vertices += [[0.0, 0.0, -dl], [0.0, 0.0, 0.0]]
        end_bodies = (
            f'<body name="end_mount" mocap="true" pos="{_fmt(common.straight_end_point(p))}" '
            f'quat="{_fmt(_quat(common.start_frame(p)))}">'
            f'<body name="end_fitting"><inertial pos="0 0 0" mass="{edge_mass:.12g}" '
            f'diaginertia="{_fmt([fitting_polar] * 3)}"/><joint name="end_roll" axis="0 0 1"/></body></body>'
        )
    elements = " ".join(f"{i} {i + 1}" for i in range(n))
    return f"""
<mujoco model="hose">
  <option timestep="{timestep:.12g}" integrator="discrete" solver="Newton" gravity="0 0 0"/>
  <worldbody>
    {end_bodies}
    {''.join(nodes)}
    {''.join(twists)}
  </worldbody>
  <deformable>
    <flex name="H" dim="1" radius="{p.outer_radius:.12g}" body="{' '.join(vertex_bodies)}"
          vertex="{_fmt(np.concatenate([np.ravel(v) for v in vertices]))}" element="{elements}">
      <elasticity young="{p.equivalent_youngs_modulus:.12g}" shear="{p.equivalent_shear_modulus:.12g}"/>
      <contact contype="0" conaffinity="0"/>
    </flex>
  </deformable>
  <equality>
    <flex flex="H" solref="{_fmt([EDGE_TIMECONST_PER_STEP * timestep, 1.0])}" solimp="{_fmt(EDGE_SOLIMP)}"/>
  </equality>
</mujoco>"""


class _Runner:
    """Steps the model with mass-proportional damping and tracks step count and rest detection.

    MuJoCo refuses joint damping on flex vertex bodies, so the damping force
    -rate * (mass or rotary inertia of the dof) * velocity is applied through
    ``qfrc_applied`` before every step (explicit; rate * h << 1 here).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, damping_rate: float, check_every: int):
        self.m, self.d, self.check_every = model, data, check_every
        self.damping = damping_rate * model.dof_M0.copy()
        self.steps = 0

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            self.d.qfrc_applied[:] = -self.damping * self.d.qvel
            mujoco.mj_step(self.m, self.d)
        self.steps += n
        if self.d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number:
            raise RuntimeError("MuJoCo peer went unstable")

    def centerline(self) -> np.ndarray:
        return self.d.flexvert_xpos.copy()

    def run_to_rest(self, tol_mm: float, max_checks: int = 100000) -> None:
        previous = self.centerline()
        for _ in range(max_checks):
            self.step(self.check_every)
            current = self.centerline()
            if common.max_node_shift(current, previous) < tol_mm:
                return
            previous = current
        raise RuntimeError("MuJoCo peer did not come to rest")


def _ramp(k: int, n: int) -> float:
    """Smooth ramp 0 -> 1 over n steps (zero start and end velocity)."""
    return 0.5 - 0.5 * np.cos(np.pi * k / n)


def _apply_perturbation(m: mujoco.MjModel, d: mujoco.MjData, p: common.HoseProblem, segments: int) -> None:
    """Displace the node bodies by the lateral imperfection (slide-joint coordinates)."""
    s = np.linspace(0.0, p.length, segments + 1)
    shift = common.perturbation_shape(s, p)
    for i in range(2, segments - 1):
        adr = m.jnt_qposadr[m.body_jntadr[m.body(f"H_{i}").id]]
        d.qpos[adr:adr + 3] += shift[i]


def _setup(p: common.HoseProblem, segments: int, driven_end: bool):
    """Compile the model and return (model, data, runner, ramp_steps, timestep, damping_rate)."""
    omega1 = common.lowest_bending_omega(p, DENSITY)
    h = 2.0 * np.pi / omega1 / STEPS_PER_PERIOD
    m = mujoco.MjModel.from_xml_string(build_model_xml(p, segments, DENSITY, h, driven_end))
    d = mujoco.MjData(m)
    damping = DAMPING_PER_OMEGA1 * omega1
    runner = _Runner(m, d, damping, check_every=max(1, int(round(CHECK_PERIODS * STEPS_PER_PERIOD))))
    return m, d, runner, int(round(RAMP_PERIODS * STEPS_PER_PERIOD)), h, damping


def run(segments: int = 100, twist_deg: float = 180.0, tol_mm: float = 0.01) -> dict:
    """Solve the brake-hose placement with MuJoCo.

    Returns a dict with ``centerline`` ((segments+1, 3) node positions in mm, start to
    end), ``wall_time`` [s], ``sim_steps`` (time steps taken) and ``notes``.
    """
    p = common.BRAKE_HOSE
    wall0 = time.perf_counter()
    m, d, runner, n_ramp, h, damping = _setup(p, segments, driven_end=True)
    _apply_perturbation(m, d, p, segments)
    mujoco.mj_forward(m, d)
    roll = m.joint("end_roll")
    roll_q = m.jnt_qposadr[roll.id]

    # Phase "place": mocap pose along the path; the end_roll hinge is free.
    for k in range(1, n_ramp + 1):
        a = _ramp(k, n_ramp)
        d.mocap_pos[0] = common.place_position(a, p)
        d.mocap_quat[0] = _quat(common.place_orientation(a, p))
        runner.step()
    runner.run_to_rest(tol_mm)
    free_roll = float(d.qpos[roll_q])

    # Phase "twist": lock the roll with a stiff spring and turn its rest angle.
    m.jnt_stiffness[roll.id] = ROLL_LOCK_STIFFNESS_PER_GJ_L * p.torsional_stiffness / p.length
    for k in range(1, n_ramp + 1):
        m.qpos_spring[roll_q] = free_roll + common.twist_about_tangent(_ramp(k, n_ramp), twist_deg)
        runner.step()
    runner.run_to_rest(tol_mm)

    notes = (
        f"MuJoCo {mujoco.__version__} 1D flex elasticity (discrete elastic rod), {segments} elements, "
        f"E={p.equivalent_youngs_modulus:.1f} N/mm^2, G={p.equivalent_shear_modulus:.1f} N/mm^2, "
        f"density={DENSITY:g} t/mm^3, integrator=discrete, h={h:.3e} s, damping rate {damping:.1f} 1/s, "
        f"ramps {n_ramp} steps each; free-roll angle at end of place phase {np.degrees(free_roll):.2f} deg, "
        f"end roll after twist {np.degrees(d.qpos[roll_q] - free_roll):.2f} deg"
    )
    return common.outcome(runner.centerline(), wall0, runner.steps, notes, p.length)


def cantilever(
    segments: int = 100, load_parameter: float = common.CANTILEVER_LOAD_PARAMETER, tol_mm: float = 1e-4
) -> dict:
    """Clamped cantilever (the hose data, straight from the start mount) under a transverse tip dead load.

    The load P = load_parameter * EI / L^2 acts along d1 of the start frame on the last
    vertex body, ramped in over one ramp duration, then the model is run to rest.
    Returns tip deflection and tip shortening divided by L, and the step count.
    """
    p = common.BRAKE_HOSE
    frame0 = common.start_frame(p)
    load = load_parameter * p.bending_stiffness / p.length**2 * frame0[:, 0]
    m, d, runner, n_ramp, _, _ = _setup(p, segments, driven_end=False)
    tip_body = m.body(f"H_{segments}").id
    for k in range(1, n_ramp + 1):
        d.xfrc_applied[tip_body, :3] = _ramp(k, n_ramp) * load
        runner.step()
    runner.run_to_rest(tol_mm)
    tip = d.flexvert_xpos[-1] - p.start_point
    return common.cantilever_outcome(tip, frame0, runner.steps, p)


if __name__ == "__main__":
    common.print_outcome(run())
