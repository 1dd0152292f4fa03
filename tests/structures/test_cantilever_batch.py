"""Tests of the batched tip-loaded cantilever modes (flexsat.structures.beam.cantilever_modes_batch)
against the scalar solver of the same module (grid scan, Wittrick–Williams count, brentq).

Tolerances: both solvers stop at a bracket of 4 eps relative on the same bounded determinant, so
their roots agree to a few ulps (asserted at 1e-12 relative, the issue's bound); the mode
coefficients are null vectors of a 4×4 matrix whose smallest singular values are separated by
O(1), so they follow the roots to ~cond × eps (1e-12 of the largest coefficient).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.structures.beam import CantileverModesBatch, TipMassCantilever, cantilever_modes_batch

L, EI, RHO = 1.156, 1.06, 0.1312


def _cases(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    tip_mass = rng.uniform(0.0, 3.0, n) * RHO * L
    tip_inertia = rng.uniform(0.0, 0.05, n) * RHO * L**3
    tip_mass[:3] = 0.0
    tip_inertia[::4] = 0.0
    return {
        "length": L * rng.uniform(0.8, 1.2, n),
        "EI": EI * rng.uniform(0.5, 1.5, n),
        "rho": RHO,
        "tip_mass": tip_mass,
        "tip_inertia": tip_inertia,
    }


def test_each_case_equals_the_scalar_modes():
    cases = _cases(40)
    batch = cantilever_modes_batch(**cases, k=12)
    assert isinstance(batch, CantileverModesBatch)
    for c in range(40):
        one = TipMassCantilever(
            cases["length"][c], cases["EI"][c], RHO, cases["tip_mass"][c], cases["tip_inertia"][c]
        ).modes(12)
        np.testing.assert_allclose(batch.betas[c], one.betas, rtol=1e-12, atol=0)
        np.testing.assert_allclose(batch.omegas[c], one.omegas, rtol=1e-12, atol=0)
        scale = np.abs(one.coefficients).max()
        np.testing.assert_allclose(
            batch.coefficients[c], one.coefficients, rtol=0, atol=1e-12 * scale
        )
        s = np.linspace(0.0, 1.0, 9)
        for j in (0, 1):
            ref = one.evaluate(s * cases["length"][c], j).T
            got = batch.evaluate(s, j)[c]
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-11 * np.abs(ref).max())


def test_a_case_has_the_same_bits_in_any_batch():
    cases = _cases(30, seed=1)
    full = cantilever_modes_batch(**cases, k=8)
    for lo, hi in ((0, 1), (11, 12), (5, 12), (0, 30)):
        part = cantilever_modes_batch(
            **{f: v[lo:hi] if np.ndim(v) else v for f, v in cases.items()}, k=8
        )
        assert np.array_equal(part.betas, full.betas[lo:hi])
        assert np.array_equal(part.coefficients, full.coefficients[lo:hi])


def test_extreme_tip_bodies():
    """μ = 10⁶ puts β₁L ≈ (3/μ)^(1/4) ≈ 0.042 near the start of the scan, μ = 10¹³ below it
    (7.4e-4 < 10⁻³: that case is left to the scalar scan); ι = 10³ makes the upper roots
    nearly those of a clamped–clamped beam: every root matches the scalar solver."""
    tips = [(1e6, 0.0), (1e13, 0.0), (0.5, 1e3), (1e-3, 0.0)]
    batch = cantilever_modes_batch(1.0, 1.0, 1.0, *zip(*tips), k=5)
    assert batch.betas[1, 0] < 1e-3
    for c, (m, J) in enumerate(tips):
        np.testing.assert_allclose(
            batch.betas[c], TipMassCantilever(1.0, 1.0, 1.0, m, J).betas(5), rtol=1e-12
        )


@pytest.mark.parametrize(
    ("field", "value"),
    [("EI", -1.0), ("length", 0.0), ("tip_mass", -0.1), ("rho", np.nan), ("tip_inertia", np.inf)],
)
def test_bad_values_are_refused_by_name(field, value):
    cases = {"length": 1.0, "EI": 1.0, "rho": 1.0, "tip_mass": 0.1, "tip_inertia": 0.0}
    cases[field] = [1.0, value] if field != "tip_mass" else [0.1, value]
    with pytest.raises(ValueError, match=field):
        cantilever_modes_batch(**cases, k=3)
