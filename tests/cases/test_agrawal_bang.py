"""Agrawal & Bang L structure with collocated piezo pairs (Agrawal & Bang 1996)."""

import json

import numpy as np
import pytest

import control
from flexsat.cases.agrawal_bang import PUBLISHED, agrawal_bang


@pytest.fixture(scope="module")
def case():
    return agrawal_bang()


def _undamped_zeros(b, w):
    """Zeros (rad/s) of Σ b_k² / (s² + ω_k²): √ of the eigenvalues of PΩ²P on b⊥
    (P = I − bbᵀ/bᵀb)."""
    P = np.eye(b.size) - np.outer(b, b) / (b @ b)
    mu = np.sort(np.linalg.eigvalsh(P @ np.diag(w**2) @ P))[1:]  # drop the zero along b
    return np.sqrt(mu)


def test_geometry_mass_and_mesh(case):
    m = case.modal_model()
    A = case.width * case.thickness
    assert m.total_mass == pytest.approx(
        case.density * A * (case.beam1_length + case.beam2_length), rel=1e-12
    )
    assert m.rigid_mass[0, 0] == pytest.approx(m.rigid_mass[1, 1], rel=1e-12)
    xyz = dict(zip(case.modal_model().node_ids, case.modal_model().coordinates))
    np.testing.assert_allclose(xyz[case.corner_node], [0, case.beam1_length, 0])
    np.testing.assert_allclose(xyz[case.tip_node], [case.beam2_length, case.beam1_length, 0])
    for p in case.piezo_pairs():
        a, b = xyz[p.node_a], xyz[p.node_b]
        assert np.linalg.norm(b - a) == pytest.approx(case.patch_length, rel=1e-12)
    assert case.piezo_pairs()[0].node_a == case.base_node  # pair 1 at the root (L349)


def test_frequencies_converge_with_the_mesh(case):
    f = case.frequencies_hz(3)
    assert f.size == PUBLISHED["n_modes"] and np.all(np.diff(f) > 0)
    finer = agrawal_bang(element_length="0.0125 m")
    np.testing.assert_allclose(finer.frequencies_hz(3), f, rtol=1e-6)


def test_collocated_pairs(case):
    """B = Cᵀ up to the positive gain ratio a_1 L_p / (a_2 t/2), pair by pair."""
    n = 6
    sys = case.to_statespace(n)
    assert (sys.nstates, sys.ninputs, sys.noutputs) == (2 * n, 3, 3)
    ratio = case.patch_length / (case.thickness / 2)
    for j, p in enumerate(case.piezo_pairs(n)):
        assert p.ratio == pytest.approx(ratio, rel=1e-14)
        np.testing.assert_allclose(sys.B[n:, j], ratio * sys.C[j, :n], rtol=1e-13)
        assert np.all(sys.B[:n, j] == 0) and np.all(sys.C[j, n:] == 0)
    g = agrawal_bang(actuator_gain=2e-3, sensor_gain=150.0)
    for p, q in zip(g.piezo_pairs(n), case.piezo_pairs(n)):
        np.testing.assert_allclose(p.actuator, 2e-3 * q.actuator, rtol=1e-13)
        np.testing.assert_allclose(p.sensor, 150.0 * q.sensor, rtol=1e-13)
        assert p.ratio == pytest.approx(2e-3 / 150.0 * ratio, rel=1e-14)


@pytest.mark.parametrize("n", [3, 8])
def test_collocated_poles_and_zeros_interlace(case, n):
    """Undamped collocated SISO transfer functions: ω_1 < z_1 < ω_2 < z_2 < … < ω_n."""
    w = case.modal_model(n).frequencies
    for p in case.piezo_pairs(n):
        z = _undamped_zeros(p.actuator, w)
        assert z.size == n - 1
        assert np.all(w[:-1] < z) and np.all(z < w[1:])
        # the same zeros from python-control's transmission zeros
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), np.zeros((n, n))]])
        sys = control.ss(
            A, np.r_[np.zeros(n), p.actuator][:, None], np.r_[p.sensor, np.zeros(n)][None, :], 0
        )
        tz = np.sort(np.abs(control.zeros(sys).imag))[::2]
        np.testing.assert_allclose(tz, z, rtol=1e-6)


def test_collocated_system_is_positive_real(case):
    """With damping, the rate-output MIMO transfer jω G(jω) has a positive semi-definite
    Hermitian part at every frequency (passivity of collocated pairs)."""
    sys = case.to_statespace(6)
    for om in np.logspace(-1, 4, 60):
        H = 1j * om * sys(1j * om)
        assert np.linalg.eigvalsh((H + H.conj().T) / 2).min() >= -1e-12 * np.abs(H).max()


def test_tip_outputs_and_weight(case):
    """Eq. 33: Eᵗ = (y_1ᵗ, −l_2 α − y_2ᵗ) is the tip displacement of structure 2 (small
    deflection, axially stiff strips); Eq. 35: ζᵀQ̄ζ expands to the published integrand."""
    m = case.modal_model(3)
    Z = case.tip_outputs(3)
    y1, alpha, y2, beta = Z
    l2 = case.beam2_length
    np.testing.assert_allclose(y1, m.displacement_output(case.tip_node, "x"), rtol=1e-4)
    np.testing.assert_allclose(
        -l2 * alpha - y2, m.displacement_output(case.tip_node, "y"), atol=1e-4 * np.abs(Z).max()
    )
    np.testing.assert_allclose(alpha + beta, -m.rotation_output(case.tip_node, "z"), rtol=1e-14)
    zeta = np.random.default_rng(1).standard_normal(4)
    w1, w2 = 500.0, 100.0
    Q = case.tip_weight(w1, w2)
    y1, a, y2, b = zeta
    assert zeta @ Q @ zeta == pytest.approx(
        y1**2 + w1 * (l2 * a + y2) ** 2 + w2 * (a + b) ** 2, rel=1e-13
    )


