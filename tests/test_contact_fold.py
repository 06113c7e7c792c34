"""The fold watch of the contact continuation (procedures/contact/continuation.py, FoldWatch; docs/model.md, Contact,
"Passing folds").

At a fold the lowest eigenvalue of the Hessian on the constraint tangent space goes to zero as sqrt(t_fold - t), so
its square is linear in the path fraction t: the watch extrapolates the square of the product of the two lowest from
the last two equilibria.  It acts only on evidence: where the path bisects (a second failed try in a row from an
equilibrium reached by a shortened step) and the predicted fold lies in the later half of the failed try, it steps
towards it, on while each prediction comes nearer, and snaps just past it without a Newton try.  Checked here: the
extrapolation itself (eigenvalues made up to vanish as a square root: exact; a line in lambda instead of lambda^2 is
not), each rule of the watch on made-up eigenvalues, the plectoneme's first fold against the bisection of the old
continuation (the same code with the watch blind: FoldWatch.fold returning None), no failed Newton try between the
start of the watch and the snap, and the same final equilibria as the old path on the loop (whose lowest eigenvalue
dips at fraction 0.825 without vanishing), the drum and the floor, where no eigenvalue is asked for.
"""

import math

import numpy as np
import pytest

import hoseline.procedures.contact.continuation as continuation
from hoseline.demos.floor import SYMMETRIC, floor_data
from hoseline.io.problem_file import problem_from_dict
from hoseline.procedures.contact.continuation import APPROACH, FoldWatch
from hoseline.procedures.placement.continuation import StepControl
from hoseline.procedures.placement.sequence import solve

PLECTONEME = {"hose": {"length": 200.0, "outer_diameter": 4.0, "bending_stiffness": 1e5, "torsional_stiffness": 8e4,
                       "segments": 40},
              "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
              "end": {"point": [100.0, 0.0, 0.0], "direction": [-1.0, 0.0, 0.0], "twist": 720.0},
              "contact": {"self": True}}  # bench/bench_contact_placement.py --plectoneme
LOOP = {"hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "torsional_stiffness": 1e5,
                 "segments": 50},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
        "end": {"point": [150.0, 2.0, 0.0], "direction": [-1.0, 0.0, 0.0]}, "contact": {"self": True}}  # --loop
ARCH = {"hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]}}
DRUM = {"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0], "radius": 30.0, "name": "drum"}
CASES = {"loop": LOOP, "drum": ARCH | {"contact": {"obstacles": [DRUM]}},
         "drum along the path": ARCH | {"contact": {"placement": "along_path", "obstacles": [DRUM]}},
         "floor": floor_data(*SYMMETRIC)}
CONTROL = StepControl()


# --- the watch on made-up eigenvalues --------------------------------------------------------------------------------

def _watch(monkeypatch, lowest, fractions, bisecting=True):
    """A FoldWatch fed equilibria at `fractions` whose eigenvalues are lowest(t) (the contact evaluation skipped),
    the last reached after a failed try (bisecting) or not; the fractions it asked the eigenvalues of are in the list
    returned with it."""
    asked = []
    monkeypatch.setattr(continuation, "evaluate_contact", lambda props, clamps, state, model: clamps)
    monkeypatch.setattr(continuation, "lowest_stiffnesses",
                        lambda system, count: (asked.append(system), np.asarray(lowest(system), float))[1])
    watch = FoldWatch(None)
    for k, t in enumerate(fractions):
        if bisecting and k == len(fractions) - 1 and k > 0:
            watch.failed(fractions[k - 1], 2.0 * (t - fractions[k - 1]))
        watch.add(t, None, t, None)  # the clamps stand for the fraction
    assert not asked
    return watch, asked


def _square_root_fold(t_fold, other=lambda t: 40.0 + 30.0 * t):
    """The two lowest eigenvalues where one vanishes as sqrt(t_fold - t) (a fold at t_fold) beside another."""
    return lambda t: sorted([math.sqrt(max(25e3 * (t_fold - t), 0.0)), other(t)])


@pytest.mark.parametrize("fractions, late", [((0.5, 0.6), 0.2), ((0.6, 0.66), 0.07), ((0.655, 0.659), 0.007)])
def test_the_watch_extrapolates_the_square_of_the_eigenvalues_to_the_fold(monkeypatch, fractions, late):
    """lambda^2 is linear near a fold, so two equilibria predict it exactly while the other eigenvalue is constant,
    from far (0.16 of the path) or near, the vanishing one above the other or below it (63 against 40 at 0.5, 17 at
    0.659).  With the other one rising (40 + 30 t: the product's square is then not linear) the prediction comes late
    by `late` of the distance from the nearer equilibrium, less as the equilibria near the fold.  A line in lambda
    instead (its square root) would meet zero late by 1.6, 7.8 and 1.7 times that distance."""
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661, other=lambda t: 40.0), fractions)
    assert watch.fold() == pytest.approx(0.661, abs=1e-12)
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661), fractions)
    assert 0.0 < watch.fold() - 0.661 < late * (0.661 - fractions[1])


