"""Fuzzing the command line (short run): mutated and generated inputs of every kind never break it.

For each kind of tests/fuzz_cases.py, Hypothesis generates inputs and the oracle checks: no
traceback, exit code 0/2/3/4 only, nothing written on failure, a one-line "error:" message,
feasible problems solved (or a clear solver failure), and every exit-0 result finite,
converged, stable and of exact length.  The long campaign (10 000 inputs) is bench/fuzz.py.
"""

import pytest
from fuzz_cases import KINDS, STRATEGIES, fresh_folder, run_input
from hypothesis import HealthCheck, Phase, given, settings

# examples per kind in `make test`: the sweeps and scans cost about a second each when they succeed
SHORT_RUN = {"problem": 30, "iges": 20, "feasible": 10, "sweep": 6, "poses": 5, "mesh": 5, "feasible_sweep": 2,
             "cloud": 5, "contact": 16}


@pytest.mark.parametrize("kind", KINDS)
def test_generated_inputs_never_break_the_command_line(kind, tmp_path_factory):
    root = tmp_path_factory.mktemp(f"fuzz-{kind}")

    # no shrinking: a failing sweep costs seconds per try; the message gives the whole input instead
    @settings(max_examples=SHORT_RUN[kind], deadline=None, derandomize=True, database=None,
              phases=(Phase.explicit, Phase.generate), suppress_health_check=list(HealthCheck))
    @given(STRATEGIES[kind]())
    def check(case):
        outcome = run_input(case, fresh_folder(root, "case"))
        assert outcome.failure is None, f"{outcome.failure}: {outcome.detail}\nargs: {case.args}\nout: {case.out}"

    check()


def test_the_oracle_catches_what_it_must(tmp_path, monkeypatch):
    """The oracle is not blind: a traceback, files left after a failure, a wrong result, a result inside an
    obstacle and a contact layout refused without naming the obstacle or what to change are each caught."""
    from cases import THESIS_TOML
    from fuzz_cases import THESIS_WITH_CONTACT, FuzzInput

    from hoseline.io import results
    from hoseline.procedures.placement import sequence

    case = FuzzInput("problem", {"problem.toml": THESIS_TOML.encode()}, ["solve", "problem.toml", "-o", "OUT", "-q"])
    assert run_input(case, fresh_folder(tmp_path, "good")).failure is None

    def crash(problem, **options):
        raise ZeroDivisionError("a bug")

    with monkeypatch.context() as patch:
        patch.setattr(sequence, "solve", crash)
        assert run_input(case, fresh_folder(tmp_path, "crash")).failure == "traceback"

    def partial(problem, **options):
        (tmp_path / "left" / "out").mkdir()
        raise sequence.PlacementError("failed after writing")

    with monkeypatch.context() as patch:
        patch.setattr(sequence, "solve", partial)
        folder = fresh_folder(tmp_path, "left")
        assert run_input(case, folder).failure == "partial_output"

    document = results.result_document

    def stretched(result):
        data = document(result)
        data["stations"]["centerline"][-1][0] += 1.0  # the end station moved: longer, and off its mount
        return data

    with monkeypatch.context() as patch:
        patch.setattr(results, "result_document", stretched)
        outcome = run_input(case, fresh_folder(tmp_path, "stretched"))
        assert outcome.failure == "bad_result" and "mm long" in outcome.detail and "off its mount" in outcome.detail

    def entering(result):
        data = document(result)
        data["summary"]["contact"] = {"min_gap_mm": -0.01, "obstacles": []}  # as if the hose were 0.01 mm inside
        return data

    with monkeypatch.context() as patch:
        patch.setattr(results, "result_document", entering)
        outcome = run_input(case, fresh_folder(tmp_path, "entering"))
        assert outcome.failure == "bad_result" and "enters an obstacle" in outcome.detail

    # a contact layout refused: the message must name an obstacle (or the self-contact) and say what to change
    layout = FuzzInput("contact", {"problem.toml": THESIS_WITH_CONTACT}, ["solve", "problem.toml", "-o", "OUT", "-q"],
                       obstacles=("plane", "box"))
    for message, verdict in (("placement phase 'place' failed at fraction 0.45: iteration limit reached", "unclear_error"),
                             ("the hose is inside obstacle 'box' at station 5", "unclear_error"),
                             ("the hose is inside obstacle 'box' at station 5: move the obstacle", None),
                             ("pressed hardest against 'self': try more segments", None)):

        def refused(problem, **options):
            raise sequence.PlacementError(message)

        with monkeypatch.context() as patch:
            patch.setattr(sequence, "solve", refused)
            outcome = run_input(layout, fresh_folder(tmp_path, "refused"))
            assert outcome.exit_code == 3 and outcome.failure == verdict, message
