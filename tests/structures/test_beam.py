"""Tests of flexsat.structures.beam against closed forms and independent FEM models.

The FEM reference is written here from scratch (Hermite cubic elements, consistent mass, for
the hub a relative-coordinate formulation) and shares no code with the module under test.  Its
eigenvalue error is C h^4: measured against the exact solution, 20 -> 40 elements reduces it by
16.0x (mode 3: 2.2e-6 -> 1.4e-7).  Finer meshes do not help in double precision (cond(K) ~ N^4
brings round-off of ~1e-8 at 200 elements), so the reference is the Richardson extrapolation
(16 λ_40 − λ_20)/15, accurate to ~3e-10 for the first three modes (measured) -> tolerance 2e-9.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

import flexsat.structures.beam as beam_mod
from flexsat.structures import (
    CLAMPED_FREE_BETA_L,
    FREE_FREE_BETA_L,
    CantileverModes,
    TipMassCantilever,
    clamped_free_beta_L,
    hub_free_frequencies,
)

# TAMU slewing testbed (Junkins & Turner), converted from oz-in-s units.
OZF, INCH = 0.278013851, 0.0254
TAMU = dict(
    length=45.523 * INCH,
    EI=131380.8 * OZF * INCH**2,
    rho=0.003007 * OZF / INCH**2,
    tip_mass=0.15627 * OZF / INCH,
)
TAMU_HUB_RADIUS = 5.547 * INCH
TAMU_HUB_INERTIA = 50 * OZF * INCH

# a deliberately non-unit beam: m/(ρL) = 1.1, J/(ρL³) = 0.02
L0, EI0, RHO0 = 1.7, 3.2, 0.45
M0, J0 = 1.1 * RHO0 * L0, 0.02 * RHO0 * L0**3


# ------------------------------------------------------------------------------------------------
# independent reference models
def _root(f, a, b):
    return brentq(f, a, b, xtol=1e-300, rtol=1e-15)


def _cf_roots(k):
    """Roots of 1 + cos z cosh z = 0 as cos z + sech z = 0, one per ((i-1)π, iπ), brentq."""
    f = lambda z: math.cos(z) + 1.0 / math.cosh(z)  # noqa: E731
    return np.array([_root(f, (i - 1) * math.pi + 1e-9, i * math.pi) for i in range(1, k + 1)])


def _hermite_fem(L, EI, rho, n_el):
    """Full (unconstrained) Hermite-cubic stiffness and consistent mass, dofs (w_j, w'_j)."""
    h = L / n_el
    ke = (
        EI
        / h**3
        * np.array(
            [
                [12, 6 * h, -12, 6 * h],
                [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                [-12, -6 * h, 12, -6 * h],
                [6 * h, 2 * h * h, -6 * h, 4 * h * h],
            ]
        )
    )
    me = (
        rho
        * h
        / 420
        * np.array(
            [
                [156, 22 * h, 54, -13 * h],
                [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                [54, 13 * h, 156, -22 * h],
                [-13 * h, -3 * h * h, -22 * h, 4 * h * h],
            ]
        )
    )
    ndof = 2 * (n_el + 1)
    K, M = np.zeros((ndof, ndof)), np.zeros((ndof, ndof))
    for e in range(n_el):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += ke
        M[s, s] += me
    return K, M, np.linspace(0.0, L, n_el + 1)


def _lowest_eigs(K, M, k, shift):
    """k lowest λ of K x = λ M x, accurately: the *largest* μ = 1/(λ + shift) of
    M x = μ (K + shift M) x carry only eps·μ_max absolute error, whereas eigh(K, M) loses
    eps·cond(K) ~ 1e-4 relative on the lowest λ of a 200-element beam."""
    mu = scipy.linalg.eigh(M, K + shift * M, eigvals_only=True)
    return np.sort(1.0 / mu[-k:] - shift)


def _richardson(fem):
    """√((16 λ_40 − λ_20)/15) from a function fem(n_elements) -> frequencies."""
    lam20, lam40 = fem(20) ** 2, fem(40) ** 2
    return np.sqrt((16 * lam40 - lam20) / 15)


def _fem_cantilever(L, EI, rho, m, J, n_el, k):
    K, M, _ = _hermite_fem(L, EI, rho, n_el)
    K, M = K[2:, 2:], M[2:, 2:].copy()  # clamp the root
    M[-2, -2] += m
    M[-1, -1] += J
    return np.sqrt(_lowest_eigs(K, M, k, 0.0))


def _fem_hub(L, EI, rho, m, J, l0, I_hub, n, n_el, k):
    """Hub angle θ plus beam deflection y relative to the rotating frame (clamped root).

    T = ½ I_hub θ'² + n ½ [∫ρ (y' + (l0+ξ)θ')² + m (y_L' + l θ')² + J (y_L'' + θ')²],
    U = n ½ ∫EI y''² ; the rigid field (l0+ξ, slope 1) is exactly cubic-interpolable, so the
    coupling is M_full @ u_rigid.
    """
    K, M, x = _hermite_fem(L, EI, rho, n_el)
    l = l0 + L
    u = np.zeros(K.shape[0])
    u[0::2], u[1::2] = l0 + x, 1.0
    d = (M @ u)[2:]
    d[-2] += m * l
    d[-1] += J
    I_b = u @ M @ u + m * l**2 + J
    Kf, Mf = K[2:, 2:], M[2:, 2:].copy()
    Mf[-2, -2] += m
    Mf[-1, -1] += J
    nf = Kf.shape[0]
    Ms = np.zeros((nf + 1, nf + 1))
    Ks = np.zeros_like(Ms)
    Ms[0, 0] = I_hub + n * I_b
    Ms[0, 1:] = Ms[1:, 0] = n * d
    Ms[1:, 1:] = n * Mf
    Ks[1:, 1:] = n * Kf
    lam = _lowest_eigs(Ks, Ms, k + 1, EI / (rho * L**4))
    assert abs(lam[0]) < 1e-8 * lam[1]  # rigid-body mode
    return np.sqrt(lam[1:])


# ------------------------------------------------------------------------------------------------
# clamped-free, no tip body
def test_clamped_free_matches_tabulated_constants():
    # the constants are printed to 10 significant digits -> 1e-9 relative is their own accuracy
    z = clamped_free_beta_L(5)
    np.testing.assert_allclose(z, CLAMPED_FREE_BETA_L, rtol=1e-9, atol=0)
    tabulated = [1.875104069, 4.694091133, 7.854757438, 10.99554073]
    np.testing.assert_allclose(z[:4], tabulated, rtol=1e-9)


def test_clamped_free_full_precision_and_asymptote():
    # independent closed-form root finding: relative 1e-12 is the accuracy promised by betas()
    k = 20
    z = clamped_free_beta_L(k)
    np.testing.assert_allclose(z, _cf_roots(k), rtol=1e-12, atol=0)
    # z_i - (2i-1)π/2 ≈ 2 (-1)^(i+1) e^{-z_i}: the exponentially small correction is resolved
    # (bound 2.1 e^{-z} + rounding), and from i = 11 on z_i equals the asymptote to 1e-14
    asym = (2 * np.arange(1, k + 1) - 1) * math.pi / 2
    i = np.arange(3, k)
    assert np.all(np.abs(z[i] - asym[i]) <= 2.1 * np.exp(-asym[i]) + 1e-14 * asym[i])
    np.testing.assert_allclose(z[10:], asym[10:], rtol=1e-14)


def test_dimensional_scaling_of_frequencies():
    # ω = (βL)² √(EI/(ρL⁴)) exactly; 1e-13 leaves room for rounding only
    b = TipMassCantilever(L0, EI0, RHO0)
    np.testing.assert_allclose(b.betas(6) * L0, clamped_free_beta_L(6), rtol=1e-13)
    np.testing.assert_allclose(
        b.frequencies(6), clamped_free_beta_L(6) ** 2 * math.sqrt(EI0 / (RHO0 * L0**4)), rtol=1e-13
    )


def test_free_free_constants_are_clamped_clamped_roots():
    # 1 - cos z cosh z = 0  <=>  cos z = sech z, one root per (iπ, (i+1)π) for i >= 1;
    # the constants have 10 significant digits -> 1e-9 relative
    f = lambda z: math.cos(z) - 1.0 / math.cosh(z)  # noqa: E731
    ref = [_root(f, i * math.pi + 0.1, (i + 1) * math.pi - 0.1) for i in range(1, 5)]
    np.testing.assert_allclose(FREE_FREE_BETA_L, ref, rtol=1e-9)


# ------------------------------------------------------------------------------------------------
# tip mass and tip inertia
def test_tip_body_frequencies_match_fem():
    # Richardson-extrapolated FEM: 2e-9 relative (see module docstring).  The raw 40-element
    # FEM must lie above (Rayleigh–Ritz upper bound) and within 3e-7 (its h^4 error)
    b = TipMassCantilever(L0, EI0, RHO0, M0, J0)
    w = b.frequencies(4)
    fem = lambda n: _fem_cantilever(L0, EI0, RHO0, M0, J0, n, 4)  # noqa: E731
    np.testing.assert_allclose(w[:3], _richardson(fem)[:3], rtol=2e-9)
    e40 = fem(40) / w - 1
    assert np.all(e40[1:] > 0) and np.all(e40[:3] < 3e-7)


def test_tip_mass_lowers_and_interlaces():
    # adding a tip body lowers every frequency (Rayleigh) but a finite one only down to the
    # next-lower clamped-free root: β_{i-1}^{cf} < β_i < β_i^{cf}
    z_cf = clamped_free_beta_L(8)
    z = TipMassCantilever(1.0, 1.0, 1.0, 3.0, 0.0).betas(8)
    assert np.all(z < z_cf)
    assert np.all(z[1:] > z_cf[:-1])


def test_extreme_tip_body_and_spring_mass_limit():
    # μ = m/(ρL) = 1e4: first mode is the tip mass on the static cantilever spring with an
    # effective beam mass 33/140 ρL: ω² = 3EI/L³ / (m + 33/140 ρL); error O(μ^-2) ~ 1e-8
    mu = 1e4
    b = TipMassCantilever(1.0, 1.0, 1.0, mu, 0.0)
    w1 = b.frequencies(1)[0]
    np.testing.assert_allclose(w1**2, 3.0 / (mu + 33 / 140), rtol=1e-7)
    # a heavy, large-inertia tip body still gives all roots, in agreement with the FEM
    b = TipMassCantilever(L0, EI0, RHO0, 50 * RHO0 * L0, 5 * RHO0 * L0**3)
    fem = lambda n: _fem_cantilever(  # noqa: E731
        L0, EI0, RHO0, 50 * RHO0 * L0, 5 * RHO0 * L0**3, n, 4
    )
    np.testing.assert_allclose(b.frequencies(4)[:3], _richardson(fem)[:3], rtol=2e-9)


def test_coarse_scan_does_not_miss_roots(monkeypatch):
    # with a scan step of ~1.3 π several grid intervals hold two roots and no sign change; the
    # Wittrick–Williams count must force the subdivision that recovers them (exact agreement up
    # to brentq's 4 eps tolerance)
    b = TipMassCantilever(L0, EI0, RHO0, M0, J0)
    ref = b.betas(12)
    href = hub_free_frequencies(b, 0.3, 0.7, 3, 8)
    monkeypatch.setattr(beam_mod, "_SCAN_STEP", 4.1)
    np.testing.assert_allclose(b.betas(12), ref, rtol=1e-14)
    np.testing.assert_allclose(hub_free_frequencies(b, 0.3, 0.7, 3, 8), href, rtol=1e-14)


# ------------------------------------------------------------------------------------------------
# modes
@pytest.mark.parametrize("m,J", [(0.0, 0.0), (M0, J0)])
def test_modes_orthonormal(m, J):
    # 400-point Gauss–Legendre integrates these entire functions (β L ≤ 37) to ~1e-15, so 1e-10
    # (mass) and 1e-8 relative (stiffness) test the modes, not the quadrature
    k = 12
    b = TipMassCantilever(L0, EI0, RHO0, m, J)
    modes = b.modes(k)
    assert isinstance(modes, CantileverModes)
    s, wq = np.polynomial.legendre.leggauss(400)
    xi, wq = 0.5 * L0 * (s + 1), 0.5 * L0 * wq
    phi, ddphi = modes.evaluate(xi, 0), modes.evaluate(xi, 2)
    tip, dtip = modes.evaluate(L0, 0)[0], modes.evaluate(L0, 1)[0]
    mass = RHO0 * (phi * wq[:, None]).T @ phi + m * np.outer(tip, tip) + J * np.outer(dtip, dtip)
    np.testing.assert_allclose(mass, np.eye(k), atol=1e-10)
    stiff = EI0 * (ddphi * wq[:, None]).T @ ddphi
    w = modes.omegas
    np.testing.assert_allclose(stiff / np.outer(w, w), np.eye(k), atol=1e-8)
    np.testing.assert_allclose(w, b.frequencies(k), rtol=1e-14)
    assert np.all(tip > 0)  # sign convention


def test_modes_satisfy_ode_and_boundary_conditions_high_modes():
    # k = 20 (βL ≈ 61): every residual relative to its natural scale (EI β^j max|φ|) is
    # rounding-level; 1e-11 would be violated by any cosh/sinh cancellation (~e^{61} eps)
    k = 20
    b = TipMassCantilever(L0, EI0, RHO0, M0, J0)
    md = b.modes(k)
    beta, w = md.betas, md.omegas
    xi = np.linspace(0, L0, 301)
    d = [md.evaluate(xi, j) for j in range(5)]
    scale = np.abs(d[0]).max(0)
    assert d[0].shape == (301, k)
    ode = (EI0 * d[4] - RHO0 * w**2 * d[0]) / (EI0 * beta**4 * scale)
    np.testing.assert_allclose(ode, 0, atol=1e-11)
    np.testing.assert_allclose(d[0][0] / scale, 0, atol=1e-12)
    np.testing.assert_allclose(d[1][0] / (beta * scale), 0, atol=1e-12)
    np.testing.assert_allclose(
        (EI0 * d[2][-1] - J0 * w**2 * d[1][-1])
        / (EI0 * beta**2 * scale * (1 + J0 * beta**3 / RHO0)),
        0,
        atol=1e-11,
    )
    np.testing.assert_allclose(
        (EI0 * d[3][-1] + M0 * w**2 * d[0][-1]) / (EI0 * beta**3 * scale * (1 + M0 * beta / RHO0)),
        0,
        atol=1e-11,
    )
    # mass normalisation still holds for the highest modes (quadrature as above)
    s, wq = np.polynomial.legendre.leggauss(400)
    x, wq = 0.5 * L0 * (s + 1), 0.5 * L0 * wq
    phi = md.evaluate(x)
    norm = RHO0 * wq @ phi**2 + M0 * d[0][-1] ** 2 + J0 * d[1][-1] ** 2
    np.testing.assert_allclose(norm, 1.0, rtol=1e-10)
    # derivative consistency: φ' by central differences of φ (h = 1e-6 L -> error ~1e-6)
    h = 1e-6 * L0
    fd = (md.evaluate(xi[1:-1] + h) - md.evaluate(xi[1:-1] - h)) / (2 * h)
    np.testing.assert_allclose(fd[:, :5], d[1][1:-1, :5], atol=1e-5 * np.abs(d[1][:, :5]).max())


# ------------------------------------------------------------------------------------------------
# free hub
@pytest.mark.parametrize("l0,I_hub,n", [(0.3, 0.7, 3), (0.05, 20.0, 1), (0.0, 0.01, 2)])
def test_hub_free_matches_fem(l0, I_hub, n):
    # relative-coordinate FEM (θ + clamped beam dofs, a different formulation from the inertial
    # w of the module), Richardson-extrapolated: 2e-9 relative (measured agreement ≤ 3e-10)
    b = TipMassCantilever(L0, EI0, RHO0, M0, J0)
    w = hub_free_frequencies(b, l0, I_hub, n, 4)
    fem = lambda N: _fem_hub(L0, EI0, RHO0, M0, J0, l0, I_hub, n, N, 4)  # noqa: E731
    np.testing.assert_allclose(w[:3], _richardson(fem)[:3], rtol=2e-9)
    # freeing the hub raises each frequency, but not above the next clamped one (interlacing)
    wc = b.frequencies(5)
    assert np.all(w > wc[:4]) and np.all(w < wc[1:5])


def test_hub_free_tends_to_clamped_for_rigid_hub():
    # I_hub = 1e9 × (n × beam inertia): ω² shifts by O(I_b/I_hub) ~ 1e-9; 1e-6 relative
    p = dict(TAMU)
    b = TipMassCantilever(**p)
    l0, n = TAMU_HUB_RADIUS, 4
    l = l0 + p["length"]
    I_b = p["rho"] * (l**3 - l0**3) / 3 + p["tip_mass"] * l**2
    w = hub_free_frequencies(b, l0, 1e9 * n * I_b, n, 5)
    np.testing.assert_allclose(w, b.frequencies(5), rtol=1e-6)
    w_free = hub_free_frequencies(b, l0, TAMU_HUB_INERTIA, n, 5)
    assert w_free[0] > b.frequencies(1)[0]


def test_hub_free_massless_hub_is_pinned_free():
    # l0 = 0, m = J = 0, I_hub -> 0: the root becomes a pin (w(0) = 0, w''(0) = 0), so the
    # n = 1 roots solve tan z = tanh z; for n = 2 the two beams form one free-free beam of
    # length 2L moving in its odd modes, z = FREE_FREE_BETA_L[1], [3] / 2.  η = 1e-12 perturbs by
    # ~1e-12; 1e-10 relative for the closed form, 1e-9 for the 10-digit constants
    b = TipMassCantilever(1.0, 1.0, 1.0)
    z = np.sqrt(hub_free_frequencies(b, 0.0, 1e-12, 1, 4))
    f = lambda t: math.sin(t) - math.cos(t) * math.tanh(t)  # noqa: E731
    # one root per (iπ, iπ + π/2), just below (i + 1/4)π
    ref = [_root(f, i * math.pi + 1e-3, (i + 0.5) * math.pi - 1e-9) for i in range(1, 5)]
    np.testing.assert_allclose(z, ref, rtol=1e-10)
    z2 = np.sqrt(hub_free_frequencies(b, 0.0, 1e-12, 2, 2))
    np.testing.assert_allclose(2 * z2, [FREE_FREE_BETA_L[1], FREE_FREE_BETA_L[3]], rtol=1e-9)


def test_tamu_realistic_numbers():
    # published: clamped first mode ≈ 0.75 Hz for the TAMU appendage (2 % check of the units)
    b = TipMassCantilever(**TAMU)
    f = b.frequencies(5) / (2 * math.pi)
    assert abs(f[0] - 0.75) < 0.015
    w = hub_free_frequencies(b, TAMU_HUB_RADIUS, TAMU_HUB_INERTIA, 4, 5)
    fem = lambda N: _fem_hub(  # noqa: E731
        TAMU["length"],
        TAMU["EI"],
        TAMU["rho"],
        TAMU["tip_mass"],
        0.0,
        TAMU_HUB_RADIUS,
        TAMU_HUB_INERTIA,
        4,
        N,
        3,
    )
    # the 3rd hub-free TAMU mode has βL ≈ 11.6, where the extrapolation leaves 2.1e-9 -> 5e-9
    np.testing.assert_allclose(w[:3], _richardson(fem), rtol=5e-9)


# ------------------------------------------------------------------------------------------------
# input validation
@pytest.mark.parametrize(
    "field,value",
    [
        ("length", 0.0),
        ("length", -1.0),
        ("EI", 0.0),
        ("EI", float("nan")),
        ("rho", -2.0),
        ("rho", float("inf")),
        ("tip_mass", -1e-3),
        ("tip_mass", float("nan")),
        ("tip_inertia", -1.0),
        ("length", "1 m"),
    ],
)
def test_bad_beam_input_names_field(field, value):
    kw = dict(length=1.0, EI=1.0, rho=1.0, tip_mass=0.0, tip_inertia=0.0)
    kw[field] = value
    with pytest.raises(ValueError, match=field):
        TipMassCantilever(**kw)


@pytest.mark.parametrize("k", [0, -3, 2.5, True, "3"])
def test_bad_k_names_field(k):
    b = TipMassCantilever(1.0, 1.0, 1.0)
    for fn in (b.betas, b.frequencies, b.modes, clamped_free_beta_L):
        with pytest.raises(ValueError, match="k"):
            fn(k)
    with pytest.raises(ValueError, match="k"):
        hub_free_frequencies(b, 0.1, 1.0, 1, k)


@pytest.mark.parametrize(
    "field,args",
    [
        ("hub_radius", (-0.1, 1.0, 2)),
        ("hub_radius", (float("nan"), 1.0, 2)),
        ("hub_inertia", (0.1, 0.0, 2)),
        ("hub_inertia", (0.1, -1.0, 2)),
        ("n_appendages", (0.1, 1.0, 0)),
        ("n_appendages", (0.1, 1.0, 1.5)),
    ],
)
def test_bad_hub_input_names_field(field, args):
    b = TipMassCantilever(1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match=field):
        hub_free_frequencies(b, *args, 3)
    with pytest.raises(ValueError, match="beam"):
        hub_free_frequencies("not a beam", 0.1, 1.0, 1, 3)


def test_bad_evaluate_input_names_field():
    md = TipMassCantilever(1.0, 1.0, 1.0).modes(3)
    with pytest.raises(ValueError, match="derivative"):
        md.evaluate([0.5], 5)
    with pytest.raises(ValueError, match="xi"):
        md.evaluate([1.5])
    with pytest.raises(ValueError, match="xi"):
        md.evaluate([float("nan")])


def test_the_roots_depend_on_the_tip_ratios_alone_and_are_shared_read_only():
    # βL solves the frequency equation in μ = m/(ρL) and ι = J/(ρL³) only: a stiffer beam with
    # the same ratios gets the cached roots themselves (the Monte Carlo case), equal to a fresh
    # search bit for bit, and nobody can overwrite them
    a = beam_mod.TipMassCantilever(length=1.2, EI=9.3, rho=0.5, tip_mass=0.3, tip_inertia=1e-3)
    b = beam_mod.TipMassCantilever(length=1.2, EI=2 * 9.3, rho=0.5, tip_mass=0.3, tip_inertia=1e-3)
    assert a._beta_L(6) is b._beta_L(6)
    fresh = beam_mod._tip_loaded_roots.__wrapped__(a._mu, a._iota, 6)
    np.testing.assert_array_equal(a._beta_L(6), fresh)
    with pytest.raises(ValueError, match="read-only"):
        a._beta_L(6)[0] = 1.0
    np.testing.assert_allclose(b.frequencies(6), math.sqrt(2) * a.frequencies(6), rtol=1e-15)
