"""NPS Flexible Spacecraft Simulator (Hailey, Sortun & Agrawal c. 1992)."""

import json

import numpy as np
import pytest

from flexsat.cases.nps import PUBLISHED, inertia_budget, nps
from flexsat.structures.beam import TipMassCantilever, hub_free_frequencies
from flexsat.structures.modal_model import hub_appendage_matrices
from flexsat.units import to_si


@pytest.fixture(scope="module")
def case():
    return nps()


def test_first_cantilever_frequency_is_the_published_0_14_hz(case):
    """L21: the mast EI is solved (Brent) so that the finite-element cantilever gives 0.14 Hz."""
    f = case.modal_model().frequencies_hz
    assert f.size == 6 == PUBLISHED["n_modes"]
    assert f[0] == pytest.approx(0.14, rel=1e-6)
    assert np.all(case.modal_model().damping == 0.004)
    # the distributed-parameter beam with the solved EI agrees (20 cubic elements)
    beam = TipMassCantilever(
        case.mast_length,
        case.mast_bending_stiffness_value,
        case.mast_mass_per_length,
        case.reflector_mass,
        case.reflector_inertia,
    )
    exact = beam.frequencies(3) / (2 * np.pi)
    assert exact[0] == pytest.approx(0.14, rel=1e-6)
    np.testing.assert_allclose(f[:3], exact, rtol=1e-5)


def test_other_frequency_and_given_stiffness():
    c = nps(cantilever_frequency="0.2 Hz")
    assert c.modal_model().frequencies_hz[0] == pytest.approx(0.2, rel=1e-6)
    # for a fixed mass, the frequency scales with sqrt(EI): a given EI is used as is
    base = nps()
    EI = 4 * base.mast_bending_stiffness_value
    c = nps(mast_bending_stiffness=EI)
    assert c.mast_bending_stiffness == EI
    assert c.modal_model().frequencies_hz[0] == pytest.approx(0.28, rel=1e-9)


def test_pd_gains_reproduce_the_printed_values(case):
    """L212–L220: ω_n = 0.06 Hz, ξ = 0.9 → k = 1.3985 N m/rad, kτ = 6.6773 N m s/rad."""
    pd = case.pd_gains()
    assert round(float(pd.kp), 4) == 1.3985
    assert round(float(pd.kd), 4) == 6.6773
    assert float(pd.kp) == pytest.approx(to_si(PUBLISHED["position_gain"], "N*m/rad"), abs=5e-5)
    assert float(pd.kd) == pytest.approx(to_si(PUBLISHED["rate_gain"], "N*m*s/rad"), abs=5e-5)
    wn = 2 * np.pi * 0.06
    assert float(pd.kp) == pytest.approx(9.84 * wn**2, rel=1e-14)
    assert float(pd.kd) == pytest.approx(2 * 0.9 * wn * 9.84, rel=1e-14)


@pytest.mark.parametrize("n", [1, 3, 6])
def test_eq18_as_repaired_equals_the_direct_inverse(case, n):
    """Notes §2: the repaired A = (1/I0)[…] and B of Eq. 18 equal M⁻¹K, M⁻¹C, M⁻¹e₁ of Eq. 16."""
    A18, B18, C18, _ = case.statespace_eq18(n)
    A, B, C, _ = case.statespace_direct(n)
    assert A18.shape == (2 * n + 2, 2 * n + 2)
    assert np.abs(A18 - A).max() <= 1e-12 * np.abs(A).max()
    assert np.abs(B18 - B).max() <= 1e-12 * np.abs(B).max()
    np.testing.assert_array_equal(C18, C)
    sys = case.to_statespace(n)
    assert sys.nstates == 2 * n + 2 and sys.ninputs == 1 and sys.noutputs == 2


