"""Att. 4 Eq. (33) modal LQR with r tuned to ω_i ζ_i ≥ T_i (flexsat.control.r_tuning)."""

import numpy as np
import pytest

from flexsat.control.r_tuning import ATT4_TARGETS, modal_lqr, tune_r
from flexsat.input_checks import FieldError


def _closed_form(w, z, b, r):
    """SISO LQR on one mode, Q = diag(ω², 1), R = r, by the symmetric root locus:
    Δc(s)Δc(−s) = Δ(s)Δ(−s) + (b²/r)(ω² − s²), Δ = s² + a1 s + a0, Δc = s² + c1 s + c0."""
    a0, a1 = w**2, 2 * z * w
    c0 = np.sqrt(a0**2 + b**2 * w**2 / r)
    c1 = np.sqrt(2 * c0 - 2 * a0 + a1**2 + b**2 / r)
    return c0, c1, (c0 - a0) / b, (c1 - a1) / b


@pytest.mark.numerics
def test_single_mode_gains_and_poles_match_the_symmetric_root_locus():
    w, z, b, r = 2.0, 0.01, 0.7, 0.3
    design = modal_lqr([w], [z], [[b]], r)
    c0, c1, k1, k2 = _closed_form(w, z, b, r)
    # round-off of a 2-state Riccati solve: 1e-12 relative
    np.testing.assert_allclose(design.gain, [[k1, k2]], rtol=1e-12)
    lam = design.eigenvalues[0]
    np.testing.assert_allclose([-2 * lam.real, abs(lam) ** 2], [c1, c0], rtol=1e-12)


@pytest.mark.numerics
def test_tuned_r_puts_the_single_mode_on_its_target():
    w, z, b, target = 2.0, 0.01, 0.7, 0.25
    res = tune_r([w], [z], [[b]], targets=[target], rtol=1e-12)
    c0, c1, _, _ = _closed_form(w, z, b, res.r)
    # Att. 4: ω = Im λ, ζ = −Re λ/|λ|, so ωζ = (c1/2) √(c0 − c1²/4)/√c0
    zeta_omega = 0.5 * c1 * np.sqrt(c0 - c1**2 / 4) / np.sqrt(c0)
    # the bracket on r is 1e-12 wide, dωζ/dlog r = O(0.1): the target holds to 1e-11
    assert zeta_omega == pytest.approx(target, abs=1e-11)
    assert res.design.zeta_omega[0] == pytest.approx(zeta_omega, rel=1e-12)
    assert res.binding == 0 and res.margins[0] >= 0


def test_tuned_r_is_the_largest_feasible_one():
    rng = np.random.default_rng(3)
    w = np.array([1.5, 3.0, 4.2, 7.0])
    d = rng.normal(size=(4, 2))
    res = tune_r(w, 0.005, d, targets=ATT4_TARGETS)
    assert np.all(res.margins >= 0)
    # just above the tuned r a target is missed: the tuned r is the cheapest feasible design
    above = modal_lqr(w, 0.005, d, res.r * (1 + 1e-6))
    assert np.min(above.zeta_omega[:3] - np.array(ATT4_TARGETS)) < 0
    # the search record holds only feasible designs at or below the returned r
    assert all(r <= res.r * (1 + 1e-12) for r, m in res.history if m >= 0)


@pytest.mark.numerics
def test_condition_number_of_the_undamped_open_loop_is_omega_max():
    w = np.array([1.5, 3.0, 40.0])
    # r = 1e12: the gain is ~1e-12, the closed loop is the open loop to ~1e-10
    design = modal_lqr(w, 0.0, np.ones((3, 1)), 1e12)
    assert design.condition == pytest.approx(w.max(), rel=1e-8)


def test_unreachable_target_and_bad_inputs_name_the_field():
    d = np.array([[0.0], [1.0]])  # mode 1 cannot be moved
    with pytest.raises(FieldError, match="targets.*mode 1"):
        tune_r([1.0, 2.0], 0.01, d, targets=[0.2], r_range=(1e-4, 1e4))
    with pytest.raises(FieldError, match="^r"):
        modal_lqr([1.0], 0.01, [[1.0]], -1.0)
    with pytest.raises(FieldError, match="d_bar"):
        modal_lqr([1.0, 2.0], 0.01, [[1.0]], 1.0)
    with pytest.raises(FieldError, match="modes"):
        tune_r([1.0, 2.0], 0.01, np.ones((2, 1)), targets=[0.2], modes=[5])
    with pytest.raises(FieldError, match="omega"):
        modal_lqr([0.0], 0.01, [[1.0]], 1.0)


def test_frequencies_and_targets_take_units():
    d = np.array([[0.7]])
    a = tune_r([2.0], 0.01, d, targets=[0.25])
    b = tune_r(["2 rad/s"], 0.01, d, targets=["0.25 rad/s"])
    assert a.r == b.r
    with pytest.raises(FieldError, match="targets"):
        tune_r([2.0], 0.01, d, targets=["0.25 m"])
