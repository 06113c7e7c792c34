"""Newton's method for the rod with frictionless contact: the rod's Lagrangian plus the barrier energy.

The rod's terms come from newton.evaluate (clips included: clipped_newton through it), the
contact terms from contact.py.  The contact Hessian couples every segment before a station in
contact (contact.py), but only through the stations: it is the banded rod Hessian plus a
low-rank term, and contact_solve.py solves the KKT system [[H, J^T], [J, 0]] with the banded
factor bordered by the constraint rows and the low-rank columns, which also gives the number of
unstable directions on the constraint tangent space (neg(KKT) - m, as in banded.py).  Where that
factor is not to be trusted it falls back to the dense matrix and LAPACK's sytrf.

Step filter (StepFilter).  No step may cross into an obstacle or the hose itself: a rotation
delta_i moves every station beyond segment i by at most h |delta_i| (a rotation by an angle moves
a unit vector by less than the angle), which bounds how far each pair can approach along the
step.  The step is cut so that no primitive can pass through the body it faces (its diameter;
a plane is infinitely thick), and a trial state is accepted only if every gap it could have
closed stays above a tenth of its value: a primitive cannot cross a body without ending inside
it or passing through it, so no accepted step crosses into penetration.  Then the step is
halved until the residual falls (the tracking Newton of newton.py).

Restoring steps.  The constraint rows are linear: a step that turns a long stretch of hose by an
angle theta (on the issue's strut, the half beyond the clip rolling about the line from the clip to
the end, 0.46 rad in one step) leaves the end or a clip off its point by about its length times
theta^2 / 2 (6.5 mm there), and the residual of that trial rises however far its energy fell: the
line search cut those steps to 1/16 and 1/32 for twenty iterations in a row (the Maratos effect).
Where the residual does not fall, the trial is moved back onto the constraints (least-norm
Gauss-Newton steps, _onto_constraints: a second-order correction) and taken if the state's KKT
inertia is stable (the step goes downhill on the constraints' tangent space), nothing is within the
barrier's reach at the state, the trial and the restored trial (the rod alone; near an obstacle the
residual decides, and a fold beyond which the hose slides off is met by the path as before), the
restored trial is on the constraints to RESTORED_OFF of the length with an energy below the state's
Lagrangian E - lambda.c (its energy on the constraints, to first order), and the move there passes
the move check of moving obstacles (hose_move_clear).  It is a longer step along Newton's own
direction from a stable state, toward the minimum the shorter steps would reach: the issue's strut
took 546 Newton iterations instead of 579, the loop of bench/bench_contact_placement.py 318
instead of 409, to the same equilibria (1e-11 mm; tests/test_contact_restoring.py).

Downhill mode (minimise_with_contact): the shifted Newton of newton._minimise_kernel with the same
step filter, judged by the total energy with the barrier (see its docstring); used after folds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg

from hoseline.mechanics.blas_threads import one_blas_thread
from hoseline.mechanics.banded import NEUTRAL, band_to_dense, banded_matvec
from hoseline.mechanics.clipped_newton import clip_forces, segment_unknowns
from hoseline.mechanics.contact import (
    MESH_KINDS,
    PAIR_KINDS,
    SEGMENT_BALL,
    SEGMENT_CAPSULE,
    SEGMENT_EDGE,
    SEGMENT_SEGMENT,
    STATION_KINDS,
    STATION_PLANE,
    node_terms,
    pair_gaps,
    rotation_terms,
)
from hoseline.mechanics.contact_mesh import MeshArrays, swept_edges_clear
from hoseline.mechanics.contact_solve import (
    banded_step,
    dense_step,
    log_abs_det,
    kkt_solves,
    low_rank_columns,
    rotation_gradient_and_band,
)
from hoseline.mechanics.newton import NewtonReport, RodProperties, apply_step, evaluate
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.mechanics.step_pairs import pairs_clear, watched_pairs

SAFE_FRACTION = 0.1  # a step may shrink no gap below this fraction of its value
RESTORED_OFF = 1e-9  # relative to the hose length: the farthest a restored trial may stay off its constraints
RESTORED_FALL = 1e-12  # relative: how much lower a restored trial's energy must be than the state's (rounding)
STALLED_STEP = 1.0 / 64.0  # of a Newton step: a step cut below it makes no headway (solve_with_contact's stall)
SWEPT_EVALUATIONS = 256  # distances per segment-edge pair in the swept check of a step (contact_mesh.swept_edges_clear)


@dataclass(frozen=True)
class ContactModel:
    """What the hose may touch, packed for the kernels (internal units: mm, N).

    hose_radius: outer radius, mm.  activation: barrier distance d_hat, mm (pairs closer than it
    push).  stiffness: barrier stiffness kappa, N/mm^2 (see docs/model.md, Contact).
    planes (P, 6): point, unit normal.  balls (S, 4): centre, radius.  capsules (C, 7): axis
    start, axis end, radius.  owners_*: index into `names` of each primitive's obstacle.
    mesh: the triangle meshes and boxes (contact_mesh.MeshArrays, with their owners).
    self_exclusion: segments i < j can touch when j - i > self_exclusion; -1: no self-contact.
    """

    hose_radius: float
    activation: float
    stiffness: float
    planes: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    balls: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    capsules: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))
    owners_planes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    owners_balls: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    owners_capsules: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    mesh: MeshArrays = field(default_factory=MeshArrays)
    names: tuple[str, ...] = ()
    self_exclusion: int = -1

    def pairs(self, nodes: np.ndarray, cutoff: float, *, meshes: bool = True, stop_inside: bool = False):
        """(kinds, first, second, gaps) of every pair with a gap below `cutoff` mm (contact.pair_gaps); the mesh pairs
        (contact_mesh.mesh_pairs) only below the smaller of `cutoff` and d_hat (the barrier's: a mesh has too many
        to list them all), none without `meshes`.  stop_inside: of a mesh the hose is inside, only the first pair
        found inside (MeshArrays.pairs)."""
        found = pair_gaps(nodes, self.hose_radius, self.planes, self.balls, self.capsules, self.self_exclusion, cutoff)
        if not meshes or self.mesh.count == 0:
            return found
        on_meshes = self.mesh.pairs(nodes, self.hose_radius, min(cutoff, self.activation), stop_inside=stop_inside)
        return tuple(np.concatenate([a, b]) for a, b in zip(found, on_meshes))

    def terms(self, nodes: np.ndarray, weight: float, kinds, first, second):
        """contact.node_terms of the pairs (kinds, first, second) with this model's obstacles; weight: kappa h, N/mm."""
        return node_terms(nodes, self.hose_radius, weight, self.activation, self.planes, self.balls, self.capsules,
                          self.mesh.triangles, self.mesh.edges, self.mesh.planar, kinds, first, second)

    def with_activation(self, activation: float) -> ContactModel:
        """The same obstacles and reference pressure (kappa d_hat) with the barrier acting across `activation` mm."""
        return replace(self, activation=activation, stiffness=self.stiffness * self.activation / activation)

    def owner(self, kind: int, second: int) -> str:
        """Name of the obstacle of a pair ("self" for self-contact)."""
        if kind == SEGMENT_SEGMENT:
            return "self"
        if kind in MESH_KINDS:
            return self.names[self.mesh.owner(kind, second)]
        owners = (self.owners_planes, self.owners_balls, self.owners_capsules)[kind]
        return self.names[int(owners[second])]

    def penetration(self, nodes: np.ndarray) -> str | None:
        """What the hose with centreline `nodes` (mm) is inside or touching, where and by how much; None if it clears all."""
        kinds, first, second, gaps = self.pairs(nodes, 0.0, meshes=False)
        if kinds.size:
            worst = int(np.argmin(gaps))
            return penetration_message(self, kinds[worst], first[worst], second[worst], gaps[worst])
        if self.mesh.count:
            mesh_gaps, nearest = self.mesh.segment_gaps(nodes[:-1], nodes[1:], self.hose_radius, 0.0)
            if np.any(nearest >= 0):
                mesh, segment = np.unravel_index(int(np.argmin(mesh_gaps)), mesh_gaps.shape)
                return (f"the hose is inside obstacle {self.names[int(self.mesh.owners[mesh])]!r} at segment {segment} "
                        f"by {-mesh_gaps[mesh, segment]:.4g} mm (segment-triangle)")
        return None

    def smallest_gaps(self, nodes: np.ndarray, within: float = math.inf, beyond: float = math.inf) -> dict[str, float]:
        """The smallest gap (mm, surface to surface) of the hose with centreline `nodes` to each obstacle (and "self");
        for a mesh farther than `within` mm inf, and one bounded below by at least `beyond` mm that bound
        (MeshArrays.smallest_gaps)."""
        smallest = {name: math.inf for name in self.names} | ({"self": math.inf} if self.self_exclusion >= 0 else {})
        (kinds, second, gaps), mesh_gaps, itself = self._all_gaps(nodes, within, beyond)
        if self.self_exclusion >= 0:
            smallest["self"] = itself
        for kind, owners in zip((STATION_PLANE, SEGMENT_BALL, SEGMENT_CAPSULE),
                                (self.owners_planes, self.owners_balls, self.owners_capsules)):
            of_kind = kinds == kind
            for owner in np.unique(owners[second[of_kind]]):
                name = self.names[int(owner)]
                smallest[name] = min(smallest[name], float(np.min(gaps[of_kind][owners[second[of_kind]] == owner])))
        for mesh in range(self.mesh.count):
            name = self.names[int(self.mesh.owners[mesh])]
            smallest[name] = min(smallest[name], float(mesh_gaps[mesh]))
        return smallest

    def smallest_gap(self, nodes: np.ndarray) -> float:
        """The smallest gap (mm, surface to surface) of the hose with centreline `nodes` to anything it may touch."""
        (_, _, gaps), mesh_gaps, itself = self._all_gaps(nodes)
        return float(min(np.min(gaps, initial=math.inf), np.min(mesh_gaps, initial=math.inf), itself))

    def _all_gaps(self, nodes: np.ndarray, within: float = math.inf, beyond: float = math.inf):
        """((kinds, second, gaps) of every analytic obstacle's pair, the smallest gap (K,) to each mesh (inf farther
        than `within` mm, a lower bound where that is at least `beyond` mm), the smallest self-contact gap (inf
        without self-contact))."""
        no_self = -1
        kinds, _, second, gaps = pair_gaps(nodes, self.hose_radius, self.planes, self.balls, self.capsules, no_self,
                                           math.inf)
        mesh_gaps = self.mesh.smallest_gaps(nodes[:-1], nodes[1:], self.hose_radius, self.activation, within, beyond)
        return (kinds, second, gaps), mesh_gaps, self._smallest_self_gap(nodes)

    def _smallest_self_gap(self, nodes: np.ndarray) -> float:
        """The smallest gap (mm) between segments that may touch (inf without self-contact): the pairs below a cutoff
        that grows eightfold from d_hat until one is found, or until it spans the hose (every pair of a long hose, N^2 / 2
        distances, at every pose of a sweep cost more than the solve)."""
        if self.self_exclusion < 0:
            return math.inf
        span = float(np.linalg.norm(np.ptp(nodes, axis=0)))
        nothing, no_balls, no_capsules = np.zeros((0, 6)), np.zeros((0, 4)), np.zeros((0, 7))
        cutoff = self.activation
        while True:
            gaps = pair_gaps(nodes, self.hose_radius, nothing, no_balls, no_capsules, self.self_exclusion, cutoff)[3]
            if gaps.size or cutoff > span:
                return float(np.min(gaps, initial=math.inf))
            cutoff *= 8.0


