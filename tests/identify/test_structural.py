"""Creamer–Junkins substructure identification (Att. 7): undamped (Eqs. 1–9), damping (10–24).

Models (all documented here, built with :mod:`flexsat.structures`):

* ``_frame``: planar two-storey, two-bay portal frame (aluminium tubes, beam2d), clamped bases;
  four substructures: left columns, middle + right columns, first-floor beams, roof beams.
* ``_arm``: our stand-in for the Att. 7 Example 1 manipulator arm (its numbers are not given):
  two flexible appendages (Euler-Bernoulli bending, 1.0 m and 0.8 m aluminium tubes, 4 elements
  each), a soft rotational spring at the base (pinned base), a rotational spring at the joint
  (hinge), and a tip grip with mass 20 kg and inertia 0.5 kg m^2.  Groups as in the paper: mass
  I app. 1, II app. 2, III tip inertia, IV tip mass; stiffness I app. 1, II app. 2, III base
  spring, IV joint spring.
* ``_truss``: stand-in for the Att. 7 Example 2 planar tapered truss (geometry only in Fig. 3):
  10 bays of 1 m, depth tapering 1.0 m -> 0.5 m, cantilevered at the root; 20 upper/lower chord
  beams (group I), 20 X-diagonals (group II), 11 verticals (fixed part, as in the paper);
  ``E`` calibrated so that the first frequency is 6.73 rad/s like the paper's Table 3.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from flexsat.identify.structural import (
    SubstructureModel,
    damped_eigenvalues,
    fit_modal_normalization,
    identify_damping,
    identify_undamped,
    modal_energy_distribution,
    substructures_from_builder,
    update_model,
)
from flexsat.structures import elements as el
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def test_blocks_sum_to_assembly(frame, frame_builder):
    a = frame_builder(np.ones(3), np.ones(3))
    assert np.allclose(frame.K(), a.K.toarray(), rtol=0, atol=1e-6 * abs(a.K).max())
    assert np.allclose(frame.M(), a.M.toarray(), rtol=0, atol=1e-9 * abs(a.M).max())
    assert np.abs(frame.K0).max() == 0.0 and np.abs(frame.M0).max() == 0.0


def test_modal_energy_distribution_sums_to_one(frame):
    w, phi = frame.modes(n_modes=6)
    e = modal_energy_distribution(frame.K_blocks, frame.M_blocks, phi, w)
    assert e["kinetic"].shape == (6, 3) and e["strain"].shape == (6, 3)
    assert np.allclose(e["kinetic"].sum(1), 1.0) and np.allclose(e["strain"].sum(1), 1.0)
    assert np.all(e["kinetic"] >= -1e-12) and np.all(e["strain"] >= -1e-12)
    # mass-normalised modes of the full model: kinetic shares are the raw phi^T M_g phi
    raw = np.array([np.einsum("ij,ik,kj->j", phi, Mg, phi) for Mg in frame.M_blocks]).T
    assert np.allclose(raw, e["kinetic"])


@pytest.mark.parametrize("noise", [0.0, 1e-3])
def test_model_update_recovers_15_percent_stiffness_error(frame, noise):
    """+15 % on one substructure stiffness, 25 frequencies (0.1 % noise: 10 noise draws)."""
    p_true = np.array([1.0, 1.15, 1.0])
    w_true, _ = frame.modes(p_true)
    m = 25
    for seed in range(10 if noise else 1):
        rng = np.random.default_rng(seed)
        w_meas = w_true[:m] * (1.0 + noise * rng.standard_normal(m))
        res = update_model(frame, w_meas, frequency_sigma=noise * w_meas if noise else None)
        p = res.p
        assert res.undamped.converged
        assert abs(p[1] / 1.15 - 1.0) < (1e-8 if noise == 0 else 0.01)
        for k in (0, 2):
            assert abs(p[k] - 1.0) < (1e-8 if noise == 0 else 0.005)
        assert np.allclose(res.q, 1.0)  # no FRF: the mass is the held scale
        if noise:
            sd = np.sqrt(np.diag(res.covariance))[:3]
            assert np.all(sd > 0) and np.all(sd < 0.003)
        w_upd, _ = res.model.modes()  # the scaled model is the identified one
        assert np.allclose(w_upd[:m], res.undamped.frequencies)


# ------------------------------------------------------------------------------------------------
ARM = dict(
    L1=5.0,
    L2=4.0,
    n_el=4,
    E=1.45297e11,
    rho=2700.0,
    k_base=1.0209,
    k_joint=18.2436,
    tip_mass=20.0,
    tip_inertia=0.5,
)  # E, k_base, k_joint tuned to modes 1-3 of Table 2


def _arm():
    """Bending-only arm: pinned base with spring, hinge with spring at the joint, tip grip."""
    a = ARM
    sec = Section.tube(0.05, 0.003)
    bend = [1, 2, 4, 5]
    ne = a["n_el"]
    keys = [("th", 0)] + [(d, i) for i in range(1, ne + 1) for d in ("w", "th")] + [("thb", ne)]
    keys += [(d, i) for i in range(ne + 1, 2 * ne + 1) for d in ("w", "th")]
    idx = {key: i for i, key in enumerate(keys)}
    n = len(keys)
    Kb = [np.zeros((n, n)) for _ in range(4)]
    Mb = [np.zeros((n, n)) for _ in range(4)]
    for e in range(2 * ne):
        g, L = (0, a["L1"] / ne) if e < ne else (1, a["L2"] / ne)
        k = el.beam2d_local_stiffness(a["E"], sec.A, sec.Iz, L)[np.ix_(bend, bend)]
        mm = el.beam2d_local_mass(a["rho"], sec.A, L)[np.ix_(bend, bend)]
        ends = [("w", e), ("thb" if e == ne else "th", e), ("w", e + 1), ("th", e + 1)]
        d = np.array([idx.get(key, -1) for key in ends])
        keep = d >= 0
        Kb[g][np.ix_(d[keep], d[keep])] += k[np.ix_(keep, keep)]
        Mb[g][np.ix_(d[keep], d[keep])] += mm[np.ix_(keep, keep)]
    Kb[2][idx["th", 0], idx["th", 0]] = a["k_base"]
    t = [idx["th", ne], idx["thb", ne]]
    Kb[3][np.ix_(t, t)] = a["k_joint"] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    Mb[2][idx["th", 2 * ne], idx["th", 2 * ne]] = a["tip_inertia"]
    Mb[3][idx["w", 2 * ne], idx["w", 2 * ne]] = a["tip_mass"]
    return SubstructureModel(Kb, Mb, names=("appendage 1", "appendage 2", "III", "IV")), idx


EPS = np.finfo(float).eps


def _eigenvalue_roundoff(K, M, phi):
    """Relative first-order change of each eigenvalue when every entry of K and M is perturbed
    by its own round-off, |dK| <= eps |K|, |dM| <= eps |M|: ``eps (|phi|^T |K| |phi| /
    phi^T K phi + |phi|^T |M| |phi| / phi^T M phi)`` (the componentwise condition number of a
    simple eigenvalue of a symmetric definite pencil).  No float64 solver can resolve an
    eigenvalue more finely than this; for the arm's base-spring mode it is 2e-8, where a
    Cholesky-reduced solve (absolute error ~ eps max(lambda), relative 1e-5) is far coarser.
    """
    a = np.abs(phi)
    kinetic = np.einsum("ij,ij->j", phi, M @ phi)
    strain = np.einsum("ij,ij->j", phi, K @ phi)
    return EPS * (
        np.einsum("ij,ij->j", a, np.abs(K) @ a) / strain
        + np.einsum("ij,ij->j", a, np.abs(M) @ a) / kinetic
    )


def _exact_eigenvalue_enclosure(K, M, X):
    """Guaranteed bounds [lo, hi] on the eigenvalues of the stored pencil (K, M).

    ``X`` holds approximations of all n eigenvectors.  In exact rational arithmetic: Rayleigh
    quotients rho_j and residuals r_j = K x_j - rho_j M x_j, eps_j = ||r_j||_{M^-1} /
    ||x_j||_M.  Each interval rho_j +- eps_j holds an eigenvalue (Weinberger); if the n
    intervals are disjoint each holds exactly one, the j-th.  Kato-Temple with the neighbours'
    interval ends (a, b) then tightens it: rho - eps^2/(b - rho) <= lambda <= rho + eps^2/(rho - a).
    Independent of the solver and of the BLAS kernel (the M^-1 norm needs only a few digits).
    """
    Kq = [[Fraction(v) for v in row] for row in K]
    Mq = [[Fraction(v) for v in row] for row in M]
    rho, eps2 = np.zeros(len(K)), np.zeros(len(K))
    for j in range(len(K)):
        x = [Fraction(v) for v in X[:, j]]
        Kx = [sum(a * b for a, b in zip(row, x)) for row in Kq]
        Mx = [sum(a * b for a, b in zip(row, x)) for row in Mq]
        xMx = sum(a * b for a, b in zip(x, Mx))
        r = sum(a * b for a, b in zip(x, Kx)) / xMx
        res = np.array([float(a - r * b) for a, b in zip(Kx, Mx)])
        rho[j], eps2[j] = float(r), res @ np.linalg.solve(M, res) / float(xMx)
    order = np.argsort(rho)
    rho, eps2 = rho[order], eps2[order]
    e = np.sqrt(eps2)
    assert np.all(rho[1:] - e[1:] > rho[:-1] + e[:-1]), "residual intervals overlap"
    below = np.r_[-np.inf, (rho + e)[:-1]]
    above = np.r_[(rho - e)[1:], np.inf]
    ulp = np.spacing(rho)  # float(Fraction) rounds rho to nearest: widen by one ulp
    return rho - eps2 / (above - rho) - ulp, rho + eps2 / (rho - below) + ulp


def test_arm_subset_modes_match_the_exact_pencil_to_its_conditioning():
    """``modes(n_modes=5)`` and the full solve give the arm's eigenvalues (spanning 5e-4 .. 4e7)
    each to its own round-off (:func:`_eigenvalue_roundoff`), checked against exact bounds."""
    arm, _ = _arm()
    K, M = arm.K(), arm.M()
    w_all, phi_all = arm.modes()
    lo, hi = _exact_eigenvalue_enclosure(K, M, phi_all)
    assert np.all(hi - lo <= 4 * EPS * hi)  # the enclosure is as sharp as float64
    assert hi[-1] / lo[0] > 1e10
    w5, phi5 = arm.modes(n_modes=5)
    floor = _eigenvalue_roundoff(K, M, phi5)
    # the base-spring mode is 1e-3 of the normwise floor eps lambda_max / lambda_1 (1e-5)
    assert floor[0] < 1e-2 * EPS * hi[-1] / lo[0] and floor[0] > 1e3 * EPS
    for lam in (w5**2, w_all[:5] ** 2):
        assert np.all(lam >= lo[:5] * (1 - floor)) and np.all(lam <= hi[:5] * (1 + floor))
    # the same for the shifted-scaled model the identification starts from
    p0, q0 = 0.9 * np.ones(4), 1.1 * np.ones(4)
    w_start, phi_start = arm.modes(p0, q0, n_modes=5)
    lo0, hi0 = _exact_eigenvalue_enclosure(arm.K(p0), arm.M(q0), arm.modes(p0, q0)[1])
    floor0 = _eigenvalue_roundoff(arm.K(p0), arm.M(q0), phi_start)
    assert np.all(w_start**2 >= lo0[:5] * (1 - floor0))
    assert np.all(w_start**2 <= hi0[:5] * (1 + floor0))


def test_example1_arm_recovers_first_five_frequencies():
    arm, _ = _arm()
    w_true, phi = arm.modes(n_modes=5)
    assert np.allclose(w_true[:3], [0.0230, 1.062, 55.44], rtol=1e-3)
    # Table 1 pattern: mode 1 base spring, mode 2 joint spring, modes 3-5 appendages
    e = modal_energy_distribution(arm.K_blocks, arm.M_blocks, phi, w_true)
    assert e["strain"][0, 2] > 0.95 and e["strain"][1, 3] > 0.95
    assert np.all(e["strain"][2:, :2].sum(1) > 0.99) and e["kinetic"][0, 3] > 0.8
    # every frequency below carries the eigen-solve's relative round-off, half the eigenvalue's
    # componentwise floor (2e-8 on mode 1): two solves compared -> the floor itself
    floor = _eigenvalue_roundoff(arm.K(), arm.M(), phi)
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
TRUSS = dict(bays=10, bay=1.0, depth=(1.0, 0.5), E=70e9, rho=2700.0, tube=(0.04, 0.002))


def _truss_builder(fk, fm):
    """Tapered planar truss, cantilevered at x = 0; groups: 0 chords, 1 diagonals; verticals
    fixed."""
    t = TRUSS
    s = Structure("tapered truss")
    sec = Section.tube(*t["tube"])
    nb = t["bays"]
    for i in range(nb + 1):
        x = i * t["bay"]
        d = t["depth"][0] + (t["depth"][1] - t["depth"][0]) * i / nb
        s.add_node(i, (x, 0.0, 0.0))
        s.add_node(100 + i, (x, d, 0.0))
    mat = [Material(E=t["E"] * fk[g], rho=t["rho"] * fm[g]) for g in range(2)]
    for i in range(nb):
        s.add_beam2d(i, i + 1, mat[0], sec)
        s.add_beam2d(100 + i, 100 + i + 1, mat[0], sec)
        s.add_beam2d(i, 100 + i + 1, mat[1], sec)
        s.add_beam2d(100 + i, i + 1, mat[1], sec)
    for i in range(1, nb + 1):
        s.add_beam2d(i, 100 + i, Material(E=t["E"], rho=t["rho"]), sec)
    s.clamp(0)
    s.clamp(100)
    return s.assemble()


def test_example2_damped_truss_table3_pattern():
    truss = substructures_from_builder(_truss_builder, 2, names=("chords", "diagonals"))
    assert np.abs(truss.K0).max() > 0  # verticals: fixed part
    scale = (6.73 / truss.modes(n_modes=1)[0][0]) ** 2  # E calibrated: mode 1 at 6.73 rad/s
    truss = SubstructureModel(
        [scale * K for K in truss.K_blocks],
        truss.M_blocks,
        K0=scale * truss.K0,
        M0=truss.M0,
        names=truss.names,
    )
    K_t, M_t = truss.K(), truss.M()
    a_ext, b_int = 0.175, 1.0e-7  # external (mass-proportional) + internal (stiffness-prop.)
    lam_true = damped_eigenvalues(K_t, M_t, a_ext * M_t + b_int * K_t, n_modes=8)
    assert np.all(np.abs(lam_true.real + 0.09) < 0.01)  # Table 3: real parts ~ -0.09
    rng = np.random.default_rng(3)  # noise model: SD 1 % of each part (Att. 7, L3016)
    lam_meas = lam_true.real * (1 + 0.01 * rng.standard_normal(8)) + 1j * lam_true.imag * (
        1 + 0.01 * rng.standard_normal(8)
    )
    # a-priori model: mass +10 %, stiffness -10 %, damping blocks with the right coupling but
    # magnitudes off by orders of magnitude
    model = SubstructureModel(
        truss.K_blocks,
        truss.M_blocks,
        [50.0 * 1.1 * M_t, 1e-4 * 0.9 * K_t],
        K0=truss.K0,
        M0=truss.M0,
    )
    p0, q0 = 0.9 * np.ones(2), 1.1 * np.ones(2)
    w0, _ = model.modes(p0, q0, n_modes=8)
    assert np.all(w0 < 0.95 * lam_true.imag)  # like Table 3's lambda_0 column
    res = update_model(
        model, lam_meas.imag, lam_meas, p0=p0, q0=q0, frequency_sigma=0.01 * lam_meas.imag
    )
    lam_f = res.damping.eigenvalues
    # identified frequencies within the paper's error (Table 3: up to 2.5 % from measured)
    assert np.all(np.abs(lam_f.imag / lam_true.imag - 1) < 0.025)
    # real parts ~ -0.09, reproducing the measured ones like Table 3's lambda_f column
    assert np.all(np.abs(lam_f.real + 0.09) < 0.012)
    assert np.all(np.abs(lam_f.real / lam_meas.real - 1) < 0.05)
    # first-order theory (Eq. 23) agrees with the exact state-space eigenvalues
    assert np.allclose(res.damping.predicted_real_parts, lam_f.real, rtol=1e-3)
    # without an FRF the identified model is 1.1 x the true (M, K) (mass held at its start
    # scale), so the identified C is 1.1 x the true one: r_ext = 1.1 a / (50 x 1.1)
    assert abs(res.r[0] / (a_ext / 50.0) - 1) < 0.05  # external damping (dominant) recovered


# ------------------------------------------------------------------------------------------------
def test_degenerate_inputs_raise_clear_errors(frame):
    w, _ = frame.modes()
    with pytest.raises(ValueError, match="more parameters than data"):
        identify_undamped(frame, w[:2])
    with pytest.raises(ValueError, match="measured_frequencies: must be finite"):
        identify_undamped(frame, [w[0], np.nan, w[2]])
    with pytest.raises(ValueError, match="measured_frequencies"):
        identify_undamped(frame, [-1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="measured_shapes: must have shape"):
        identify_undamped(frame, w[:4], measured_shapes=np.ones((3, 4)))
    with pytest.raises(ValueError, match="identify_mass"):
        identify_undamped(frame, w[:4], identify_mass=True)
    with pytest.raises(ValueError, match="C_blocks"):
        identify_damping(frame, [-0.1 + 1j])
    damped = SubstructureModel(frame.K_blocks, frame.M_blocks, [frame.M(), frame.K()])
    with pytest.raises(ValueError, match="more parameters than data"):
        identify_damping(damped, [-0.1 + 1j * w[0]])
    with pytest.raises(ValueError, match="no NaN"):
        identify_damping(damped, [np.nan, -0.1])
    with pytest.raises(ValueError, match="real parts must be < 0"):
        identify_damping(damped, [0.1 + 1j, -0.1 + 2j])
    with pytest.raises(ValueError, match=r"K_blocks\[1\]: must be symmetric"):
        SubstructureModel([frame.K_blocks[0], np.triu(frame.K_blocks[1])], frame.M_blocks)
    with pytest.raises(ValueError, match="p: must have 3 entries"):
        frame.K([1.0, 2.0])
    with pytest.raises(ValueError, match="mass scalings: M\\(q\\) is not positive definite"):
        frame.modes(q=[-1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="stiffness scalings: K\\(p\\) is not positive semi-"):
        frame.modes(p=[-1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="n_modes: must be a positive integer"):
        frame.modes(n_modes=0)
    with pytest.raises(ValueError, match="frf"):
        identify_undamped(frame, w[:4], frf=[(0, 0, [1.0], [1.0, 2.0])])


def test_fit_modal_normalization_exact_for_complete_modes(frame):
    w, phi = frame.modes()
    K, M = frame.K(), frame.M()
    wf = np.array([20.0, 100.0, 250.0, 400.0, 600.0, 900.0, 1500.0])
    h = np.array([np.linalg.solve(K - x**2 * M, np.eye(len(K))[3])[5] for x in wf])
    m = 4
    known = (phi[5, m:] * phi[3, m:] / (w[m:][None, :] ** 2 - wf[:, None] ** 2)).sum(1)
    alpha, a1, a2 = fit_modal_normalization(
        (5, 3, wf, h), 2.0 * phi[:, :m], w[:m], known_part=[known]
    )
    assert np.allclose(alpha, 0.25, rtol=1e-6) and abs(a2[0]) < 1e-9 * np.abs(h).max()


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
    arm, idx = _arm()
    w_true, _ = arm.modes(n_modes=5)
    base = idx["th", 0]
    clean = _arm_frf(arm, [(idx["w", 4], base), (idx["w", 8], base)], ARM_FRF_OMEGAS)
    p0, q0 = 0.9 * np.ones(4), 1.1 * np.ones(4)
    # exact data: the error left is the last Gauss-Newton step, below the stopping tolerance
    # tol (quadratic convergence leaves far less), plus the data's own round-off, which is the
    # eigenvalues' componentwise floor (2e-8 on the base-spring mode, far below tol)
    tol = 1e-6
    assert _eigenvalue_roundoff(arm.K(), arm.M(), arm.modes(n_modes=5)[1]).max() < 0.1 * tol
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
    arm, idx = _arm()
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


# ------------------------------------------------------------------------------------------------
# measured eigenvalues are paired with the model modes by frequency, not by position


@pytest.fixture(scope="module")
def proportional(frame):
    """The frame with C = a M + b K (a = 0.3 1/s, b = 2e-4 s) and its first six eigenvalues.

    Proportional damping keeps the undamped modes, so Eq. 24 is exact here: sigma_r =
    -(a + b w_r^2)/2 and the identified r is (a, b) to the eigen-solve's rounding."""
    damped = SubstructureModel(frame.K_blocks, frame.M_blocks, [frame.M(), frame.K()])
    lam = damped_eigenvalues(frame.K(), frame.M(), 0.3 * frame.M() + 2e-4 * frame.K(), n_modes=6)
    return damped, lam


