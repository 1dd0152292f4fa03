"""Model reduction (issue 24): balanced truncation and residualisation against Glover's bound on
five plants (the H∞ error by flexsat.analysis.norms), the Hankel singular values against the
eigenvalues of PQ, the balanced Gramians, DC matching of the residualised model, rigid modes
kept exactly, and the modal indices against their identities and Gawronski's closed forms."""

import math

import numpy as np
import pytest

import control as ct
from flexsat.analysis.frequency_domain import frequency_response
from flexsat.analysis.norms import h2_norm
from flexsat.analysis.reduction import (
    balanced_reduction,
    compare_reductions,
    hankel_singular_values,
    modal_form,
    modal_indices,
    modal_truncation,
    reduction_error,
    split_stable,
)
from flexsat.input_checks import FieldError


def modal_plant(omegas, zetas, b, cq, cv, rigid=False, seed_name="plant"):
    """A plant of decoupled modes (companion blocks), optionally with a rigid double integrator."""
    blocks, B, C = [], [], []
    if rigid:
        blocks.append(np.array([[0.0, 1.0], [0.0, 0.0]]))
        B.append(np.array([[0.0] * b.shape[1], list(b[0])]))
        C.append(np.column_stack([cq[:, 0], cv[:, 0]]))
    k0 = 1 if rigid else 0
    for i, (w, z) in enumerate(zip(omegas, zetas)):
        blocks.append(np.array([[0.0, 1.0], [-(w**2), -2 * z * w]]))
        B.append(np.vstack([np.zeros(b.shape[1]), b[k0 + i]]))
        C.append(np.column_stack([cq[:, k0 + i], cv[:, k0 + i]]))
    import scipy.linalg as sla

    A = sla.block_diag(*blocks)
    return ct.ss(A, np.vstack(B), np.hstack(C), np.zeros((cq.shape[0], b.shape[1])), name=seed_name)


def random_stable(n, p, m, rng):
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.3) * np.eye(n)
    return ct.ss(A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), np.zeros((p, m)))


def tamu_plant():
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.linear_model import plant_state_space

    return plant_state_space(tamu().model(), outputs=["theta", "theta_dot", "root_moment"])


def five_plants():
    rng = np.random.default_rng(24)
    w = np.array([1.0, 2.7, 6.1, 11.0, 19.0, 30.0])
    n = w.size
    beam = modal_plant(
        w,
        np.full(n, 0.01),
        rng.standard_normal((n, 2)),
        rng.standard_normal((3, n)),
        np.zeros((3, n)),
    )
    rigid = modal_plant(
        w,
        np.full(n, 0.005),
        rng.standard_normal((n + 1, 1)),
        rng.standard_normal((2, n + 1)),
        rng.standard_normal((2, n + 1)),
        rigid=True,
    )
    return {
        "tamu_10_modes": (tamu_plant(), 6),
        "modal_mimo": (beam, 5),
        "modal_with_rigid_mode": (rigid, 4),
        "random_siso_12": (random_stable(12, 1, 1, rng), 4),
        "random_mimo_15": (random_stable(15, 3, 2, rng), 7),
    }


PLANTS = five_plants()


@pytest.mark.parametrize("method", ["truncate", "residualize"])
@pytest.mark.parametrize("name", sorted(PLANTS))
def test_error_under_glover_bound(name, method):
    """σ_{r+1} <= ‖G − G_r‖∞ <= 2 Σ_{i>r} σ_i (Glover 1984: the lower bound holds for every
    order-r model, the upper for balanced truncation and residualisation); the H∞ norm is
    bracketed to 2e-8 relative by hinf_norm, far inside both."""
    plant, order = PLANTS[name]
    red = balanced_reduction(plant, order, method)
    err = reduction_error(red)
    s = red.hankel_singular_values
    assert red.error_bound == pytest.approx(2 * s[order:].sum(), rel=1e-14)
    assert err <= red.error_bound * (1 + 1e-6)
    assert err >= s[order] * (1 - 1e-6)
    assert red.system.nstates == order + red.n_kept_exactly
    assert list(red.system.input_labels) == list(plant.input_labels)
    assert list(red.system.output_labels) == list(plant.output_labels)