def self_exclusion(hose_radius: float, segment_length: float) -> int:
    """Segments i < j may touch when j - i exceeds this: their arc-length gap (j - i - 1) h is at
    least pi r, the tightest U-turn of two touching passes (a straight hose has them 2r + apart)."""
    return int(math.ceil(math.pi * hose_radius / segment_length))


@dataclass
class ContactSystem:
    """The rod's Lagrangian with contact at one state: Hessian, constraint, residual, active pairs.

    The Hessian is band + columns diag(signs) columns^T (contact_solve.py): band, the rod's and the
    contact's segment-load blocks (lower band storage); columns (n, r) and signs (r,) of +-1, the
    station term, worked out when first asked for (a trial of the line search that is refused needs
    only the residual).  dense() assembles it as one matrix by contact.rotation_terms, independently.
    """

    energy: float
    grad: np.ndarray
    band: np.ndarray
    jac_t: np.ndarray
    constraint: np.ndarray
    residual: float
    pairs: tuple  # (kinds, first, second) of the active pairs (gap < activation)
    forces: np.ndarray  # (pairs, 3) N on the hose
    on_hose: np.ndarray
    on_other: np.ndarray
    gaps: np.ndarray
    stations: tuple  # (rod band, frames, h, node_grad, node_hess, index): what dense() and the columns come from
    _low_rank: tuple | None = None

    @property
    def columns(self) -> np.ndarray:
        """U (n, r) of the station term U diag(signs) U^T (contact_solve.low_rank_columns)."""
        return self._columns_and_signs()[0]

    @property
    def signs(self) -> np.ndarray:
        """sigma (r,) of +-1 of the station term U diag(signs) U^T."""
        return self._columns_and_signs()[1]

    def _columns_and_signs(self) -> tuple[np.ndarray, np.ndarray]:
        if self._low_rank is None:
            _, frames, h, _, node_hess, index = self.stations
            if index is None:
                self._low_rank = np.zeros((self.grad.size, 0)), np.zeros(0)
            else:
                self._low_rank = low_rank_columns(frames, h, node_hess, *self.pairs, index, self.grad.size)
        return self._low_rank

    def dense(self) -> np.ndarray:
        """The Hessian (n, n) assembled dense: the rod's band and contact.rotation_terms (suffix sums, O(N^2))."""
        rod_band, frames, h, node_grad, node_hess, index = self.stations
        hess = band_to_dense(rod_band)
        if index is not None:
            rows = (index[:, None] + np.arange(3)[None, :]).reshape(-1)
            hess[np.ix_(rows, rows)] += rotation_terms(frames, h, node_grad, node_hess)[1]
        return hess


