"""The unstable count of the bordered solve (neg(H) + pos(S) - r) against a dense count: the
eigenvalues of the Hessian on the null space of the border, on random banded matrices of the
rod's shape (half bandwidth 5) with borders of 3 + 3c rows like the end and clip rows."""

import numpy as np
import pytest
import scipy.linalg

from hoseline.mechanics.banded import NEUTRAL, band_to_dense, ldlt_banded
from hoseline.mechanics.bordered import kkt_solve_bordered

HALF_BANDWIDTH = 5
UNKNOWNS = 61  # 20 segments and a roll


def random_band(rng, kind):
    """A symmetric banded matrix: "definite" (positive definite), "indefinite", or "growth": indefinite
    with its leading 3 x 3 block (the first segment) singular to 1e-11 and coupled to the next rows,
    as a coaxial clip makes it (tests/test_clips.py): the factor without pivoting grows by ~1e10."""
    band = np.zeros((UNKNOWNS, HALF_BANDWIDTH + 1))
    band[:, 1:] = rng.normal(size=(UNKNOWNS, HALF_BANDWIDTH))
    band[:, 0] = 3.0 * rng.normal(size=UNKNOWNS)
    for k in range(1, HALF_BANDWIDTH + 1):
        band[:k, k] = 0.0
    if kind == "growth":
        rank_two = rng.normal(size=(3, 2))
        lead = rank_two @ rank_two.T + rng.choice([-1.0, 1.0]) * 1e-11 * np.eye(3)
        for i in range(3):
            band[i, : i + 1] = lead[i, i::-1]
    if kind == "definite":
        band[:, 0] += 1.0 - np.linalg.eigvalsh(band_to_dense(band))[0]
    return band


def random_border(rng, clips, clip_scales, dependence):
    """J^T (n, 3 + 3c): three dense end rows, then three rows per clip reaching only the unknowns
    before it, scaled by clip_scales.  dependence: None, or the size (relative to the rows) of what
    keeps the last row from being a combination of two others (a span nearly pulled straight)."""
    rows = [rng.normal(size=UNKNOWNS) for _ in range(3)]
    for scale in clip_scales[:clips]:
        reach = rng.integers(6, UNKNOWNS - 6)
        for _ in range(3):
            row = np.zeros(UNKNOWNS)
            row[:reach] = scale * rng.normal(size=reach)
            rows.append(row)
    jac = np.array(rows)
    if dependence is not None:
        jac[-1] = 0.7 * jac[3] + 0.2 * jac[4] + dependence * np.max(np.abs(jac[3])) * rng.normal(size=UNKNOWNS)
    return jac.T.copy()


def dense_unstable_count(band, jac_t):
    """Negative eigenvalues of H on the null space of the independent rows of J: singular values
    of J below sqrt(NEUTRAL) of the largest are dependent rows, as in bordered.tangent_space_inertia."""
    basis = scipy.linalg.null_space(jac_t.T, rcond=np.sqrt(NEUTRAL))
    values = np.linalg.eigvalsh(basis.T @ band_to_dense(band) @ basis)
    return int(np.sum(values < -NEUTRAL * np.max(np.abs(values))))


@pytest.mark.parametrize("kind, clip_scales, dependence", [
    ("definite", (1.0, 1.0), None),
    ("indefinite", (1.0, 1.0), None),
    ("definite", (1e-3, 30.0), None),  # rows of mixed scales: a clip near the start, one far along
    ("indefinite", (1e-3, 30.0), None),
    ("growth", (1.0, 1.0), None),
    ("growth", (1e-3, 30.0), None),
    ("definite", (1.0, 1.0), 1e-4),  # a row nearly dependent: still independent
    ("indefinite", (1.0, 1.0), 1e-4),
    ("definite", (1e-3, 30.0), 1e-7),  # dependent to 1e-7: counted on the independent rows
    ("indefinite", (1e-3, 30.0), 1e-7),
])
def test_bordered_count_equals_the_dense_null_space_count(kind, clip_scales, dependence):
    for seed in range(24):
        rng = np.random.default_rng(seed)
        band = random_band(rng, kind)
        jac_t = random_border(rng, 1 + seed % 2, clip_scales, dependence)
        m = jac_t.shape[1]
        lower, diag, negative, _ = ldlt_banded(band, 0.0)
        unstable = kkt_solve_bordered(lower, diag, negative, jac_t, np.zeros(UNKNOWNS), np.zeros(m))[2]
        assert unstable == dense_unstable_count(band, jac_t), f"seed {seed}"


def test_pivot_count_is_that_of_the_dense_eigenvalues_when_the_factor_grows():
    """Without pivoting, a pivot near zero that couples to the next rows makes the next pivot huge
    (-b^2 / pivot, ~1e10 of the matrix scale here).  The negative pivots of ordinary size must still
    count (a threshold relative to the largest pivot dropped them: -3 unstable directions)."""
    grown = 0
    for seed in range(24):
        band = random_band(np.random.default_rng(seed), "growth")
        _, diag, negative, _ = ldlt_banded(band, 0.0)
        grown += np.max(np.abs(diag)) > 1e6 * np.max(np.abs(band[:, 0]))
        assert negative == int(np.sum(np.linalg.eigvalsh(band_to_dense(band)) < 0.0)), f"seed {seed}"
    assert grown >= 20  # the cases do grow


@pytest.mark.parametrize("kind, dependence", [("definite", None), ("indefinite", None), ("growth", None),
                                              ("indefinite", 1e-7)])
def test_sliding_count_equals_the_dense_null_space_count_with_the_arc_lengths(kind, dependence):
    """A sliding clip adds its arc length s to the unknowns, outside the band (clipped_newton._step): the count is
    that of the Hessian in (rotations, arc lengths) on the null space of the constraint rows over both."""
    from hoseline.mechanics.clipped_newton import SlidingSystem, _step

    for seed in range(24):
        rng = np.random.default_rng(100 + seed)
        band = random_band(rng, kind)
        jac_t = random_border(rng, 2, (1.0, 1e-2), dependence)
        m, sliding = jac_t.shape[1], 1 + seed % 2
        mixed = rng.normal(size=(UNKNOWNS, sliding))
        stretch_hessian = rng.normal(size=(sliding, sliding))
        stretch_hessian = stretch_hessian + stretch_hessian.T
        stretch_jac = rng.normal(size=(m, sliding))
        if dependence is not None:  # the nearly dependent row stays so over the arc lengths too
            stretch_jac[-1] = 0.7 * stretch_jac[3] + 0.2 * stretch_jac[4]
        system = SlidingSystem(0.0, np.zeros(UNKNOWNS), band, jac_t, np.zeros(m), 0.0, True, np.zeros(sliding), mixed,
                               stretch_hessian, stretch_jac)
        unstable = _step(system, 0.0)[2]
        hessian = np.block([[band_to_dense(band), mixed], [mixed.T, stretch_hessian]])
        rows = np.hstack([jac_t.T, stretch_jac])
        basis = scipy.linalg.null_space(rows, rcond=np.sqrt(NEUTRAL))
        values = np.linalg.eigvalsh(basis.T @ hessian @ basis)
        assert unstable == int(np.sum(values < -NEUTRAL * np.max(np.abs(values)))), f"seed {seed}"
