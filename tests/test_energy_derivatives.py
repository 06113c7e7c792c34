"""Finite-difference checks of the rod's gradient and Hessian: bending, torsion (isotropic
and anisotropic), gravity, the end-position constraint and the free end roll."""

import numpy as np
import pytest

from hoseline.mechanics.energy import BANDWIDTH, assemble
from hoseline.mechanics.newton import RodProperties, apply_step
from hoseline.mechanics.rod import Clamps, RodState, segment_loads
from hoseline.mechanics.rotations import rotate_frames, rotation_matrix


def random_frames(rng, count, spread=0.4):
    base = np.eye(3)
    frames = np.empty((count, 3, 3))
    for i in range(count):
        base = base @ rotation_matrix(rng.normal(scale=spread, size=3)).T
        frames[i] = base
    return frames


def lagrangian(frames, start, end, stiffness, h, loads, roll_free):
    n = 3 * frames.shape[0] + (1 if roll_free else 0)
    grad = np.empty(n)
    band = np.empty((n, BANDWIDTH + 1))
    e_el, e_seg = assemble(frames, start, end, stiffness, h, loads, roll_free, grad, band)
    return e_el + e_seg, grad, band


def dense(band):
    n = band.shape[0]
    out = np.zeros((n, n))
    for k in range(band.shape[1]):
        for i in range(k, n):
            out[i, i - k] = out[i - k, i] = band[i, k]
    return out


def perturbed(frames, end, delta, roll_free):
    n_seg = frames.shape[0]
    new = rotate_frames(frames, delta[: 3 * n_seg].reshape(n_seg, 3))
    if roll_free:
        end = end @ rotation_matrix(delta[-1] * end[2]).T
    return new, end


def finite_differences(energy_and_gradient, frames, end, n, roll_free, eps):
    """Central differences of the energy (-> gradient) and of the gradient (-> Hessian) over
    the n rotation unknowns; energy_and_gradient(frames, end_frame) -> (energy, gradient)."""
    fd_grad = np.empty(n)
    fd_hess = np.empty((n, n))
    for j in range(n):
        delta = np.zeros(n)
        delta[j] = eps
        e_plus, g_plus = energy_and_gradient(*perturbed(frames, end, delta, roll_free))
        e_minus, g_minus = energy_and_gradient(*perturbed(frames, end, -delta, roll_free))
        fd_grad[j] = (e_plus - e_minus) / (2 * eps)
        fd_hess[:, j] = (g_plus - g_minus) / (2 * eps)
    return fd_grad, fd_hess


@pytest.mark.parametrize(
    "stiffness, loaded, roll_free",
    [
        ((1.0, 1.0, 1.0 / 1.5), False, False),  # isotropic bending + torsion
        ((1.0, 2.5, 25.0), False, False),  # anisotropic, stiff torsion
        ((1.0, 1.0, 25.0), True, False),  # with gravity and constraint loads
        ((1.0, 3.0, 0.3), True, True),  # free end roll
    ],
)
def test_gradient_and_hessian_match_finite_differences(stiffness, loaded, roll_free):
    rng = np.random.default_rng(7)
    count, h = 6, 0.8
    frames = random_frames(rng, count)
    start = rotation_matrix(rng.normal(size=3))
    end = rotation_matrix(rng.normal(size=3))
    stiffness = np.array(stiffness)
    loads = rng.normal(size=(count, 3)) if loaded else np.zeros((count, 3))
    energy, grad, band = lagrangian(frames, start, end, stiffness, h, loads, roll_free)
    hess = dense(band)
    fd_grad, fd_hess = finite_differences(
        lambda f, e: lagrangian(f, start, e, stiffness, h, loads, roll_free)[:2], frames, end, grad.size, roll_free, 1e-5
    )
    assert np.allclose(grad, fd_grad, rtol=1e-7, atol=1e-8 * np.max(np.abs(grad)))
    # the gradient is taken at delta = 0 each time, so its finite difference is the Hessian
    # of the pulled-back energy only up to the antisymmetric Lie-bracket term 1/2 [delta_j] x g;
    # compare symmetric parts and check that the Hessian itself is exactly symmetric.
    sym_fd = 0.5 * (fd_hess + fd_hess.T)
    assert np.allclose(hess, sym_fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(hess)))


def test_hessian_second_order_expansion():
    """E(exp(delta)) = E + g.delta + 1/2 delta.H.delta + O(|delta|^3): the error falls as eps^3."""
    rng = np.random.default_rng(3)
    count, h = 5, 1.3
    frames = random_frames(rng, count)
    start, end = rotation_matrix(rng.normal(size=3)), rotation_matrix(rng.normal(size=3))
    stiffness = np.array([2.0, 1.0, 20.0])
    loads = rng.normal(size=(count, 3))
    e0, g, band = lagrangian(frames, start, end, stiffness, h, loads, True)
    hess = dense(band)
    direction = rng.normal(size=g.size)
    errors = []
    for eps in (1e-2, 5e-3, 2.5e-3):
        fp, ep = perturbed(frames, end, eps * direction, True)
        e, _, _ = lagrangian(fp, start, ep, stiffness, h, loads, True)
        errors.append(abs(e - (e0 + eps * g @ direction + 0.5 * eps**2 * direction @ hess @ direction)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 2.8), orders


def test_constraint_jacobian_and_weight_potential_match_finite_differences():
    """J = d(tip)/d(delta) and the segment loads are the gradient of the weight potential."""
    from hoseline.mechanics.rod import centerline, constraint_jacobian_t, gravity_energy

    rng = np.random.default_rng(11)
    count, h = 7, 2.0
    frames = random_frames(rng, count)
    start = np.array([1.0, -2.0, 0.5])
    weight = np.array([0.1, -0.3, -1.0])
    jac = constraint_jacobian_t(frames, h).T
    loads = segment_loads(frames, np.zeros(3), weight, h)
    eps = 1e-6
    for j in range(3 * count):
        delta = np.zeros(3 * count)
        delta[j] = eps
        fp = rotate_frames(frames, delta.reshape(count, 3))
        fm = rotate_frames(frames, -delta.reshape(count, 3))
        d_tip = (centerline(fp, start, h)[-1] - centerline(fm, start, h)[-1]) / (2 * eps)
        assert np.allclose(d_tip, jac[:, j], atol=1e-8)
        d_potential = (gravity_energy(fp, start, weight, h) - gravity_energy(fm, start, weight, h)) / (2 * eps)
        i, axis = divmod(j, 3)
        assert np.isclose(d_potential, np.cross(loads[i], frames[i, 2])[axis], atol=1e-8)