def test_hankel_values_are_roots_of_pq_and_reduced_model_is_balanced():
    """σ_i² = eig(PQ) (definition); the truncated model's Gramians are both diag(σ_1..σ_r)
    (balanced truncation preserves balancing, Moore 1981). Tolerance: Lyapunov solves at
    condition ~1e4 × eps."""
    import scipy.linalg as sla

    plant, order = PLANTS["random_mimo_15"]
    A, B, C = plant.A, plant.B, plant.C
    P = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Q = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
    ref2 = np.sort(np.linalg.eigvals(P @ Q).real)[::-1]
    s = hankel_singular_values(plant)
    # eig of the non-symmetric PQ: absolute error ~ n κ eps ‖PQ‖ on σ² (the reason the
    # square-root method is used), so σ² is compared with that absolute tolerance
    np.testing.assert_allclose(s**2, ref2, rtol=1e-8, atol=1e3 * np.finfo(float).eps * ref2[0])
    red = balanced_reduction(plant, order)
    Ar, Br, Cr, _ = red.stable_reduced
    Pr = sla.solve_continuous_lyapunov(Ar, -Br @ Br.T)
    Qr = sla.solve_continuous_lyapunov(Ar.T, -Cr.T @ Cr)
    np.testing.assert_allclose(Pr, np.diag(s[:order]), atol=1e-8 * s[0])
    np.testing.assert_allclose(Qr, np.diag(s[:order]), atol=1e-8 * s[0])


@pytest.mark.numerics
def test_hankel_values_of_a_stiff_weakly_controllable_mode_are_accurate():
    """TAMU's highest modes are barely controllable from the hub torque and strongly observable
    in the root moment: their Gramian entries are ~1e-11 against ‖P‖ = 4.5, below the
    ε‖P‖-per-entry error of a Bartels–Stewart solve on the whole matrix. Solved block pair by
    block pair in the modal form, (a) each mode's pair of Hankel values brackets, within the
    modal coupling, that mode's own Hankel index (Gawronski 2004 §5.3, its 2 × 2 Lyapunov
    equations), and (b) the values do not move when that mode's states are rescaled by 1e±3 (a
    similarity: the transfer function and so every σ are unchanged). Tolerances: (a) 2 % — the
    mode's coupling to its neighbours through the Gramians, ζ = 0.005 and spacing > 25 %;
    (b) 1e-9 relative, the eigenvector matrix's condition (< 1e4) times eps, with margin."""
    import control as ct
    from flexsat.analysis.reduction import modal_form, modal_indices, split_stable
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.linear_model import plant_state_space

    plant = plant_state_space(tamu().model())
    s = hankel_singular_values(plant)
    form = modal_form(split_stable(plant).stable)
    own = np.sort(modal_indices(form, "hankel"))[::-1]
    pairs = s.reshape(-1, 2)
    assert np.all(pairs[:, 1] <= own * 1.02) and np.all(pairs[:, 0] >= own * 0.98)
    A, B, C, D = form.matrices
    for factor in (1e-3, 1e3):
        scale = np.ones(A.shape[0])
        scale[form.blocks[-1]] = factor  # the 430 Hz mode
        scaled = ct.ss(A * scale[None, :] / scale[:, None], B / scale[:, None], C * scale, D)
        np.testing.assert_allclose(hankel_singular_values(scaled), s, rtol=1e-9)


def test_residualisation_matches_dc_gain_and_truncation_matches_infinity():
    """SPA keeps G(0) exactly (Liu & Anderson 1989); truncation keeps D = G(∞)."""
    plant, order = PLANTS["random_siso_12"]
    spa = balanced_reduction(plant, order, "residualize").system
    bt = balanced_reduction(plant, order, "truncate").system
    g0 = frequency_response(plant, omega_rad_s=np.array([0.0])).values
    np.testing.assert_allclose(
        frequency_response(spa, omega_rad_s=np.array([0.0])).values, g0, rtol=1e-9
    )
    np.testing.assert_allclose(bt.D, plant.D)
    assert abs(frequency_response(bt, omega_rad_s=np.array([0.0])).values - g0).max() > 1e-6


def test_rigid_modes_kept_exactly():
    """The marginal part is kept: the reduced model has the double integrator, and G − G_r stays
    under the bound even at 1e-4 rad/s where each is ~1e8 (the rigid parts cancel)."""
    plant, order = PLANTS["modal_with_rigid_mode"]
    red = balanced_reduction(plant, order)
    eig = np.linalg.eigvals(red.system.A)
    assert np.sum(np.abs(eig) < 1e-9) == 2
    w = np.concatenate([[1e-4, 1e-2], np.geomspace(0.1, 100, 400)])
    diff = (
        frequency_response(plant, omega_rad_s=w).values
        - frequency_response(red.system, omega_rad_s=w).values
    )
    assert np.linalg.norm(diff, 2, axis=(1, 2)).max() <= red.error_bound * (1 + 1e-6)
    assert split_stable(plant).unstable[0].shape == (2, 2)


