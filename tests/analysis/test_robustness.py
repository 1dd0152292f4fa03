"""Robustness over modal-parameter boxes (issue 24): the modal loop reproduces the loop it came
from, the certified stability margin is exact against Routh–Hurwitz on one mode and never above
the dense sweep's on random non-collocated loops (and within 5 % of it), and the certified bound
of sup ‖S‖∞ over ±10 % on the TAMU loop's 10 modes is never below the sweep's and within 10 %."""

import math
import time

import numpy as np
import pytest
import scipy.linalg as sla

import control as ct
from flexsat.analysis.frequency_domain import build_loop, frequency_response
from flexsat.analysis.robustness import (
    ParameterBox,
    certify,
    modal_loop,
    stability_margin,
    sweep,
    sweep_stability_margin,
)
from flexsat.input_checks import FieldError


def tamu_loop():
    from flexsat.cases.tamu import tamu
    from flexsat.control.state_space_export import continuous_law
    from flexsat.dynamics.linear_model import plant_state_space

    case = tamu()
    P = plant_state_space(case.model())
    K = continuous_law(case.law_i("600 ozf*in/rad", "800 ozf*in*s/rad", 0.0))
    return P, K


def random_loop(seed, n=4):
    """A rigid body and n modes with non-collocated (random-sign) sensing under a PD law."""
    rng = np.random.default_rng(seed)
    w = np.sort(rng.uniform(1, 20, n))
    z = rng.uniform(0.01, 0.05, n)
    A = sla.block_diag(
        np.array([[0, 1], [0, 0.0]]),
        *[np.array([[0, 1], [-(a**2), -2 * c * a]]) for a, c in zip(w, z)],
    )
    b = np.zeros((A.shape[0], 1))
    C = np.zeros((2, A.shape[0]))
    b[1], C[0, 0], C[1, 1] = 1, 1, 1
    for i in range(n):
        b[3 + 2 * i] = rng.standard_normal()
        phi = rng.standard_normal()
        C[0, 2 + 2 * i], C[1, 3 + 2 * i] = phi, phi
    P = ct.ss(A, b, C, 0, inputs=["u"], outputs=["y", "y_dot"])
    gains = [[-rng.uniform(0.5, 3) * w[0] ** 2 / 4, -rng.uniform(0.5, 3) * w[0] / 2]]
    K = ct.ss([], [], [], gains, inputs=["y", "y_dot"], outputs=["u"])
    return P, K


def stable_random_loops(count):
    out = []
    for seed in range(40):
        P, K = random_loop(seed)
        if build_loop(P, K).stable:
            out.append((seed, P, K))
        if len(out) == count:
            return out
    raise AssertionError("too few nominally stable random loops")


def test_modal_loop_reproduces_the_loop():
    """|S| of the modal form at the nominal member equals S of build_loop, and the batch
    closed-loop matrix has the closed-loop poles of build_loop (tolerance: eigenvalue
    condition of the lightly damped modes ~1e3 × eps × ‖A‖)."""
    P, K = tamu_loop()
    loop = modal_loop(P, K)
    assert loop.n_modes == 10
    ref = build_loop(P, K, "input")
    w = np.geomspace(0.05, 5e3, 300)
    S = np.abs(frequency_response(ref.sensitivity(), omega_rad_s=w).values[:, 0, 0])
    np.testing.assert_allclose(
        loop.sensitivity(w, loop.omega0[None], loop.zeta0[None])[0], S, rtol=1e-8
    )
    p1 = np.sort_complex(
        np.linalg.eigvals(loop.closed_loop_matrices(loop.omega0[None], loop.zeta0[None])[0])
    )
    p2 = np.sort_complex(ref.poles)
    np.testing.assert_allclose(p1, p2, rtol=1e-8, atol=1e-9 * np.abs(p2).max())


@pytest.mark.parametrize("beta", [-0.01, -0.05, -0.09])
def test_single_mode_margin_against_routh_hurwitz(beta):
    """One mode, F = d + (α + βs): stable iff 2ζω + β > 0 and ω² + α > 0. With a rate term
    β < 0 the box ω0(1 ± k f), ζ0(1 ± k g) loses stability when 2ζ0ω0(1 − k g)(1 − k f) = −β:
    the certified margin is at most that k, and within the stated factor: 5 % below it (the
    convex hull of the mode's value set; observed 3 %)."""
    w0, z0, f, g = 3.0, 0.02, 0.3, 0.5
    P = ct.ss(
        [[0, 1], [-(w0**2), -2 * z0 * w0]],
        [[0], [1]],
        [[1.0, 0.0], [0.0, 1.0]],
        0,
        inputs=["u"],
        outputs=["q", "q_dot"],
    )
    K = ct.ss([], [], [], [[-0.5, -beta]], inputs=["q", "q_dot"], outputs=["u"])
    loop = modal_loop(P, K)
    shape = ParameterBox.of(loop, f, g)
    # (1 − k g)(1 − k f) = −β/(2 ζ0 ω0): the smaller root of f g k² − (f + g) k + 1 − r = 0
    r = -beta / (2 * z0 * w0)
    exact = ((f + g) - math.sqrt((f + g) ** 2 - 4 * f * g * (1 - r))) / (2 * f * g)
    k = stability_margin(loop, shape, k_max=0.99, steps=14)
    exact = min(exact, 0.99)  # the search stops at k_max
    assert k <= exact * (1 + 1e-9)
    assert k >= 0.95 * exact