def rotation_index(props: RodProperties, clamps: Clamps) -> np.ndarray:
    """Index of each segment's first rotation unknown (N,) in the system of newton.evaluate."""
    if not clamps.clips:
        return 3 * np.arange(props.segments)
    return segment_unknowns(props.segments, clamps)


def evaluate_contact(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> ContactSystem:
    """Assemble the Lagrangian with the barrier energy at a state (internal units)."""
    base = evaluate(props, clamps, state)
    h = props.segment_length
    nodes = centerline(state.frames, clamps.start_point, h)
    kinds, first, second, _ = model.pairs(nodes, model.activation, stop_inside=True)  # inside: the energy is inf
    weight = model.stiffness * h
    energy, node_grad, node_hess, forces, on_hose, on_other, gaps = model.terms(nodes, weight, kinds, first, second)
    grad = base.grad.copy()
    band = base.band.copy()
    index = None
    if kinds.size:
        index = rotation_index(props, clamps)
        grad += rotation_gradient_and_band(state.frames, h, node_grad, index, band)
    clip_force = clip_forces(clamps, state).ravel()
    # norms as np.linalg.norm takes them (the square root of the dot product), without its overhead
    end_forces = math.sqrt(state.end_force @ state.end_force) + math.sqrt(clip_force @ clip_force)
    contact_total = float(np.sum(np.linalg.norm(forces, axis=1))) if kinds.size else 0.0
    weight_total = math.sqrt(clamps.line_weight @ clamps.line_weight) * props.length
    scale = props.largest_stiffness / props.length + (end_forces + weight_total + contact_total) * props.length
    residual = max(float(np.max(np.abs(grad))) / scale, float(np.max(np.abs(base.constraint))) / props.length)
    return ContactSystem(base.energy + energy, grad, band, base.jac_t, base.constraint, residual,
                         (kinds, first, second), forces, on_hose, on_other, gaps,
                         (base.band, state.frames, h, node_grad, node_hess, index))


def _kkt_step(system: ContactSystem, shift: float = 0.0) -> tuple[np.ndarray, np.ndarray, int, float]:
    """(step, multiplier step, unstable directions on the constraint tangent space, the pivots of the solve, whose
    contact_solve.log_abs_det is that of the KKT matrix) of the KKT system.

    The banded factor with the low-rank border (contact_solve.banded_step); the dense matrix and
    LAPACK's sytrf where that is not to be trusted (counted in contact_solve.kkt_solves).
    shift: sigma of the Hessian H + sigma I (the downhill mode, minimise_with_contact), N*mm/rad^2.
    """
    band = system.band
    if shift != 0.0:
        band = band.copy()
        band[:, 0] += shift
    solved = banded_step(band, system.jac_t, system.columns, system.signs, system.grad, system.constraint)
    if solved is not None:
        kkt_solves["banded"] += 1
        return solved
    kkt_solves["dense"] += 1
    hess = system.dense()
    hess[np.diag_indices_from(hess)] += shift
    return dense_step(hess, system.jac_t, system.grad, system.constraint)


def tangent_log_det(jac_t: np.ndarray, pivots) -> float:
    """log |det| of the Hessian on the constraint tangent space, from the pivots of the KKT solve (_kkt_step) and the
    constraint Jacobian's transpose jac_t: det KKT = (-1)^m det(Jc Jc^T) det(Z^T H Z) for an orthonormal basis Z of the
    tangent space (NaN where Jc is rank deficient or the solve failed)."""
    if pivots is None:
        return math.nan
    kkt_log_det = log_abs_det(*pivots)
    if jac_t.shape[1] == 0:
        return kkt_log_det
    gram, info = scipy.linalg.lapack.dpotrf(jac_t.T @ jac_t)  # Cholesky: det = prod(diagonal)^2
    return kkt_log_det - 2.0 * float(np.sum(np.log(np.diagonal(gram)))) if info == 0 else math.nan


@dataclass
class StepFilter:
    """The pairs a step could bring into contact, their gaps (mm) now, and the largest fraction of the step.

    A rotation delta_i moves every station beyond segment i by at most h |delta_i| per unit of the
    step, so a pair further apart than that (plus d_hat) cannot be reached and is not watched.
    limit: no primitive can pass through the body it faces: the fraction of the step is kept below
    (gap + thickness) / move bound, the thickness being the other body's diameter (infinite for a
    plane); the pairs are watched for the step cut to the limit (step_pairs.watched_pairs).  A trial
    state is accepted only if every watched gap stays above SAFE_FRACTION of its value (`admits`, at
    no more than the limit); as a primitive cannot cross a body without ending inside it or passing
    through it, no accepted step crosses into penetration.
    Meshes are surfaces, not bodies (contact_mesh.py, step filter): the whole path of every station
    and of every segment near an edge must stay clear by SAFE_FRACTION of its gap now.  swept: (the
    stations now (N+1, 3) mm, the reach (N+1,) mm within which their gaps to the meshes matter, the
    bound (N+1,) mm of each station path's distance from its chord for the whole step), or None
    without meshes.  The stations' gaps and the segment-edge pairs are found at each trial, within
    the reach of its real move (the chords of its stations and their bend: far tighter than the bound
    of the whole step, which on a fine mesh took every station and thousands of edges in); the
    stations' gaps are kept for the trials after (a halved step's reach is mostly within the last's).
    """

    pairs: tuple
    gaps: np.ndarray
    limit: float
    swept: tuple | None = None
    _station_gaps: tuple | None = None  # (bounds (N+1,) mm, the stations' mesh gaps, inf at or beyond the bound)

    def admits(self, props: RodProperties, clamps: Clamps, trial: RodState, model: ContactModel, alpha: float) -> bool:
        """Whether the trial state, `alpha` times the step, keeps every watched gap above SAFE_FRACTION of its value."""
        return self.admits_centerline(centerline(trial.frames, clamps.start_point, props.segment_length), model, alpha)

    def admits_centerline(self, nodes: np.ndarray, model: ContactModel, alpha: float) -> bool:
        """Whether the hose with centreline `nodes` (N+1, 3) mm, `alpha` times the move, keeps every watched gap above
        SAFE_FRACTION of its value.  alpha may not exceed the limit: the pairs are watched for the move cut to it."""
        if alpha > self.limit:
            raise ValueError(f"a trial at {alpha} of the move, beyond the step filter's limit {self.limit}")
        kinds, first, second = self.pairs  # the analytic pairs first: their check costs least
        if self.gaps.size and not pairs_clear(nodes, model.hose_radius, model.planes, model.balls, model.capsules,
                                              model.mesh.triangles, model.mesh.edges, kinds, first, second,
                                              SAFE_FRACTION * self.gaps):
            return False
        return self.swept is None or self._paths_clear(nodes, model, alpha)

    def _paths_clear(self, nodes: np.ndarray, model: ContactModel, alpha: float) -> bool:
        """Whether every station and every segment near a mesh edge stays clear of the meshes along its path, by
        SAFE_FRACTION of its gap now.

        The path of station k lies within alpha^2 bend_k of its chord (contact_mesh.py), so its gap along the
        step is at least the chord's gap less that; a segment's points within alpha^2 bend of the segment
        carried along its ends' chords (contact_mesh.swept_edges_clear)."""
        start, reach, bend = self.swept
        bend = alpha * alpha * bend
        # how far each station, and each segment's points, can be from where they are now along the move: its chord
        # and the bend; a station or segment-edge pair whose gap cannot shrink to SAFE_FRACTION of it by that much
        # is clear whatever the path (as `watched` for the analytic pairs), and is not checked
        moves = np.linalg.norm(nodes - start, axis=1) + bend
        closable = moves / (1.0 - SAFE_FRACTION)  # a station farther than this is clear: its gap is not measured
        gaps = self._gaps_below(model, np.minimum(reach, closable * (1.0 + 1e-9) + 1e-9))
        near = (1.0 - SAFE_FRACTION) * gaps <= moves  # False where the gap is inf (out of reach)
        if np.any(near):
            needed = SAFE_FRACTION * gaps[near] + bend[near]  # a chord farther than this is clear: no need to know more
            chord_gaps = np.min(model.mesh.segment_gaps(start[near], nodes[near], model.hose_radius,
                                                        needed + 1e-9 * (1.0 + needed))[0], axis=0)
            if not np.all(chord_gaps - bend[near] > SAFE_FRACTION * gaps[near]):
                return False
        segment_moves = np.maximum(moves[:-1], moves[1:])
        kinds, segments, edges, edge_gaps = model.mesh.pairs(start, model.hose_radius,
                                                             (np.full(start.shape[0], -np.inf),  # no stations
                                                              (1.0 + 1e-9) * segment_moves / (1.0 - SAFE_FRACTION)),
                                                             every_feature=True)
        on_edges = kinds == SEGMENT_EDGE
        segments, edges, edge_gaps = segments[on_edges], edges[on_edges], edge_gaps[on_edges]
        clearances = model.hose_radius + SAFE_FRACTION * edge_gaps + bend[segments + 1]
        return bool(swept_edges_clear(start, nodes, segments, edges, model.mesh.edges, clearances, SWEPT_EVALUATIONS))

    def _gaps_below(self, model: ContactModel, bounds: np.ndarray) -> np.ndarray:
        """The stations' gaps (N+1,) mm to the meshes where below `bounds` (mm), inf where not: from the last trial's
        where its bounds were as long (a gap is known exactly below the bound it was sought within), else sought."""
        if self._station_gaps is None or np.any(bounds > self._station_gaps[0]):
            sought = model.mesh.station_gaps(self.swept[0], model.hose_radius, bounds)
            self._station_gaps = bounds, sought
        gaps = self._station_gaps[1].copy()
        gaps[gaps >= bounds] = math.inf
        return gaps


def step_filter(props: RodProperties, clamps: Clamps, state: RodState, step: np.ndarray, model: ContactModel) -> StepFilter:
    """The StepFilter of `step` from `state` (see StepFilter)."""
    index = rotation_index(props, clamps)
    turns = np.linalg.norm(step[index[:, None] + np.arange(3)[None, :]], axis=1)
    nodes = centerline(state.frames, clamps.start_point, props.segment_length)
    return motion_filter(nodes, turns, 0.0, props.segment_length, model)


def motion_filter(nodes: np.ndarray, turns: np.ndarray, start_move: float, h: float, model: ContactModel) -> StepFilter:
    """The StepFilter of a move of the hose from centreline `nodes` (N+1, 3) mm (see StepFilter).

    turns: (N,) rad, a bound of how far each segment's tangent turns along the move (a Newton step: its
    rotation); start_move: mm, how far the start point moves (on a line).  h: segment length, mm.
    """
    reach = start_move + np.concatenate([[0.0], h * np.cumsum(turns)])  # bound of station k's move
    cutoff = float(reach[-1]) + model.activation
    kinds, first, second, gaps, limit = watched_pairs(nodes, model.hose_radius, model.planes, model.balls,
                                                      model.capsules, model.self_exclusion, reach, cutoff,
                                                      1.0 - SAFE_FRACTION)
    swept = None
    if model.mesh.count:
        bend = np.concatenate([[0.0], h / 8.0 * np.cumsum(turns**2)])  # |path - chord| <= h/8 sum (alpha |delta_i|)^2
        swept = (nodes, reach + model.activation, bend)  # a station farther than its reach and d_hat is out of reach
    return StepFilter((kinds, first, second), gaps, limit, swept)


def solve_with_contact(
    props: RodProperties,
    clamps: Clamps,
    state: RodState,
    model: ContactModel,
    *,
    tolerance: float = 1e-10,
    max_iterations: int = 60,
    max_halvings: int = 30,
    start_is_clear: bool = False,
    stall: int = 0,
    filtered: bool = True,
) -> tuple[RodState, NewtonReport]:
    """Newton iterations from `state` (which must not penetrate) to an equilibrium with contact.

    Returns the final state and a report as newton.solve_equilibrium does; the state is only
    meaningful when report.converged.  tolerance: relative residual of force and moment balance.
    max_halvings: of a step before the iteration gives up ("no acceptable step found"); a
    continuation gives up sooner and halves its own step instead.
    start_is_clear: the caller has shown that `state` clears everything (the move check of
    procedures/contact/moving.py admitted it), so it is not searched for penetration again (on a
    fine mesh that search costs as much as an iteration's pairs).
    stall: if above 0, give up ("stalled") after that many iterations in a row whose step was cut below
    STALLED_STEP: a continuation halves its step sooner than Newton creeps on (0: never).
    filtered: False leaves out the step filter: a trial is taken where the residual falls, and the answer may lie
    beyond an obstacle or the hose itself (a step may carry a station through a thin mesh, or the hose through
    itself).  Only for a caller that then checks the whole move from a known clear equilibrium to the answer (the
    sweep's poses, procedures/sweep/quasi_static.py: contact_motion's move check) and, where that fails, solves again
    with the filter.
    Unstable directions counted by the KKT pivots at the converged state are confirmed by the dense
    reduced Hessian (_lowest_mode): an eigenvalue above -NEUTRAL times the largest is zero (neutral).
    One BLAS thread: the dense systems are small, and threads only contend for the cores (10x
    slower on a loaded two-core machine).
    """
    with one_blas_thread():
        return _solve_with_contact(props, clamps, state, model, tolerance, max_iterations, max_halvings,
                                   start_is_clear, stall, filtered)


def _solve_with_contact(props, clamps, state, model, tolerance, max_iterations, max_halvings, start_is_clear, stall,
                        filtered):
    """solve_with_contact without the thread limit."""
    inside = None if start_is_clear else model.penetration(centerline(state.frames, clamps.start_point,
                                                                      props.segment_length))
    if inside is not None:
        return state, NewtonReport(False, 0, math.inf, -1, inside)
    system = evaluate_contact(props, clamps, state, model)
    unstable, stalled = -1, 0
    for iteration in range(max_iterations + 1):
        if not np.isfinite(system.residual):
            return state, NewtonReport(False, iteration, system.residual, -1, "non-finite residual")
        step, force_step, unstable, pivots = _kkt_step(system)
        if system.residual <= tolerance:
            if unstable > 0 and _lowest_mode(system)[0] >= -NEUTRAL:
                unstable = 0  # the pivots counted an eigenvalue that is zero to rounding (see NEUTRAL_MODE)
            elif unstable < 0:  # an impossible count (fewer negative pivots than constraints): rounding in a KKT
                # matrix with the barrier's stiff rows next to a nearly taut span; the eigenvalues decide
                unstable = 0 if _lowest_mode(system)[0] >= -NEUTRAL else 1
            return state, NewtonReport(True, iteration, system.residual, unstable,
                                       factored=(system.jac_t, pivots))
        if iteration == max_iterations:
            break
        if not np.all(np.isfinite(step)):  # e.g. a free tip: its constraint rows are empty (see _multipliers)
            return state, NewtonReport(False, iteration, system.residual, unstable,
                                       "non-finite Newton step (a singular system)")
        watch = step_filter(props, clamps, state, step, model) if filtered else None
        alpha = watch.limit if filtered else 1.0
        accepted = None
        # a trial is taken where the step filter admits it and the residual falls; the cheaper test first: the
        # filter's few distances without meshes, the evaluation with them (a mesh's swept check costs more)
        filter_first = model.mesh.count == 0
        for _ in range(max_halvings):
            trial = apply_step(props, clamps, state, alpha * step, alpha * force_step)
            if filtered and filter_first and not watch.admits(props, clamps, trial, model, alpha):
                alpha *= 0.5
                continue
            trial_system = evaluate_contact(props, clamps, trial, model)
            falls = trial_system.residual < (1.0 - 1e-4 * alpha) * system.residual or trial_system.residual <= tolerance
            if falls and (not filtered or filter_first or watch.admits(props, clamps, trial, model, alpha)):
                accepted = trial, trial_system
                break
            if not falls and unstable == 0 and _rod_alone(system) and _rod_alone(trial_system):
                accepted = _restored(props, clamps, state, system, trial, model)  # see the module doc
                if accepted is not None:
                    break
            alpha *= 0.5
        if accepted is None:
            return state, NewtonReport(False, iteration + 1, system.residual, unstable, "no acceptable step found")
        state, system = accepted
        stalled = stalled + 1 if alpha < STALLED_STEP else 0
        if stall and stalled >= stall:
            return state, NewtonReport(False, iteration + 1, system.residual, unstable, "stalled")
    return state, NewtonReport(False, max_iterations, system.residual, -1, "iteration limit reached")


def _rod_alone(system: ContactSystem) -> bool:
    """Whether nothing is within the barrier's reach at the system's state (its energy finite: the rod's alone)."""
    return system.pairs[0].size == 0 and math.isfinite(system.energy)


def _restored(props: RodProperties, clamps: Clamps, state: RodState, system: ContactSystem, trial: RodState,
              model: ContactModel) -> tuple[RodState, ContactSystem] | None:
    """(the trial moved back onto the constraints, its system) where that is a step to take, else None (see the
    module doc, Restoring steps).  The trial, a Newton step from `state` (whose `system` has nothing within the
    barrier's reach and a stable KKT inertia), did not lower the residual."""
    if not clamps.end_clamped:  # a free tip: no constraint to restore
        return None
    restored = _onto_constraints(props, clamps, trial)
    restored_system = evaluate_contact(props, clamps, restored, model)
    on_constraints = system.energy - float(_multipliers(clamps, state) @ system.constraint)  # to first order
    if (not _rod_alone(restored_system)
            or np.max(np.abs(restored_system.constraint)) > RESTORED_OFF * props.length
            or not restored_system.energy < on_constraints - RESTORED_FALL * abs(on_constraints)):
        return None
    h = props.segment_length
    if not hose_move_clear(clamps.start_point, state.frames, clamps.start_point, restored.frames, h, model):
        return None
    return restored, restored_system


def hose_move_clear(start_before: np.ndarray, frames_before: np.ndarray, start_after: np.ndarray,
                    frames_after: np.ndarray, h: float, model: ContactModel) -> bool:
    """Whether the hose can go from one configuration to another (start point (3,) mm and frames (N, 3, 3) each;
    h: segment length, mm) without crossing any obstacle of `model` or itself: the virtual path of
    contact_motion.py's move check (the start point on a straight line, each tangent on a great circle), judged by
    the step filter (motion_filter).  The configuration before must not penetrate."""
    a, b = frames_before[:, 2], frames_after[:, 2]  # the tangents' cross product written out: np.cross costs more
    sines = np.sqrt((a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]) ** 2 + (a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]) ** 2
                    + (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) ** 2)
    turns = np.arctan2(sines, np.einsum("ij,ij->i", a, b))
    start_move = float(np.linalg.norm(start_after - start_before))
    if start_move == 0.0 and not np.any(turns):
        return True
    watch = motion_filter(centerline(frames_before, start_before, h), turns, start_move, h, model)
    return watch.limit >= 1.0 and watch.admits_centerline(centerline(frames_after, start_after, h), model, 1.0)