def test_the_watch_predicts_nothing_where_the_eigenvalues_rise_or_are_too_few(monkeypatch):
    watch, _ = _watch(monkeypatch, lambda t: [1.0 + t, 50.0], (0.2, 0.4))
    assert watch.fold() is None
    watch, _ = _watch(monkeypatch, lambda t: [1.0 - t], (0.2, 0.4))  # one eigenvalue (a tangent space of one)
    assert watch.fold() is None
    watch, asked = _watch(monkeypatch, lambda t: [1.0 - t, 50.0], (0.4,))
    assert watch.fold() is None and not asked


def test_the_watch_steps_towards_a_fold_only_after_a_second_failed_try_past_it_while_bisecting(monkeypatch):
    """A single failed try is halved without eigenvalues, and so are all from an equilibrium the path reached by a
    step it did not shorten (a step grown too long); the second in a row from one reached by a shortened step asks
    them, and the path goes APPROACH of the way to a fold predicted in the later half of the failed try, else halves."""
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.6, 0.65), bisecting=False)
    for dt in (0.028, 0.014, 0.007):
        assert watch.failed(0.65, dt) == 0.5 * dt
    assert not asked
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.6, 0.65))
    assert watch.failed(0.65, 0.016) == 0.008 and not asked  # the first failure: halved
    step = watch.failed(0.65, 0.008)  # the fold (about 0.661) is not within the failed try
    assert step == 0.004 and len(asked) == 2 and watch.aim is None
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661), (0.6, 0.65))
    watch.failed(0.65, 0.06)
    assert watch.failed(0.65, 0.03) == 0.015  # within the failed try's first half: halved
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661), (0.6, 0.65))
    watch.failed(0.65, 0.028)
    step = watch.failed(0.65, 0.014)  # within its later half: towards it
    ahead = watch.fold()
    assert 0.657 < ahead < 0.664 and step == pytest.approx(APPROACH * (ahead - 0.65))
    assert watch.aim == pytest.approx(ahead - 0.65) and watch.fallback == 0.007


def test_the_watch_goes_on_while_the_fold_comes_nearer_and_snaps_just_past_it(monkeypatch):
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661), (0.6, 0.65))
    watch.failed(0.65, 0.028)
    t, steps, snap = 0.65, 0, None
    step = watch.failed(0.65, 0.014)
    while snap is None:  # each step converges (made up): the prediction comes nearer
        t += step
        watch.add(t, None, t, None)
        step, snap = watch.converged(t, CONTROL)
        steps += 1
    assert steps < 10 and abs(snap - 0.661) < 1e-5 and t < 0.661
    assert snap - t <= 2 * CONTROL.smallest and step == pytest.approx(snap - t + CONTROL.smallest)


def test_the_watch_snaps_only_after_a_prediction_came_nearer(monkeypatch):
    """A fold predicted within two control.smallest at the start of a watch is stepped towards, not snapped at: the
    failed try and one prediction are not evidence enough (the loop's dip was predicted 3e-4 ahead)."""
    watch, _ = _watch(monkeypatch, _square_root_fold(0.661, other=lambda t: 40.0), (0.6605, 0.66085))
    watch.failed(0.66085, 4.8e-4)
    step = watch.failed(0.66085, 2.4e-4)
    assert step == pytest.approx(APPROACH * 1.5e-4)
    watch.add(0.66085 + step, None, 0.66085 + step, None)
    step, snap = watch.converged(0.66085 + step, CONTROL)
    assert snap == pytest.approx(0.661) and step == pytest.approx(0.25 * 1.5e-4 + CONTROL.smallest)


def test_the_watch_falls_back_to_halving_where_the_fold_recedes(monkeypatch):
    """The loop's dip (fraction 0.825, eigenvalues as measured): the lowest eigenvalue falls from 0.072 to 0.024 and
    rises again, so a prediction 3e-4 ahead moves to 3e-3 ahead after a step towards it: the watch ends and the path
    takes the step that halving would have taken.  (On the loop itself the path does not bisect there, and were it
    to, its failed tries, 0.05 and 0.025 long, would leave a fold 3e-4 ahead in their first half.)"""
    dip = {0.775: [0.0716, 3.77], 0.825: [0.0240, 0.877], 0.8252: [0.0235, 0.867]}
    watch, _ = _watch(monkeypatch, lambda t: dip[round(t, 4)], (0.775, 0.825))  # (bisecting, unlike the loop)
    assert watch.failed(0.825, 0.05) == 0.025
    assert watch.failed(0.825, 0.025) == 0.0125 and watch.aim is None
    watch.failed(0.825, 0.0004)  # a failed try short enough for the prediction to lie in its later half
    assert watch.aim is not None
    watch.add(0.8252, None, 0.8252, None)
    assert watch.converged(0.8252, CONTROL) == (0.0002, None) and watch.aim is None


