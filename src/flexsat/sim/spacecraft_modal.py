r"""Modal coordinates of a flexible three-axis spacecraft's linear part, and the fourth-order
exponential propagators in them (the flexible loop of :mod:`flexsat.sim.kernels_attitude`).

The linear part of :class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`
(its linearisation about rest, without translation) is, in x = [β0, β_v, ω, η, η̇],

.. math::

    \dot\beta_0 = 0, \quad 2\dot\beta_v = \omega, \quad
    \mathcal M \begin{bmatrix}\dot\omega\\ \ddot\eta\end{bmatrix} =
    \begin{bmatrix}0\\ -C\dot\eta - K\eta\end{bmatrix}, \quad
    \mathcal M = \begin{bmatrix}J & \Delta^T\\ \Delta & I\end{bmatrix}

(:mod:`flexsat.dynamics.flexible_spacecraft`). With G = J⁻¹Δᵀ the rigid rotation
θ_r = 2β_v + G η and its rate ω_r = ω + G η̇ decouple from the elastic motion: the first row
gives J ω̇_r = J ω̇ + Δᵀ η̈ = 0, and eliminating ω̇ from the second leaves

.. math::

    M_e \ddot\eta + C\dot\eta + K\eta = 0, \qquad M_e = I - \Delta J^{-1}\Delta^T

(the constrained elastic modes; M_e is the Schur complement of J in the positive definite
𝓜). So z = [β0, (θ_r1, ω_r1), (θ_r2, ω_r2), (θ_r3, ω_r3), elastic pairs] makes the linear
part block-diagonal: 0 on β0, [[0, 1], [0, 0]] on each rigid pair and [[0, 1], [−a, −b]] on
each elastic pair. The elastic pairs come from the undamped modes of (K, M_e) (Cholesky
M_e = L Lᵀ, then ``eigh`` of L⁻¹ K L⁻ᵀ, which keeps repeated frequencies, the EPS's symmetric
antenna, orthogonal): with damping diagonal in those modes each mode is its own pair
(q_i, q̇_i), a = ω_i², b = the modal damping; otherwise (non-proportional damping, from a
coupling Δ ≠ 0) each complex pair of eigenvalues of the balanced first-order form gives one
pair, as in :func:`flexsat.sim.integrators.modal_coordinates`. Also, h = J ω + Δᵀ η̇ = J ω_r:
the body angular momentum is read off the rigid rates alone.

The exponential Runge-Kutta scheme is invariant under the change of coordinates x = T z
(φ(T⁻¹AT) = T⁻¹ φ(A) T), so Krogstad's scheme run in z equals the scheme of
:class:`~flexsat.sim.integrators.ExpRK4Stepper` in x up to round-off, of order
cond(T) · eps per step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.linalg import expm, solve_triangular

from flexsat.input_checks import FieldError

__all__ = ["HEAD", "SpacecraftModes", "modal_propagators", "spacecraft_modal_form"]

#: off-diagonal modal damping below this fraction of the largest entry (a few ulps) is the
#: round-off of a diagonal one: each mode is then its own pair
PROPORTIONAL = 64 * np.finfo(float).eps
#: rigid rows of z: β0, then the three pairs (θ_r, ω_r) (the rows the attitude's force
#: columns reach)
HEAD = 7


class SpacecraftModes(NamedTuple):
    """x = T z, z = T_inv x (module docstring); blocks (n_blocks, 2) the (a, b) of each pair
    [[0, 1], [−a, −b]] after β0: three rigid (0, 0), then the elastic ones; elastic_energy
    the energy's quadratic form on the elastic coordinates z_e = z[HEAD:]: a vector d (2 n_e,)
    when it is diagonal (each mode its own pair: d = (ω_1², 1, ω_2², 1, ...)), else the
    matrix Q_e (2 n_e, 2 n_e). The energy T + V = ½[ω; η̇]ᵀ𝓜[ω; η̇] + ½ηᵀKη is then
    ½ ω_rᵀ J ω_r + ½ z_eᵀ Q_e z_e (module docstring: ½ η̇ᵀ M_e η̇ + ½ ηᵀ K η in the elastic
    pairs; SᵀM_e S = I, SᵀK S = diag(ω²) for the undamped modes S)."""

    T: np.ndarray
    T_inv: np.ndarray
    blocks: np.ndarray
    elastic_energy: np.ndarray


def _elastic(Me: np.ndarray, K: np.ndarray, C: np.ndarray):
    """(Te, Te_inv, a, b, energy) with [η; η̇] = Te z_e for M_e η̈ + C η̇ + K η = 0 (module
    docstring), energy the ``elastic_energy`` of :class:`SpacecraftModes`; K, C diagonal
    (vectors)."""
    ne = K.size
    L = np.linalg.cholesky(Me)
    Li = solve_triangular(L, np.eye(ne), lower=True)
    Kt = (Li * K) @ Li.T
    lam, Phi = np.linalg.eigh(0.5 * (Kt + Kt.T))
    if lam.min() <= 0:
        raise FieldError("stiffness", "an elastic mode without stiffness (K must be positive)")
    S = Li.T @ Phi  # η = S q
    Sinv = Phi.T @ L.T
    Ct = (S.T * C) @ S
    off = Ct - np.diag(np.diag(Ct))
    if np.abs(off).max(initial=0.0) <= PROPORTIONAL * np.abs(Ct).max(initial=1.0):
        Te, Te_inv = np.zeros((2 * ne, 2 * ne)), np.zeros((2 * ne, 2 * ne))
        Te[:ne, 0::2], Te[ne:, 1::2] = S, S
        Te_inv[0::2, :ne], Te_inv[1::2, ne:] = Sinv, Sinv
        energy = np.ones(2 * ne)
        energy[0::2] = lam
        return Te, Te_inv, lam, np.diag(Ct).copy(), energy
    # non-proportional damping: the complex pairs of the balanced form x̃ = [√λ q; q̇]
    s = np.sqrt(lam)
    At = np.zeros((2 * ne, 2 * ne))
    At[:ne, ne:] = np.diag(s)
    At[ne:, :ne] = -np.diag(s)
    At[ne:, ne:] = -0.5 * (Ct + Ct.T)
    mu, V = np.linalg.eig(At)
    if np.any(np.abs(mu.imag) <= 1e-12 * np.abs(mu)):
        raise FieldError("damping", "an overdamped elastic mode (a real eigenvalue)")
    Tt = np.zeros((2 * ne, 2 * ne))
    a, b = [], []
    upper = np.flatnonzero(mu.imag > 0)
    for col, i in enumerate(upper[np.argsort(np.abs(mu[upper]))]):
        lm, v = mu[i], V[:, i]
        pos = v[:ne]
        v = v * np.exp(-0.5j * np.angle(np.sum(pos**2))) / np.linalg.norm(pos)
        ai, bi = abs(lm) ** 2, -2.0 * lm.real
        v2 = (-1j * v / lm.imag).real
        Tt[:, 2 * col] = At @ v2 + bi * v2
        Tt[:, 2 * col + 1] = v2
        a.append(ai)
        b.append(bi)
    Sx = np.zeros((2 * ne, 2 * ne))  # [η; η̇] = Sx x̃
    Sx[:ne, :ne], Sx[ne:, ne:] = S / s, S
    Sx_inv = np.zeros((2 * ne, 2 * ne))
    Sx_inv[:ne, :ne], Sx_inv[ne:, ne:] = Sinv * s[:, None], Sinv
    Te = Sx @ Tt
    Q = np.zeros((2 * ne, 2 * ne))
    Q[:ne, :ne], Q[ne:, ne:] = np.diag(K), Me
    energy = Te.T @ Q @ Te
    return Te, np.linalg.solve(Tt, Sx_inv), np.array(a), np.array(b), 0.5 * (energy + energy.T)


def spacecraft_modal_form(
    inertia: np.ndarray, coupling: np.ndarray, stiffness: np.ndarray, damping: np.ndarray
) -> SpacecraftModes:
    """The modal coordinates of the module docstring of a spacecraft with inertia J (3, 3),
    coupling Δ (n, 3), modal stiffness Ω² (n,) and damping 2ζΩ (n,) (the attributes
    ``inertia``, ``coupling``, ``stiffness``, ``damping`` of a
    :class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`).

    Raises
    ------
    FieldError
        An overdamped elastic mode (its pair is real; the dense path takes the run).
    """
    J = np.asarray(inertia, float)
    Delta = np.asarray(coupling, float)
    ne = Delta.shape[0]
    G = np.linalg.solve(J, Delta.T)  # J⁻¹ Δᵀ (3, ne)
    Me = np.eye(ne) - Delta @ G
    Me = 0.5 * (Me + Me.T)
    Te, Te_inv, a, b, energy = _elastic(Me, np.asarray(stiffness), np.asarray(damping))
    n = HEAD + 2 * ne
    T, Ti = np.zeros((n, n)), np.zeros((n, n))
    T[0, 0] = Ti[0, 0] = 1.0
    for i in range(3):
        T[1 + i, 1 + 2 * i] = 0.5  # β_v = (θ_r − G η) / 2
        T[4 + i, 2 + 2 * i] = 1.0  # ω = ω_r − G η̇
        Ti[1 + 2 * i, 1 + i] = 2.0  # θ_r = 2 β_v + G η
        Ti[2 + 2 * i, 4 + i] = 1.0  # ω_r = ω + G η̇
    T[1:4, HEAD:] = -0.5 * G @ Te[:ne]
    T[4:7, HEAD:] = -G @ Te[ne:]
    T[HEAD:, HEAD:] = Te
    Ti[1:7:2, HEAD : HEAD + ne] = G
    Ti[2:7:2, HEAD + ne :] = G
    Ti[HEAD:, HEAD:] = Te_inv
    blocks = np.zeros((3 + ne, 2))
    blocks[3:, 0], blocks[3:, 1] = a, b
    return SpacecraftModes(T, Ti, blocks, energy)


def _block_phis(blocks: np.ndarray, tau: float) -> tuple[np.ndarray, ...]:
    """(e^{τA}, τ φ1(τA), τ φ2(τA), τ φ3(τA)) of every block A = [[0, 1], [−a, −b]], each
    (n_blocks, 2, 2): the Van Loan exponential of :func:`~flexsat.sim.integrators.
    phi_products` (B = I₂, order 3), one 8 × 8 exponential per block in one batched call."""
    nb = blocks.shape[0]
    C = np.zeros((nb, 8, 8))
    C[:, 0, 1] = 1.0
    C[:, 1, 0], C[:, 1, 1] = -blocks[:, 0], -blocks[:, 1]
    for r in range(3):  # the chain [[A, I, 0, 0], [0, 0, I, 0], [0, 0, 0, I], 0]
        C[:, 2 * r, 2 * r + 2] = C[:, 2 * r + 1, 2 * r + 3] = 1.0
    M = expm(tau * C)
    return M[:, :2, :2], M[:, :2, 2:4], M[:, :2, 4:6] / tau, M[:, :2, 6:8] / tau**2


def modal_propagators(
    blocks: np.ndarray, B: np.ndarray, Bf: np.ndarray, dt: float, substeps: int
) -> tuple[np.ndarray, ...]:
    """(E2, E, Q1u, P1u, F) of :class:`~flexsat.sim.kernels_attitude.AttitudeLoop` for the
    block-diagonal linear part of ``blocks`` (after the 1×1 β0 block), input columns B (n, m)
    and force columns Bf (n, 7) in z, step h = dt / substeps: E2, E (n, 2) the rows of
    e^{hA/2}, e^{hA} in their 2×2 blocks; Q1u = (h/2) φ1(hA/2) B, P1u = h φ1(hA) B;
    F (5, n, 7) = [(h/2) φ1(hA/2), h φ2(hA/2), h φ1(hA), h φ2(hA), h φ3(hA)] Bf, the
    matrices of :meth:`flexsat.sim.integrators.ExpRK4Stepper.build` (β0, A = 0: φ_k = 1/k!)."""
    h = dt / substeps
    n = 1 + 2 * blocks.shape[0]
    Eh2, R1, R2, _ = _block_phis(blocks, h / 2)
    Eh, P1, P2, P3 = _block_phis(blocks, h)
    E2, E = np.zeros((n, 2)), np.zeros((n, 2))
    E2[0, 0] = E[0, 0] = 1.0
    E2[1:], E[1:] = Eh2.reshape(-1, 2), Eh.reshape(-1, 2)

    def apply(blk: np.ndarray, beta0: float, X: np.ndarray) -> np.ndarray:
        out = np.empty_like(X)
        out[0] = beta0 * X[0]
        out[1:] = np.einsum("bij,bjk->bik", blk, X[1:].reshape(-1, 2, X.shape[1])).reshape(
            -1, X.shape[1]
        )
        return out

    F = np.stack(
        [
            apply(R1, h / 2, Bf),
            apply(2 * R2, h / 2, Bf),
            apply(P1, h, Bf),
            apply(P2, h / 2, Bf),
            apply(P3, h / 6, Bf),
        ]
    )
    return E2, E, apply(R1, h / 2, B), apply(P1, h, B), F