def minimise_with_contact(
    props: RodProperties,
    clamps: Clamps,
    state: RodState,
    model: ContactModel,
    *,
    tolerance: float = 1e-10,
    max_iterations: int = 200,
) -> tuple[RodState, NewtonReport]:
    """Walk downhill from `state` (which must not penetrate) to a stable equilibrium with contact.

    The downhill mode of solve_with_contact, as newton._minimise_kernel is that of the contact-free
    Newton: where the KKT inertia counts unstable directions on the constraint tangent space, the
    Hessian is shifted, H + sigma I, sigma grown tenfold until the count is zero; a step is
    accepted (after the step filter) only if the merit, the total energy with the barrier minus
    the multipliers times the constraint plus a penalty on the constraint, falls by at least a
    tenth of the quadratic model's prediction; sigma shrinks after good steps and grows after poor
    ones, so the method ends as plain Newton at a stable minimum.  A step's part that restores the
    constraints (-J^T (J J^T)^-1 c) does not shorten as sigma grows: once sigma dominates the
    Hessian's diagonal, a refused step is also halved (where restoring the end's position carries the
    hose into an obstacle's barrier, sigma alone grew without end and the walk gave up).  Returns the
    final state and a report as solve_with_contact; tolerance: relative residual.
    """
    with one_blas_thread():
        return _minimise_with_contact(props, clamps, state, model, tolerance, max_iterations)