def test_modal_cost_sums_to_h2_and_gawronski_indices():
    """Σ V_i = ‖G‖₂² (Skelton & Yousuff 1983); for ζ = 0.002 and well separated modes the exact
    per-mode H2 and Hankel indices match Gawronski's ‖b‖‖c‖/(2√(ζω)) and ‖b‖‖c‖/(4ζω) with c the
    output in (ωq, q̇) coordinates, to O(ζ) (here 1 %)."""
    rng = np.random.default_rng(5)
    w = np.array([1.0, 4.0, 16.0])
    z = np.full(3, 0.002)
    b = rng.standard_normal((3, 1))
    cv = rng.standard_normal((1, 3))
    plant = modal_plant(w, z, b, np.zeros((1, 3)), cv)
    form = modal_form(split_stable(plant).stable)
    cost = modal_indices(form, "modal_cost")
    assert cost.sum() == pytest.approx(h2_norm(plant) ** 2, rel=1e-9)
    np.testing.assert_allclose(form.frequencies_rad_s, w, rtol=1e-12)
    gb = np.abs(b[:, 0] * cv[0])
    np.testing.assert_allclose(modal_indices(form, "h2"), gb / (2 * np.sqrt(z * w)), rtol=1e-2)
    np.testing.assert_allclose(modal_indices(form, "hankel"), gb / (4 * z * w), rtol=1e-2)


def test_modal_truncation_keeps_the_largest_and_compare():
    """The kept modes are those of largest index; the error of keeping them is the H∞ norm of
    the dropped ones (checked on a grid: grid max <= norm <= 1.001 × grid max near the peaks)."""
    plant, _ = PLANTS["modal_mimo"]
    red = modal_truncation(plant, 3, "hankel")
    idx = modal_indices(modal_form(split_stable(plant).stable), "hankel")
    assert sorted(red.kept_modes) == sorted(np.argsort(-idx)[:3].tolist())
    err = reduction_error(red)
    w = np.unique(
        np.concatenate(
            [np.geomspace(0.1, 100, 3000), modal_form(split_stable(plant).stable).frequencies_rad_s]
        )
    )
    diff = (
        frequency_response(plant, omega_rad_s=w).values
        - frequency_response(red.system, omega_rad_s=w).values
    )
    grid = np.linalg.norm(diff, 2, axis=(1, 2)).max()
    assert grid <= err * (1 + 1e-8) and err <= 1.001 * grid
    table = compare_reductions(plant, 3)
    assert set(table) == {
        "modal:modal_cost",
        "modal:h2",
        "modal:hankel",
        "balanced_truncation",
        "residualization",
    }
    bt = table["balanced_truncation"]
    assert bt[1] <= bt[0].error_bound


def test_static_correction_matches_dc():
    plant, _ = PLANTS["modal_mimo"]
    red = modal_truncation(plant, 2, "h2", static_correction=True).system
    g0 = frequency_response(plant, omega_rad_s=np.array([0.0])).values
    np.testing.assert_allclose(
        frequency_response(red, omega_rad_s=np.array([0.0])).values, g0, rtol=1e-9, atol=1e-12
    )


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda p: balanced_reduction(p, 99), "order"),
        (lambda p: balanced_reduction(p, -1), "order"),
        (lambda p: balanced_reduction(p, 2, "svd"), "method"),
        (lambda p: modal_truncation(p, 99), "n_modes"),
        (lambda p: modal_truncation(p, 2, "energy"), "index"),
        (lambda p: balanced_reduction(ct.c2d(p, 0.1), 2), "system"),
    ],
    ids=["order_high", "order_negative", "method", "n_modes", "index", "discrete"],
)
def test_bad_input_names_the_field(call, field):
    plant, _ = PLANTS["modal_mimo"]
    with pytest.raises(FieldError) as err:
        call(plant)
    assert err.value.field == field if hasattr(err.value, "field") else field in str(err.value)


def test_reduced_plant_feeds_lqg_design():
    """The reduced model is a plain labelled StateSpace: LQGController.design takes it."""
    from flexsat.control.lqg import LQGController

    plant = PLANTS["tamu_10_modes"][0]
    red = modal_truncation(plant, 2, "h2").system
    n = red.nstates
    law = LQGController.design(
        ct.ss(red.A, red.B, red.C[[0]], 0),
        np.eye(n),
        np.eye(1),
        np.eye(1),
        np.eye(1) * 1e-4,
        0.01,
        measurements="theta",
    )
    assert law.K.shape == (1, n) and math.isfinite(float(np.abs(law.K).max()))
