"""PyElastica peer: the brake-hose placement solved by damped Cosserat-rod dynamics.

Units: mm, N, s; mass in tonnes (t = N s^2 / mm), so density is in t/mm^3.

Model
-----
* ``CosseratRod.straight_rod`` with the hose's outer radius. PyElastica derives the
  section from the radius (I = pi r^4 / 4, J = 2 I), so E = EI / I and G = GJ / J
  reproduce EI and GJ exactly. The same E and G give the stretch stiffness EA and the
  shear stiffness (27/28) G A, so the rod is nearly inextensible (strains ~1e-4 here).
* Start: ``OneEndFixedBC`` on node 0 and element 0 (position and full frame clamped).
* End: :class:`DrivenEnd`, a constraint that writes the last node position and the
  last element's directors every stage of the time step (kinematic drive):

  - place phase (free roll): only the end TANGENT is imposed. The current end
    directors are turned by the smallest rotation that brings d3 onto the prescribed
    tangent, and only the angular-velocity component about d3 is kept. The end element
    therefore spins freely about its own axis, driven by the rod's torsional moment,
    so the roll settles where the torque about the tangent vanishes.
  - twist phase: the end frame settled at the end of the place phase is locked and
    rotated about the end mount direction, i.e. the full frame is imposed.

* Damping: ``AnalyticalLinearDamper`` with a uniform rate (1/s) on velocities and
  angular velocities, tuned near critical for the lowest bending mode.
* Time stepping: ``PositionVerlet`` at a fixed fraction of the explicit stability limit.

The end is moved along the path with a smooth (cosine) ramp in time, then the rod is
run to rest: rest = the largest node displacement over one check interval is below
``tol_mm`` after the boundary reached its final value.
"""

from __future__ import annotations

import time

import elastica as ea
import numpy as np
from numba import njit

try:
    from . import common
except ImportError:  # run as a script from bench/peers
    import common

# Dynamics parameters (they do not change the equilibrium, only how fast it is reached).
DENSITY = 1.3e-9  # t/mm^3 (rubber hose ~1.3 g/cm^3)
CFL = 0.6  # time step as a fraction of the axial wave time across one element
DAMPING_PER_OMEGA1 = 1.5  # uniform damping rate / lowest bending eigenfrequency of the clamped hose
RAMP_PERIODS = 6.0  # duration of each boundary ramp, in lowest bending periods
CHECK_PERIODS = 0.1  # rest-check interval, in lowest bending periods


@njit(cache=True)
def _align_tangent(director: np.ndarray, tangent: np.ndarray) -> np.ndarray:
    """Turn a director matrix (rows d1, d2, d3) by the smallest rotation taking d3 to ``tangent``.

    The result is re-orthonormalised (d3 = tangent, d1 made normal to it, d2 = d3 x d1)
    so round-off cannot accumulate over millions of calls.
    """
    d1 = director[0].copy()
    d3 = director[2] / np.linalg.norm(director[2])
    axis = np.cross(d3, tangent)
    s = np.linalg.norm(axis)
    if s > 1e-14:
        k = axis / s
        c = np.dot(d3, tangent)
        d1 = c * d1 + s * np.cross(k, d1) + (1.0 - c) * np.dot(k, d1) * k
    d1 = d1 - np.dot(d1, tangent) * tangent
    d1 = d1 / np.linalg.norm(d1)
    out = np.empty((3, 3))
    out[0] = d1
    out[1] = np.cross(tangent, d1)
    out[2] = tangent
    return out


