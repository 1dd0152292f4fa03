"""The controller summary of a report (flexsat.report.controller_summary), checked by other
means than the ones it uses: the gain margin against the eigenvalues of the closed loop with
the gain scaled, the peak sensitivity against S evaluated on a dense grid of the unit circle,
the closed-loop poles of a PD loop on a rigid hub against the characteristic polynomial of its
sampled loop; a nonlinear law and an unstable loop are stated, never given numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

import control as ct
from flexsat.control.attitude_laws import QuaternionPD
from flexsat.control.pd import PD
from flexsat.report.controller_summary import summarise_law, summarise_laws, summary_html

J, DT = 2.0, 0.05


def hub() -> ct.StateSpace:
    """θ'' = u/J, measured (θ, θ')."""
    return ct.ss(
        [[0, 1], [0, 0]],
        [[0], [1 / J]],
        np.eye(2),
        0,
        states=["theta", "theta_dot"],
        inputs=["torque"],
        outputs=["theta", "theta_dot"],
    )


def sampled_closed_loop(kp: float, kd: float) -> np.ndarray:
    """The closed-loop matrix of the rigid hub's exact ZOH equivalent under u_k = −kp θ_k −
    kd θ'_k (written out by hand: Φ = [[1, T], [0, 1]], Γ = [T²/2J, T/J])."""
    Phi = np.array([[1.0, DT], [0.0, 1.0]])
    Gamma = np.array([[DT**2 / (2 * J)], [DT / J]])
    return Phi - Gamma @ np.array([[kp, kd]])


def test_gains_and_poles_of_a_pd_loop_are_those_of_the_sampled_loop():
    s = summarise_law("PD", hub(), PD(3.0, 4.0), DT)
    assert s.reason == "" and s.law == "PD"
    assert s.gains == (("torque", "theta", -3.0), ("torque", "theta_dot", -4.0))
    z = np.linalg.eigvals(sampled_closed_loop(3.0, 4.0))
    want = np.sort_complex(np.log(z.astype(complex)) / DT)
    got = np.sort_complex(np.array([p.pole for p in s.poles]))
    # a 2 x 2 eigenproblem of entries O(1): round-off times the conditioning (~10)
    assert np.allclose(got, want, rtol=0, atol=1e-12)
    for p in s.poles:
        assert p.damping_ratio == pytest.approx(-p.pole.real / abs(p.pole), rel=1e-12)
        assert p.mode == "theta"  # θ and θ' are one mode


def test_the_gain_margin_is_where_the_scaled_loop_turns_unstable():
    kp, kd = 3.0, 4.0
    s = summarise_law("PD", hub(), PD(kp, kd), DT)
    gm = s.margins.gain_margin
    assert 1 < gm < math.inf

    def radius(k: float) -> float:
        return float(max(abs(np.linalg.eigvals(sampled_closed_loop(k * kp, k * kd)))))

    # the margin is found to the solver's tolerance; 1e-6 relative is well above it
    assert radius(gm * (1 - 1e-6)) < 1 < radius(gm * (1 + 1e-6))


def test_the_peak_sensitivity_is_the_largest_value_on_the_unit_circle():
    s = summarise_law("PD", hub(), PD(3.0, 4.0), DT)
    P = ct.c2d(hub(), DT, "zoh")
    w = np.linspace(1e-4, math.pi / DT, 200_001)
    z = np.exp(1j * w * DT)
    K = np.array([-3.0, -4.0])
    L = np.array([-(K @ np.linalg.solve(zi * np.eye(2) - P.A, P.B))[0] for zi in z])
    peak = float(np.max(np.abs(1 / (1 + L))))
    # the dense grid can only miss the peak from below, by O(grid spacing²) near a smooth
    # maximum: 1e-6 relative for this spacing
    assert peak <= s.sensitivity_peak * (1 + 1e-9)
    assert peak == pytest.approx(s.sensitivity_peak, rel=1e-6)
    # the disk margin with no skew is 1/‖S − 1/2‖∞ >= 1/(‖S‖∞ + 1/2)
    assert s.disk[0].alpha >= 1 / (s.sensitivity_peak + 0.5) - 1e-12


def test_a_nonlinear_law_and_an_unstable_loop_are_stated_without_numbers():
    nonlinear = summarise_law("q", hub(), QuaternionPD(1.0, 1.0), DT)
    assert "QuaternionPD is nonlinear" in nonlinear.reason and nonlinear.margins is None
    # a rate gain too high for the sample rate: the sampled loop is unstable
    assert max(abs(np.linalg.eigvals(sampled_closed_loop(3.0, 200.0)))) > 1
    unstable = summarise_law("fast", hub(), PD(3.0, 200.0), DT)
    assert "unstable" in unstable.reason and unstable.poles == ()
    page = summary_html(summarise_laws(hub(), {"q": QuaternionPD(1.0, 1.0)}, DT))
    assert "No linear summary: " in page and "Gain margin" not in page
    assert summary_html(()) == ""


def test_the_section_shows_margins_and_poles_of_each_law():
    page = summary_html(summarise_laws(hub(), {"soft": PD(1.0, 2.0), "stiff": PD(9.0, 6.0)}, DT))
    assert page.count("Margins and norms of the sampled-data loop") == 2
    for heading in ("Gain margin", "Phase margin (deg)", "Delay margin (s)", "Peak sensitivity"):
        assert page.count(heading) == 2
    assert "nan" not in page.lower().replace("nanos", "")
