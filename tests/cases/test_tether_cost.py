"""The continuous tether run's cost estimate (flexsat.cases.tether.continuous_evaluations)
against the evaluations the adaptive integrator makes, and the refusal of gains that would make
it crawl (issue 21: K1 = 1e12 ran for hours, 1e300 ended in an IndexError)."""

import numpy as np
import pytest

import flexsat.sim.continuous as continuous
from flexsat.cases.tether import (
    INITIAL,
    closed_loop_rates,
    continuous_evaluations,
    make_law,
    run_law,
)
from flexsat.input_checks import FieldError

GAINS = {
    "coupled": dict(K1=1.0, K2=0.0, K3=3.0, K4=2.0),
    "decoupled": dict(K1=1.0, K2=0.0, K3=3.0),
    "rate": dict(K1=0.25, K2=0.01, K3=1.0),
}


@pytest.mark.parametrize(
    "law, scale, window",
    [
        ("coupled", 1e2, 0.2),
        ("coupled", 1e4, 0.05),
        ("decoupled", 1e4, 0.05),
        ("rate", 1e2, 0.2),
        ("rate", 1e4, 0.05),
    ],
)
def test_the_estimate_bounds_the_integrator_s_evaluations_within_a_small_factor(
    monkeypatch, law, scale, window
):
    # the estimate decides refusals, so it must not undercount; it is a scale (the constants
    # are the worst measured cases), so it may overcount, here by less than 5 times
    counted = []
    solve = continuous.solve_ivp

    def counting(*args, **kwargs):
        solution = solve(*args, **kwargs)
        counted.append(solution.nfev)
        return solution

    monkeypatch.setattr(continuous, "solve_ivp", counting)
    gains = dict(GAINS[law], K1=GAINS[law]["K1"] * scale)
    tether = make_law(law, gains, 0.01)
    run_law(tether, INITIAL, np.linspace(0.0, window, 11))
    estimate = continuous_evaluations(tether, INITIAL, window)
    assert counted[0] <= estimate <= 5 * counted[0]


def test_the_rates_are_the_eigenvalues_of_the_analytic_linearisation():
    # Eq. 4 with controller 2 linearised by hand at the target (λ = λ_f, θ = φ = 0, at rest):
    # in plane, from λ(1 + θ')² − T̂ and −2(λ'/λ)(1 + θ') − 3 sin θ cos θ,
    #   δλ'' = −K1 δλ − K3 δλ' + 2λ_f δθ',   δθ'' = −3 δθ − 2 δλ'/λ_f;
    # out of plane, from −sinφ cosφ (1 + 3) + F̂/λ with F̂ = −K4 λ φ',  δφ'' = −4 δφ − K4 δφ'
    K1, K3, K4, lf = 1e4, 3.0, 2.0, 0.01
    tether = make_law("coupled", dict(K1=K1, K2=0.0, K3=K3, K4=K4), lf)
    in_plane = np.array(
        [[0, 0, 1, 0], [0, 0, 0, 1], [-K1, 0, -K3, 2 * lf], [0, -3, -2 / lf, 0]], float
    )
    roll = np.array([[0, 1], [-4, -K4]], float)
    s = np.concatenate([np.linalg.eigvals(in_plane), np.linalg.eigvals(roll)])
    osc, dec = closed_loop_rates(tether, [lf, 0, 0, 0, 0, 0])
    # central differences with a 1e-6 step: O(h²) truncation, ~1e-10 × |x''| / h rounding
    assert osc[0] == pytest.approx(np.abs(s.imag).max(), rel=1e-6)
    assert dec[0] == pytest.approx(np.abs(s.real).max(), rel=1e-6)


@pytest.mark.parametrize("K1", [1e12, 1e300])
def test_gains_too_stiff_for_the_continuous_integrator_are_refused_before_the_run(K1):
    tether = make_law("coupled", dict(GAINS["coupled"], K1=K1), 0.01)
    with pytest.raises(FieldError, match=r"gains: K1 = .*MAX_ADAPTIVE_EVALUATIONS"):
        run_law(tether, INITIAL, np.linspace(0.0, 2 * np.pi, 101))


def test_the_paper_s_examples_are_well_within_the_limit():
    from flexsat import limits
    from flexsat.cases.tether import EXAMPLES

    for e in EXAMPLES.values():
        tether = make_law(e.law, e.gains, e.final_length)
        cost = continuous_evaluations(tether, INITIAL, 2 * np.pi * e.orbits)
        assert cost < 0.3 * limits.MAX_ADAPTIVE_EVALUATIONS, e.key


@pytest.mark.parametrize(
    "initial, message",
    [([np.nan] * 6, r"initial: must be finite"), ([1.0, 0.0], r"initial: must be \[λ")],
)
def test_a_bad_initial_state_is_named_not_blamed_on_the_gains(initial, message):
    # a NaN state made the cost estimate NaN, which was refused as "gains"
    tether = make_law("coupled", GAINS["coupled"], 0.01)
    with pytest.raises(FieldError, match=message):
        run_law(tether, initial, np.linspace(0.0, 0.1, 5))


def test_a_stiff_tether_law_past_the_estimate_ends_at_the_evaluation_limit(monkeypatch):
    """K1 = 1e12 run straight through the engine (the estimate of run_law skipped): the
    continuous run counts its evaluations and ends at the limit with an error naming it and
    the likely cause (the limit lowered here to keep the test short; at the default 1e6 the
    run ends after about as many evaluations, minutes, not hours)."""
    from flexsat import limits
    from flexsat.cases.tether import tether_simulation
    from flexsat.sim.engine import simulate

    stiff = make_law("coupled", dict(GAINS["coupled"], K1=1e12), 0.01)
    mild = make_law("coupled", GAINS["coupled"], 0.01)
    # at the target length, swinging 0.01 rad: the stiff length loop holds it (from INITIAL
    # it pulls the tether to collapse within microseconds, a domain exit)
    start = [0.01, 0.01, 0.0, 0.0, 0.0, 0.0]
    plant, config, options = tether_simulation(mild, start, np.linspace(0.0, 2 * np.pi, 101))
    monkeypatch.setattr(limits, "MAX_ADAPTIVE_EVALUATIONS", 5_000)
    with pytest.raises(FieldError) as info:
        simulate(plant, stiff, config, **options)
    assert info.value.field == "law_mode"
    assert "MAX_ADAPTIVE_EVALUATIONS" in info.value.rule
    assert "too stiff" in info.value.rule