def test_case_protocol(case):
    assert len(case.mode_descriptions(3)) == 3
    assert "structure 1" in case.mode_descriptions(1)[0]
    details = case.mode_details(3)
    json.dumps(details)
    assert [p["structure"] for p in details["patches"]] == [1, 2, 2]


def test_overrides_and_bad_input():
    c = agrawal_bang(beam2_length="60 cm", patches=[(1, 0), (1, "0.5 m"), (2, "10 cm")])
    assert c.beam2_length == pytest.approx(0.6)
    assert [p.beam for p in c.piezo_pairs()] == [1, 1, 2]
    assert c.piezo_pairs()[2].start == pytest.approx(0.1)
    with pytest.raises(ValueError, match=r"^agrawal_bang: unknown parameter\(s\) \['thicknes'\]"):
        agrawal_bang(thicknes=1e-3)
    with pytest.raises(ValueError, match=r"^thickness: must be > 0"):
        agrawal_bang(thickness="-1 mm")
    with pytest.raises(ValueError, match=r"^modulus: incompatible units"):
        agrawal_bang(modulus="70 kg")
    with pytest.raises(ValueError, match=r"^patches\[2\]: the patch .* runs past the end"):
        agrawal_bang(patches=[(1, 0), (2, 0), (2, "0.79 m")])
    with pytest.raises(ValueError, match=r"^patches\[1\]: structure must be 1 or 2"):
        agrawal_bang(patches=[(1, 0), (3, 0), (2, 0)])
    with pytest.raises(ValueError, match=r"^patches\[2\]: overlaps patches\[1\]"):
        agrawal_bang(patches=[(1, 0), (2, 0), (2, "0.02 m")])
    with pytest.raises(ValueError, match=r"^patches: must be three"):
        agrawal_bang(patches=[(1, 0)])
    with pytest.raises(ValueError, match=r"^element_length: must not exceed"):
        agrawal_bang(element_length="2 m")
    with pytest.raises(ValueError, match=r"^damping: must be < 1"):
        agrawal_bang(damping=2)
    with pytest.raises(ValueError, match=r"^n_modes: the finite-element model has"):
        agrawal_bang().modal_model(10_000)


# -- the plant protocol (issue #10) ---------------------------------------------------------------
def test_plant_channels_are_the_piezo_pairs(case):
    """Modal plant: inputs u1-u3 (moment pairs a₁V, Eq. 36) and outputs y1-y3 (a₂ × strain,
    Eq. 37) are piezo_pairs' vectors, so the plant is to_statespace's model exactly; rates
    y_j_dot read η̇; the modes are exposed as 2×2 blocks."""
    plant, sys = case.plant(), case.to_statespace()
    A, B = plant.linear_part()
    np.testing.assert_array_equal(A, sys.A)
    np.testing.assert_array_equal(B, sys.B)
    rows = np.vstack([plant.output_matrices(f"y{j}")[0] for j in (1, 2, 3)])
    np.testing.assert_array_equal(rows, sys.C)
    m = case.modal_model().n_modes
    np.testing.assert_array_equal(plant.output_matrices("y2_dot")[0][0, m:], sys.C[1, :m])
    assert [(c.name, c.unit) for c in plant.inputs] == [("u1", "V"), ("u2", "V"), ("u3", "V")]
    blocks = plant.modal_blocks
    np.testing.assert_array_equal(blocks.frequencies, case.modal_model().frequencies)
    np.testing.assert_allclose(blocks.damping, case.damping, rtol=1e-15)


def test_fe_plant_moment_pairs_project_to_the_modal_ones(case):
    """The finite-element plant's pair j is the load vector ±a₁ on the patch-end rz dofs (pair 1
    has its root end on the clamped base: only +a₁ at the other end, seed 004 L349); projected on
    the mass-normalised FE modes it is the modal plant's input, and the sensors likewise (same
    vectors, to summation order: 1e-12 relative). Its lowest frequencies are the modal model's
    to eps·λ_max/λ_1 of the dense generalized eigenproblem (~2e-6)."""
    fe, modal = case.plant(coordinates="fe"), case.plant()
    asm, pairs = case.fe_modes.assembly, case.piezo_pairs()
    assert pairs[0].node_a == case.base_node
    f = fe.model.B[:, 0]
    assert np.count_nonzero(f) == 1 and f[asm.index(pairs[0].node_b, "rz")] == case.actuator_gain
    Phi = case.fe_modes.shapes[:, : case.n_modes]
    for j in range(3):
        ref = modal.model.B[:, j]
        np.testing.assert_allclose(
            Phi.T @ fe.model.B[:, j], ref, rtol=0, atol=1e-12 * np.abs(ref).max()
        )
        np.testing.assert_allclose(
            Phi.T @ fe.model.Cq[j],
            modal.model.Cq[j],
            rtol=0,
            atol=1e-12 * np.abs(modal.model.Cq[j]).max(),
        )
    w = fe.model.frequencies()
    np.testing.assert_allclose(w[:3], case.modal_model().frequencies, rtol=2e-6)
    with pytest.raises(ValueError, match=r"^coordinates: must be 'modal' or 'fe'"):
        case.plant(coordinates="ritz")
    with pytest.raises(ValueError, match=r"^n_modes: the finite-element plant keeps"):
        case.plant(3, coordinates="fe")
