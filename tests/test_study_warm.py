"""Warm start: Newton from the nominal hose gives the published sequence's answers, and says when it does not."""

from __future__ import annotations

import numpy as np

from hoseline.demos.thesis_hose import demo_problem
from hoseline.model import Hose, Mount, Problem
from hoseline.procedures.variation.engine import Where
from hoseline.procedures.variation.run import run_study
from hoseline.procedures.variation.samples import CHECKED_WARM_STARTS, StudyBase
from hoseline.procedures.variation.study import Sampling, Study
from hoseline.procedures.variation.tolerances import Tolerance, Variation

THESIS_TOLERANCES = Variation((
    Tolerance("end.point", "sphere", (1.0,)),
    Tolerance("end.direction", "cone", (2.0,)),
    Tolerance("start.direction", "cone", (2.0,)),
    Tolerance("hose.length", "uniform", (-13.2, 6.6)),
    Tolerance("hose.bending_stiffness", "lognormal", (2.0,)),
    Tolerance("end.twist", "normal", (3.0,)),
))


def _run(problem: Problem, variation: Variation, start: str, count: int):
    study = Study("warm", StudyBase(problem), variation, Sampling("monte-carlo", count, 4, None, start), (),
                  sensitivities=False)
    return run_study(study, where=Where(workers=0))


def test_warm_start_lands_where_the_published_sequence_does():
    """The thesis hose at 180 degrees (a shape with a mirror image) with the full tolerances: every sample by
    Newton from the nominal hose equals the placement from the straight hose within 1e-6 mm (measured 4e-7 mm
    on 256 samples, 2e-7 mm on the checked ones)."""
    problem = demo_problem(180.0, 30)
    warm = _run(problem, THESIS_TOLERANCES, "nominal", 48)
    straight = _run(problem, THESIS_TOLERANCES, "straight", 48)
    assert warm.samples["warm"].mean() > 0.9 and not straight.samples["warm"].any()
    assert np.nanmax(np.abs(warm.samples["shapes"] - straight.samples["shapes"])) < 1e-6
    checked = np.isfinite(warm.samples["branch_distance"])
    first = np.arange(48) < CHECKED_WARM_STARTS
    assert np.array_equal(checked, warm.samples["warm"] & first)
    assert warm.notes[0].startswith("warm start: ") and len(warm.notes) == 1


def test_where_newton_cannot_follow_the_published_sequence_takes_over():
    """A hose compressed between coaxial mounts bows out to whichever side a misalignment decides; from the
    nominal hose, bowed to one side, Newton mostly ends on an unstable state: those samples are placed from the
    straight hose, so every answer equals the published sequence's."""
    hose = Hose(length=110.0, outer_diameter=4.0, bending_stiffness=1e4, torsional_stiffness=1e4 / 1.5, segments=30)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([100.0, 0.0, 0.0], [-1.0, 0.0, 0.0]))
    variation = Variation((Tolerance("end.point", "normal", (0.05, 0.05, 0.05)),))
    warm, straight = _run(problem, variation, "nominal", 40), _run(problem, variation, "straight", 40)
    assert (~warm.samples["warm"]).sum() > 30
    assert np.max(np.abs(warm.samples["shapes"] - straight.samples["shapes"])) < 1e-2


def test_a_warm_start_on_another_branch_is_caught(monkeypatch):
    """A warm start that lands elsewhere (here: its answer turned by 1 degree about the mounts' axis) is caught
    by the check on the first samples and said in the notes."""
    import hoseline.procedures.variation.samples as samples
    from hoseline.mechanics.rotations import rotate_frames

    original = samples.warm_start

    def elsewhere(nominal, deviation):
        problem, props, clamps, state = original(nominal, deviation)
        axis = np.radians(1.0) * np.array([1.0, 0.0, 0.0])
        state.frames = rotate_frames(state.frames, np.tile(axis, (len(state.frames), 1)))
        return problem, props, clamps, state

    monkeypatch.setattr(samples, "warm_start", elsewhere)
    outcome = _run(demo_problem(90.0, 20), Variation((Tolerance("end.point", "sphere", (0.5,)),)), "nominal", 8)
    assert np.nanmin(outcome.samples["branch_distance"]) > 1.0
    assert any("another branch than the published sequence on 8 of 8" in note for note in outcome.notes)