def _multipliers(clamps: Clamps, state: RodState) -> np.ndarray:
    """The end force and the clip forces (N) in the order of the constraint rows (zeros for a free tip)."""
    if not clamps.end_clamped:
        return np.zeros(3)
    return np.concatenate([state.end_force, clip_forces(clamps, state).reshape(-1)])


def _hessian_times(system: ContactSystem, step: np.ndarray) -> np.ndarray:
    """H step with H = band + columns diag(signs) columns^T (the unshifted Hessian)."""
    return banded_matvec(system.band, step).reshape(-1) + system.columns @ (system.signs * (system.columns.T @ step))


def merit(system: ContactSystem, multipliers: np.ndarray, penalty: float) -> float:
    """The downhill mode's merit at a state: its energy with the barrier, less the multipliers (those of the state
    the step starts from, N) times the constraint, plus penalty (N/mm) / 2 times the constraint squared (N*mm)."""
    return system.energy - float(multipliers @ system.constraint) + 0.5 * penalty * float(
        system.constraint @ system.constraint)


def merit_model(system: ContactSystem, alpha: float, step: np.ndarray, penalty: float,
                diag_scale: float) -> tuple[float, float]:
    """(the predicted change of the merit, the penalty) for `step`, alpha times a KKT step from `system`'s state.

    The quadratic model of the Lagrangian, g.step + step.H step / 2, plus the penalty's change on the linearised
    constraint: the KKT step's constraint rows give J step = -alpha c, so c goes to (1 - alpha) c and |c|^2 falls by
    alpha (2 - alpha) |c|^2 (counting the whole fall for a step the step filter cut promised a fall the merit could
    not give: the walk gave up at a snap of the plectoneme of tests/test_contact_selfloop.py, its path followed with
    a check of each step tried in session 23).
    The penalty is raised where needed so that the model falls (a tiny margin of diag_scale, N*mm/rad^2, above).
    """
    quadratic = float(system.grad @ step + 0.5 * step @ _hessian_times(system, step))
    restored = alpha * (2.0 - alpha) * float(system.constraint @ system.constraint)
    if restored > 0.0:
        penalty = max(penalty, 2.0 * max(quadratic, 0.0) / restored + 1e-8 * diag_scale)
    return quadratic - 0.5 * penalty * restored, penalty


