"""The modal coordinates of a flexible three-axis spacecraft (flexsat.sim.spacecraft_modal):
x = T z makes the linear part block-diagonal -- 0 on β0, [[0, 1], [0, 0]] on each rigid pair,
[[0, 1], [−a, −b]] on each elastic pair -- T⁻¹ is its inverse, the rigid rates carry the
body angular momentum (h = J ω_r), and the exponential propagators are those of the blocks.

Tolerances: each product with T or T⁻¹ rounds to cond(T) · eps of its largest entry; the bounds
below are 16 n cond(T) eps of the matrix's norm (n the state size), a bound on a product's
round-off, not a fit.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from flexsat.sim.spacecraft_modal import HEAD, modal_propagators, spacecraft_modal_form

sys.path.insert(0, str(Path(__file__).parents[1] / "testing"))
from test_conformance import _flexible  # noqa: E402  (the conformance suite's small spacecraft)

pytestmark = pytest.mark.numerics

EPS = np.finfo(float).eps


def _plants():
    from flexsat.cases.eps import eps

    return {"coupled": _flexible(), "eps": eps().plant(n_modes=6)}


@pytest.fixture(scope="module", params=["coupled", "eps"])
def spacecraft(request):
    return _plants()[request.param]


def _attitude_part(plant):
    """The linear part on x = [β0, β_v, ω, η, η̇] (a plant without translation)."""
    A, B = plant.linear_part()
    assert A.shape[0] == plant.nx
    return A, B


def test_t_inverse_is_the_inverse_of_t(spacecraft):
    modes = spacecraft_modal_form(
        spacecraft.inertia, spacecraft.coupling, spacecraft.stiffness, spacecraft.damping
    )
    n = modes.T.shape[0]
    bound = 16 * n * np.linalg.cond(modes.T) * EPS
    assert np.abs(modes.T @ modes.T_inv - np.eye(n)).max() <= bound


def test_the_linear_part_is_block_diagonal_in_z(spacecraft):
    """T⁻¹ A T = diag(0, [[0, 1], [−a_k, −b_k]] ...) with (a, b) = ``blocks``: (0, 0) for the
    three rigid pairs, then the elastic pairs."""
    p = spacecraft
    modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
    A, _ = _attitude_part(p)
    Az = modes.T_inv @ A @ modes.T
    want = np.zeros_like(Az)
    for k, (a, b) in enumerate(modes.blocks):
        i = 1 + 2 * k
        want[i, i + 1] = 1.0
        want[i + 1, i], want[i + 1, i + 1] = -a, -b
    assert np.all(modes.blocks[:3] == 0.0)
    scale = np.abs(A).max() * np.linalg.cond(modes.T)
    assert np.abs(Az - want).max() <= 16 * A.shape[0] * scale * EPS


def test_the_rigid_rates_carry_the_angular_momentum(spacecraft):
    """h = J ω + Δᵀ η̇ = J ω_r: the rigid rates of z alone give the body momentum."""
    p = spacecraft
    modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
    x = np.random.default_rng(5).standard_normal(p.nx)
    ne = p.coupling.shape[0]
    w, eta_dot = x[4:7], x[7 + ne : 7 + 2 * ne]
    h = p.inertia @ w + p.coupling.T @ eta_dot
    z = modes.T_inv @ x
    w_r = z[2:HEAD:2]
    bound = 16 * p.nx * np.linalg.cond(modes.T) * EPS * np.abs(p.inertia).max() * np.abs(x).max()
    assert np.abs(p.inertia @ w_r - h).max() <= bound


def test_the_propagators_are_the_exponentials_of_the_blocks(spacecraft):
    """E holds e^{hA} block by block, and P1u = h φ1(hA) B: both read off the exponential of
    the augmented matrix [[hA, hB], [0, 0]] (Van Loan 1978), an independent route. Bound: a few
    ulps of each entry's scale (the 2 × 2 closed forms against scipy's Padé expm)."""
    p = spacecraft
    modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
    n = modes.T.shape[0]
    B = np.random.default_rng(2).standard_normal((n, 3))
    Bf = np.zeros((n, 7))
    h = 0.05
    _, E, _, P1u, _ = modal_propagators(modes.blocks, B, Bf, h, 1)
    for k, (a, b) in enumerate(modes.blocks):
        rows = slice(1 + 2 * k, 3 + 2 * k)
        aug = np.zeros((5, 5))
        aug[:2, :2] = h * np.array([[0.0, 1.0], [-a, -b]])
        aug[:2, 2:] = h * B[rows]
        flow = sla.expm(aug)
        scale = max(1.0, np.abs(flow).max())
        assert np.abs(E[rows] - flow[:2, :2]).max() <= 64 * EPS * scale
        assert np.abs(P1u[rows] - flow[:2, 2:]).max() <= 64 * EPS * scale


def test_an_overdamped_mode_is_refused_by_name():
    from flexsat.input_checks import FieldError

    p = _flexible()
    damping = 2.0 * 3.0 * np.sqrt(p.stiffness)  # ζ = 3
    with pytest.raises(FieldError):
        spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, damping)