def test_damping_eigenvalues_in_any_order_are_matched_by_frequency(proportional):
    damped, lam = proportional
    ref = identify_damping(damped, lam)
    # exact first-order theory; eigenvalues to ~1e-13 relative -> 1e-9 on r
    np.testing.assert_allclose(ref.r, [0.3, 2e-4], rtol=1e-9)
    np.testing.assert_array_equal(ref.mode_indices, np.arange(6))
    perm = [3, 0, 5, 1, 4, 2]  # modes 3 and 4 are only 3 % apart (348 and 360 rad/s)
    out = identify_damping(damped, lam[perm])
    np.testing.assert_allclose(out.r, ref.r, rtol=1e-12)
    np.testing.assert_array_equal(out.mode_indices, perm)
    np.testing.assert_allclose(out.predicted_real_parts, ref.predicted_real_parts[perm], rtol=1e-12)
    np.testing.assert_allclose(out.eigenvalues, lam[perm], rtol=1e-9)
    # given in that order, the pairing stated by mode_indices is the same
    np.testing.assert_allclose(
        identify_damping(damped, lam[perm], mode_indices=perm).r, ref.r, rtol=1e-12
    )
    # the conjugates carry the same frequencies
    np.testing.assert_allclose(identify_damping(damped, np.conj(lam[perm])).r, ref.r, rtol=1e-12)