NEUTRAL_MODE = "unstable by the pivot count only: the lowest eigenvalue is zero to rounding (neutral)"


def _lowest_mode(system: ContactSystem) -> tuple[float, np.ndarray]:
    """(lowest eigenvalue of the Hessian on the constraint tangent space relative to its largest magnitude,
    its eigenvector in the unknowns scaled to a largest entry of 1); dense, O(n^3): met once per fold."""
    basis = scipy.linalg.null_space(system.jac_t.T)
    values, vectors = scipy.linalg.eigh(basis.T @ system.dense() @ basis)
    direction = basis @ vectors[:, 0]
    relative = float(values[0]) / max(float(np.max(np.abs(values))), 1e-300)
    return relative, direction / max(float(np.max(np.abs(direction))), 1e-300)


def lowest_stiffnesses(system: ContactSystem, count: int) -> np.ndarray:
    """The `count` lowest eigenvalues (N*mm/rad^2, ascending) of the Hessian on the constraint tangent space that are
    not neutral: an eigenvalue within NEUTRAL of the largest magnitude is the zero mode of a symmetry (the whole hose
    turned about the axis of coaxial mounts, as the plectoneme's) and says nothing of a fold.  Fewer where the tangent
    space has fewer.  Dense, O(n^3), for the fold watch of procedures/contact/continuation.py.  One BLAS thread, as
    solve_with_contact."""
    with one_blas_thread():
        hessian = tangent_hessian(system)
        if hessian.shape[0] == 0:
            return np.zeros(0)
        tridiagonal = tridiagonal_form(hessian)
    asked = count + 1  # (a symmetry has one neutral mode, the coaxial mounts' turn)
    while True:
        values, scale = spectrum_ends(tridiagonal, asked)
        stiff = values[np.abs(values) > NEUTRAL * scale]
        if stiff.size >= count or values.size == hessian.shape[0]:
            return stiff[:count]
        asked *= 2


