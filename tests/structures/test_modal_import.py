"""What the modal-model readers share (flexsat.structures.modal_import): units, ω, rigid mass."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexsat.input_checks import FieldError
from flexsat.structures.modal_import import (
    eigen_frequencies,
    mass_properties_from_modes,
    rigid_vectors,
    unit_scales,
)

EPS = np.finfo(float).eps
#: 1 lbf = 0.45359237 kg × 9.80665 m/s² (exact by definition, NIST SP 811), 1 in = 0.0254 m
SLINCH_KG = 0.45359237 * 9.80665 / 0.0254


@pytest.mark.parametrize(
    "units, expected",
    [
        (None, (1.0, 1.0, 1.0)),
        ({"length": "mm", "mass": "tonne", "time": "s"}, (1e-3, 1e3, 1.0)),  # NASTRAN mm-t-s
        ({"length": "in", "mass": "lbf*s**2/in", "time": "s"}, (0.0254, SLINCH_KG, 1.0)),
        ({"length": "m", "mass": "kg", "time": "ms"}, (1.0, 1.0, 1e-3)),
    ],
)
def test_unit_scales_of_known_unit_systems(units, expected):
    """Metres, kilograms, seconds per model unit; the values are exact definitions, so only
    the float round-off of pint's products (a few ε) separates them."""
    assert unit_scales(units) == pytest.approx(expected, rel=10 * EPS)


def test_mm_tonne_second_is_consistent_with_the_newton():
    """A consistent system's force unit is mass · length / time²: the newton for mm-t-s."""
    length, mass, time = unit_scales({"length": "mm", "mass": "tonne", "time": "s"})
    assert mass * length / time**2 == pytest.approx(1.0, rel=10 * EPS)


def test_unit_refusals_name_the_field():
    with pytest.raises(FieldError, match="units.*'length', 'mass' and 'time'"):
        unit_scales({"length": "m", "mass": "kg"})
    with pytest.raises(FieldError, match="units\\['mass'\\]"):
        unit_scales({"length": "m", "mass": "s", "time": "s"})


def test_omega_from_eigenvalues_with_rigid_roundoff_set_to_zero():
    """ω = √max(λ, 0) / t_u: rigid roundoff (±1e-9, |ω| ~ 3e-5 rad/s below the 1e-3 threshold)
    becomes exactly 0; λ = 4, 9 give 2, 3 rad/s. In ms model units ω is 1000× larger, the
    roundoff too (0.03 rad/s): it is rigid below a 0.1 rad/s threshold, refused below 0.01."""
    lam = np.array([-1e-9, 1e-9, 4.0, 9.0])
    assert eigen_frequencies(lam, 1.0, 1e-3).tolist() == [0.0, 0.0, 2.0, 3.0]
    assert eigen_frequencies(lam, 1e-3, 0.1) == pytest.approx([0.0, 0.0, 2e3, 3e3], rel=EPS)
    with pytest.raises(FieldError, match="rigid_frequency.*mode 1 "):
        eigen_frequencies(lam, 1e-3, 0.01)


def test_a_large_negative_eigenvalue_is_refused_as_an_unstable_model():
    """λ = −0.25 is |ω| = 0.5 rad/s, far above a 1e-3 rad/s rigid threshold: refused, naming
    the field and the mode."""
    with pytest.raises(FieldError, match="rigid_frequency.*mode 2 .*unstable"):
        eigen_frequencies(np.array([0.0, -0.25, 4.0]), 1.0, 1e-3)


def test_eigenvalues_out_of_order_are_refused():
    with pytest.raises(FieldError, match="rigid_frequency.*not ascending"):
        eigen_frequencies(np.array([0.0, 9.0, 4.0]), 1.0, 1e-3)


def test_rigid_vectors_move_a_node_by_t_plus_theta_cross_r():
    rng = np.random.default_rng(0)
    nodes, ref = rng.normal(size=(3, 3)), rng.normal(size=3)
    t, theta = rng.normal(size=3), rng.normal(size=3)
    u = (rigid_vectors(nodes, ref) @ np.r_[t, theta]).reshape(3, 6)
    assert np.allclose(u[:, :3], t + np.cross(theta, nodes - ref), rtol=0, atol=1e-14)
    assert np.allclose(u[:, 3:], theta, rtol=0, atol=0)