def test_damping_eigenvalues_that_do_not_match_the_model_are_refused(proportional):
    damped, lam = proportional
    w, _ = damped.modes()
    with pytest.raises(
        ValueError,
        match=r"^mode_indices: measured_eigenvalues\[0\] \(natural "
        r"frequency 347\.\d+ rad/s\) is nearest model mode 3 "
        r".* but mode_indices pairs it with mode 0",
    ):
        identify_damping(damped, lam[[3, 0, 5, 1, 4, 2]], mode_indices=range(6))
    # a measured mode between two model modes (geometric mean of modes 1 and 2): missing
    between = lam.copy()
    between[1] = -1.0 + 1j * np.sqrt(w[1] * w[2])
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues\[1\]: natural frequency .* has "
        r"no clearly nearest model mode \(modes 1 at .* and 2 at",
    ):
        identify_damping(damped, between)
    twice = lam.copy()
    twice[2] = lam[1] * 1.01
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues\[1\] and \[2\] are both nearest "
        r"model mode 1 ",
    ):
        identify_damping(damped, twice)
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues: give every eigenvalue as sigma "
        r"\+ i w with w != 0",
    ):
        identify_damping(damped, np.append(lam[:3], -1.0 + 0j))
    with pytest.raises(ValueError, match=r"^mode_indices: each model mode at most once"):
        identify_damping(damped, lam, mode_indices=[0, 1, 2, 3, 4, 4])


def test_damping_real_parts_are_paired_in_order(proportional):
    # real parts carry no frequency: the documented pairing is by position (lowest modes)
    damped, lam = proportional
    out = identify_damping(damped, lam.real)
    np.testing.assert_allclose(out.r, [0.3, 2e-4], rtol=1e-9)
    np.testing.assert_array_equal(out.mode_indices, np.arange(6))