def test_random_loops_margin_never_contradicted_by_sweep():
    """Certified margin <= the sweep's (an unstable member found); stated factor: the sweep's
    margin is within 5 % above the certified one (observed 0.5–1 %)."""
    for seed, P, K in stable_random_loops(2):
        loop = modal_loop(P, K)
        shape = ParameterBox.uniform(loop, 0.5, 0.5)
        k_cert = stability_margin(loop, shape, steps=10)
        k_sweep = sweep_stability_margin(loop, shape, steps=10, n_members=300)
        assert k_cert <= k_sweep, seed
        assert k_sweep <= 1.05 * k_cert + 2 * 0.99 / 2**10, seed


def test_tamu_plus_minus_ten_percent_on_ten_modes():
    """±10 % on the frequency and damping of the 10 modes of the TAMU loop (Law I): certified
    stable, the sweep's 2000+ members all stable, sweep peak |S| <= certified bound <= 1.10 ×
    sweep peak (the stated factor), analysis within the issue's 10 s."""
    P, K = tamu_loop()
    start = time.perf_counter()
    loop = modal_loop(P, K)
    box = ParameterBox.uniform(loop, 0.1, 0.1)
    cert = certify(loop, box)
    took = time.perf_counter() - start
    sw = sweep(loop, box, n_members=1000, n_frequencies=2000)
    assert cert.stable and sw.all_stable
    assert sw.sensitivity_peak <= cert.sensitivity_bound
    assert cert.sensitivity_bound <= 1.10 * sw.sensitivity_peak
    assert took < 10.0


def test_sensitivity_bound_on_random_loops():
    """On loops whose |S| peak is set by a mode, the certified bound over ±5 % is never below
    the sweep's peak and within the stated factor 1.2 of it (observed 1.03–1.05)."""
    for seed, P, K in stable_random_loops(2):
        loop = modal_loop(P, K)
        box = ParameterBox.uniform(loop, 0.05, 0.05)
        cert = certify(loop, box)
        if not cert.stable:
            continue
        sw = sweep(loop, box, n_members=400, n_frequencies=4000)
        assert sw.sensitivity_peak <= cert.sensitivity_bound, seed
        assert cert.sensitivity_bound <= 1.2 * sw.sensitivity_peak, seed


def test_refusals_name_the_field():
    P, K = tamu_loop()
    with pytest.raises(FieldError, match="continuous"):
        modal_loop(P, ct.c2d(K, 0.01))
    # an overdamped (real) pole is not a lightly damped mode
    real = ct.ss([[-2.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["q"])
    with pytest.raises(FieldError, match="real pole"):
        modal_loop(real, ct.ss([], [], [], [[-1.0]], inputs=["q"], outputs=["u"]))
    loop = modal_loop(P, K)
    with pytest.raises(FieldError, match="frequency"):
        ParameterBox.uniform(loop, 1.2)
    box = ParameterBox.uniform(loop, 0.1)
    with pytest.raises(FieldError, match="tol"):
        certify(loop, box, tol=0.0)
    with pytest.raises(FieldError, match="n_members"):
        sweep(loop, box, n_members=0)
    rigid = ct.ss([[0, 1], [0, 0.0]], [[0], [1]], np.eye(2), 0, inputs=["u"], outputs=["y", "v"])
    with pytest.raises(FieldError, match="no lightly damped mode"):
        modal_loop(rigid, ct.ss([], [], [], [[-1.0, -1.0]], inputs=["y", "v"], outputs=["u"]))


def lqg_on_two_modes():
    """An LQG on a 2-mode modal truncation of TAMU, to be closed on the full 10-mode plant."""
    from flexsat.analysis.reduction import modal_truncation
    from flexsat.cases.tamu import tamu
    from flexsat.control.estimation import kalman
    from flexsat.control.lqr import lqr
    from flexsat.dynamics.linear_model import plant_state_space

    P = plant_state_space(tamu().model(), outputs=["theta", "tip_deflection"])
    red = modal_truncation(P, 2, "h2").system
    A, B, C = red.A, red.B, red.C
    n = A.shape[0]
    K = lqr(A, B, np.diag([100.0] + [1.0] * (n - 1)), np.eye(1)).gain
    L = kalman(A, B, C, np.eye(1) * 10, np.diag([1e-6, 1e-4])).gain
    law = ct.ss(A - B @ K - L @ C, L, -K, 0, inputs=list(P.output_labels), outputs=["torque"])
    return P, law


def test_dynamic_law_reproduces_the_loop_and_is_certified():
    """A 6-state LQG: the modal form's |S| equals build_loop's (1e-7: the law's polynomials
    come from eigenvalues, conditioning ~1e8 × eps), its closed-loop poles too; over ±10 % the
    certified bound is never below the sweep's peak and within the stated factor 1.1 (observed
    1.02)."""
    P, law = lqg_on_two_modes()
    loop = modal_loop(P, law)
    ref = build_loop(P, law, "input")
    w = np.geomspace(0.05, 5e3, 300)
    S = np.abs(frequency_response(ref.sensitivity(), omega_rad_s=w).values[:, 0, 0])
    nominal = (loop.omega0[None], loop.zeta0[None])
    np.testing.assert_allclose(loop.sensitivity(w, *nominal)[0], S, rtol=1e-7)
    p1 = np.sort_complex(np.linalg.eigvals(loop.closed_loop_matrices(*nominal)[0]))
    np.testing.assert_allclose(p1, np.sort_complex(ref.poles), atol=1e-7 * np.abs(p1).max())
    box = ParameterBox.uniform(loop, 0.1, 0.1)
    cert = certify(loop, box)
    sw = sweep(loop, box, n_members=400, n_frequencies=3000)
    assert cert.stable and sw.all_stable
    assert sw.sensitivity_peak <= cert.sensitivity_bound <= 1.1 * sw.sensitivity_peak
