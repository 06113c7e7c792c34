"""MuJoCo peer: the brake-hose placement solved with a 1D elastic flex (discrete elastic rod).

Units: mm, N, s; mass in tonnes (t = N s^2 / mm). MuJoCo itself is unit-free.

MuJoCo 4.0 removed the ``cable`` plugin and the ``composite`` element; rods are 1D
flexes with ``<elasticity>`` (discrete elastic rods: bending stiffness
k = E I / (l0 + l1) per interior vertex, torsion k_t = G J / (l0 + l1), circular
section I = pi r^4 / 4, J = pi r^4 / 2). With E = EI / I and G = GJ / J the flex
reproduces EI and GJ exactly. Stretching is not part of rod elasticity: the edge
lengths are held by the flex equality constraint (soft, see EDGE_SOLREF).

Model (written as a raw ``<flex dim="1">`` with the bodies ``flexcomp`` would create,
because the end must sit on a different body than the start):

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
DAMPING_PER_OMEGA1 = 1.5  # damping rate (damping / mass) / lowest bending eigenfrequency
RAMP_PERIODS = 3.0  # duration of each boundary ramp, in lowest bending periods
CHECK_PERIODS = 0.1  # rest-check interval, in lowest bending periods
EDGE_SOLREF = (0.0, 1.0)  # (timeconst, dampratio) of the edge-length constraints; 0 -> 2 h
EDGE_SOLIMP = (0.99, 0.999, 0.001)  # impedance of the edge-length constraints
ROLL_LOCK_STIFFNESS_PER_GJ_L = 1e5  # twist-phase roll lock spring / (GJ / L)


def lowest_bending_omega(p: common.HoseProblem, density: float) -> float:
    """First bending eigenfrequency [rad/s] of the clamped-free hose (1.875^2 sqrt(EI / (rho A L^4)))."""
    area = np.pi * p.outer_radius**2
    return 1.8751**2 * np.sqrt(p.bending_stiffness / (density * area * p.length**4))


def _fmt(values) -> str:
    return " ".join(f"{v:.12g}" for v in np.ravel(values))


def _quat(frame: np.ndarray) -> np.ndarray:
    """MuJoCo quaternion (w, x, y, z) of a rotation matrix whose columns are the body axes."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(frame).ravel())
    return q


