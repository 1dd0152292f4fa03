"""Att. 6 differential correction: free and forced response fitted together (Eqs. 3–13).

The ``frame`` fixture (tests/identify/conftest.py) is the planar two-storey, two-bay portal frame
with three stiffness/mass substructures: left columns, other columns, beams.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify.differential_correction import CorrectionData, differential_correction
from flexsat.identify.structural import SubstructureModel, damped_eigenvalues
from flexsat.input_checks import FieldError

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


# ------------------------------------------------------------------------------------------------
# Att. 6 differential correction (Eqs. 3-13) on the portal frame with Rayleigh damping blocks
# 0.5 M + 2e-5 K (damping ratios 0.3-0.6 % in modes 1-8), scalings r ~ 1.
def _damped(frame):
    return SubstructureModel(
        frame.K_blocks, frame.M_blocks, [0.5 * frame.M(), 2e-5 * frame.K()], names=frame.names
    )


def _receptance(model, p, q, r, output, inp, omegas):
    K, M, C = model.K(p), model.M(q), model.C(r)
    n = model.n_dofs
    c = np.eye(n)[output] if np.ndim(output) == 0 else output
    b = np.eye(n)[inp] if np.ndim(inp) == 0 else inp
    return np.array([c @ np.linalg.solve(K - w**2 * M + 1j * w * C, b) for w in omegas])


# FRF points >= 8 % away from every resonance of the nominal frame (47.6 ... 632 rad/s), of the
# frame with columns 2-3 at 1/1.15 stiffness, and of the x 0.905 start model; closer points
# trapped the mass/stiffness fit from the x 0.905 start in a local minimum (Att. 6 L2489: the
# start must be good).  Driving points 3 and 20 and one transfer element.
FRAME_FRF = dict(
    omegas=np.array([20.0, 100.0, 200.0, 230.0, 460.0, 500.0]), pairs=((3, 3), (10, 3), (20, 20))
)


def _frame_data(model, p, q, r, rng=None, items=None):
    """8 frequencies (SD 0.1 %), 8 damping ratios (SD 2 %), FRF points (SD 1 %) at the
    FRAME_FRF omegas: 3 x 6 of the FRAME_FRF pairs, or of ``items`` (output, input, gain,
    output_gain, input_gain), the receptance times ``gain`` (Att. 6 Eqs. 6-7)."""
    if items is None:
        items = [(j, k, 1.0, None, None) for j, k in FRAME_FRF["pairs"]]
    m = 8
    w, _ = model.modes(p, q)
    lam = damped_eigenvalues(model.K(p), model.M(q), model.C(r), n_modes=m)
    zeta = -lam.real / np.abs(lam)
    noise = (lambda size: rng.standard_normal(size)) if rng is not None else np.zeros
    frf = []
    for out, inp, gain, og, ig in items:
        h = gain * _receptance(model, p, q, r, out, inp, FRAME_FRF["omegas"])
        sd = 0.01 * np.abs(h) / np.sqrt(2)  # complex SD 1 %: real and imaginary parts each
        frf.append(
            (
                out,
                inp,
                FRAME_FRF["omegas"],
                h + sd * (noise(h.size) + 1j * noise(h.size)),
                sd,
                og,
                ig,
            )
        )
    return CorrectionData(
        frequencies=w[:m] * (1 + 1e-3 * noise(m)),
        frequency_sigma=1e-3 * w[:m],
        damping_ratios=zeta * (1 + 0.02 * noise(m)),
        damping_sigma=0.02 * zeta,
        frf=frf,
    )


def _fourth_order_jacobian(f, x):
    """Fourth-order central differences, h = 1e-3 x: truncation ~1e-12; the eigen-solves carry
    ~1e-11 relative round-off (eigenvalue spread 1e5), i.e. ~1e-8 after / h.  A second-order
    difference cannot separate the two below ~1e-7."""
    cols = []
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = 1e-3 * x[k]
        cols.append((8 * (f(x + e) - f(x - e)) - (f(x + 2 * e) - f(x - 2 * e))) / (12 * e[k]))
    return np.column_stack(cols)


def test_correction_jacobian_matches_central_differences(frame):
    """A = dQ/dP (Att. 6 Eq. 13) of every measurement kind against central differences."""
    model = _damped(frame)
    n = model.n_dofs
    x = np.array([0.97, 1.02, 0.99, 1.01, 0.98, 1.03, 1.2, 0.75])  # off-nominal P
    w, phi = model.modes(x[:3], x[3:6])
    rng = np.random.default_rng(0)
    strain = np.zeros(n)
    strain[[10, 20]] = (1.0, -1.0)  # an output row of H: difference of two dofs
    torque = np.zeros(n)
    torque[[3, 5]] = (0.5, 1.0)  # an input column of B
    partial = CorrectionData(
        frequencies=w[[0, 1, 3]],
        frequency_sigma=1.0,
        frequency_modes=[0, 1, 3],
        shapes=phi[[3, 5, 10, 20]][:, [0, 2]] * 2.0,
        shape_sigma=1.0,
        shape_dofs=[3, 5, 10, 20],
        shape_modes=[0, 2],
        damping_ratios=[0.005, 0.004, 0.004],
        damping_sigma=1.0,
        damping_modes=[0, 1, 4],
        # 0.95 w_4: on the flank of resonance 4 (amplification ~10, Att. 6 R^r, R^i); closer,
        # the FRF's curvature (scale zeta ~ 0.3 %) spoils the differences below
        frf=[
            (3, 3, [20.0, 120.0], [1.0, 1.0], 1.0),
            (strain, torque, [100.0, 0.95 * w[3]], [1.0, 1.0], 1.0),
        ],
    )
    full = CorrectionData(
        shapes=phi[:, :3] + 0.01 * rng.standard_normal((n, 3)),
        shape_sigma=1.0,
        orthogonality_sigma=1.0,
        normalization_sigma=1.0,
    )
    for data in (partial, full):
        _, A = data.predict(model, x[:3], x[3:6], x[6:])

        def f(y, data=data):
            return data.predict(model, y[:3], y[3:6], y[6:])[0]

        A_fd = _fourth_order_jacobian(f, x)
        # error relative to each row's largest derivative (entries that vanish, e.g. the
        # frequencies' damping columns, are compared at that scale)
        scale = np.abs(A_fd).max(axis=1, keepdims=True)
        assert np.all(scale > 0)
        assert np.all(np.abs(A - A_fd) < 1e-6 * scale)


def test_differential_correction_finds_15_percent_stiffness_error(frame):
    """A-priori columns 2-3 stiffness +15 %: free + forced data locate it (Att. 6 Eqs. 9-13).

    Mass held (known); stiffness and both damping scalings fitted from 8 frequencies, 8
    damping ratios and 18 complex FRF points, noise 0.1 % / 2 % / 1 %, 10 seeds.
    """
    model = _damped(frame)
    p_true = np.array([1.0, 1.0 / 1.15, 1.0])
    ones = np.ones(3)
    for seed in range(10):
        data = _frame_data(model, p_true, ones, np.ones(2), np.random.default_rng(seed))
        res = differential_correction(model, data, fixed_mass=[0, 1, 2])
        assert res.converged
        err = res.p / p_true - 1
        sd = np.sqrt(np.diag(res.covariance))
        # predicted SDs: columns 2-3 0.18 %, the others 0.16 %: 1 % and 0.5 % are >= 3 SD
        assert sd[1] < 0.002 and sd[0] < 0.0017 and sd[2] < 0.0017 and np.all(sd[3:6] == 0)
        assert abs(err[1]) < 0.01 and abs(err[0]) < 0.005 and abs(err[2]) < 0.005
        assert np.array_equal(res.q, ones)
        # damping scalings: predicted SD 2 % (mass-proportional) and 1 % (stiffness-prop.)
        assert np.all(np.abs(res.r - 1) < 4 * sd[6:])
        # halving keeps the cost falling, to the round-off of evaluating it (a few ε of the
        # residual per entry, over ~100 entries) once it has converged
        history = np.asarray(res.residual_history)
        assert np.all(np.diff(history) <= 1e-12 * history[1:])
    # the update only scales the a-priori blocks: symmetry and zero pattern are kept
    for upd, prior in (
        (res.model.K(), model.K()),
        (res.model.M(), model.M()),
        (res.model.C(), model.C()),
    ):
        assert np.array_equal(upd, upd.T)
        assert not np.any((upd != 0) & (prior == 0))


def test_forced_response_fixes_the_scale(frame):
    """Mass x 1.1, stiffness x 0.9 a priori: FRF + free response recover both; free alone can't.

    Frequencies and damping ratios are unchanged by scaling K, M, C together, so the fit
    without FRF is rank-deficient along (p, q, r) -> c (p, q, r) and must say so.
    """
    model = _damped(frame)
    ones = np.ones(3)
    start = dict(p0=0.9 * ones, q0=1.1 * ones)
    exact = _frame_data(model, ones, ones, np.ones(2))
    res = differential_correction(model, exact, **start)
    assert res.converged
    # exact data: 1e-8 (the Gauss-Newton fixed point to eigen-solve round-off)
    assert np.abs(np.r_[res.p, res.q, res.r] - 1).max() < 1e-8
    assert res.residual_history[-1] < 1e-12 * res.residual_history[0]
    noisy = _frame_data(model, ones, ones, np.ones(2), np.random.default_rng(1))
    res = differential_correction(model, noisy, **start)
    sd = np.sqrt(np.diag(res.covariance))
    # within 4 predicted SDs (mass and stiffness SDs < 0.5 %)
    assert np.all(sd[:6] < 0.005) and np.all(np.abs(np.r_[res.p, res.q, res.r] - 1) < 4 * sd)
    free = CorrectionData(
        frequencies=exact.frequencies,
        frequency_sigma=exact.frequency_sigma,
        damping_ratios=exact.damping_ratios,
        damping_sigma=exact.damping_sigma,
    )
    with pytest.raises(ValueError, match=r"not identifiable.*p\[0\].*q\[0\].*r\[0\]"):
        differential_correction(model, free, **start)
    # a 0_p prior (SD 5 %) makes it solvable, but the scale is then the prior's: from p0 = 0.9,
    # q0 = 1 the data fix K/M and the prior splits the scale between the start values (~0.96)
    held = differential_correction(model, free, p0=0.9 * ones, prior_sigma=0.05)
    x = np.r_[held.p, held.q]
    assert held.converged and np.all((x > 0.93) & (x < 0.99))
    assert np.all(np.sqrt(np.diag(held.covariance))[:6] > 0.015)  # prior-sized SDs


def test_differential_correction_errors(frame):
    model = _damped(frame)
    w, _ = model.modes()
    h = np.array([1e-6 + 1e-7j, np.nan])
    with pytest.raises(ValueError, match=r"frf\[0\].values: must be finite"):
        CorrectionData(frf=[(3, 3, [20.0, 30.0], h, 1e-8)])
    with pytest.raises(ValueError, match=r"frf\[0\]: omegas and values must be equal-length"):
        CorrectionData(frf=[(3, 3, [20.0, 30.0], [1e-6], 1e-8)])
    with pytest.raises(ValueError, match="shape_sigma: must be a scalar or shaped like shapes"):
        CorrectionData(shapes=np.ones((4, 2)), shape_sigma=np.ones((3, 2)), shape_dofs=[0, 1, 2, 3])
    with pytest.raises(ValueError, match="shape_dofs: must be 4 distinct dof indices"):
        CorrectionData(shapes=np.ones((4, 2)), shape_sigma=1.0, shape_dofs=[0, 1, 2])
    with pytest.raises(ValueError, match="shapes: without shape_dofs must have one row per dof"):
        CorrectionData(shapes=np.ones((4, 2)), shape_sigma=1.0).predict(model)
    with pytest.raises(ValueError, match="orthogonality_sigma: needs measured shapes on all"):
        CorrectionData(
            shapes=np.ones((4, 2)),
            shape_sigma=1.0,
            shape_dofs=[0, 1, 2, 3],
            orthogonality_sigma=0.01,
        )
    with pytest.raises(FieldError, match="frequencies: no measurement given"):
        CorrectionData()
    with pytest.raises(ValueError, match="frequency_sigma: give the standard deviations"):
        CorrectionData(frequencies=w[:3])
    with pytest.raises(ValueError, match="frequency_modes: must be 3 distinct mode numbers"):
        CorrectionData(frequencies=w[:3], frequency_sigma=1.0, frequency_modes=[0, 0, 1])
    data = CorrectionData(frequencies=w[:4], frequency_sigma=1e-3 * w[:4])
    # 4 frequencies, 8 scalings: refused without a prior, accepted with one
    with pytest.raises(ValueError, match="4 measurements for 8 free parameters: more parameters"):
        differential_correction(model, data)
    assert differential_correction(model, data, prior_sigma=0.1).converged
    with pytest.raises(ValueError, match="damping_ratios: the model has no damping blocks"):
        CorrectionData(damping_ratios=[0.01], damping_sigma=1e-3).predict(frame)
    with pytest.raises(ValueError, match="data: must be a CorrectionData"):
        differential_correction(model, {"frequencies": w[:4]})
    with pytest.raises(ValueError, match=r"fixed_mass: must be block indices in \[0, 3\)"):
        differential_correction(model, data, fixed_mass=[3], prior_sigma=0.1)


def test_complex_frf_sigma_weights_real_and_imaginary_parts_apart():
    """``sd_real + 1j sd_imag``: the SDs of the stacked (real, imaginary) measurement rows."""
    w = np.array([10.0, 20.0])
    h = np.array([1.0 + 0.1j, 2.0 - 0.2j])
    data = CorrectionData(frf=[(0, 1, w, h, np.array([0.01 + 0.5j, 0.02 + 0.6j]))])
    assert np.allclose(data.measured, [1.0, 2.0, 0.1, -0.2])
    assert np.allclose(data.sigma, [0.01, 0.02, 0.5, 0.6])
    same = CorrectionData(frf=[(0, 1, w, h, 0.03)])
    assert np.allclose(same.sigma, 0.03)
    with pytest.raises(ValueError, match=r"frf\[0\].sigma: must be a scalar or 2 values, > 0"):
        CorrectionData(frf=[(0, 1, w, h, 0.01 - 0.5j)])


# ------------------------------------------------------------------------------------------------
# Output and input gains (Att. 6 Eqs. 6-7): two "strain gauges" (H rows: differences of two dofs)
# with unknown gauge factors mu, a calibrated hammer at dof 3 (no gain) and a "motor" (a B
# column) with an unknown current-to-torque constant nu, as in the Att. 6 grid test.
def _gain_items(n, mu, nu):
    """FRF items (output, input, gain, output_gain, input_gain) for :func:`_frame_data`: both
    gauges from the hammer and from the motor."""
    gauges = np.zeros((2, n))
    gauges[0, [10, 20]] = (1.0, -1.0)
    gauges[1, [5, 14]] = (1.0, -1.0)
    torque = np.zeros(n)
    torque[[3, 5]] = (0.5, 1.0)
    return [
        (gauges[g], inp, mu[g] * (1.0 if m is None else nu[m]), g, m)
        for g in range(2)
        for inp, m in ((3, None), (torque, 0))
    ]


def test_gain_jacobian_matches_central_differences(frame):
    """dQ/dmu, dQ/dnu (Att. 6 Eqs. 6-7, 13), and the gain-scaled structural columns, against
    central differences; items with an output gain, an input gain, both, and a shared gain."""
    model = _damped(frame)
    n = model.n_dofs
    # off-nominal P = (p, q, r, mu, nu)
    x = np.array([0.97, 1.02, 0.99, 1.01, 0.98, 1.03, 1.2, 0.75, 1.1, 0.9, 0.8, 1.3])
    w, _ = model.modes(x[:3], x[3:6])
    strain = np.zeros(n)
    strain[[10, 20]] = (1.0, -1.0)
    torque = np.zeros(n)
    torque[[3, 5]] = (0.5, 1.0)
    data = CorrectionData(
        frequencies=w[:2],
        frequency_sigma=1.0,  # rows without gains: zero gain columns
        frf=[
            (3, 3, [20.0, 120.0], [1.0, 1.0], 1.0, 0, None),
            # 0.95 w_4: the flank of resonance 4, as in the test above
            (strain, torque, [100.0, 0.95 * w[3]], [1.0, 1.0], 1.0, 1, 0),
            (strain, 3, [60.0], [1.0], 1.0, 1, None),
            (10, torque, [300.0], [1.0], 1.0, None, 1),
        ],
    )
    assert (data.n_output_gains, data.n_input_gains) == (2, 2)

    def f(y):
        return data.predict(model, y[:3], y[3:6], y[6:8], y[8:10], y[10:])[0]

    _, A = data.predict(model, x[:3], x[3:6], x[6:8], x[8:10], x[10:])
    A_fd = _fourth_order_jacobian(f, x)  # the FRF is linear in each gain: exact to ~1e-13
    scale = np.abs(A_fd).max(axis=1, keepdims=True)
    assert np.all(scale > 0)
    assert np.all(np.abs(A - A_fd) < 1e-6 * scale)
    # linear in the gains: their columns agree to round-off (1.5e-13 seen), far below 1e-6
    assert np.all(np.abs(A - A_fd)[:, 8:] < 1e-10 * scale)
    # each gain column is the FRF over the gain (Eqs. 6-7), zero where the gain is absent
    assert np.all(A[:2, 8:] == 0)
    assert np.all(np.abs(A_fd[:, 8:]).max(axis=0) > 0)


def test_differential_correction_identifies_gauge_and_motor_gains(frame):
    """Columns 2-3 stiffness +15 %, motor constant 0.8 and gauge factors (1.1, 0.95) unknown:
    8 frequencies, 8 damping ratios and 4 x 6 FRF points recover all (Att. 6 Eqs. 6-13).

    Mass held (the absolute scale); noise 0.1 % / 2 % / 1 % as in the stiffness test, 10 seeds.
    """
    model = _damped(frame)
    p_true, mu_true, nu_true = (
        np.array([1.0, 1.0 / 1.15, 1.0]),
        np.array([1.1, 0.95]),
        np.array([0.8]),
    )
    ones = np.ones(3)
    items = _gain_items(model.n_dofs, mu_true, nu_true)
    for seed in range(10):
        data = _frame_data(model, p_true, ones, np.ones(2), np.random.default_rng(seed), items)
        res = differential_correction(model, data, fixed_mass=[0, 1, 2])
        assert res.converged
        sd = np.sqrt(np.diag(res.covariance))
        # predicted SDs: stiffness 0.32 / 0.08 / 0.18 %, gauges 0.29 / 0.33 %, motor 0.24 %:
        # 1 % is >= 3 SD of each
        assert sd.size == 11 and np.all(sd[[0, 1, 2, 8, 9, 10]] < 0.0034)
        for est, true in ((res.p, p_true), (res.mu, mu_true), (res.nu, nu_true)):
            assert np.all(np.abs(est / true - 1) < 0.01)
    # mass free: scaling K, M, C and both gauge factors together leaves every FRF item (all
    # carry a gauge factor) and the free response unchanged
    with pytest.raises(
        ValueError,
        match=r"not identifiable.*p\[0\].*q\[0\].*r\[0\].*mu\[0\]"
        r".*mu\[1\]",
    ) as err:
        differential_correction(model, data)
    assert "nu[0]" not in str(err.value)  # the calibrated hammer fixes the motor relative
    # motor items only: every item carries a gauge factor and the motor constant, so only
    # their products are determined
    motor = CorrectionData(
        frequencies=data.frequencies,
        frequency_sigma=data.frequency_sigma,
        damping_ratios=data.damping_ratios,
        damping_sigma=data.damping_sigma,
        frf=[item for item in data.frf if item[6] is not None],
    )
    with pytest.raises(ValueError, match=r"not identifiable.*mu\[0\].*mu\[1\].*nu\[0\]"):
        differential_correction(model, motor, fixed_mass=[0, 1, 2])
    # a calibrated motor (constant held at its true value) makes them identifiable again
    res = differential_correction(
        model, motor, fixed_mass=[0, 1, 2], nu0=nu_true, fixed_input_gains=[0]
    )
    assert res.converged and np.array_equal(res.nu, nu_true)
    # fewer FRF items: predicted gauge SDs 0.38 / 0.35 %; within 4 of them
    sd = np.sqrt(np.diag(res.covariance))
    assert np.all(sd[8:10] < 0.004) and np.all(np.abs(res.mu - mu_true) < 4 * sd[8:10])


def test_gain_errors(frame):
    model = _damped(frame)
    w, h = [20.0, 30.0], [1e-6 + 1e-7j, 2e-6 + 1e-7j]
    with pytest.raises(FieldError, match=r"frf\[0\].output_gain: must be None or an index in"):
        CorrectionData(frf=[(3, 3, w, h, 1e-8, -1, None)])
    with pytest.raises(FieldError, match=r"frf\[0\].input_gain: must be None or an index in"):
        CorrectionData(frf=[(3, 3, w, h, 1e-8, None, 1.0)])
    # an index beyond the items: a gain no item could share, and a vector of 10**12 gains
    with pytest.raises(FieldError, match=r"frf\[0\].output_gain: .* in \[0, 1\)"):
        CorrectionData(frf=[(3, 3, w, h, 1e-8, 10**12, None)])
    with pytest.raises(
        ValueError,
        match=r"frf\[0\]: must be \(output, input, omegas, values, "
        r"sigma\[, output_gain, input_gain\]\)",
    ):
        CorrectionData(frf=[(3, 3, w, h, 1e-8, 0)])
    data = CorrectionData(frf=[(3, 3, w, h, 1e-8, 0, None), (10, 3, w, h, 1e-8, 1, 0)])
    with pytest.raises(
        ValueError,
        match=r"frf\[1\].output_gain: must be < 1 \(the length of mu\), "
        "got 1",
    ):
        data.predict(model, mu=[1.0])
    with pytest.raises(
        ValueError,
        match=r"mu0: must have 2 entries \(one per output_gain 0..1 of "
        r"data.frf\), got 3",
    ):
        differential_correction(model, data, mu0=[1.0, 1.0, 1.0])
    with pytest.raises(
        ValueError,
        match=r"mu0: must have 0 entries \(data.frf names no "
        r"output_gain\), got 1",
    ):
        differential_correction(model, CorrectionData(frf=[(3, 3, w, h, 1e-8)]), mu0=[1.0])
    with pytest.raises(ValueError, match="nu0: must be > 0"):
        differential_correction(model, data, nu0=[-0.8])
    with pytest.raises(ValueError, match=r"fixed_output_gains: must be gain indices in \[0, 2\)"):
        differential_correction(model, data, fixed_output_gains=[2])
    with pytest.raises(ValueError, match="prior_sigma: must be a scalar or 11 values"):
        differential_correction(model, data, prior_sigma=np.ones(8))
    # gauge 0 wired with the opposite sign: the fit would need mu[0] = -1.1; steps to <= 0 are
    # refused, and the fit, creeping towards 0, says so instead of returning mu[0] ~ 0
    ones = np.ones(3)
    flipped = _frame_data(
        model,
        np.array([1.0, 1.0 / 1.15, 1.0]),
        ones,
        np.ones(2),
        np.random.default_rng(0),
        _gain_items(model.n_dofs, np.array([-1.1, 0.95]), np.array([0.8])),
    )
    with pytest.raises(ValueError, match=r"mu\[0\]: the data want a gain <= 0.*check the sign"):
        differential_correction(model, flipped, fixed_mass=[0, 1, 2])
