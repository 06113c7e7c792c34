"""PyElastica peer: the brake-hose placement solved by damped Cosserat-rod dynamics.

Units: mm, N, s; mass in tonnes (t = N s^2 / mm), so density is in t/mm^3.

Model
-----
* ``CosseratRod.straight_rod`` with the hose's outer radius. PyElastica derives the
  section from the radius (I = pi r^4 / 4, J = 2 I), so E = EI / I reproduces EI and
  gives the stretch stiffness EA (axial strains ~1e-4 here). The transverse shear
  stiffness uses G_s = E / 3 (incompressible rubber); the torsional stiffness is set
  to the hose's GJ directly (see :func:`build_rod`).
* Start: ``OneEndFixedBC`` on node 0 and element 0 (position and full frame clamped).
* End: :class:`DrivenEnd`, a constraint that writes the last node position and the
  last element's directors at every stage of the time step (kinematic drive):

  - place phase (free roll): only the end TANGENT is imposed. The current end
    directors are turned by the smallest rotation that brings d3 onto the prescribed
    tangent, and only the angular-velocity component about d3 is kept. The end element
    therefore spins freely about its own axis, driven by the rod's torsional moment,
    so the roll settles where the torque about the tangent vanishes.
  - twist phase: the end frame settled at the end of the place phase is locked and
    rotated about the end mount direction, i.e. the full frame is imposed.

* Damping: ``AnalyticalLinearDamper`` with a uniform rate (1/s) on velocities and
  angular velocities, a multiple of the lowest bending eigenfrequency.
* Time stepping: ``PositionVerlet`` at a fixed fraction of the explicit stability limit.

The end is moved along the path with a smooth (cosine) ramp in time, then the rod is
run to rest: rest = the largest node displacement over one check interval is below
``tol_mm`` after the boundary reached its final value.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from importlib.metadata import version

import elastica as ea
import numpy as np
from numba import njit

try:
    from . import common
except ImportError:  # run as a script from bench/peers
    import common

# Dynamics parameters (they do not change the equilibrium, only how fast it is reached).
DENSITY = 1.3e-9  # t/mm^3 (rubber hose ~1.3 g/cm^3)
CFL = 0.8  # time step / (dl sqrt(rho / E)); 0.9 still ran, 1.0 diverged
DAMPING_PER_OMEGA1 = 2.0  # uniform damping rate / lowest bending eigenfrequency (critical for that mode)
RAMP_PERIODS = 1.0  # duration of each boundary ramp, in lowest bending periods
CHECK_PERIODS = 0.1  # rest-check interval, in lowest bending periods


@njit
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


@dataclass
class EndTarget:
    """Prescribed state of the driven end, updated by the simulation loop between steps.

    position  last-node position [mm]
    tangent   end tangent d3 (imposed when ``free_roll``)
    frame     end directors, rows d1, d2, d3 (imposed when not ``free_roll``)
    free_roll True: only the tangent is imposed and the roll about it is free
    """

    position: np.ndarray
    tangent: np.ndarray
    frame: np.ndarray
    free_roll: bool = True


class DrivenEnd(ea.ConstraintBase):
    """Kinematic drive of the last node and the last element's directors (see :class:`EndTarget`)."""

    def __init__(self, target: EndTarget, **kwargs) -> None:
        super().__init__(**kwargs)
        self.target = target

    def constrain_values(self, system, time: np.float64) -> None:
        system.position_collection[:, -1] = self.target.position
        if self.target.free_roll:
            system.director_collection[..., -1] = _align_tangent(
                np.ascontiguousarray(system.director_collection[..., -1]), self.target.tangent
            )
        else:
            system.director_collection[..., -1] = self.target.frame

    def constrain_rates(self, system, time: np.float64) -> None:
        system.velocity_collection[:, -1] = 0.0
        spin = system.omega_collection[2, -1]  # local (material) components; 2 = about d3
        system.omega_collection[:, -1] = 0.0
        if self.target.free_roll:
            system.omega_collection[2, -1] = spin


class _Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
    pass


def stable_time_step(p: common.HoseProblem, segments: int, density: float) -> float:
    """Time step [s]: CFL fraction of the axial wave time across one element, dl sqrt(rho / E).

    With the shear modulus tied to E and the rotary inertia scaled (see build_rod), the
    axial wave is the fastest mode of the discrete rod.
    """
    dl = p.length / segments
    return CFL * dl * np.sqrt(density / p.equivalent_youngs_modulus)


