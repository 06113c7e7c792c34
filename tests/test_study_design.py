"""Design search on a case built so that the answer is known.

A heavy hose hangs between two coaxial mounts 200 mm apart, under a plate (above its middle) and
between two side walls.  The longer the hose, the deeper it sags: the clearance to the plate grows
with the length, and the bend at the mounts tightens.  Clocking the end fitting either way turns the
sag out of its vertical plane, towards a wall and up: the clearance to the plate is largest
unclocked (the mounts' mirror symmetry makes it even in the clocking).  So the best candidate is the
longest catalogue length whose bend radius still meets the limit, unclocked; the limit is put halfway
between the bend radii of two neighbouring lengths (by the plain placement, not the search).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import trimesh

from hoseline.model import Hose, Mount, Problem
from hoseline.model.motion import Translation, generated_motion
from hoseline.model.sweep import Obstacle, SweepProblem
from hoseline.procedures.placement.sequence import solve
from hoseline.demos.thesis_hose import demo_problem
from hoseline.procedures.variation.design_search import (CLOCKING_TOLERANCE, MAX_EVALUATIONS, DesignGrid, RefineTask,
                                                         candidate_margins, candidate_rows, refine_length)
from hoseline.procedures.variation.engine import Where
from hoseline.procedures.variation.quantities import Limit, quantities
from hoseline.procedures.variation.run import run_study
from hoseline.procedures.variation.samples import StudyBase, evaluate_batch, nominal_context
from hoseline.procedures.variation.study import Sampling, Study
from hoseline.procedures.variation.tolerances import INDEX, Tolerance, Variation

LENGTHS = (205.0, 210.0, 215.0, 220.0, 225.0, 230.0, 235.0, 240.0)
CLOCKINGS = (-60.0, -30.0, 0.0, 30.0, 60.0)
EXPECTED_LENGTH = 225.0


def _box(name: str, low, high, clearance: float) -> Obstacle:
    mesh = trimesh.creation.box(bounds=[low, high])
    return Obstacle(name, np.asarray(mesh.vertices), np.asarray(mesh.faces), clearance)


def _case() -> tuple[Problem, SweepProblem]:
    hose = Hose(length=220.0, outer_diameter=6.0, bending_stiffness=2e4, torsional_stiffness=2e4 / 1.5,
                mass_per_length=0.5, segments=30)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([200.0, 0.0, 0.0], [-1.0, 0.0, 0.0]), 0.0,
                      gravity=np.array([0.0, 0.0, -9.81]))
    still = generated_motion("frame", [Translation(np.array([0.0, 0.0, 1.0]), (0.0, 0.0), 1)])  # the assembly pose
    obstacles = (_box("plate", [50, -60, 30], [150, 60, 40], 5.0), _box("wall_left", [-20, 40, -100], [220, 50, 50], 5.0),
                 _box("wall_right", [-20, -50, -100], [220, -40, 50], 5.0))
    return problem, SweepProblem(problem, None, None, (still,), obstacles, compare_free_roll=False)


def _bend_radius(problem: Problem, length: float) -> float:
    return solve(replace(problem, hose=replace(problem.hose, length=length)), estimate_error=False).min_bend_radius


def test_the_search_finds_the_longest_length_within_the_bend_limit_unclocked():
    problem, sweep = _case()
    limit_value = 0.5 * (_bend_radius(problem, EXPECTED_LENGTH) + _bend_radius(problem, EXPECTED_LENGTH + 5.0))
    names = quantities(("plate", "wall_left", "wall_right"))
    limits = (Limit(names[0], 5.0), Limit(names[1], 5.0), Limit(names[2], 5.0), Limit(names[3], limit_value))
    study = Study("design", StudyBase(problem, sweep), Variation(()), Sampling(count=0), limits,
                  design=DesignGrid(LENGTHS, CLOCKINGS, "clearance:plate"))
    outcome = run_study(study, where=Where(workers=0))
    design = outcome.design
    plate, bend = design.margins[:, :, 0], design.margins[:, :, 3]
    # the construction holds: plate clearance grows with length, bend margin shrinks, both even in the clocking
    assert np.all(np.diff(plate, axis=0) > 0.0) and np.all(np.diff(bend[:, 2]) < 0.0)
    assert np.allclose(plate, plate[:, ::-1], atol=1e-6) and np.all(np.argmax(plate, axis=1) == 2)
    best = design.table()[0]
    assert (best["length_mm"], best["clocking_deg"]) == (EXPECTED_LENGTH, 0.0)
    # every candidate ranked meets every limit, and the longer lengths are out on the bend radius
    assert all(np.all(design.margins[i, j] >= 0.0) for i, j in design.ranking)
    assert all(LENGTHS[i] <= EXPECTED_LENGTH for i, _ in design.ranking)


def test_with_tolerances_a_candidate_is_judged_on_the_margin_95_percent_keep():
    """Judging over tolerance samples: the margin is the 5th percentile over a candidate's samples, and a
    candidate with a failed sample meets no limit (synthetic values: the ranking logic alone)."""
    from hoseline.procedures.variation.design_search import judge

    names = quantities(())
    limit = Limit(names[0], 10.0)  # bend radius at least 10 mm
    grid = DesignGrid((300.0, 310.0), (0.0,), "bend_radius", samples=20)
    values = np.full((40, len(names)), np.nan)
    values[:20, 0] = np.linspace(9.0, 19.0, 20)  # 300 mm: 5th percentile 9.5 -> not met
    values[20:, 0] = np.linspace(11.0, 21.0, 20)  # 310 mm: 5th percentile 11.5 -> met
    failed = np.zeros(40, dtype=bool)
    outcome = judge(grid, (limit,), [q.name for q in names],
                    {"values": values, "failed": failed, "reason": np.full(40, "")})
    assert np.allclose(outcome.margins[:, 0, 0], [np.percentile(values[:20, 0], 5) - 10.0,
                                                  np.percentile(values[20:, 0], 5) - 10.0])
    assert outcome.ranking == [(1, 0)]
    failed[25] = True
    values[25] = np.nan
    reasons = np.where(failed, "PlacementError: no path", "")
    outcome = judge(grid, (limit,), [q.name for q in names], {"values": values, "failed": failed, "reason": reasons})
    assert outcome.ranking == [] and outcome.failed[1, 0] == 1 and outcome.reasons == ["PlacementError: no path"]


def test_the_optimiser_finds_the_clocking_between_grid_points():
    """The same case on a clocking grid that misses the optimum (-50, -20, 10, 40 degrees): the plate clearance
    is largest unclocked by the mounts' mirror symmetry, so the optimiser must find 0 degrees between the grid
    points -20 and 10, to its tolerance (measured: within 0.0015 degrees, 6 solves per length), for every
    length; the best stays the longest length within the bend limit, and the heat map keeps the grid."""
    problem, sweep = _case()
    limit_value = 0.5 * (_bend_radius(problem, EXPECTED_LENGTH) + _bend_radius(problem, EXPECTED_LENGTH + 5.0))
    names = quantities(("plate", "wall_left", "wall_right"))
    limits = (Limit(names[0], 5.0), Limit(names[1], 5.0), Limit(names[2], 5.0), Limit(names[3], limit_value))
    grid = DesignGrid(LENGTHS, (-50.0, -20.0, 10.0, 40.0), "clearance:plate", method="optimise")
    study = Study("design", StudyBase(problem, sweep), Variation(()), Sampling(count=0), limits, design=grid)
    design = run_study(study, where=Where(workers=0)).design
    assert design.margins.shape == (len(LENGTHS), 4, 4)  # the grid, for the heat map
    feasible_lengths = sorted({LENGTHS[i] for i, _ in design.ranking})
    assert sorted(r.length for r in design.refined) == feasible_lengths
    for refined in design.refined:
        assert refined.optimised and abs(refined.clocking) <= CLOCKING_TOLERANCE
        assert refined.bracket == (-20.0, 40.0) and refined.evaluations < 30
        i = LENGTHS.index(refined.length)
        assert refined.margins[0] > np.nanmax(design.margins[i, :, 0])  # better than every grid cell of its length
        assert np.all(refined.margins >= 0.0)
    best = design.table()[0]
    assert best["length_mm"] == EXPECTED_LENGTH and abs(best["clocking_deg"]) <= CLOCKING_TOLERANCE
    assert best["clocking from"] == "optimiser"


def test_the_optimiser_keeps_every_limit_where_the_ranked_margin_peaks_beyond_one(monkeypatch):
    """Synthetic margins (the optimiser's logic alone): the ranked margin peaks at 7 degrees, where the other limit
    is broken (its margin is clocking - 9): the best clocking meeting both is 9 degrees (margins 46 and 0), better
    than the grid's cell at 10 degrees (41 and 1); every clocking the optimiser tried that broke the torque limit
    is left out."""
    import hoseline.procedures.variation.design_search as design_search

    names = [q.name for q in quantities(())]
    limits = (Limit(quantities(())[0], 10.0), Limit(quantities(())[1], 100.0))  # bend radius >= 10, torque <= 100
    tried = []

    def synthetic(context, indices, rows):
        clocking = rows[:, INDEX["end.twist"]]
        tried.extend(clocking)
        values = np.zeros((len(rows), len(names)))
        values[:, 0] = 10.0 + 50.0 - (clocking - 7.0) ** 2  # bend radius margin 50 - (c - 7)^2
        values[:, 1] = 100.0 - (clocking - 9.0)  # torque margin c - 9
        return {"values": values, "failed": np.zeros(len(rows), dtype=bool)}

    monkeypatch.setattr(design_search, "evaluate_batch", synthetic)
    task = RefineTask(300.0, (-5.0, 25.0), 10.0, np.array([41.0, 1.0]), 300.0, 0.0, np.zeros((1, 15)), limits,
                      tuple(names), 0)
    result = refine_length(None, task)
    assert result["optimised"][0] and 9.0 <= result["clocking"][0] <= 9.0 + CLOCKING_TOLERANCE
    assert result["margins"][1] >= 0.0 and result["margins"][0] >= 46.0 - 2 * 2.0 * CLOCKING_TOLERANCE
    assert min(tried) < 9.0  # the optimiser did try clockings breaking the torque limit
    # without the other limit the optimiser finds the peak
    task = RefineTask(300.0, (-5.0, 25.0), 10.0, np.array([41.0]), 300.0, 0.0, np.zeros((1, 15)), limits[:1],
                      tuple(names), 0)
    result = refine_length(None, task)
    assert result["optimised"][0] and abs(result["clocking"][0] - 7.0) <= CLOCKING_TOLERANCE


def _heavy_demo(twist_deg: float, mass_per_length: float) -> Problem:
    problem = demo_problem(twist_deg)
    gravity = np.array([0.0, 0.0, -9.81 if mass_per_length else 0.0])
    return replace(problem, hose=replace(problem.hose, mass_per_length=mass_per_length), gravity=gravity)


# (twist at assembly deg, kg/m, lengths mm, clockings deg from, to, {limited quantity: limit}, rank_by): the
# issue's case (the bend radius ranked, the end torque limit active left of the grid's best cell), the thesis hose
# at 180 degrees (the end torque limit active right of it), and the heavy hose ranked by the end torque (a kink at
# zero torque) with the bend radius limit active
BRUTE_FORCE_CASES = (
    (90.0, 0.25, (350.0, 360.0), (-90.0, 90.0), {"bend_radius": 30.0, "end_torque": 200.0}, "bend_radius"),
    (180.0, 0.0, (330.6, 340.0), (90.0, 270.0), {"bend_radius": 30.0, "end_torque": 400.0}, "bend_radius"),
    (90.0, 0.25, (360.0,), (-90.0, 90.0), {"bend_radius": 39.5, "end_torque": 200.0}, "end_torque"),
)
BRUTE_FORCE_STEP = 2.5  # degrees between the brute-force grid's clockings


@pytest.mark.parametrize("twist, mass, lengths, span, limited, rank_by", BRUTE_FORCE_CASES)
def test_the_optimiser_beats_a_brute_force_grid_and_meets_every_limit(twist, mass, lengths, span, limited, rank_by):
    """The search on a 30-degree clocking grid with the optimiser, against a brute-force grid of placements at
    BRUTE_FORCE_STEP over the same clockings: per length, the answer meets every limit (solved again) and its ranked
    margin is at least the best of the brute-force candidates meeting every limit."""
    problem = _heavy_demo(twist, mass)
    names = quantities(())
    limits = tuple(Limit(q, limited[q.name]) for q in names if q.name in limited)
    clockings = tuple(float(c) for c in np.arange(span[0], span[1] + 1.0, 30.0))
    study = Study("design", StudyBase(problem), Variation(()), Sampling(count=0), limits,
                  design=DesignGrid(lengths, clockings, rank_by, method="optimise"))
    design = run_study(study, where=Where(workers=0)).design
    rank = [limit.quantity.name for limit in limits].index(rank_by)
    context, _ = nominal_context(StudyBase(problem))
    brute = np.arange(clockings[0], clockings[-1] + 1e-9, BRUTE_FORCE_STEP)
    assert sorted(r.length for r in design.refined) == sorted(lengths)
    for refined in design.refined:
        rows = np.concatenate([candidate_rows(refined.length - problem.hose.length, c - twist, np.zeros((1, 15)))
                               for c in (*brute, refined.clocking)])
        out = evaluate_batch(context, np.arange(len(rows)), rows)
        margins = candidate_margins(limits, [q.name for q in names], out["values"][:, None], out["failed"][:, None])
        feasible = np.all(margins[:-1] >= 0.0, axis=1)
        assert np.all(margins[-1] >= 0.0) and np.allclose(margins[-1], refined.margins)
        assert refined.margins[rank] >= margins[:-1][feasible, rank].max()
        assert refined.evaluations <= MAX_EVALUATIONS


def test_ranking_on_the_p95_margin_chooses_the_candidate_that_keeps_its_margins_over_the_tolerances():
    """A case built so that the nominal ranking is misled: the heavy thesis hose at 90 degrees, a torque limit of
    290 N*mm, the bend radius ranked, with the end point (2 mm sphere), EI (factor 2) and the clocking (5 degrees)
    toleranced.  At nominal 345 mm at -60 degrees has the largest bend-radius margin and meets the torque limit,
    but its torque is the most sensitive: over the tolerances more than 5 % of those hoses break the limit.  Ranked
    on the first-order 5th percentile of margin it is refused, and 340 mm at -60 degrees (ranked below 345 mm at
    -45 degrees at nominal) comes first.  Checked by solving 64 samples of every candidate: the sampled 5th
    percentiles choose the same candidate and refuse the nominal one (its torque margin -35 N*mm)."""
    problem = _heavy_demo(90.0, 0.25)
    base = StudyBase(replace(problem, hose=replace(problem.hose, segments=24)))
    by_name = {q.name: q for q in base.quantities}
    limits = (Limit(by_name["bend_radius"], 30.0), Limit(by_name["end_torque"], 290.0))
    variation = Variation((Tolerance("end.point", "sphere", (2.0,)), Tolerance("hose.bending_stiffness", "lognormal",
                                                                                (2.0,)),
                           Tolerance("end.twist", "normal", (5.0,))))
    chosen = {}
    for rank_on, samples in (("nominal", 0), ("p95_margin", 0), ("nominal", 64)):
        grid = DesignGrid((340.0, 345.0), (-60.0, -45.0), "bend_radius", samples, rank_on=rank_on)
        study = Study("robust", base, variation, Sampling("sobol", 64, 1), limits, False, grid)
        design = run_study(study, where=Where(workers=0)).design
        best = design.table()[0]
        chosen[rank_on, samples] = (best["length_mm"], best["clocking_deg"])
        if samples:
            sampled = design
    assert chosen["nominal", 0] == (345.0, -60.0)
    assert chosen["p95_margin", 0] == chosen["nominal", 64] == (340.0, -60.0)
    assert sampled.margins[1, 0, 1] < 0.0  # 345 mm at -60 degrees: the sampled 5th percentile breaks the torque limit
    # the optimiser judges its clockings the same way: at 345 mm it stops where the torque's P95 margin reaches the
    # limit (measured -58.97 degrees), between the grid's -60 (refused) and -45 degrees, and beats both
    grid = DesignGrid((340.0, 345.0), (-60.0, -45.0), "bend_radius", method="optimise", rank_on="p95_margin")
    study = Study("robust", base, variation, Sampling("sobol", 64, 1), limits, False, grid)
    refined = {r.length: r for r in run_study(study, where=Where(workers=0)).design.refined}[345.0]
    assert refined.optimised and -60.0 < refined.clocking < -45.0
    assert np.all(refined.margins >= 0.0) and refined.margins[1] < 1.0 and refined.margins[0] > 8.82


def test_ranking_on_the_p95_margin_with_solved_samples_per_candidate_is_refused():
    with pytest.raises(ValueError, match="rank_on"):
        DesignGrid((340.0,), (0.0,), "bend_radius", samples=16, rank_on="p95_margin")
