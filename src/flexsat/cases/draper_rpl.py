"""Draper/RPL rigid hub with four flexible appendages (Junkins & Kim 1990, Example 2).

Source: Junkins & Kim, J. Astronautical Sciences 38(1), 1990 (Att. 5 of Junkins, Pollock & Rahman
1990), Example 2 ("Numerical Demonstrations"): Table 3 (configuration
parameters, entered here as printed in slug-ft-lbf-in units and converted with pint), the Ritz
model of Eqs. 50-54, the modal reduction of Eqs. 56-58, the structural feedback of Eq. 59 with the
converged gains G1, G2, and Table 4 (open- and closed-loop characteristics).

The model keeps only antisymmetric deflection of opposing beams, so the two beam pairs
(appendages 1&3 and 2&4) carry one set of Ritz coordinates each:
x = {θ, q_11 … q_N1, q_12 … q_N2}. ``n_functions`` is N, the number of comparison functions *per
pair*: the default N = 10 gives 21 degrees of freedom and the paper's "full (42nd) order" model;
the paper's "N = 20" counts both pairs (see docs/draper_rpl.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.input_checks import FieldError, require_count, require_finite, require_positive
from flexsat.units import QuantityArrayLike, to_si

if TYPE_CHECKING:
    import control
    from flexsat.dynamics.structural import StructuralPlant

SOURCE = CASES["draper_rpl"].source

#: Att. 5 Table 3, exactly as printed
PUBLISHED = {
    "hub_radius": "1 ft",
    "hub_inertia": "8 slug*ft**2",
    "density": "0.0271875 slug/ft",
    "modulus": "0.1584e10 lbf/ft**2",
    "thickness": "0.125 in",
    "height": "6.0 in",
    "length": "4.0 ft",
    "tip_mass": "0.156941 slug",
    "tip_inertia": "0.0018 slug*ft**2",
}

#: Att. 5 converged gains of Eq. 59 as (values, unit as implied, SI unit). The
#: paper gives no unit; its model is in slug-ft-s and Dᵀx is an angle, so G1 is in ft·lbf/rad and
#: G2 in ft·lbf·s/rad.
PUBLISHED_GAINS = {
    "G1": (
        [[1.8342, 0.2592, 0.2601], [0.2592, 0.0409, 0.0405], [0.2601, 0.0405, 0.0403]],
        "ft*lbf",
        "N*m",
    ),
    "G2": (
        [[7.4284, 0.4579, 0.8335], [0.4579, 0.2411, 0.0211], [0.8335, 0.0211, 0.3509]],
        "ft*lbf*s",
        "N*m*s",
    ),
}

#: Gauss-Legendre points for the mass integrals of Eq. 54: 400 (an earlier value), or 40 per
#: comparison function when that is more (the integrands oscillate like cos(2Nπz/L)).
QUADRATURE_POINTS = 400
_POINTS_PER_FUNCTION = 40

#: the overridable inputs of the case: Table 3 as printed, N = 10 functions per beam pair
_INPUTS = {
    "hub_radius": Param(PUBLISHED["hub_radius"], "m", "nonneg"),
    "hub_inertia": Param(PUBLISHED["hub_inertia"], "kg*m**2"),
    "density": Param(PUBLISHED["density"], "kg/m"),
    "modulus": Param(PUBLISHED["modulus"], "Pa"),
    "thickness": Param(PUBLISHED["thickness"], "m"),
    "height": Param(PUBLISHED["height"], "m"),
    "length": Param(PUBLISHED["length"], "m"),
    "tip_mass": Param(PUBLISHED["tip_mass"], "kg", "nonneg"),
    "tip_inertia": Param(PUBLISHED["tip_inertia"], "kg*m**2", "nonneg"),
    "n_functions": Param(10, rule="count"),
}
_INPUT_NAMES = ("u1_hub", "u2_tips_1_3", "u3_tips_2_4")
_OUTPUT_NAMES = ("theta", "rot_tips_1_3", "rot_tips_2_4")


def comparison_functions(
    z: npt.ArrayLike, n: int, length: float, derivative: int = 0
) -> np.ndarray:
    """Clamped-free comparison functions of Eq. 53 and their derivatives.

    φ_j(z) = 1 − cos(jπz/L) + ½ (−1)^{j+1} (jπz/L)²,  j = 1 … n  (Att. 5 Eq. 53).

    Parameters
    ----------
    z : array_like
        Positions along the beam from its root, m (0 ≤ z ≤ L).
    n : int
        Number of functions.
    length : float
        Beam length L, m.
    derivative : {0, 1, 2}
        Order of the z-derivative.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(z), n)``; φ is dimensionless, φ' in 1/m, φ'' in 1/m².
    """
    j = np.arange(1, n + 1)
    a = j * np.pi / float(require_positive(length, "length", "m"))
    s = (-1.0) ** (j + 1)
    az = np.outer(np.atleast_1d(require_finite(z, "z", "m")), a)
    if derivative == 0:
        return 1.0 - np.cos(az) + 0.5 * s * az**2
    if derivative == 1:
        return a * np.sin(az) + s * a * az
    if derivative == 2:
        return a**2 * np.cos(az) + s * a**2
    raise FieldError("derivative", f"must be 0, 1 or 2, got {derivative!r}")


def _ordinal(k: int) -> str:
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


@dataclass(frozen=True)
class DraperRPLCase:
    """Draper/RPL hub + four appendages, Ritz model of Att. 5 Eqs. 50-54 (SI units).

    Attributes
    ----------
    hub_radius : float
        r, m.
    hub_inertia : float
        J_h, kg m².
    density : float
        ρ, mass per unit length of each beam, kg/m.
    modulus : float
        E, Pa.
    thickness, height : float
        Beam cross-section t (bending direction) and h, m; I = h t³ / 12.
    length : float
        L, m.
    tip_mass : float
        m, kg.
    tip_inertia : float
        J_t, kg m².
    n_functions : int
        N, comparison functions per beam pair (model has 1 + 2N degrees of freedom).
    """

    hub_radius: float
    hub_inertia: float
    density: float
    modulus: float
    thickness: float
    height: float
    length: float
    tip_mass: float
    tip_inertia: float
    n_functions: int

    # -- derived parameters ---------------------------------------------------------------------
    @property
    def EI(self) -> float:
        """Bending stiffness E h t³ / 12, N m² (74.5985 lb ft² for Table 3)."""
        return self.modulus * self.height * self.thickness**3 / 12.0

    @property
    def total_inertia(self) -> float:
        """J = J_h + 4∫₀ᴸ ρ(x + r)² dx + 4[J_t + m(r + L)²] (Eq. 54), kg m²."""
        r, L = self.hub_radius, self.length
        beams = 4.0 * self.density * ((r + L) ** 3 - r**3) / 3.0
        return self.hub_inertia + beams + 4.0 * (self.tip_inertia + self.tip_mass * (r + L) ** 2)

    @property
    def n_dof(self) -> int:
        return 1 + 2 * self.n_functions

    # -- Eq. 54 ---------------------------------------------------------------------------------
    def _tip_values(self) -> tuple[np.ndarray, np.ndarray]:
        n, L = self.n_functions, self.length
        return (comparison_functions(L, n, L)[0], comparison_functions(L, n, L, 1)[0])

    def _pair_blocks(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """[M_θq]_i, [M_qq]_ij by Gauss-Legendre quadrature; [K_qq]_ij in closed form."""
        n, L, r, rho = self.n_functions, self.length, self.hub_radius, self.density
        nodes, weights = np.polynomial.legendre.leggauss(
            max(QUADRATURE_POINTS, _POINTS_PER_FUNCTION * n)
        )
        z, w = 0.5 * L * (nodes + 1.0), 0.5 * L * weights
        phi = comparison_functions(z, n, L)
        phi_L, dphi_L = self._tip_values()
        m_tq = 2.0 * (
            rho * (w * (z + r)) @ phi + self.tip_mass * (r + L) * phi_L + self.tip_inertia * dphi_L
        )
        m_qq = 2.0 * (
            rho * phi.T @ (w[:, None] * phi)
            + self.tip_mass * np.outer(phi_L, phi_L)
            + self.tip_inertia * np.outer(dphi_L, dphi_L)
        )
        # φ_i'' φ_j'' = a_i² a_j² (cos a_i z + s_i)(cos a_j z + s_j); ∫cos a z = 0, ∫cos² = L/2
        j = np.arange(1, n + 1)
        a2, s = (j * np.pi / L) ** 2, (-1.0) ** (j + 1)
        k_qq = 2.0 * self.EI * L * np.outer(a2, a2) * (0.5 * np.eye(n) + np.outer(s, s))
        return m_tq, m_qq, k_qq

    @cached_property
    def _model(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = self.n_functions
        m_tq, m_qq, k_qq = self._pair_blocks()
        pair1, pair2 = slice(1, n + 1), slice(n + 1, 2 * n + 1)
        M, K = np.zeros((self.n_dof, self.n_dof)), np.zeros((self.n_dof, self.n_dof))
        B = np.zeros((self.n_dof, 3))
        M[0, 0] = self.total_inertia
        B[0] = (1.0, 2.0, 2.0)
        dphi_L = self._tip_values()[1]
        for col, pair in ((1, pair1), (2, pair2)):
            M[0, pair] = M[pair, 0] = m_tq
            M[pair, pair] = m_qq
            K[pair, pair] = k_qq
            B[pair, col] = 2.0 * dphi_L
        return M, K, B

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, stiffness and input matrices of Eq. 54, M ẍ + K x = B u (Eq. 55 calls B "D").

        Returns
        -------
        M, K : numpy.ndarray
            ``(1 + 2N, 1 + 2N)``, SI (θ in rad, q in m).
        B : numpy.ndarray
            ``(1 + 2N, 3)``: columns u1 hub torque, u2 torque at the tips of appendages 1 and 3,
            u3 at the tips of appendages 2 and 4; rows [1 2 2], [0 2φ'(L) 0], [0 0 2φ'(L)].
        """
        M, K, B = self._model
        return M.copy(), K.copy(), B.copy()

    # -- free vibration, Eqs. 56-58 -------------------------------------------------------------
    @cached_property
    def _eig(self) -> tuple[np.ndarray, np.ndarray]:
        M, K, _ = self._model
        w2, phi = sla.eigh(K, M)
        w2[0] = 0.0  # rigid rotation: K has a zero row and column for θ
        return w2, self._fix_signs(phi)

    def _fix_signs(self, phi: np.ndarray) -> np.ndarray:
        """Deterministic mode signs: θ > 0 when the hub moves, else the largest entry > 0."""
        largest = phi[np.argmax(np.abs(phi), axis=0), np.arange(phi.shape[1])]
        return phi * np.sign(np.where(self._hub_moves(phi[0]), phi[0], largest))

    def _hub_moves(self, theta):
        """The hub takes part in a mass-normalised mode when √J |θ| ≥ 1e-6."""
        return np.sqrt(self.total_inertia) * np.abs(theta) >= 1e-6

    def frequencies(self) -> np.ndarray:
        """Open-loop natural frequencies ω of the full model, rad/s, ascending (ω_1 = 0)."""
        return np.sqrt(self._eig[0])

    def frequencies_hz(self, n: int | None = None) -> np.ndarray:
        """The first ``n`` (default all) natural frequencies, Hz."""
        return self.frequencies()[: self._count(n, "n")] / (2.0 * np.pi)

    def modes(self) -> np.ndarray:
        """Mass-normalised modal matrix Φ, Φᵀ M Φ = I and Φᵀ K Φ = diag(ω²) (Eq. 56)."""
        return self._eig[1].copy()

    def reduced(self, n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Modal truncation to the first ``n_modes`` modes, Eqs. 57-58.

        Returns
        -------
        M_bar, K_bar, D_bar : numpy.ndarray
            Φ1ᵀ M Φ1 (= I), Φ1ᵀ K Φ1 (= diag ω²) and Φ1ᵀ B, with Φ1 the first ``n_modes``
            columns of :meth:`modes`.
        """
        M, K, B = self._model
        phi1 = self._eig[1][:, : self._count(n_modes, "n_modes")]
        return phi1.T @ M @ phi1, phi1.T @ K @ phi1, phi1.T @ B

    def _count(self, n, field: str) -> int:
        if n is None:
            return self.n_dof
        n = require_count(n, field)
        if n > self.n_dof:
            raise FieldError(field, f"the model has {self.n_dof} modes, got {n}")
        return n

    # -- mode descriptions ----------------------------------------------------------------------
    def mode_descriptions(self, n: int = 9) -> list[str]:
        """Words for the first ``n`` modes, read off the mass-normalised eigenvectors.

        A mode whose beam coordinates vanish is the rigid rotation. Otherwise the phase between
        the pairs is the sign of q_1ᵀ M_qq q_2, and the hub is "at rest" when √J |θ| (its share
        of the unit modal mass) is below 1e-6; by orthogonality to the rigid mode a moving hub
        always opposes the appendages' angular momentum, hence "counter-rotating". The bending
        order is the mode's rank within its family (in-phase modes couple to the hub, anti-phase
        modes are the clamped-root cantilever modes); node counts of the Ritz shapes are not used
        because they are unreliable for the highest modes of a 10-function expansion.
        """
        phi = self._eig[1][:, : self._count(n, "n")]
        ranks: dict[str, int] = {}
        words = []
        for k in range(phi.shape[1]):
            family = self._family(phi[:, k])
            if family == "rigid rotation":
                words.append(family)
                continue
            ranks[family] = ranks.get(family, 0) + 1
            words.append(f"{_ordinal(ranks[family])} bending, pairs 1&3 and 2&4 {family}")
        return words

    def _family(self, mode: np.ndarray) -> str:
        n = self.n_functions
        q1, q2 = mode[1 : n + 1], mode[n + 1 :]
        if np.abs(mode[1:]).max() < 1e-9 * np.abs(mode).max():
            return "rigid rotation"
        m_qq = self._model[0][1 : n + 1, 1 : n + 1]
        phase = "in phase" if q1 @ m_qq @ q2 > 0 else "in anti-phase"
        return f"{phase}, hub {'counter-rotating' if self._hub_moves(mode[0]) else 'at rest'}"

    # -- state space ----------------------------------------------------------------------------
    def to_statespace(self, n_modes: int | None = None) -> control.StateSpace:
        """python-control StateSpace of M ẍ + K x = B u with the collocated outputs of Eq. 59.

        State z = (x, ẋ) of the full model (``n_modes=None``, 2(1 + 2N) states) or (η1, η̇1) of
        the reduced model of Eq. 58. Inputs: ``u1_hub``, ``u2_tips_1_3``, ``u3_tips_2_4`` (N m).
        Outputs y = (Bᵀx, Bᵀẋ), the six signals of the paper's "6 outputs, 3 inputs":
        ``theta``; ``rot_tips_1_3`` = 2[θ + y_1'(L)], the sum of the absolute rotations of tips
        1 and 3 (the work conjugate of u2); ``rot_tips_2_4`` likewise; and their rates
        (suffix ``_dot``). Eq. 59 is then the static output feedback u = −[G1 G2] y, e.g.
        ``control.feedback(sys, np.hstack([g1, g2]))``.
        """
        if n_modes is None:
            M, K, B = self._model
            functions = range(1, self.n_functions + 1)
            names = ["theta"] + [f"q{j}_{p}" for p in (1, 2) for j in functions]
        else:
            M, K, B = self.reduced(n_modes)
            names = [f"eta{k}" for k in range(1, M.shape[0] + 1)]
        import control

        n = M.shape[0]
        zeros = np.zeros((n, n))
        A = np.block([[zeros, np.eye(n)], [-np.linalg.solve(M, K), zeros]])
        Bu = np.vstack([np.zeros_like(B), np.linalg.solve(M, B)])
        C = sla.block_diag(B.T, B.T)
        return control.ss(
            A,
            Bu,
            C,
            np.zeros((6, 3)),
            inputs=list(_INPUT_NAMES),
            outputs=list(_OUTPUT_NAMES) + [f"{s}_dot" for s in _OUTPUT_NAMES],
            states=names + [f"{s}_dot" for s in names],
            name="draper_rpl",
        )

    def plant(self, n_modes: int | None = None, damping: float = 0.0) -> StructuralPlant:
        """The model as a :class:`~flexsat.dynamics.structural.StructuralPlant` with the channels
        of :meth:`to_statespace`: torque inputs ``u1_hub``, ``u2_tips_1_3``, ``u3_tips_2_4``
        (N m, the columns of B, Eq. 54) and the collocated rotations ``theta``,
        ``rot_tips_1_3``, ``rot_tips_2_4`` (rad, rows Bᵀ) with their rates (``_dot``, rad/s);
        undamped (the paper's model) unless ``damping`` gives the elastic modes a modal damping
        ratio (D = 2ζΩ, modal models only). Full Ritz coordinates, or the first ``n_modes``
        modes of Eq. 58 (then :attr:`~StructuralPlant.modal_blocks` gives the frequencies)."""
        from flexsat.dynamics.second_order import SecondOrderModel
        from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant

        zeta = float(require_finite(damping, "damping"))
        if not 0.0 <= zeta < 1.0:
            raise FieldError("damping", f"must be in [0, 1), got {zeta:g}")
        if zeta and n_modes is None:
            raise FieldError("damping", "modal damping needs a modal model: give n_modes")
        M, K, B = self._model if n_modes is None else self.reduced(n_modes)
        if n_modes is not None:  # Φ1ᵀMΦ1 is I to round-off: make it exact (modal blocks)
            M, K = np.eye(M.shape[0]), np.diag(np.diag(K))
        D = np.diag(2.0 * zeta * np.sqrt(np.clip(np.diag(K), 0.0, None))) if zeta else None
        acts = [Actuator(name, "torque", B[:, j]) for j, name in enumerate(_INPUT_NAMES)]
        sensors = [Sensor(name, "rotation", B[:, j]) for j, name in enumerate(_OUTPUT_NAMES)]
        sensors += [
            Sensor(f"{name}_dot", "rotation", B[:, j], rate=True)
            for j, name in enumerate(_OUTPUT_NAMES)
        ]
        model = SecondOrderModel(M, np.zeros_like(M) if D is None else D, K, B, B.T)
        return StructuralPlant.from_second_order(model, acts, sensors)

    # -- closed loop, Eq. 59 on the full model --------------------------------------------------
    def _closed_loop_pencil(self, g1, g2) -> tuple[np.ndarray, np.ndarray]:
        """A, E of E ż = A z for u = −(G1 Bᵀx + G2 Bᵀẋ): A = [[0, M], [−K̄, −C̄]], E = diag(M, M)
        with K̄ = K + B G1 Bᵀ and C̄ = B G2 Bᵀ (Att. 5 Eqs. 34-38, 59)."""
        M, K, B = self._model
        g1, g2 = _gain(g1, "g1", "N*m/rad"), _gain(g2, "g2", "N*m*s/rad")
        zeros = np.zeros_like(M)
        A = np.block([[zeros, M], [-(K + B @ g1 @ B.T), -(B @ g2 @ B.T)]])
        return A, sla.block_diag(M, M)

    def closed_loop_eigenvalues(self, g1: QuantityArrayLike, g2: QuantityArrayLike) -> np.ndarray:
        """All 2(1 + 2N) closed-loop eigenvalues for the gains ``g1`` (N m/rad), ``g2``
        (N m s/rad), sorted by imaginary part."""
        lam = sla.eigvals(*self._closed_loop_pencil(g1, g2))
        return lam[np.lexsort((lam.real, lam.imag))]

    def closed_loop_modes(
        self, g1: QuantityArrayLike, g2: QuantityArrayLike, n: int = 9
    ) -> tuple[np.ndarray, np.ndarray]:
        """(ω_i, ζ_i ω_i) of the first ``n`` oscillatory closed-loop modes, as in Table 4.

        ω = Im λ and ζ = −Re λ / |λ| (Att. 5 Eqs. 47-49), so ζω = Im λ · (−Re λ) / |λ|, which is
        not −Re λ. Modes are the eigenvalues with Im λ > 0, ascending.
        """
        lam = self.closed_loop_eigenvalues(g1, g2)
        lam = lam[lam.imag > 0][: require_count(n, "n")]
        return lam.imag, lam.imag * -lam.real / np.abs(lam)

    def condition_number(
        self, g1: QuantityArrayLike, g2: QuantityArrayLike, normalisation: str = "plain"
    ) -> float:
        """2-norm condition number σ_max/σ_min of the closed-loop modal matrix (Att. 5 Eq. 46).

        Right eigenvectors φ_i of E ż = A z, z = (x, ẋ) in SI (θ in rad, q in m), with
        A = [[0, M], [−(K + B G1 Bᵀ), −B G2 Bᵀ]] and E = diag(M, M), are scaled column by column
        before the SVD:

        - ``"plain"``: φ_iᵀ E φ_i = 1 with the plain (non-conjugate) transpose, the convention of
          Att. 5 Eqs. 40-41, which reproduces Example 1 (8.1291); here it gives 37 828;
        - ``"hermitian"``: φ_iᴴ E φ_i = 1 (unit E-norm), which reproduces this example's
          Table 4 value 37 210.8.

        Expressing q in ft (the paper's unit) instead of m changes either value by < 3e-6
        relative; the open-loop modal matrix is singular (Jordan block of the rigid mode).
        """
        A, E = self._closed_loop_pencil(g1, g2)
        phi = sla.eig(A, E)[1]
        if normalisation == "plain":
            norm2 = np.einsum("ij,ik,kj->j", phi, E, phi)
        elif normalisation == "hermitian":
            norm2 = np.einsum("ij,ik,kj->j", phi.conj(), E, phi).real
        else:
            raise FieldError(
                "normalisation", f"must be 'plain' or 'hermitian', got {normalisation!r}"
            )
        return float(np.linalg.cond(phi / np.sqrt(norm2)))


def _gain(value, field: str, unit: str) -> np.ndarray:
    g = require_finite(value, field, unit)
    if g.shape != (3, 3):
        raise FieldError(field, f"must be a 3x3 matrix (one row per input), got shape {g.shape}")
    return g


def published_gains() -> tuple[np.ndarray, np.ndarray]:
    """G1 (N m/rad) and G2 (N m s/rad) of Att. 5 Eq. 59, converted from ft·lbf."""
    g1, g2 = (
        np.asarray(values) * to_si(f"1 {unit}", si_unit)
        for values, unit, si_unit in PUBLISHED_GAINS.values()
    )
    return g1, g2


def draper_rpl(**overrides: Any) -> DraperRPLCase:
    """Build the Draper/RPL case; override any input by name, as a number (SI) or a unit string.

    Parameters
    ----------
    **overrides
        Any of ``hub_radius``, ``hub_inertia``, ``density``, ``modulus``, ``thickness``,
        ``height``, ``length``, ``tip_mass``, ``tip_inertia`` (defaults: Att. 5 Table 3) and
        ``n_functions`` (default 10 per beam pair).

    Raises
    ------
    ValueError
        Unknown name, or a value breaking its rule (message starts with the field name).

    Examples
    --------
    >>> case = draper_rpl(n_functions=20, tip_mass="2.29 kg")
    """
    return DraperRPLCase(**read_inputs("draper_rpl", _INPUTS, overrides))


__all__ = [
    "PUBLISHED",
    "PUBLISHED_GAINS",
    "QUADRATURE_POINTS",
    "SOURCE",
    "DraperRPLCase",
    "comparison_functions",
    "draper_rpl",
    "published_gains",
]