def build_rod(p: common.HoseProblem, segments: int, density: float, perturb: bool = True):
    """Straight rod from the start mount along t0 with the start frame of common.start_frame().

    Stiffnesses: E = EI / I gives EI and the stretch stiffness EA; the transverse shear
    stiffness uses G_s = E / 3 (incompressible rubber, PyElastica's default); the
    torsional stiffness is then overwritten with the hose's GJ (braided hoses are much
    stiffer in torsion than their rubber). The rotary inertia of the elements is scaled
    by GJ / (G_s J) (about 25) so the torsional wave is no faster than the shear wave.
    The scaling is isotropic: scaling only the polar part made the explicit gyroscopic
    terms unstable while the end was twisted. Rotary inertia does not affect the
    equilibrium, only the stable time step.
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
    rod.mass_second_moment_of_inertia *= inertia_scale
    rod.inv_mass_second_moment_of_inertia /= inertia_scale
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
            shift = common.max_node_shift(current, previous)
            if not np.isfinite(shift):
                raise RuntimeError("PyElastica peer went unstable")
            if shift < tol_mm:
                return
            previous = current
        raise RuntimeError("PyElastica peer did not come to rest")


def _setup(p: common.HoseProblem, segments: int, perturb: bool, add_end):
    """Rod clamped at the start, damped, with ``add_end(sim, rod)`` adding the end condition.

    Returns (runner, rod, ramp_steps, dt, damping_rate).
    """
    sim = _Simulator()
    rod = build_rod(p, segments, DENSITY, perturb)
    sim.append(rod)
    sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
    add_end(sim, rod)
    omega1 = common.lowest_bending_omega(p, DENSITY)
    period1 = 2.0 * np.pi / omega1
    dt = stable_time_step(p, segments, DENSITY)
    damping = DAMPING_PER_OMEGA1 * omega1
    sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=damping, time_step=dt)
    sim.finalize()
    runner = _Runner(sim, rod, dt, check_every=max(1, int(round(CHECK_PERIODS * period1 / dt))))
    return runner, rod, int(round(RAMP_PERIODS * period1 / dt)), dt, damping


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
    frame0 = common.start_frame(p)
    target = EndTarget(common.straight_end_point(p), frame0[:, 2].copy(), frame0.T.copy())
    runner, rod, n_ramp, dt, damping = _setup(
        p, segments, True, lambda sim, rod: sim.constrain(rod).using(DrivenEnd, target=target)
    )

    # Phase "place": end position along the straight line, end tangent turned about n; roll free.
    for k in range(1, n_ramp + 1):
        a = _ramp(k, n_ramp)
        target.position = common.place_position(a, p)
        target.tangent = common.place_tangent(a, p)
        runner.step()
    runner.run_to_rest(tol_mm)
    locked = rod.director_collection[..., -1].copy()  # rows d1, d2, d3
    roll = common.rotation_angle_about(p.end_tangent, common.place_orientation(1.0, p)[:, 0], locked[0])

    # Phase "twist": lock the settled end frame and turn it about the end mount direction.
    target.free_roll = False
    for k in range(1, n_ramp + 1):
        target.frame = locked @ common.twist_rotation(_ramp(k, n_ramp), twist_deg, p).T
        runner.step()
    runner.run_to_rest(tol_mm)

    notes = (
        f"PyElastica {version('pyelastica')} CosseratRod, {segments} elements, "
        f"E={p.equivalent_youngs_modulus:.1f} N/mm^2, shear G_s=E/3, GJ={p.torsional_stiffness:g} N mm^2, "
        f"rotary inertia x{p.torsional_stiffness / (p.equivalent_youngs_modulus / 3 * 2 * p.section_inertia):.1f}, "
        f"density={DENSITY:g} t/mm^3, PositionVerlet dt={dt:.3e} s, uniform damping {damping:.1f} 1/s, "
        f"ramps {n_ramp} steps each; free-roll angle at end of place phase {np.degrees(roll):.2f} deg"
    )
    return common.outcome(runner.centerline(), wall0, runner.steps, notes, p.length)


def cantilever(
    segments: int = 100, load_parameter: float = common.CANTILEVER_LOAD_PARAMETER, tol_mm: float = 1e-4
) -> dict:
    """Clamped cantilever (the hose data, straight from the start mount) under a transverse tip dead load.

    The load P = load_parameter * EI / L^2 acts along d1 of the start frame, ramped in
    over one ramp duration, then the rod is run to rest. Returns tip deflection and tip
    shortening divided by L, and the step count.
    """
    p = common.BRAKE_HOSE
    frame0 = common.start_frame(p)
    load = load_parameter * p.bending_stiffness / p.length**2 * frame0[:, 0]
    ramp_time = RAMP_PERIODS * 2.0 * np.pi / common.lowest_bending_omega(p, DENSITY)

    def add_load(sim, rod):
        sim.add_forcing_to(rod).using(ea.EndpointForces, np.zeros(3), load, ramp_up_time=ramp_time)

    runner, rod, n_ramp, _, _ = _setup(p, segments, False, add_load)
    runner.step(n_ramp)
    runner.run_to_rest(tol_mm)
    tip = rod.position_collection[:, -1] - p.start_point
    return common.cantilever_outcome(tip, frame0, runner.steps, p)


if __name__ == "__main__":
    common.print_outcome(run())