def build_model_xml(p: common.HoseProblem, segments: int, density: float, timestep: float) -> str:
    """MJCF text of the hose (straight, along t0 from P0) with the end fitting on a mocap body."""
    n = segments
    dl = p.length / n
    s = np.linspace(0.0, p.length, n + 1)
    points = p.start_point + s[:, None] * common.unit(p.start_tangent)
    frame0 = common.start_frame(p)
    mass = density * np.pi * p.outer_radius**2 * p.length
    node_mass = mass / (n + 1)
    edge_mass = mass / n
    edge_polar = 0.5 * edge_mass * p.outer_radius**2  # polar rotary inertia of one edge [t mm^2]
    # Torsion between the clamped last edge and its neighbour acts on the end fitting
    # explicitly; its rotary inertia is raised to k_t h^2 so this mode stays stable.
    # Rotary inertia does not change the equilibrium.
    k_twist = p.torsional_stiffness / (2.0 * dl)
    fitting_polar = max(edge_polar, k_twist * timestep**2)

    nodes = []
    for i in range(2, n - 1):
        nodes.append(
            f'<body name="H_{i}" pos="{_fmt(points[i])}">'
            f'<inertial pos="0 0 0" mass="{node_mass:.12g}" diaginertia="{_fmt([node_mass] * 3)}"/>'
            f'<joint type="slide" axis="1 0 0"/>'
            f'<joint type="slide" axis="0 1 0"/>'
            f'<joint type="slide" axis="0 0 1"/></body>'
        )
    twists = []
    for e in range(1, n - 1):
        twists.append(
            f'<body name="H_twist_{e}"><inertial pos="0 0 0" mass="{edge_mass:.12g}" '
            f'diaginertia="{_fmt([edge_polar] * 3)}"/>'
            f'<joint name="H_twist_{e}" axis="1 0 0"/></body>'
        )
    vertex_bodies = ["world", "world"] + [f"H_{i}" for i in range(2, n - 1)] + ["end_fitting"] * 2
    # Vertex coordinates in their body frames: world for the first two, own body origin for
    # the nodes, and (0, 0, -dl), (0, 0, 0) in the end fitting (its z axis is the tangent).
    vertices = np.concatenate([points[0], points[1], np.zeros(3 * (n - 3)), [0.0, 0.0, -dl], np.zeros(3)])
    elements = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    solref = (EDGE_SOLREF[0] or 2.0 * timestep, EDGE_SOLREF[1])
    q_start = _quat(frame0)
    end0 = common.straight_end_point(p)
    return f"""
<mujoco model="brake_hose">
  <option timestep="{timestep:.12g}" integrator="discrete" solver="Newton" gravity="0 0 0"/>
  <worldbody>
    <body name="end_mount" mocap="true" pos="{_fmt(end0)}" quat="{_fmt(q_start)}">
      <body name="end_fitting">
        <inertial pos="0 0 0" mass="{edge_mass:.12g}" diaginertia="{_fmt([fitting_polar] * 3)}"/>
        <joint name="end_roll" axis="0 0 1"/>
      </body>
    </body>
    {''.join(nodes)}
    {''.join(twists)}
  </worldbody>
  <deformable>
    <flex name="H" dim="1" radius="{p.outer_radius:.12g}" body="{' '.join(vertex_bodies)}"
          vertex="{_fmt(vertices)}" element="{_fmt(elements.astype(int)).replace('.0', '')}">
      <elasticity young="{p.equivalent_youngs_modulus:.12g}" shear="{p.equivalent_shear_modulus:.12g}"/>
      <contact contype="0" conaffinity="0"/>
    </flex>
  </deformable>
  <equality>
    <flex flex="H" solref="{_fmt(solref)}" solimp="{_fmt(EDGE_SOLIMP)}"/>
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
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"H_{i}")
        adr = m.jnt_qposadr[m.body_jntadr[body]]
        d.qpos[adr:adr + 3] += shift[i]


def run(segments: int = 100, twist_deg: float = 180.0, tol_mm: float = 0.01) -> dict:
    """Solve the brake-hose placement with MuJoCo.

    Returns a dict with ``centerline`` ((segments+1, 3) node positions in mm, start to
    end), ``wall_time`` [s], ``sim_steps`` (time steps taken) and ``notes``.
    """
    p = common.BRAKE_HOSE
    wall0 = time.perf_counter()
    omega1 = lowest_bending_omega(p, DENSITY)
    period1 = 2.0 * np.pi / omega1
    h = period1 / STEPS_PER_PERIOD
    m = mujoco.MjModel.from_xml_string(build_model_xml(p, segments, DENSITY, h))
    d = mujoco.MjData(m)
    _apply_perturbation(m, d, p, segments)
    mujoco.mj_forward(m, d)
    runner = _Runner(m, d, DAMPING_PER_OMEGA1 * omega1, check_every=max(1, int(round(CHECK_PERIODS * STEPS_PER_PERIOD))))
    n_ramp = int(round(RAMP_PERIODS * STEPS_PER_PERIOD))
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
        b = _ramp(k, n_ramp)
        m.qpos_spring[roll_q] = free_roll + common.twist_about_tangent(b, twist_deg, p)
        runner.step()
    runner.run_to_rest(tol_mm)

    centerline = runner.centerline()
    length = float(np.sum(np.linalg.norm(np.diff(centerline, axis=0), axis=1)))
    notes = (
        f"MuJoCo {mujoco.__version__} 1D flex elasticity (discrete elastic rod), {segments} elements, "
        f"E={p.equivalent_youngs_modulus:.1f} N/mm^2, G={p.equivalent_shear_modulus:.1f} N/mm^2, "
        f"density={DENSITY:g} t/mm^3, integrator=discrete, h={h:.3e} s, damping rate "
        f"{DAMPING_PER_OMEGA1 * omega1:.1f} 1/s, ramps {n_ramp} steps each; free-roll angle at end of "
        f"place phase {np.degrees(free_roll):.2f} deg, end roll after twist "
        f"{np.degrees(d.qpos[roll_q] - free_roll):.2f} deg; centerline length {length:.3f} mm "
        f"(rest {p.length} mm)"
    )
    return {
        "centerline": centerline,
        "wall_time": time.perf_counter() - wall0,
        "sim_steps": runner.steps,
        "notes": notes,
    }


if __name__ == "__main__":
    result = run()
    cl = result["centerline"]
    print(f"wall time {result['wall_time']:.2f} s, sim steps {result['sim_steps']}")
    print("start node", np.array2string(cl[0], precision=4))
    print("end node  ", np.array2string(cl[-1], precision=4))
    print(result["notes"])
