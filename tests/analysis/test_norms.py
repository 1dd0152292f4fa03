"""H2 and H∞ norms without slycot (issue 24): the Lyapunov H2 norm and the Hamiltonian
(Boyd–Balakrishnan / Bruinsma–Steinbuch) H∞ norm against closed forms, against each other on
a SISO system (‖G‖∞ >= the largest |G(jω)| on any grid), and against python-control where its
own fallback works (square systems)."""

import math

import numpy as np
import pytest

import control as ct
from flexsat.analysis.frequency_domain import frequency_response
from flexsat.analysis.norms import h2_norm, hinf_norm
from flexsat.input_checks import FieldError

S = ct.tf("s")


@pytest.mark.parametrize("a", [0.1, 1.0, 7.0])
def test_first_order_closed_forms(a):
    """1/(s + a): ‖·‖∞ = 1/a at ω = 0, ‖·‖₂ = 1/√(2a); tolerance: the bisection's 2 tol."""
    g = ct.ss(1 / (S + a))
    assert h2_norm(g) == pytest.approx(1 / math.sqrt(2 * a), rel=1e-12)
    h = hinf_norm(g)
    assert h.value == pytest.approx(1 / a, rel=2e-8)
    assert h.lower <= 1 / a * (1 + 1e-12) and h.upper >= 1 / a * (1 - 1e-12)


@pytest.mark.parametrize("zeta", [0.001, 0.01, 0.2])
def test_lightly_damped_mode_peak(zeta):
    """ω²/(s² + 2ζωs + ω²): peak 1/(2ζ√(1 − ζ²)) at ω√(1 − 2ζ²); H2² = ω/(4ζ)."""
    w = 3.0
    g = ct.ss(w**2 / (S**2 + 2 * zeta * w * S + w**2))
    h = hinf_norm(g)
    assert h.value == pytest.approx(1 / (2 * zeta * math.sqrt(1 - zeta**2)), rel=2e-8)
    assert h.peak_rad_s == pytest.approx(w * math.sqrt(1 - 2 * zeta**2), rel=1e-5)
    assert h2_norm(g) == pytest.approx(math.sqrt(w / (4 * zeta)), rel=1e-10)


def test_discrete_norms_against_python_control_and_a_grid():
    """A sampled lightly damped mode: H2 equal to python-control's (Lyapunov, same method) to
    1e-12; H∞ at least the grid maximum on the unit circle and within python-control's own
    bisection tolerance (it stops at a relative 1e-6); the grid holds the peak frequency found,
    where |G| must reach the norm to its bracket."""
    g = ct.c2d(ct.ss(4 / (S**2 + 0.04 * S + 4)), 0.05)
    assert h2_norm(g) == pytest.approx(ct.norm(g, 2), rel=1e-12)
    h = hinf_norm(g)
    w = np.sort(np.r_[np.linspace(0, math.pi / 0.05, 200001), h.peak_rad_s])
    grid_max = np.abs(frequency_response(g, omega_rad_s=w).values).max()
    assert h.upper >= grid_max and h.value == pytest.approx(grid_max, rel=2e-8)
    assert h.value == pytest.approx(ct.norm(g, "inf"), rel=2e-6)


@pytest.mark.parametrize("seed", range(5))
def test_random_mimo_against_frequency_sweep(seed):
    """Random stable 3-output 2-input systems: H∞ is the sup of σ̄ (a dense sweep never
    exceeds the upper bound and reaches the value to the sweep's resolution); H2 against the
    impulse-response integral ∫ ‖C e^{At} B‖_F² dt by the frequency-domain Parseval sum."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((6, 6))
    A -= (max(np.linalg.eigvals(A).real) + 0.05 + rng.random()) * np.eye(6)
    g = ct.ss(A, rng.standard_normal((6, 2)), rng.standard_normal((3, 6)), np.zeros((3, 2)))
    h = hinf_norm(g)
    w = np.unique(np.concatenate([np.geomspace(1e-3, 1e3, 20001), [h.peak_rad_s]]))
    sig = np.linalg.svd(frequency_response(g, omega_rad_s=w).values, compute_uv=False)[:, 0]
    assert sig.max() <= h.upper * (1 + 1e-12)
    assert sig.max() == pytest.approx(h.value, rel=1e-7)
    # Parseval: ‖G‖₂² = (1/π) ∫_0^∞ ‖G(jω)‖_F² dω on a fine grid (trapezoid, tail < 1e-6)
    wf = np.concatenate([[0.0], np.geomspace(1e-6, 1e6, 400001)])
    F = (np.abs(frequency_response(g, omega_rad_s=wf).values) ** 2).sum(axis=(1, 2))
    assert h2_norm(g) ** 2 == pytest.approx(np.trapezoid(F, wf) / math.pi, rel=1e-5)
    if g.ninputs == g.noutputs:
        assert h.value == pytest.approx(ct.norm(g, "inf"), rel=2e-6)


def test_square_mimo_against_python_control():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((5, 5))
    A -= (max(np.linalg.eigvals(A).real) + 0.3) * np.eye(5)
    g = ct.ss(A, rng.standard_normal((5, 2)), rng.standard_normal((2, 5)), 0.1 * np.eye(2))
    assert hinf_norm(g).value == pytest.approx(ct.norm(g, "inf"), rel=2e-6)
    assert h2_norm(g) == math.inf  # continuous with D ≠ 0
    g0 = ct.ss(g.A, g.B, g.C, 0 * g.D)
    assert h2_norm(g0) == pytest.approx(ct.norm(g0, 2), rel=1e-12)


def test_unstable_and_bad_input_refused_by_name():
    with pytest.raises(FieldError, match="plant_x.*not asymptotically stable"):
        hinf_norm(ct.ss(1 / (S - 1)), field="plant_x")
    with pytest.raises(FieldError, match="not asymptotically stable"):
        h2_norm(ct.ss(1 / S))
    with pytest.raises(FieldError, match="tol"):
        hinf_norm(ct.ss(1 / (S + 1)), tol=0.5)
    with pytest.raises(FieldError, match="StateSpace"):
        h2_norm(np.eye(2))