def test_hybrid_matrices_are_eq_16(case):
    M, C, K = case.hybrid_matrices()
    D = case.coupling()
    w, z = case.modal_model().frequencies, case.modal_model().damping
    assert M[0, 0] == pytest.approx(case.total_inertia, rel=1e-15)
    np.testing.assert_array_equal(M[1:, 0], D)
    np.testing.assert_array_equal(M[0, 1:], D)
    np.testing.assert_array_equal(M[1:, 1:], np.eye(6))
    np.testing.assert_allclose(np.diag(K), np.r_[0.0, w**2], rtol=1e-15)
    np.testing.assert_allclose(np.diag(C), np.r_[0.0, 2 * z * w], rtol=1e-15)
    assert np.count_nonzero(K - np.diag(np.diag(K))) == 0
    M2, C2, K2 = hub_appendage_matrices(case.modal_model(), case.hub_inertia_value, axis=2)
    np.testing.assert_array_equal(M, M2)


def test_single_mode_identity(case):
    """Notes §2: with one mode, ω_sys² = ω₁² I_zz / I0 exactly (I0 = I_zz − D₁²)."""
    w1 = case.modal_model(1).frequencies[0]
    D1 = case.coupling(1)[0]
    I0 = case.total_inertia - D1**2
    assert case.cantilevered_inertia(1) == pytest.approx(I0, rel=1e-15)
    w_sys = case.system_frequencies(1)
    assert w_sys.size == 1
    assert w_sys[0] ** 2 == pytest.approx(w1**2 * case.total_inertia / I0, rel=1e-12)


def test_coupling_completeness(case):
    """Σ D_i² grows with the modes towards the appendage inertia about the hub axis:
    with every finite-element mode it reaches it up to the attachment node's consistent-mass
    share, which vanishes with the mesh."""
    budget = inertia_budget(case)
    assert budget["appendage"] == pytest.approx(budget["appendage_continuous"], rel=1e-12)
    sums = [float(case.coupling(n) @ case.coupling(n)) for n in (1, 2, 3, 6, 12, 24, 40)]
    assert np.all(np.diff(sums) > 0)
    D = case.coupling("all")
    assert D.size == 40
    gap = case.appendage_inertia - D @ D
    assert 0 < gap < 2e-4 * case.appendage_inertia
    assert sums[3] > 0.999 * case.appendage_inertia  # six modes hold 99.9 %
    finer = nps(n_elements=40)
    D = finer.coupling("all")
    assert 0 < finer.appendage_inertia - D @ D < 0.6 * gap


def test_hub_free_frequencies(case):
    """frequencies_hz: hub-free system frequencies, above the cantilever ones (interlacing);
    with every finite-element mode the hybrid model is the free-hub finite-element model, which
    agrees with the exact distributed-parameter solution."""
    fc = case.modal_model().frequencies_hz
    fs = case.frequencies_hz(6)
    assert np.all(fs > fc)
    assert np.all(fs[:-1] < fc[1:])
    exact = hub_free_frequencies(
        TipMassCantilever(
            case.mast_length,
            case.mast_bending_stiffness_value,
            case.mast_mass_per_length,
            case.reflector_mass,
            case.reflector_inertia,
        ),
        case.attachment_radius,
        case.hub_inertia_value,
        1,
        3,
    ) / (2 * np.pi)
    full = case.system_frequencies("all")[:3] / (2 * np.pi)
    np.testing.assert_allclose(full, exact, rtol=1e-5)
    assert full[0] == pytest.approx(exact[0], rel=1e-8)
    assert fs[0] == pytest.approx(full[0], rel=1e-8)  # six modes suffice for the first
    with pytest.raises(ValueError, match=r"^n_modes: the model has 6 modes"):
        case.frequencies_hz(7)


def test_inertia_conventions():
    """Default: I⁰zz (six modes) = 9.84 kg m² (the issue); "total": I_zz = 9.84 kg m²."""
    c = nps()
    assert c.inertia_convention == "cantilevered"
    assert c.cantilevered_inertia() == pytest.approx(9.84, rel=1e-13)
    assert c.total_inertia > 9.84
    t = nps(inertia_convention="total")
    assert t.total_inertia == pytest.approx(9.84, rel=1e-13)
    assert t.hub_inertia_value == pytest.approx(9.84 - t.appendage_inertia, rel=1e-13)
    assert t.cantilevered_inertia() < 9.84
    h = nps(hub_inertia="2 kg*m**2")
    assert h.hub_inertia_value == 2.0
    assert h.total_inertia == pytest.approx(2.0 + h.appendage_inertia, rel=1e-15)
    assert h.pd_gains().kp == pytest.approx(c.pd_gains().kp, rel=1e-15)  # design unchanged


