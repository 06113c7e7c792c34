"""The fold watch of the contact continuation (procedures/contact/continuation.py, FoldWatch; docs/model.md, Contact,
"Passing folds").

At a fold the lowest eigenvalue of the Hessian on the constraint tangent space goes to zero as sqrt(t_fold - t), so
its square is linear in the path fraction t: the watch extrapolates the square of the product of the two lowest from
the last two equilibria.  It looks ahead: where the determinant of that Hessian (free from the converged Newton's
factor) extrapolates to zero within DETERMINANT_REACH of the next step, or on the first step after a snap, it asks the
eigenvalues, and where they predict a fold within the next step it steps towards it, on while each prediction comes
nearer, and snaps just past it without a Newton try.  Behind that, the old rules: where the path bisects (a second
failed try in a row from an equilibrium reached by a shortened step) and the predicted fold lies in the later half of
the failed try, it steps towards it.  Checked here: the extrapolation itself (eigenvalues made up to vanish as a square
root: exact; a line in lambda instead of lambda^2 is not), each rule of the watch on made-up eigenvalues and
determinants, the twisted hose of three turns passing its folds without a failed Newton try where halving alone fails
tens, and ending where a path of steps twelve times shorter ends, and the same final equilibria as the old path on the
loop (whose lowest eigenvalue dips at fraction 0.825 without vanishing), the drum and the floor.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

import hoseline.procedures.contact.bring_in as bring_in
import hoseline.procedures.contact.continuation as continuation
import hoseline.procedures.contact.cushion as cushion
import hoseline.procedures.placement.tracking as tracking
from hoseline.demos.floor import SYMMETRIC, floor_data
from hoseline.io.problem_file import problem_from_dict
from hoseline.procedures.contact.continuation import APPROACH, DETERMINANT_REACH, FoldWatch
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

def _watch(monkeypatch, lowest, fractions, bisecting=True, log_det=lambda t: math.nan, probing=False):
    """A FoldWatch fed equilibria at `fractions` whose eigenvalues are lowest(t) and the log of whose determinant is
    log_det(t) (the contact evaluation skipped), the last reached after a failed try (bisecting) or not, the watch
    started at a snap (probing) or not; the fractions it asked the eigenvalues of are in the list returned with it."""
    asked = []
    monkeypatch.setattr(continuation, "evaluate_contact", lambda props, clamps, state, model: clamps)
    monkeypatch.setattr(continuation, "lowest_stiffnesses",
                        lambda system, count: (asked.append(system), np.asarray(lowest(system), float))[1])
    watch = FoldWatch(None, probing=probing)
    for k, t in enumerate(fractions):
        if bisecting and k == len(fractions) - 1 and k > 0:
            watch.failed(fractions[k - 1], 2.0 * (t - fractions[k - 1]))
        watch.add(t, None, t, None, log_det(t))  # the clamps stand for the fraction
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


def _falling_determinant(t_fold):
    """log |det| of a Hessian whose one eigenvalue vanishes as sqrt(t_fold - t) while the others stay (det^2 linear)."""
    return lambda t: 0.5 * math.log(max(25e3 * (t_fold - t), 1e-300)) + 100.0


def test_the_watch_looks_ahead_where_the_determinant_falls_towards_zero(monkeypatch):
    """After a converged step the watch asks the eigenvalues only where the determinant's square, extrapolated along
    the last two equilibria, reaches zero within DETERMINANT_REACH of the next step (the determinant costs nothing:
    the converged Newton's factor gives it); where they predict a fold within the next step it steps APPROACH of the
    way to it, so that no Newton try meets the fold.  A fold first predicted in the first half of the next step is
    left to the path (the strut's lowest eigenvalues fall 17-fold as the hose slides on it and rise again: a fold
    predicted 0.012 ahead of a step of 0.2 receded after the step towards it, three times, 40 ms)."""
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False,
                          log_det=_falling_determinant(0.661))
    assert watch.ahead(0.6, 0.1) == pytest.approx(APPROACH * (watch.fold() - 0.6)) and asked
    assert watch.aim == pytest.approx(watch.fold() - 0.6) and watch.fallback == 0.1
    far = (0.061 - 1e-3) / DETERMINANT_REACH  # the fold just beyond the determinant's reach
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False,
                          log_det=_falling_determinant(0.661))
    assert watch.ahead(0.6, far) == far and not asked and watch.aim is None
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False,
                          log_det=lambda t: 100.0 + t)  # a rising determinant
    assert watch.ahead(0.6, 0.1) == 0.1 and not asked
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False)  # none known
    assert watch.ahead(0.6, 0.1) == 0.1 and not asked
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False,
                          log_det=_falling_determinant(0.661))
    assert watch.ahead(0.6, 0.05) == 0.05 and asked and watch.aim is None  # asked: the fold lies beyond this step
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661), (0.55, 0.6), bisecting=False,
                          log_det=_falling_determinant(0.661))
    assert watch.ahead(0.6, 0.15) == 0.15 and asked and watch.aim is None  # first seen in the step's first half: left


def test_the_watch_asks_again_only_where_the_determinant_falls_faster_than_where_no_fold_was_near(monkeypatch):
    """Once the eigenvalues saw no fold near (a fold far beyond the step: the determinant fell as a contact let go),
    the watch does not ask them again on the branch while log |det| falls no faster per unit of the path; where it
    falls faster (towards a fold its fall steepens without end) it asks, and steps towards the fold it sees."""
    falls = {0.5: 100.0, 0.55: 99.0, 0.6: 98.5, 0.62: 97.5, 0.64: 92.0}  # log |det| at each fraction
    watch, asked = _watch(monkeypatch, _square_root_fold(0.7), (0.5, 0.55), bisecting=False, log_det=falls.get)
    assert watch.ahead(0.55, 0.05) == 0.05 and asked and watch.calm == pytest.approx(20.0)  # 0.7 is beyond 0.6
    asked.clear()
    watch.add(0.6, None, 0.6, None, falls[0.6])  # falling 10 per unit: slower than where no fold was near
    assert watch.ahead(0.6, 0.02) == 0.02 and not asked
    watch.add(0.62, None, 0.62, None, falls[0.62])  # 50 per unit, faster: asked, and the fold at 0.7 lies beyond
    assert watch.ahead(0.62, 0.02) == 0.02 and asked and watch.calm == pytest.approx(50.0)
    asked.clear()
    watch.add(0.64, None, 0.64, None, falls[0.64])  # 275 per unit: asked, and the fold is in the next step's later half
    assert watch.ahead(0.64, 0.08) == pytest.approx(APPROACH * (watch.fold() - 0.64)) and asked and watch.calm is None


def test_the_watch_asks_the_eigenvalues_at_the_first_step_after_a_snap(monkeypatch):
    """A branch that starts at a snap (its start's determinant unknown) asks the eigenvalues after its first, short
    step: the plectoneme's second fold lies 0.006 of its phase past the first."""
    watch, asked = _watch(monkeypatch, _square_root_fold(0.661, other=lambda t: 40.0), (0.655, 0.6554),
                          bisecting=False, probing=True)
    assert watch.ahead(0.6554, 0.0417) == pytest.approx(APPROACH * (0.661 - 0.6554)) and asked
    assert watch.ahead(0.6554, 0.0417) == 0.0417  # once: the next steps go by the determinant


# --- the twisted hose, the loop, the drum and the floor: with the watch and without ------------------------------------

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


THREE_TURNS = PLECTONEME | {"end": PLECTONEME["end"] | {"twist": 1080.0}}
FINE = 0.02  # of the path: the longest step of the reference path (the default takes up to 0.25, the twist 0.0625)


@pytest.fixture(scope="module")
def three_turns():
    with pytest.MonkeyPatch.context() as patch:
        return _placed(THREE_TURNS, patch), _placed(THREE_TURNS, patch, watching=False)


def test_the_twisted_hose_passes_every_fold_without_a_failed_newton_try(three_turns):
    """Twisted three turns (bench/bench_contact_placement.py --plectoneme --turns 3), the hose meets folds in the place
    and the twist phases: the watch predicts each, snaps just past it without a Newton try, and no try fails on the
    whole placement (as measured: 3 folds passed, 0 failed tries); halving alone fails tens (93)."""
    (result, record), (_, old) = three_turns
    folds = [k for k, item in enumerate(record) if item[0] == "fold"]
    assert len(folds) >= 2 and any(record[k + 1][1] == "twist" for k in folds)
    for k in folds:
        assert record[k + 1][0] == "snap" and "predicted" in record[k + 1][3]
    assert _failed_tries(record) == 0
    assert _failed_tries(old) > 20
    assert result.stable


def test_the_twisted_hose_ends_where_a_path_of_short_steps_ends(three_turns, monkeypatch):
    """The snaps' places decide which of the hose's many stable shapes the path ends in: halving alone, from steps up
    to 0.25 of the path, ends elsewhere (58 243 against 36 270 N*mm) than the same halving with steps of at most FINE,
    twelve times shorter in the twist phase; the watch, which stops short of each fold and snaps there, ends where the
    short steps end, with fewer Newton iterations (as measured: 462 against 850)."""
    (result, _), (old, _) = three_turns
    follow = continuation.follow_contact

    def short_steps(*args, control=StepControl(), **kwargs):
        return follow(*args, control=replace(control, first=min(control.first, FINE),
                                             largest=min(control.largest, FINE)), **kwargs)

    for module in (continuation, cushion, bring_in, tracking):  # every caller of the contact continuation
        monkeypatch.setattr(module, "follow_contact", short_steps)
    fine, _ = _placed(THREE_TURNS, monkeypatch, watching=False)
    assert fine.elastic_energy == pytest.approx(result.elastic_energy, rel=1e-9)
    assert fine.contacts[0].min_gap == pytest.approx(result.contacts[0].min_gap, rel=1e-6)
    assert abs(old.elastic_energy - result.elastic_energy) > 0.1 * result.elastic_energy
    assert result.iterations < fine.iterations


@pytest.mark.parametrize("case", list(CASES))
def test_the_watch_leaves_the_final_equilibrium_where_the_old_path_ends(monkeypatch, case):
    """The drum and the floor fail no try and their determinants predict no fold near: the watch asks no eigenvalues
    and the path is the old one.  The loop's lowest eigenvalue dips at fraction 0.825 (0.072 to 0.024) and rises again:
    its determinant asks the eigenvalues there, the watch steps towards the dip until the prediction recedes, and the
    path ends at the same equilibrium, with no more failed tries (all steps grown too long: as measured 8 against 10)
    and no more Newton iterations (310 against 318)."""
    asked = []
    lowest = continuation.lowest_stiffnesses
    monkeypatch.setattr(continuation, "lowest_stiffnesses", lambda system, count: (asked.append(1),
                                                                                    lowest(system, count))[1])
    result, record = _placed(CASES[case], monkeypatch)
    old, old_record = _placed(CASES[case], monkeypatch, watching=False)
    assert np.max(np.abs(result.centerline - old.centerline)) < 1e-6
    if case == "loop":
        assert 0 < _failed_tries(record) <= _failed_tries(old_record) and result.iterations <= old.iterations
    else:
        assert result.iterations == old.iterations and not asked and _failed_tries(record) == 0