class DrivenEnd(ea.ConstraintBase):
    """Kinematic drive of the last node and last element of the rod.

    The driver attributes are set by the simulation loop between time steps:

    ``position``  prescribed last-node position [mm], shape (3,)
    ``tangent``   prescribed end tangent (used when ``free_roll`` is True)
    ``frame``     prescribed end directors, rows d1, d2, d3 (used when ``free_roll`` is False)
    ``free_roll`` True: only the tangent is imposed, the roll about it is free.
    """

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        rod = self._system
        self.position = rod.position_collection[:, -1].copy()
        self.frame = rod.director_collection[..., -1].copy()
        self.tangent = self.frame[2].copy()
        self.free_roll = True

    def constrain_values(self, system, time: np.float64) -> None:
        system.position_collection[:, -1] = self.position
        if self.free_roll:
            system.director_collection[..., -1] = _align_tangent(
                np.ascontiguousarray(system.director_collection[..., -1]), self.tangent
            )
        else:
            system.director_collection[..., -1] = self.frame

    def constrain_rates(self, system, time: np.float64) -> None:
        system.velocity_collection[:, -1] = 0.0
        spin = system.omega_collection[2, -1]  # local (material) components, index 2 = about d3
        system.omega_collection[:, -1] = 0.0
        if self.free_roll:
            system.omega_collection[2, -1] = spin


class _Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
    pass


def lowest_bending_omega(p: common.HoseProblem, density: float) -> float:
    """First bending eigenfrequency [rad/s] of the clamped-free hose (1.875^2 sqrt(EI / (rho A L^4)))."""
    area = np.pi * p.outer_radius**2
    return 1.8751**2 * np.sqrt(p.bending_stiffness / (density * area * p.length**4))


def stable_time_step(p: common.HoseProblem, segments: int, density: float) -> float:
    """Time step [s]: CFL fraction of the axial wave time across one element, dl sqrt(rho / E).

    With the shear modulus tied to E and the torsional rotary inertia scaled (see
    build_rod), the axial wave is the fastest mode of the discrete rod.
    """
    dl = p.length / segments
    return CFL * dl * np.sqrt(density / p.equivalent_youngs_modulus)


def build_rod(p: common.HoseProblem, segments: int, density: float, perturb: bool = True):
    """Straight rod from the start mount along t0 with the start frame of common.start_frame().

    Stiffnesses: E = EI / I gives EI and the stretch stiffness EA; the transverse shear
    stiffness uses G_s = E / 3 (incompressible rubber, PyElastica's default); the
    torsional stiffness is then overwritten with the hose's GJ (braided hoses are much
    stiffer in torsion than their rubber). The polar rotary inertia is scaled by
    GJ / (G_s J) so the torsional wave is no faster than the shear wave; rotary
    inertia does not affect the equilibrium, only the stable time step.
    """
    frame = common.start_frame(p)
    shear_modulus = p.equivalent_youngs_modulus / 3.0
    rod = ea.CosseratRod.straight_rod(
        n_elements=segments,
        start=p.start_point.astype(float),
        direction=frame[:, 2],
        normal=frame[:, 0].copy(),
        base_length=p.length,
        base_radius=p.outer_radius,
        density=density,
        youngs_modulus=p.equivalent_youngs_modulus,
        shear_modulus=shear_modulus,
    )
    rod.bend_matrix[2, 2, :] = p.torsional_stiffness
    inertia_scale = p.torsional_stiffness / (shear_modulus * 2.0 * p.section_inertia)
    rod.mass_second_moment_of_inertia[2, 2, :] *= inertia_scale
    rod.inv_mass_second_moment_of_inertia[2, 2, :] /= inertia_scale
    if perturb:
        s = np.linspace(0.0, p.length, segments + 1)
        rod.position_collection += common.perturbation_shape(s, p).T
    return rod


class _Runner:
    """Steps the simulator and tracks step count and rest detection."""

    def __init__(self, sim, rod, dt: float, check_every: int):
        self.sim, self.rod, self.dt, self.check_every = sim, rod, dt, check_every
        self.stepper = ea.PositionVerlet()
        self.time = np.float64(0.0)
        self.steps = 0

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            self.time = self.stepper.step(self.sim, self.time, self.dt)
        self.steps += n

    def centerline(self) -> np.ndarray:
        return self.rod.position_collection.T.copy()

    def run_to_rest(self, tol_mm: float, max_checks: int = 100000) -> None:
        previous = self.centerline()
        for _ in range(max_checks):
            self.step(self.check_every)
            current = self.centerline()
            if common.max_node_shift(current, previous) < tol_mm:
                return
            previous = current
        raise RuntimeError("PyElastica peer did not come to rest")