def test_mode_details_are_json_ready(case):
    d = case.mode_details(3)
    json.dumps(d)
    assert d["constrained_fe_hz"][0] == pytest.approx(0.14, rel=1e-6)
    assert d["constrained_hz"][0] == pytest.approx(0.14, rel=1e-6)
    assert len(d["exact_unconstrained_hz"]) == len(d["coupling_D_sqrt_kg_m"]) == 3
    assert d["inertia_budget_kg_m2"]["I0_zz"] == pytest.approx(9.84, rel=1e-13)
    assert d["inertia_convention"] == "cantilevered"
    assert len(case.mode_descriptions(6)) == 6


def test_overrides_accept_units_and_reject_bad_input():
    c = nps(mast_length="200 cm", reflector_mass="1500 g", n_elements=12)
    assert c.mast_length == 2.0 and c.reflector_mass == pytest.approx(1.5)
    assert c.modal_model().frequencies_hz[0] == pytest.approx(0.14, rel=1e-6)
    with pytest.raises(ValueError, match=r"^nps: unknown parameter\(s\) \['mast_lenght'\]"):
        nps(mast_lenght=1.0)
    with pytest.raises(ValueError, match=r"^mast_length: must be > 0"):
        nps(mast_length=0.0)
    with pytest.raises(ValueError, match=r"^mast_mass_per_length: incompatible units"):
        nps(mast_mass_per_length="3 kg")
    with pytest.raises(ValueError, match=r"^cantilever_frequency: must be > 0"):
        nps(cantilever_frequency="-0.1 Hz")
    with pytest.raises(ValueError, match=r"^damping: must be >= 0"):
        nps(damping=-0.01)
    with pytest.raises(ValueError, match=r"^damping: must be < 1"):
        nps(damping=1.5)
    with pytest.raises(ValueError, match=r"^inertia_convention: must be one of"):
        nps(inertia_convention="hub")
    with pytest.raises(ValueError, match=r"^n_modes: must be a positive integer"):
        nps(n_modes=2.5)
    with pytest.raises(ValueError, match=r"^n_elements: must be >= 2"):
        nps(n_elements=1)
    with pytest.raises(ValueError, match=r"^mast_bending_stiffness: give either"):
        nps(mast_bending_stiffness=1.0, cantilever_frequency="0.1 Hz")
    with pytest.raises(ValueError, match=r"^design_inertia: .* too small for I_zz"):
        nps(inertia_convention="total", reflector_mass="3 kg")
    with pytest.raises(ValueError, match=r"^hub_inertia: must be > 0"):
        nps(hub_inertia=0)
    assert nps(damping="0.4 percent").damping == pytest.approx(0.004)


def test_cable_spring_steady_state_error_is_eq_23():
    # Eq. 23: under T = −k θ_e + T_D the PD step settles at θ_ss = T_D / k; 400 s of the
    # closed loop (slowest pole 0.34 /s, e^{−136}) leaves only round-off: 1e-6 relative
    from flexsat.sim.disturbances import CableSpring

    case = nps()
    k = float(case.pd_gains().kp)
    run = case.cable_slew()
    theta_ss = float(run["theta"].values[0, -1]) - case.slew_angle
    assert theta_ss == pytest.approx(1e-3 / k, rel=1e-6)
    assert np.degrees(theta_ss) == pytest.approx(0.041, abs=5e-4)  # as printed
    # a linear cable spring adds its stiffness: θ_ss = (T_D + k_c θ_c) / (k + k_c) about the
    # target, here with θ_c at the target; a tabulated straight line is the same spring
    kc = 0.5
    lin = CableSpring(constant="1 mN*m", stiffness=kc, center=case.slew_angle)
    a = float(case.cable_slew(lin)["theta"].values[0, -1]) - case.slew_angle
    assert a == pytest.approx(1e-3 / (k + kc), rel=1e-6)
    angles = np.array([-1.0, 3.0])
    tab = CableSpring(angles=tuple(angles), torques=tuple(1e-3 - kc * (angles - case.slew_angle)))
    b = float(case.cable_slew(tab)["theta"].values[0, -1]) - case.slew_angle
    assert b == pytest.approx(a, rel=1e-9)
