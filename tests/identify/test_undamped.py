"""Undamped identification (:mod:`flexsat.identify.structural.undamped`, Att. 7 Eqs. 1-9)
on the Example 1 arm of tests/att7_arm.py: frequencies alone, with FRFs, with a mass prior."""

from __future__ import annotations

import numpy as np
import pytest

from att7_arm import arm_model, eigenvalue_roundoff
from flexsat.identify.structural import (
    identify_undamped,
    modal_energy_distribution,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def test_example1_arm_recovers_first_five_frequencies():
    arm, _ = arm_model()
    w_true, phi = arm.modes(n_modes=5)
    assert np.allclose(w_true[:3], [0.0230, 1.062, 55.44], rtol=1e-3)
    # Table 1 pattern: mode 1 base spring, mode 2 joint spring, modes 3-5 appendages
    e = modal_energy_distribution(arm.K_blocks, arm.M_blocks, phi, w_true)
    assert e["strain"][0, 2] > 0.95 and e["strain"][1, 3] > 0.95
    assert np.all(e["strain"][2:, :2].sum(1) > 0.99) and e["kinetic"][0, 3] > 0.8
    # every frequency below carries the eigen-solve's relative round-off, half the eigenvalue's
    # componentwise floor (2e-8 on mode 1): two solves compared -> the floor itself
    floor = eigenvalue_roundoff(arm.K(), arm.M(), phi)
    p0, q0 = 0.9 * np.ones(4), 1.1 * np.ones(4)
    w_start, _ = arm.modes(p0, q0, n_modes=5)
    assert np.all(np.abs(w_start / w_true / np.sqrt(0.9 / 1.1) - 1) <= floor)
    # no FRF: the (wrong) mass is the held scale; stiffness 4 groups from 5 frequencies
    res = identify_undamped(arm, w_true, p0=p0, q0=q0)
    paper_err = np.abs(
        np.array([0.0230, 1.066, 55.55, 91.19, 156.98]) / [0.0230, 1.062, 55.44, 91.12, 156.75] - 1
    )
    err = np.abs(res.frequencies / w_true - 1)
    assert np.all(err <= np.maximum(paper_err, floor))
    # the stiffness scalings solve for the eigenvalues: each identified p then carries the
    # eigenvalues' round-off (data and model, 2 x floor) over the group's strain share (> 0.95
    # for the springs, the lowest share among the 4 groups' dominant modes)
    assert np.allclose(res.p, 1.1, rtol=2 * floor.max() / 0.95, atol=0)  # K = 1.1 K_true


# ------------------------------------------------------------------------------------------------
def _arm_frf(arm, pairs, omegas):
    """Receptance elements of the true arm, direct solve of (K - w^2 M) x = e_k."""
    K, M = arm.K(), arm.M()
    eye = np.eye(arm.n_dofs)
    return [
        (j, k, omegas, np.array([np.linalg.solve(K - w**2 * M, eye[k])[j] for w in omegas]))
        for j, k in pairs
    ]


# FRF points away from the resonances of both the true arm (0.023, 1.06, 55.4, 95.7, 207 rad/s)
# and the start model (x 0.905), below mode 6 (261 rad/s)
ARM_FRF_OMEGAS = np.array([0.3, 0.6, 3.0, 10.0, 30.0, 70.0, 120.0])


def test_example1_arm_frf_identifies_mass_and_stiffness():
    """Att. 7 Example 1 with the FRF: mass x 1.1 and stiffness x 0.9 both recovered (Eqs. 5-9).

    Data: the first 5 frequencies and the receptances joint and tip transverse displacement per
    unit base torque (the paper's element plus one), model-predicted shapes.
    """
    arm, idx = arm_model()
    w_true, _ = arm.modes(n_modes=5)
    base = idx["th", 0]
    clean = _arm_frf(arm, [(idx["w", 4], base), (idx["w", 8], base)], ARM_FRF_OMEGAS)
    p0, q0 = 0.9 * np.ones(4), 1.1 * np.ones(4)
    # exact data: the error left is the last Gauss-Newton step, below the stopping tolerance
    # tol (quadratic convergence leaves far less), plus the data's own round-off, which is the
    # eigenvalues' componentwise floor (2e-8 on the base-spring mode, far below tol)
    tol = 1e-6
    assert eigenvalue_roundoff(arm.K(), arm.M(), arm.modes(n_modes=5)[1]).max() < 0.1 * tol
    res = identify_undamped(
        arm, w_true, frf=clean, p0=p0, q0=q0, tol=tol, frequency_sigma=1e-3 * w_true, frf_sigma=5e-3
    )
    assert res.converged
    assert np.abs(res.p - 1).max() < tol and np.abs(res.q - 1).max() < tol
    assert np.allclose(res.alpha, 1.0, rtol=0, atol=tol)  # model shapes: alpha = 1 at the solution
    # measured shapes at 3x the mass-normalised scale: Eq. 4 alpha = 1/9, same scalings
    _, phi = arm.modes(n_modes=5)
    shaped = identify_undamped(
        arm, w_true, measured_shapes=3.0 * phi, frf=clean, p0=p0, q0=q0, tol=tol
    )
    assert shaped.converged and np.allclose(shaped.alpha, 1 / 9, rtol=tol, atol=0)
    assert np.abs(shaped.p - 1).max() < tol and np.abs(shaped.q - 1).max() < tol
    sd_two = np.sqrt(np.diag(res.covariance))
    # the paper's single element sees the tip inertia (mass III) mainly through the shapes:
    # exact again, but its predicted SD is 3x worse than with the second element
    one = identify_undamped(
        arm,
        w_true,
        frf=clean[:1],
        p0=p0,
        q0=q0,
        tol=tol,
        frequency_sigma=1e-3 * w_true,
        frf_sigma=5e-3,
    )
    assert np.abs(one.p - 1).max() < tol and np.abs(one.q - 1).max() < tol
    sd_one = np.sqrt(np.diag(one.covariance))
    assert sd_one[6] > 2.5 * sd_two[6]
    # noise: 0.1 % on the frequencies, 0.5 % on the FRF values, 40 seeds
    est, sds = [], []
    for seed in range(40):
        rng = np.random.default_rng(seed)
        w_meas = w_true * (1 + 1e-3 * rng.standard_normal(5))
        frf = [(j, k, w, h * (1 + 5e-3 * rng.standard_normal(h.size))) for j, k, w, h in clean]
        r = identify_undamped(
            arm,
            w_meas,
            frf=frf,
            p0=p0,
            q0=q0,
            tol=1e-6,
            frequency_sigma=1e-3 * w_meas,
            frf_sigma=5e-3,
        )
        assert r.converged
        est.append(np.r_[r.p, r.q])
        sds.append(np.sqrt(np.diag(r.covariance)))
    err, sds = np.array(est) - 1.0, np.array(sds)
    # predicted SDs: < 1.2 % for every group except the tip inertia (< 3 %)
    assert np.all(np.delete(sds, 6, axis=1) < 0.012) and np.all(sds[:, 6] < 0.03)
    # every estimate within 4 predicted SDs (a 6e-5 two-sided tail per estimate), so within
    # 5 % of the truth except the tip inertia (12 %)
    assert np.all(np.abs(err) < 4 * sds)
    # covariance consistent with the scatter: with 40 seeds the sample SD is within +-25 % of
    # the true one (2.5 sigma of its ~11 % sampling error); allow a factor 1.5 beyond that for
    # the linearisation
    ratio = err.std(axis=0) / np.median(sds, axis=0)
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio


def test_mass_prior_regularises_toward_start():
    """Tikhonov rows (Att. 6 ``0_p``): the prior bounds the mass SD and pulls toward q0."""
    arm, idx = arm_model()
    w_true, _ = arm.modes(n_modes=5)
    frf = _arm_frf(arm, [(idx["w", 4], idx["th", 0])], ARM_FRF_OMEGAS)
    tol = 1e-6  # the stopping tolerance bounds the exact-data error (see the test above)
    kw = dict(frf=frf, tol=tol, frequency_sigma=1e-3 * w_true, frf_sigma=5e-3)
    free = identify_undamped(arm, w_true, p0=0.9 * np.ones(4), **kw)
    # prior consistent with the truth (q0 = 1, SD 2 %): still exact, tip-inertia SD below the
    # prior's and below the unregularised one
    reg = identify_undamped(arm, w_true, p0=0.9 * np.ones(4), mass_prior_sigma=0.02, **kw)
    assert np.abs(reg.p - 1).max() < tol and np.abs(reg.q - 1).max() < tol
    sd_free, sd_reg = np.sqrt(np.diag(free.covariance)), np.sqrt(np.diag(reg.covariance))
    assert sd_reg[6] < 0.02 and sd_reg[6] < 0.5 * sd_free[6]
    # a prior far tighter than the data (1e-6) holds the wrong start mass x 1.1: the frequencies
    # then fix only the K/M ratio, so the stiffness comes out x 1.1 as well
    held = identify_undamped(
        arm, w_true, p0=0.9 * np.ones(4), q0=1.1 * np.ones(4), mass_prior_sigma=1e-6, **kw
    )
    assert np.allclose(held.q, 1.1, rtol=1e-4) and np.allclose(held.p, 1.1, rtol=1e-3)
    with pytest.raises(ValueError, match="mass_prior_sigma: needs frf_sigma"):
        identify_undamped(arm, w_true, frf=frf, mass_prior_sigma=0.02)
    with pytest.raises(ValueError, match="frf_sigma: must be a scalar > 0"):
        identify_undamped(arm, w_true, frf=frf, frf_sigma=-1.0)