def _ramp(k: int, n: int) -> float:
    """Smooth ramp 0 -> 1 over n steps (zero start and end velocity)."""
    return 0.5 - 0.5 * np.cos(np.pi * k / n)


def run(segments: int = 100, twist_deg: float = 180.0, tol_mm: float = 0.01) -> dict:
    """Solve the brake-hose placement with PyElastica.

    Returns a dict with ``centerline`` ((segments+1, 3) node positions in mm, start to
    end), ``wall_time`` [s], ``sim_steps`` (time steps taken) and ``notes``.
    """
    p = common.BRAKE_HOSE
    wall0 = time.perf_counter()

    sim = _Simulator()
    rod = build_rod(p, segments, DENSITY)
    sim.append(rod)
    sim.constrain(rod).using(
        ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,)
    )
    end_bc: list[DrivenEnd] = []
    sim.constrain(rod).using(_Recorder(end_bc, DrivenEnd))

    omega1 = lowest_bending_omega(p, DENSITY)
    period1 = 2.0 * np.pi / omega1
    dt = stable_time_step(p, segments, DENSITY)
    sim.dampen(rod).using(
        ea.AnalyticalLinearDamper, uniform_damping_constant=DAMPING_PER_OMEGA1 * omega1, time_step=dt
    )
    sim.finalize()
    end = end_bc[0]
    runner = _Runner(sim, rod, dt, check_every=max(1, int(round(CHECK_PERIODS * period1 / dt))))
    n_ramp = int(round(RAMP_PERIODS * period1 / dt))

    # Phase "place": end position along the straight line, end tangent turned about n; roll free.
    end.free_roll = True
    for k in range(1, n_ramp + 1):
        a = _ramp(k, n_ramp)
        end.position = common.place_position(a, p)
        end.tangent = common.place_tangent(a, p)
        runner.step()
    runner.run_to_rest(tol_mm)
    locked = rod.director_collection[..., -1].copy()  # rows d1, d2, d3
    roll = common.rotation_angle_about(
        p.end_tangent, common.place_orientation(1.0, p)[:, 0], locked[0]
    )

    # Phase "twist": lock the settled end frame and turn it about the end mount direction.
    end.free_roll = False
    for k in range(1, n_ramp + 1):
        b = _ramp(k, n_ramp)
        end.frame = locked @ common.twist_rotation(b, twist_deg, p).T
        runner.step()
    runner.run_to_rest(tol_mm)

    centerline = runner.centerline()
    length = float(np.sum(np.linalg.norm(np.diff(centerline, axis=0), axis=1)))
    notes = (
        f"PyElastica {ea.version.VERSION if hasattr(ea, 'version') else ''} CosseratRod, "
        f"{segments} elements, E={p.equivalent_youngs_modulus:.1f} N/mm^2, "
        f"G={p.equivalent_shear_modulus:.1f} N/mm^2, density={DENSITY:g} t/mm^3, dt={dt:.3e} s, "
        f"uniform damping {DAMPING_PER_OMEGA1 * omega1:.1f} 1/s, ramps {n_ramp} steps each; "
        f"free-roll angle at end of place phase {np.degrees(roll):.2f} deg; "
        f"centerline length {length:.3f} mm (rest {p.length} mm)"
    )
    return {
        "centerline": centerline,
        "wall_time": time.perf_counter() - wall0,
        "sim_steps": runner.steps,
        "notes": notes,
    }


def _Recorder(store: list, cls):
    """Wrap a constraint class so the instance PyElastica creates at finalize() is kept in ``store``."""

    class Recorded(cls):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            store.append(self)

    return Recorded


if __name__ == "__main__":
    result = run()
    cl = result["centerline"]
    print(f"wall time {result['wall_time']:.2f} s, sim steps {result['sim_steps']}")
    print("start node", np.array2string(cl[0], precision=4))
    print("end node  ", np.array2string(cl[-1], precision=4))
    print(result["notes"])