def tridiagonal_form(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(diagonal, off-diagonal) of the tridiagonal matrix similar to the symmetric `matrix` (LAPACK dsytrd: the
    O(n^3) part of its eigenvalues, after which any of them costs O(n) by bisection)."""
    _, diagonal, off_diagonal, _, info = scipy.linalg.lapack.dsytrd(matrix, lwork=64 * matrix.shape[0])
    if info != 0:
        raise ValueError(f"the tridiagonal reduction failed (LAPACK dsytrd info {info})")
    return diagonal, off_diagonal


def spectrum_ends(tridiagonal: tuple[np.ndarray, np.ndarray], lowest: int) -> tuple[np.ndarray, float]:
    """(the `lowest` lowest eigenvalues, ascending, all if there are fewer; the largest magnitude of all) of the
    tridiagonal matrix (diagonal, off-diagonal) of tridiagonal_form: half the time of every eigenvalue (1.5 against
    3 ms for 300 unknowns)."""
    diagonal, off_diagonal = tridiagonal
    n = diagonal.shape[0]
    values = scipy.linalg.eigvalsh_tridiagonal(diagonal, off_diagonal, select="i",
                                               select_range=(0, min(lowest, n) - 1), check_finite=False)
    highest = scipy.linalg.eigvalsh_tridiagonal(diagonal, off_diagonal, select="i", select_range=(n - 1, n - 1),
                                                check_finite=False)[0]
    return values, max(abs(float(values[0])), abs(float(highest)))


def tangent_hessian(system: ContactSystem) -> np.ndarray:
    """The Hessian of `system` on the tangent space of its constraints (dense, (n - m) square, n unknowns, m
    constraints), in a basis of that space: the m Householder reflectors of J's QR applied to both sides (O(m n^2);
    null_space and two products took 40 % of 0.9 ms for 50 segments, 2.5 ms of 5 for 100), unless J is rank
    deficient.  Call it with one BLAS thread (small matrices: threads only contend)."""
    hess, jac_t = system.dense(), system.jac_t
    m = jac_t.shape[1]
    if not m:
        return hess
    reflectors, tau, _, _ = scipy.linalg.lapack.dgeqrf(jac_t)
    pivots = np.abs(np.diag(reflectors[:m]))
    if np.min(pivots) > 1e-12 * np.max(pivots):  # Q^T H Q, Q = [range J, null J^T]: its lower right block
        work = 64 * hess.shape[0]
        hess = scipy.linalg.lapack.dormqr("L", "T", reflectors, tau, hess, work)[0]
        return scipy.linalg.lapack.dormqr("R", "N", reflectors, tau, hess, work)[0][m:, m:]
    basis = scipy.linalg.null_space(jac_t.T)
    return basis.T @ hess @ basis


def _leave_saddle(props, clamps, state, system, model, turns=(0.05, 0.2, 0.8)):
    """From an unstable equilibrium, a state of lower energy along the most unstable direction, or None.

    The direction: the eigenvector of the lowest eigenvalue of the Hessian on the constraint
    tangent space (dense: a saddle is met once per fold); its largest rotation is each of `turns`
    (rad) in order, cut by the step filter, and the constraints restored (_onto_constraints: a push
    that leaves them would hand the merit's penalty a violation to undo, and the descent walks back
    to the saddle); of its two senses the one of lower energy.  The first push whose energy is
    below the saddle's is returned: a nearly degenerate saddle is flat to second order, and only a
    longer push finds the fall; if none is lower (the step filter cut them to rounding), the
    shortest, from which the shifted Newton walks on (the iteration limit bounds a return).
    """
    direction = _lowest_mode(system)[1]
    rounding = 1e-12 * max(abs(system.energy), 1.0)
    first = None
    for turn in turns:
        best = None
        for sense in (turn, -turn):
            step = sense * direction
            watch = step_filter(props, clamps, state, step, model)
            alpha = watch.limit
            trial = _onto_constraints(props, clamps, apply_step(props, clamps, state, alpha * step, np.zeros(3)))
            while not watch.admits(props, clamps, trial, model, alpha):
                alpha *= 0.5
                trial = _onto_constraints(props, clamps, apply_step(props, clamps, state, alpha * step, np.zeros(3)))
            trial_system = evaluate_contact(props, clamps, trial, model)
            if np.isfinite(trial_system.energy) and (best is None or trial_system.energy < best[1].energy):
                best = trial, trial_system
        if best is not None and best[1].energy < system.energy - rounding:
            return best
        first = first or best
    return first


def _onto_constraints(props: RodProperties, clamps: Clamps, state: RodState, corrections: int = 6) -> RodState:
    """`state` moved back onto the constraints (end and clip positions) by least-norm Gauss-Newton steps
    -J^T (J J^T)^-1 c, the multipliers kept (a free tip has no constraint)."""
    for _ in range(corrections if clamps.end_clamped else 0):
        system = evaluate(props, clamps, state)
        if float(np.max(np.abs(system.constraint))) <= 1e-13 * props.length:
            break
        jac_t = system.jac_t
        correction = -jac_t @ np.linalg.solve(jac_t.T @ jac_t, system.constraint)
        state = apply_step(props, clamps, state, correction, np.zeros(3))
    return state


def _minimise_with_contact(props, clamps, state, model, tolerance, max_iterations):
    """minimise_with_contact without the thread limit (the loop of newton._minimise_kernel, with the step filter)."""
    inside = model.penetration(centerline(state.frames, clamps.start_point, props.segment_length))
    if inside is not None:
        return state, NewtonReport(False, 0, math.inf, -1, inside)
    system = evaluate_contact(props, clamps, state, model)
    diag_scale = float(np.max(np.abs(system.band[:, 0])))
    sigma_floor = 1e-10 * diag_scale
    sigma, penalty = 0.0, 0.0
    for iteration in range(max_iterations + 1):
        if not np.isfinite(system.residual):
            return state, NewtonReport(False, iteration, system.residual, -1, "non-finite residual")
        step, force_step, unstable, pivots = _kkt_step(system)
        if system.residual <= tolerance and unstable != 0 and iteration < max_iterations:
            if _lowest_mode(system)[0] >= -NEUTRAL:  # the KKT pivots counted a rounding-level eigenvalue
                return state, NewtonReport(True, iteration, system.residual, 0, NEUTRAL_MODE)
            pushed = _leave_saddle(props, clamps, state, system, model)  # no gradient to walk down: push
            if pushed is None:
                return state, NewtonReport(False, iteration, system.residual, unstable,
                                           "an unstable equilibrium: every push along its most unstable mode gave a non-finite energy")
            state, system = pushed
            continue
        if system.residual <= tolerance:
            return state, NewtonReport(True, iteration, system.residual, unstable,
                                       factored=(system.jac_t, pivots))
        if iteration == max_iterations:
            break
        plain_newton = unstable == 0 and sigma == 0.0 and system.residual < 1e-6 and np.all(np.isfinite(step))
        multipliers = _multipliers(clamps, state)
        accepted = None
        reach = 1.0  # the largest fraction of the step tried: halved after a refusal once the shift dominates
        for _ in range(40):
            if not plain_newton and (sigma > 0.0 or unstable != 0 or not np.all(np.isfinite(step))):
                sigma = max(sigma, sigma_floor)
                step, force_step, shifted_unstable, _ = _kkt_step(system, sigma)
                if shifted_unstable != 0 or not np.all(np.isfinite(step)):
                    sigma *= 10.0
                    continue
            watch = step_filter(props, clamps, state, step, model)
            alpha = min(watch.limit, reach)
            trial = apply_step(props, clamps, state, alpha * step, alpha * force_step)
            while not watch.admits(props, clamps, trial, model, alpha) and alpha > 1e-9:
                alpha *= 0.5
                trial = apply_step(props, clamps, state, alpha * step, alpha * force_step)
            trial_system = evaluate_contact(props, clamps, trial, model)
            if plain_newton:  # close to a stable minimum: plain Newton, judged by the residual
                if trial_system.residual < system.residual:
                    accepted = trial, trial_system
                    break
                plain_newton, sigma = False, sigma_floor
                continue
            predicted, penalty = merit_model(system, alpha, alpha * step, penalty, diag_scale)
            base = merit(system, multipliers, penalty)
            actual = merit(trial_system, multipliers, penalty) - base
            rounding = 1e-13 * (abs(base) + diag_scale)
            if predicted < -rounding:
                ratio = actual / predicted
            else:
                ratio = 1.0 if actual <= rounding else -1.0
            if np.isfinite(actual) and (ratio > 0.1 or trial_system.residual <= tolerance):
                if ratio > 0.75 and alpha == 1.0:
                    sigma = 0.0 if sigma <= 4.0 * sigma_floor else 0.25 * sigma
                accepted = trial, trial_system
                break
            if sigma >= diag_scale:
                reach = 0.5 * alpha
            sigma = max(4.0 * sigma, 1e-4 * diag_scale)
        if accepted is None:
            return state, NewtonReport(False, iteration + 1, system.residual, unstable, "no descent step found")
        state, system = accepted
    return state, NewtonReport(False, max_iterations, system.residual, -1, "iteration limit reached")


def penetration_message(model: ContactModel, kind: int, first: int, second: int, gap: float) -> str:
    """Which obstacle the hose is inside, where (station or segment) and by how much."""
    where = f"station {first}" if kind in STATION_KINDS else f"segment {first}"
    if kind == SEGMENT_SEGMENT:
        return f"the hose cuts into itself: segments {first} and {second} overlap by {-gap:.4g} mm"
    return f"the hose is inside obstacle {model.owner(kind, second)!r} at {where} by {-gap:.4g} mm ({PAIR_KINDS[kind]})"


def minimum_gap(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> float:
    """The smallest gap (mm, surface to surface) over every pair: the hose's clearance to all it may touch."""
    return model.smallest_gap(centerline(state.frames, clamps.start_point, props.segment_length))
