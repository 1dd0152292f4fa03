"""Rigid hub with n identical cantilevered appendages, single axis, in hybrid coordinates.

The distributed-parameter system of Junkins, Rahman & Bang (Att. 3 of
Junkins, Pollock & Rahman 1990, Eqs. 5-7):

    I_hub θ'' = u + n (M0 − l0 S0)
    ρ (y_tt + x θ'') + EI y_xxxx = 0,       l0 < x < l
    y(l0) = y_x(l0) = 0,   EI y_xx(l) = −J (θ'' + y_xtt(l)),   EI y_xxx(l) = m (l θ'' + y_tt(l))

is discretised by Galerkin's method with k exact tip-mass cantilever modes φ_i (mass normalised
per beam), y = Σ φ_i q_i, identical for every beam (anti-symmetric deformation). The generalized
coordinates are (θ, q_1 … q_k) and the state is x = [θ, q, θ', q'] (the ordering of
Hailey, Sortun & Agrawal c. 1992):

    M = [[I_tot, n dᵀ], [n d, n 1]],   K = diag(0, n ω²),   D = diag(0, 2 n ζ ω),   B = e_θ

with I_tot = I_hub + n I_b, I_b = ρ (l³ − l0³)/3 + m l² + J the rigid inertia of one appendage
about the hub axis, and d_i = ∫ ρ x φ_i dx + m l φ_i(l) + J φ_i'(l) the rigid-elastic coupling.

Root loads are recovered by force summation (the second line of Att. 3 Eq. 5), which converges
faster than differentiating the modal sum and makes the discrete energy rate identity
dE_beams/dt = n θ' (l0 S0 − M0) exact for the truncated model:

    l0 S0 − M0 = I_b θ'' + dᵀ q''
    S0         = [ρ (l² − l0²)/2 + m l] θ'' + eᵀ q'',   e_i = ∫ ρ φ_i dx + m φ_i(l)

The optional rotational-stiffening term comes from the foreshortening of the rotating beam: the
kinetic energy gains ½ θ'² qᵀ G q with G = n (M_s − K_g), M_s_ij = ∫ρ φ_i φ_j + m φ_i(l) φ_j(l)
(spin softening) and K_g_ij = ∫ T(x) φ_i' φ_j' dx, T(x) = ρ (l² − x²)/2 + m l (centrifugal
tension per unit θ'²).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from flexsat import limits
from flexsat.dynamics.hybrid import HYBRID_OUTPUTS, HybridPlant
from flexsat.dynamics.plant import Channel
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
    set_si,
)
from flexsat.structures.beam import TipMassCantilever

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.structures.beam import CantileverModes
    from flexsat.units import FloatArray


@lru_cache(maxsize=16)
def gauss_legendre(n: int) -> tuple[FloatArray, FloatArray]:
    """Gauss–Legendre nodes and weights on [−1, 1] (numpy's ``leggauss``), read-only and cached:
    numpy recomputes them on every call, 35 % of a 10-mode hub + appendage build (a Monte Carlo
    builds one per case)."""
    s, w = np.polynomial.legendre.leggauss(n)
    s.flags.writeable = w.flags.writeable = False
    return s, w


class ModalIntegrals(TypedDict):
    """The Galerkin integrals of :class:`HubAppendage` (its :attr:`~HubAppendage.
    modal_integrals`), SI."""

    modes: CantileverModes
    omega: FloatArray  # cantilever frequencies, rad/s
    d: FloatArray  # rigid-elastic coupling of one appendage, kg m
    e: FloatArray  # shear coupling, kg
    phi_tip: FloatArray  # mode shapes at the tip
    G: FloatArray  # rotational-stiffening matrix of all appendages


@dataclass(frozen=True)
class HubAppendageParams:
    """Physical parameters of the hub + appendage system, SI units.

    Parameters
    ----------
    hub_inertia : float
        Inertia of the rigid hub alone about the rotation axis, kg m².
    n_appendages : int
        Number of identical appendages deforming anti-symmetrically (TAMU: 4).
    hub_radius : float
        Distance l0 from the hub centre to each appendage root, m.
    length : float
        Appendage (beam) length L, so the tip is at l = l0 + L, m.
    EI : float
        Bending stiffness, N m².
    rho : float
        Mass per unit length, kg/m.
    tip_mass : float
        Tip point mass m, kg.
    tip_inertia : float
        Rotary inertia J of the tip body about its own centre, kg m².
    damping : float or sequence of float
        Modal damping ratios of the cantilever modes (one value for all, or one per mode).

    Notes
    -----
    Each physical field also takes a pint Quantity or a unit string (``length="36 in"``) and is
    stored in SI.
    """

    hub_inertia: float
    n_appendages: int
    hub_radius: float
    length: float
    EI: float
    rho: float
    tip_mass: float = 0.0
    tip_inertia: float = 0.0
    damping: float | tuple[float, ...] = 0.0

    def __post_init__(self) -> None:
        for name, unit in (
            ("hub_inertia", "kg*m**2"),
            ("length", "m"),
            ("EI", "N*m**2"),
            ("rho", "kg/m"),
        ):
            set_si(self, name, require_positive, unit)
        for name, unit in (("hub_radius", "m"), ("tip_mass", "kg"), ("tip_inertia", "kg*m**2")):
            set_si(self, name, require_nonneg, unit)
        require_count(self.n_appendages, "n_appendages")
        zeta = require_finite(self.damping, "damping", "")
        if np.any(zeta < 0):
            raise FieldError("damping", f"modal damping ratios must be >= 0, got {self.damping!r}")
        object.__setattr__(self, "damping", float(zeta) if zeta.ndim == 0 else tuple(zeta.tolist()))

    @property
    def tip_radius(self) -> float:
        """Distance l from the hub centre to the appendage tip, m."""
        return self.hub_radius + self.length

    @property
    def appendage_inertia(self) -> float:
        """Rigid inertia I_b of one appendage (beam + tip body) about the hub axis, kg m²."""
        l0, l = self.hub_radius, self.tip_radius
        return self.rho * (l**3 - l0**3) / 3 + self.tip_mass * l**2 + self.tip_inertia

    @property
    def total_inertia(self) -> float:
        """Rigid inertia of the whole vehicle, I_hub + n I_b, kg m²."""
        return self.hub_inertia + self.n_appendages * self.appendage_inertia

    def beam(self) -> TipMassCantilever:
        return TipMassCantilever(self.length, self.EI, self.rho, self.tip_mass, self.tip_inertia)


@dataclass(frozen=True)
class HubAppendage(HybridPlant):
    """Assumed-modes hub + appendage model (see module docstring).

    Parameters
    ----------
    params : HubAppendageParams
    n_modes : int
        Number k of cantilever modes per appendage; the state has 2 (k + 1) entries.
    stiffening : bool
        Include the rotational-stiffening (centrifugal) term; the model is then nonlinear and
        the simulator integrates it with its exponential integrator.
    """

    params: HubAppendageParams
    n_modes: int = 10
    stiffening: bool = False
    _quad: ModalIntegrals = field(init=False, repr=False, compare=False)

    output_channels = HYBRID_OUTPUTS + (
        Channel("root_shear", "N", description="root shear force S0 of one appendage"),
        Channel("root_moment", "N*m", description="root bending moment M0 of one appendage"),
    )

    def __post_init__(self) -> None:
        require_count(self.n_modes, "n_modes")
        limits.check_count(self.n_modes, limits.MAX_MODES, "n_modes", "modes per appendage")
        zeta = np.atleast_1d(np.asarray(self.params.damping, dtype=float))
        if zeta.size not in (1, self.n_modes):
            raise FieldError(
                "damping", f"give one ratio or one per mode ({self.n_modes}), got {zeta.size}"
            )
        if "_quad" not in self.__dict__:  # given by from_modal_integrals
            object.__setattr__(self, "_quad", self._modal_integrals())

    @classmethod
    def from_modal_integrals(
        cls,
        params: HubAppendageParams,
        integrals: ModalIntegrals,
        n_modes: int,
        stiffening: bool = False,
    ) -> HubAppendage:
        """The model of ``params`` from its Galerkin integrals computed elsewhere: a case of
        :class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage`, whose cases' modes
        and integrals are computed for the whole batch at once.

        Raises
        ------
        ValueError
            Naming ``integrals`` when their shapes are not those of ``n_modes`` modes.
        """
        k = require_count(n_modes, "n_modes")
        shapes = {"omega": (k,), "d": (k,), "e": (k,), "phi_tip": (k,), "G": (k, k)}
        for name, shape in shapes.items():
            if np.shape(integrals[name]) != shape:  # type: ignore[literal-required]
                raise FieldError(
                    "integrals",
                    f"{name} has shape {np.shape(integrals[name])}, "  # type: ignore[literal-required]
                    f"expected {shape} for {k} modes",
                )
        self = object.__new__(cls)
        object.__setattr__(self, "_quad", integrals)
        cls.__init__(self, params, n_modes, stiffening)
        return self

    @property
    def modal_integrals(self) -> ModalIntegrals:
        """The Galerkin integrals of the model (module docstring): the cantilever modes, ω,
        the couplings d and e, the tip values φ(l) and the stiffening matrix G."""
        return self._quad

    # ----------------------------------------------------------------------------------------
    # modal integrals
    def _modal_integrals(self) -> ModalIntegrals:
        p, k = self.params, self.n_modes
        modes = p.beam().modes(k)
        npts = max(200, 24 * k)
        s, w = gauss_legendre(npts)
        xi = 0.5 * p.length * (s + 1.0)
        w = 0.5 * p.length * w
        phi = modes.evaluate(xi, 0)
        dphi = modes.evaluate(xi, 1)
        tip = np.array([p.length])
        phi_l, dphi_l = modes.evaluate(tip, 0)[0], modes.evaluate(tip, 1)[0]
        x = p.hub_radius + xi
        l = p.tip_radius
        coupling = p.rho * (w * x) @ phi + p.tip_mass * l * phi_l + p.tip_inertia * dphi_l
        shear_coupling = p.rho * w @ phi + p.tip_mass * phi_l
        spin_mass = p.rho * (phi * w[:, None]).T @ phi + p.tip_mass * np.outer(phi_l, phi_l)
        tension = p.rho * (l**2 - x**2) / 2 + p.tip_mass * l
        geometric = (dphi * (w * tension)[:, None]).T @ dphi
        return ModalIntegrals(
            modes=modes,
            omega=modes.omegas,
            d=coupling,
            e=shear_coupling,
            phi_tip=phi_l,
            G=p.n_appendages * (spin_mass - geometric),
        )

    # ----------------------------------------------------------------------------------------
    # second-order model
    @property
    def hub_inertia(self) -> float:
        return self.params.hub_inertia

    @property
    def n_appendages(self) -> int:
        return self.params.n_appendages

    @property
    def cantilever_frequencies(self) -> FloatArray:
        """Constrained (hub clamped) natural frequencies ω_i, rad/s (exact for these modes)."""
        return self._quad["omega"]

    @property
    def coupling(self) -> FloatArray:
        """Rigid-elastic coupling d_i of one appendage, kg m (Galerkin integral)."""
        return self._quad["d"]

    @property
    def damping_ratios(self) -> FloatArray:
        return np.broadcast_to(np.asarray(self.params.damping, float), (self.n_modes,)).copy()

    @cached_property
    def mass_matrix(self) -> FloatArray:
        p, n, k = self.params, self.params.n_appendages, self.n_modes
        M = np.zeros((k + 1, k + 1))
        M[0, 0] = p.total_inertia
        M[0, 1:] = M[1:, 0] = n * self.coupling
        M[1:, 1:] = n * np.eye(k)
        return M

    @cached_property
    def stiffness_matrix(self) -> FloatArray:
        n, w = self.params.n_appendages, self.cantilever_frequencies
        return np.diag(np.concatenate([[0.0], n * w**2]))

    @cached_property
    def damping_matrix(self) -> FloatArray:
        n, w = self.params.n_appendages, self.cantilever_frequencies
        return np.diag(np.concatenate([[0.0], 2 * n * self.damping_ratios * w]))

    def frequencies(self, constrained: bool = False) -> FloatArray:
        """Natural frequencies of the model, rad/s, ascending.

        Unconstrained (hub free): the elastic frequencies of (K, M), the rigid mode dropped.
        Constrained (hub clamped): the cantilever frequencies.
        """
        return self.cantilever_frequencies.copy() if constrained else self.hub_free_frequencies()

    def nonlinear_force(self, x: FloatArray, u: npt.ArrayLike) -> FloatArray:
        """Generalized force of the rotational-stiffening terms, shape (..., ndof).

        With s = qᵀGq the hub equation gains (I_tot + s) θ'' + 2 θ' qᵀ G q' and the modal
        equations −θ'² G q. The state-dependent inertia is folded in exactly: θ'' solves
        θ'' = a0_θ / (1 + s (M⁻¹)_θθ), a0 the acceleration without the s θ'' term.
        """
        pos, vel = self.split(x)
        f = np.zeros(pos.shape)
        if not self.stiffening:
            return f
        G = self._quad["G"]
        q, qd, thd = pos[..., 1:], vel[..., 1:], vel[..., 0]
        Gq = q @ G
        s = np.einsum("...i,...i->...", Gq, q)
        f[..., 1:] = thd[..., None] ** 2 * Gq
        f[..., 0] = -2.0 * thd * np.einsum("...i,...i->...", Gq, qd)
        Minv = self.mass_inverse
        force = self._linear_force(pos, vel, u) + f
        a0 = force @ Minv[0]
        f[..., 0] -= s * a0 / (1.0 + s * Minv[0, 0])
        return f

    @property
    def _tip_row(self) -> FloatArray:
        return self._quad["phi_tip"]

    def _output_coefficients(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray, float]:
        """Linear forms of the root loads by force summation (module docstring): ``root_torque``
        = I_b θ'' + dᵀ q'', S0 = [ρ (l² − l0²)/2 + m l] θ'' + eᵀ q'', M0 = l0 S0 − (l0 S0 − M0).
        """
        p, z = self.params, np.zeros(self.ndof)
        moment = np.concatenate([[p.appendage_inertia], self.coupling])
        shear = np.concatenate(
            [
                [p.rho * (p.tip_radius**2 - p.hub_radius**2) / 2 + p.tip_mass * p.tip_radius],
                self._quad["e"],
            ]
        )
        acc = {
            "root_torque": moment,
            "root_shear": shear,
            "root_moment": p.hub_radius * shear - moment,
        }.get(name)
        if acc is None:
            return super()._output_coefficients(name)
        return z, z, acc, 0.0

    def output_values(
        self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
    ) -> dict[str, FloatArray]:
        """Physical outputs of state x under hub torque u (SI).

        Returns hub angle and rate, root shear S0, root bending moment M0, the Lyapunov-law
        output ``root_torque`` = l0 S0 − M0 (the moment of the root loads about the hub axis,
        force summation), and the tip deflection y(l).
        """
        p = self.params
        pos, vel = self.split(x)
        acc = self.acceleration(x, u, extra_force)
        thdd, qdd = acc[..., 0], acc[..., 1:]
        l0, l = p.hub_radius, p.tip_radius
        moment_term = p.appendage_inertia * thdd + qdd @ self.coupling
        shear = (p.rho * (l**2 - l0**2) / 2 + p.tip_mass * l) * thdd + qdd @ self._quad["e"]
        return {
            "theta": pos[..., 0],
            "theta_dot": vel[..., 0],
            "root_shear": shear,
            "root_moment": l0 * shear - moment_term,
            "root_torque": moment_term,
            "tip_deflection": pos[..., 1:] @ self._quad["phi_tip"],
        }

    def momentum(self, x: FloatArray) -> FloatArray:
        """Angular momentum about the hub axis, N m s: h = (M x')_θ, plus s θ' (s = qᵀGq) with
        the stiffening on, whose hub equation (:meth:`nonlinear_force`)
        (I_tot + s) θ'' + M_θq q'' + 2 θ' qᵀG q' = u is dh/dt = u for that h."""
        h = super().momentum(x)
        if self.stiffening:
            pos, vel = self.split(x)
            q = pos[..., 1:]
            h = h + vel[..., 0] * np.einsum("...i,ij,...j->...", q, self._quad["G"], q)
        return h

    # ----------------------------------------------------------------------------------------
    # energies (Att. 3 Eqs. 7, 8, 18)
    def energy(self, x: FloatArray) -> FloatArray:
        """Total mechanical energy E (Att. 3 Eq. 7), J; includes the stiffening term if on."""
        E = super().energy(x)
        if self.stiffening:
            pos, vel = self.split(x)
            q = pos[..., 1:]
            E = E + 0.5 * vel[..., 0] ** 2 * np.einsum("...i,ij,...j->...", q, self._quad["G"], q)
        return E