def _lumped_body(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Four nodes with point masses and rotary inertias: coordinates, reference, mass matrix."""
    nodes = rng.normal(size=(4, 3))
    m = rng.uniform(1.0, 5.0, size=4)
    diag = np.concatenate([np.r_[[mi] * 3, rng.uniform(0.1, 0.5, size=3)] for mi in m])
    return nodes, np.array([0.1, -0.2, 0.3]), np.diag(diag)


def _rigid_modes(nodes, ref, M, rng):
    """Six M-orthonormal rigid modes Φ_r = R M_rr^(-1/2) Q (Q a random rotation of the basis)."""
    R = rigid_vectors(nodes, ref)
    Mrr = R.T @ M @ R
    e, V = np.linalg.eigh(Mrr)
    Q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    return R @ (V / np.sqrt(e)) @ V.T @ Q, R, Mrr


def test_rigid_mass_and_participation_from_exact_rigid_modes():
    """With M known, the rigid mass is Rᵀ M R and the participation L = Φᵀ M R (0 for an
    elastic mode): both recovered from the six rigid shapes alone. Tolerance: least squares on
    a 24 × 6 system whose condition (√cond M_rr ~ 30) times ε, with margin."""
    rng = np.random.default_rng(3)
    nodes, ref, M = _lumped_body(rng)
    phi_r, R, Mrr = _rigid_modes(nodes, ref, M, rng)
    elastic = rng.normal(size=(24, 1))
    shapes = np.concatenate([phi_r, elastic], axis=1).T.reshape(7, 4, 6)
    freqs = np.r_[np.zeros(6), 12.0]
    rigid_mass, L, boundary = mass_properties_from_modes(
        freqs, shapes, nodes, ref, None, None, Path("body.uff"), "a universal file"
    )
    assert boundary == "free"
    assert np.allclose(rigid_mass, Mrr, rtol=0, atol=1e-11 * np.abs(Mrr).max())
    assert np.allclose(L[:6], phi_r.T @ M @ R, rtol=0, atol=1e-11 * np.abs(Mrr).max())
    assert np.all(L[6] == 0.0)


def test_rounded_rigid_modes_still_give_l_transpose_l_equal_to_the_rigid_mass():
    """Shapes rounded to 6 significant digits (a UFF): the rigid mass is within the rounding
    (1e-5 relative) and Lᵀ L = M_rr holds to round-off, by construction (module notes)."""
    rng = np.random.default_rng(4)
    nodes, ref, M = _lumped_body(rng)
    phi_r, _, Mrr = _rigid_modes(nodes, ref, M, rng)
    rounded = np.array([float(f"{v:.6g}") for v in phi_r.ravel()]).reshape(phi_r.shape)
    rigid_mass, L, _ = mass_properties_from_modes(
        np.zeros(6), rounded.T.reshape(6, 4, 6), nodes, ref, None, None, Path("b.uff"), "a file"
    )
    scale = np.abs(Mrr).max()
    assert np.allclose(rigid_mass, Mrr, rtol=0, atol=1e-5 * scale)
    assert np.allclose(L.T @ L, rigid_mass, rtol=0, atol=1e-12 * scale)


def test_without_six_rigid_modes_or_with_half_the_mass_data_it_is_refused():
    f = np.r_[0.0, 0.0, 5.0]
    shapes = np.ones((3, 1, 6))
    with pytest.raises(ValueError, match="a universal file has no mass matrix.*found 2"):
        mass_properties_from_modes(
            f, shapes, np.zeros((1, 3)), np.zeros(3), None, None, Path("x.uff"), "a universal file"
        )
    with pytest.raises(ValueError, match="give both or neither"):
        mass_properties_from_modes(
            f, shapes, np.zeros((1, 3)), np.zeros(3), np.eye(6), None, Path("x.uff"), "a file"
        )