# --- the plectoneme, the loop, the drum and the floor: with the watch and without ------------------------------------

def _placed(data, monkeypatch, watching=True):
    """(the result, the record): the placement with the fold watch, or blind (the old continuation: halving only); the
    record lists ("converged", t), ("failed", t, t + dt, the watch started), ("fold", t) (the path steps just past a
    predicted fold, where the hose snaps without a Newton try) and ("snap", phase, t, what) in order."""
    record = []
    with monkeypatch.context() as patch:
        if not watching:
            patch.setattr(FoldWatch, "fold", lambda watch: None)
        add, failed, converged, snap = FoldWatch.add, FoldWatch.failed, FoldWatch.converged, continuation._snap

        def added(watch, t, *rest):
            record.append(("converged", t))
            add(watch, t, *rest)

        def failing(watch, t, dt):
            out = failed(watch, t, dt)
            record.append(("failed", t, t + dt, watch.aim is not None))
            return out

        def towards(watch, *args):
            out = converged(watch, *args)
            if out[1] is not None:
                record.append(("fold", out[1]))
            return out

        def snapping(phase, clamps, props, before, start_from, model, tolerance, t_next, what, log):
            record.append(("snap", phase, t_next, what))
            return snap(phase, clamps, props, before, start_from, model, tolerance, t_next, what, log)

        patch.setattr(FoldWatch, "add", added)
        patch.setattr(FoldWatch, "failed", failing)
        patch.setattr(FoldWatch, "converged", towards)
        patch.setattr(continuation, "_snap", snapping)
        result = solve(problem_from_dict(data), estimate_error=False)
    return result, record


def _failed_tries(record):
    """Failed Newton tries: halved ones and the old continuation's last try at a fold."""
    return sum(item[0] == "failed" or (item[0] == "snap" and "(fold)" in item[3]) for item in record)


@pytest.fixture(scope="module")
def plectoneme():
    with pytest.MonkeyPatch.context() as patch:
        return _placed(PLECTONEME, patch), _placed(PLECTONEME, patch, watching=False)


def test_the_plectoneme_snaps_at_its_first_fold_where_the_old_bisection_found_it(plectoneme):
    (_, record), (_, old) = plectoneme
    first = next(k for k, item in enumerate(old) if item[0] == "snap" and "(fold)" in item[3])
    bracket = (next(item[1] for item in reversed(old[:first]) if item[0] == "converged"), old[first][2])
    assert bracket[1] - bracket[0] < 2 * CONTROL.smallest and old[first][1] == "twist"
    folds = [item[1] for item in record if item[0] == "fold"]
    assert folds, "the hose snapped at no predicted fold"
    fold = folds[0]
    assert bracket[0] - 1e-3 < fold < bracket[1] + 1e-3
    assert abs(fold - 0.5 * sum(bracket)) < 1e-4  # as measured: 0.661562 in (0.661540, 0.661662)


def test_the_plectoneme_makes_no_failed_try_between_the_watch_starting_and_the_snap(plectoneme):
    (result, record), (old_result, old) = plectoneme
    snaps = [k for k, item in enumerate(record) if item[0] == "fold"]
    assert snaps, "the hose snapped at no predicted fold"
    snap = snaps[0]
    start = max(k for k, item in enumerate(record[:snap]) if item[0] == "failed")
    assert record[start][3]  # the last failure before the snap started the watch that ended in it
    assert record[snap + 1][0] == "snap" and "predicted" in record[snap + 1][3]
    assert 2 * _failed_tries(record) < _failed_tries(old)  # as measured: 23 against 52
    assert result.iterations < 0.8 * old_result.iterations  # 391 against 593
    # the same loop of the hose, or a symmetric image of it (here reversed end to end and turned about the mounts' axis)
    assert result.stable and result.elastic_energy == pytest.approx(old_result.elastic_energy, rel=1e-9)
    assert result.contacts[0].min_gap == pytest.approx(old_result.contacts[0].min_gap, rel=1e-6)


@pytest.mark.parametrize("case", list(CASES))
def test_the_watch_leaves_the_final_equilibrium_where_the_old_path_ends(monkeypatch, case):
    """Where the path does not bisect, the watch asks no eigenvalues: the loop's failed tries (two or three from 0.4
    and from 0.825) are each followed by a shortened step that converges and by growth from there; the drum and the
    floor fail no try.  The same path: the loop takes its 318 Newton iterations."""
    asked = []
    lowest = continuation.lowest_stiffnesses
    monkeypatch.setattr(continuation, "lowest_stiffnesses", lambda system, count: (asked.append(1),
                                                                                    lowest(system, count))[1])
    result, record = _placed(CASES[case], monkeypatch)
    old, _ = _placed(CASES[case], monkeypatch, watching=False)
    assert np.max(np.abs(result.centerline - old.centerline)) < 1e-6
    assert result.iterations == old.iterations and not asked
    assert (_failed_tries(record) > 0) == (case == "loop")
