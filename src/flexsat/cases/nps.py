"""NPS Flexible Spacecraft Simulator (Hailey, Sortun & Agrawal), pitch axis.

J. A. Hailey, C. D. Sortun and B. N. Agrawal, "Experimental Verification of Attitude Control
Techniques for Slew Maneuvers of Flexible Spacecraft", NPS (c. 1992): a rigid central body
(hub) on an air bearing carrying a cantilevered flexible appendage, "a reflector supported by a
flexible astromast" ("Experimental Setup"), planar rotation θ about the vertical z axis. The
paper prints only: fundamental cantilever frequency 0.14 Hz ("Experimental Setup"), six
cantilever modes with 0.4 % damping ("Proportional - Derivative Control"),
and the rigid-body PD design ω_n = 0.06 Hz, ζ = 0.9 → k = 1.3985 N·m/rad, kτ = 6.6773 N·m·s/rad
("Proportional - Derivative Control"). Its finite-element model (GIFTS), the geometry and
the inertias are not published.

Model used here (every dimension a parameter, documented in docs/nps.md):

- the astromast is an equivalent uniform Euler–Bernoulli beam (bending stiffness EI, mass per
  length ρ) along +x from the attachment point at radius ``attachment_radius`` on the hub; it is
  axially rigid (the ux dofs are constrained: a straight radial mast's axial motion couples
  neither with bending nor with pitch, since y_F = 0 in the coupling D_i of Eq. 10);
- the reflector is a lumped mass with rotary inertia about z at the mast tip;
- the mast EI is **solved** (Brent's method on the finite-element frequency) so that the first
  cantilever frequency is the published 0.14 Hz;
- the hub inertia is solved so that the design inertia implied by the PD gains, k/ω_n² ≈ 9.84
  kg·m², is either the cantilevered inertia I⁰zz = I_zz − Σ D_i² over the six modes
  (``inertia_convention="cantilevered"``, default, as the issue states and as the paper's rigid
  profiles Eqs. 25, 28, 30 use I⁰zz) or the total rigid inertia I_zz (``"total"``).

Hybrid coordinates (Eqs. 10, 16–18) about the hub centre (the rotation axis, origin):
M = [[I_zz, Dᵀ], [D, I]], K = diag(0, ω²), C = diag(0, 2ζω), with the coupling
D_i = Φ_iᵀ M R_θ computed with the *full* appendage mass matrix (the consistent-mass coupling of
the clamped attachment node included), so that with every finite-element mode the hybrid model
is exactly the finite-element model with a free hub.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, TypeAlias

import numpy as np
import scipy.linalg
from scipy.optimize import brentq

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.control import PD
from flexsat.dynamics.hybrid import ModalHybrid
from flexsat.input_checks import FieldError, require_count
from flexsat.structures.beam import TipMassCantilever, hub_free_frequencies
from flexsat.structures.fem import Structure
from flexsat.structures.modal_model import ModalModel, hub_appendage_matrices
from flexsat.structures.sections import Material, Section
from flexsat.units import to_si

if TYPE_CHECKING:
    import xarray as xr

    import control
    from flexsat.sim.disturbances import CableSpring

#: a number of modes, or "all" for every finite-element mode
ModeCount: TypeAlias = int | Literal["all"] | None

SOURCE = CASES["nps"].source

#: values printed in Hailey, Sortun & Agrawal c. 1992, exactly as printed
PUBLISHED: dict[str, Any] = {
    "cantilever_frequency": "0.14 Hz",  # "Experimental Setup": "fundamental cantilever frequency"
    "n_modes": 6,  # "Proportional - Derivative Control": "first six cantilever modes"
    "damping": "0.4 percent",  # ibid.: "0.4 percent critical damping", all modes
    "controller_frequency": "0.06 Hz",  # "Proportional - Derivative Control" ω_n
    "controller_damping": 0.9,  # "Proportional - Derivative Control" ξ
    "position_gain": "1.3985 N*m/rad",  # "Proportional - Derivative Control" k
    "rate_gain": "6.6773 N*m*s/rad",  # "Proportional - Derivative Control" kτ
    "pd_slew_angle": "60 deg",  # "Proportional - Derivative Control"
    "sinusoid_period": "10 s",  # "Torque Shaping -- Sinusoidal"
    "lqg_slew_angle": "30 deg",  # "Optimal Control"
}

#: I = k / ω_n² = 9.84012 and kτ / (2 ζ ω_n) = 9.84005 kg m² (derived, not printed); 9.84
#: reproduces both printed gains to their printed digits.
DESIGN_INERTIA = "9.84 kg*m**2"

INERTIA_CONVENTIONS = ("cantilevered", "total")

#: the overridable inputs of the case, defaults as written
_INPUTS = {
    "cantilever_frequency": Param(PUBLISHED["cantilever_frequency"], "Hz"),
    "damping": Param(PUBLISHED["damping"], rule="nonneg"),
    "n_modes": Param(PUBLISHED["n_modes"], rule="count", limit="MAX_MODES"),
    "design_inertia": Param(DESIGN_INERTIA, "kg*m**2"),
    "inertia_convention": Param("cantilevered", rule="choice", choices=INERTIA_CONVENTIONS),
    "hub_inertia": Param(None, "kg*m**2", optional=True),  # None: solved from design_inertia
    "attachment_radius": Param("0.3 m", "m", "nonneg"),
    "mast_length": Param("1.5 m", "m"),
    "mast_mass_per_length": Param("0.25 kg/m", "kg/m"),
    "mast_bending_stiffness": Param(None, "N*m**2", optional=True),  # None: solved
    "reflector_mass": Param("1.0 kg", "kg"),
    "reflector_inertia": Param("0.02 kg*m**2", "kg*m**2", "nonneg"),
    "n_elements": Param(20, rule="count", limit="MAX_ELEMENTS"),
    "controller_frequency": Param(PUBLISHED["controller_frequency"], "Hz"),
    "controller_damping": Param(PUBLISHED["controller_damping"], rule="nonneg"),
}


@dataclass(frozen=True)
class _Solution:
    """The finite-element solution behind a case (all SI)."""

    EI: float
    modal: ModalModel  # cantilevered, every finite-element mode, reference = hub centre
    appendage_inertia: float  # R_θᵀ M R_θ of the whole appendage about the hub axis
    hub_inertia: float


@dataclass(frozen=True)
class NPSCase:
    """NPS FSS pitch-axis model (SI); build it with :func:`nps`.

    ``hub_inertia`` and ``mast_bending_stiffness`` are None when solved (see :func:`nps`); the
    solved values are :attr:`hub_inertia_value` and :attr:`mast_bending_stiffness_value`.
    """

    cantilever_frequency: float  # Hz
    damping: float
    n_modes: int
    design_inertia: float
    inertia_convention: str
    hub_inertia: float | None
    attachment_radius: float
    mast_length: float
    mast_mass_per_length: float
    mast_bending_stiffness: float | None
    reflector_mass: float
    reflector_inertia: float
    n_elements: int
    controller_frequency: float  # Hz
    controller_damping: float
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    # -- finite-element model ------------------------------------------------------------------
    @property
    def node_ids(self) -> np.ndarray:
        """Mast nodes 1 (attachment, clamped to the hub) … n_elements + 1 (reflector)."""
        return np.arange(1, self.n_elements + 2)

    @property
    def reflector_node(self) -> int:
        return self.n_elements + 1

    def structure(self, EI: float | None = None) -> Structure:
        """The appendage: beam2d mast along +x from the attachment point (clamped: the hub
        support), reflector at the tip."""
        EI = self.mast_bending_stiffness_value if EI is None else EI
        s = Structure("NPS FSS appendage")
        x = self.attachment_radius + np.linspace(0.0, self.mast_length, self.n_elements + 1)
        for node, xi in zip(self.node_ids, x):
            s.add_node(int(node), (xi, 0.0, 0.0))
        # equivalent beam: E·Iz = EI and rho·A = mass per length on a unit section
        mast = Material(E=EI, rho=self.mast_mass_per_length, name="astromast (equivalent)")
        unit = Section.general(1.0, 1.0, 1.0, 1.0, name="unit section")
        for a, b in zip(self.node_ids[:-1], self.node_ids[1:]):
            s.add_beam2d(int(a), int(b), mast, unit, label="mast")
        s.add_mass(
            self.reflector_node, self.reflector_mass, inertia=(0.0, 0.0, self.reflector_inertia)
        )
        s.clamp(self.reflector_node, ("uz", "rx", "ry"))  # planar: out-of-plane dofs of the mass
        for node in self.node_ids:
            s.clamp(int(node), ("ux",))  # axially rigid mast
        s.clamp(1)
        return s

    def _first_frequency(self, EI: float) -> float:
        return float(self.structure(EI).assemble().modes(1).frequencies_hz[0])

    def _solve_EI(self) -> float:
        """EI with first cantilever frequency = ``cantilever_frequency`` (Brent's method).

        Start from the Rayleigh estimate of a tip-mass cantilever, 3 EI / L³ = ω² (M + 33/140 ρL),
        and bracket by factors of 4."""
        L, w = self.mast_length, 2 * np.pi * self.cantilever_frequency
        guess = w**2 * L**3 * (self.reflector_mass + 33 / 140 * self.mast_mass_per_length * L) / 3
        lo, hi = guess / 4, guess * 4
        target = self.cantilever_frequency
        f = lambda ei: self._first_frequency(ei) - target  # noqa: E731
        while f(lo) > 0:
            lo /= 4
        while f(hi) < 0:
            hi *= 4
        return float(
            brentq(f, lo, hi, xtol=1e-14 * guess, rtol=4 * np.finfo(float).eps, maxiter=200)
        )

    @property
    def _solution(self) -> _Solution:
        if "solution" not in self._cache:
            self._cache["solution"] = self._solve()
        return self._cache["solution"]

    def _solve(self) -> _Solution:
        EI = self.mast_bending_stiffness_value
        clamped = self.structure(EI).assemble()
        modes = clamped.modes(clamped.n_dofs)
        # hybrid coordinates about the hub centre: from_fe uses the whole appendage's mass
        # (the attachment node moves with the hub), L = Φᵀ (M_full R) on the clamped dofs
        modal = ModalModel.from_fe(modes, self.damping, boundary="cantilevered")
        I_app = float(modal.rigid_mass[5, 5])
        if self.hub_inertia is not None:
            hub = self.hub_inertia
        else:
            if self.n_modes > modal.n_modes:
                raise FieldError(
                    "n_modes", f"the model has {modal.n_modes} modes; raise n_elements"
                )
            D = modal.participation[: self.n_modes, 5]
            appendage_share = I_app - (
                float(D @ D) if self.inertia_convention == "cantilevered" else 0.0
            )
            hub = self.design_inertia - appendage_share
            if hub <= 0:
                which = "I0zz" if self.inertia_convention == "cantilevered" else "I_zz"
                raise FieldError(
                    "design_inertia",
                    f"{self.design_inertia:.6g} kg m² is too small for {which}: the "
                    f"appendage alone contributes {appendage_share:.6g} kg m², so the hub inertia "
                    "would not be positive (lighten the appendage or change inertia_convention)",
                )
        return _Solution(EI=EI, modal=modal, appendage_inertia=I_app, hub_inertia=float(hub))

    # -- solved values -------------------------------------------------------------------------
    @property
    def mast_bending_stiffness_value(self) -> float:
        """Mast EI, N m² (solved for ``cantilever_frequency`` unless given)."""
        if self.mast_bending_stiffness is not None:
            return self.mast_bending_stiffness
        if "EI" not in self._cache:
            self._cache["EI"] = self._solve_EI()
        return self._cache["EI"]

    @property
    def hub_inertia_value(self) -> float:
        """Inertia of the hub alone (with the wheel) about z, kg m²."""
        return self._solution.hub_inertia

    @property
    def appendage_inertia(self) -> float:
        """Rigid inertia of the whole appendage about the hub axis, kg m²."""
        return self._solution.appendage_inertia

    @property
    def appendage_inertia_exact(self) -> float:
        """ρ((r+L)³ − r³)/3 + m_R (r+L)² + J_R, kg m² (continuous mast)."""
        r, L = self.attachment_radius, self.mast_length
        return (
            self.mast_mass_per_length * ((r + L) ** 3 - r**3) / 3
            + self.reflector_mass * (r + L) ** 2
            + self.reflector_inertia
        )

    @property
    def total_inertia(self) -> float:
        """I_zz = hub + appendage (Eq. 7), kg m²."""
        return self.hub_inertia_value + self.appendage_inertia

    def coupling(self, n_modes: ModeCount = None) -> np.ndarray:
        """Rigid–elastic coupling D_i = ∫(x φ_iʸ − y φ_iˣ) dm (Eq. 10), kg^½ m, first n modes."""
        return self.modal_model(n_modes).participation[:, 5].copy()

    def cantilevered_inertia(self, n_modes: ModeCount = None) -> float:
        """I⁰zz = I_zz − Σ D_i² over the first ``n_modes`` modes (Eq. 18), kg m²."""
        D = self.coupling(n_modes)
        return self.total_inertia - float(D @ D)

    # -- modal model and hybrid matrices -------------------------------------------------------
    def modal_model(self, n_modes: ModeCount = None) -> ModalModel:
        """Cantilevered modal model of the appendage (reference: hub centre, the rotation axis).

        ``n_modes`` defaults to the case's (6); ``"all"`` keeps every finite-element mode."""
        modal = self._solution.modal
        if n_modes == "all":
            return modal
        n = self.n_modes if n_modes is None else require_count(n_modes, "n_modes")
        if n > modal.n_modes:
            raise FieldError(
                "n_modes",
                f"the finite-element model has {modal.n_modes} modes; raise "
                f"n_elements for more than that, got {n}",
            )
        return modal.truncate(n)

    def model(self, n_modes: ModeCount = None) -> ModalHybrid:
        """The simulator plant: hub + appendage in hybrid coordinates (Eq. 16), with the
        reflector's transverse displacement as ``tip_deflection``."""
        return ModalHybrid(
            self.modal_model(n_modes),
            self.hub_inertia_value,
            axis="z",
            tip=(self.reflector_node, "y"),
        )

    @property
    def reference_inertia(self) -> float:
        """Rigid inertia the shaped references and the PD gains are designed on (the case's
        ``design_inertia`` = 9.84 kg m², see ``inertia_convention``)."""
        return self.design_inertia

    def hybrid_matrices(
        self, n_modes: ModeCount = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Second-order model of Eq. 16 in (θ, q_1 … q_n): M = [[I_zz, Dᵀ], [D, I]],
        K = diag(0, ω²), C = diag(0, 2ζω). Returns (M, C, K)."""
        modal = self.modal_model(n_modes)
        M, C, K = hub_appendage_matrices(modal, self.hub_inertia_value, axis="z")
        return M, C, K

    def statespace_eq18(
        self, n_modes: ModeCount = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) of Eqs. 16–19 exactly as repaired (the print has misprints).

        X = [θ, q_1..q_n, θ', q'_1..q'_n], U = T_t (total torque on the hub), Y = [θ, θ'];
        I0 = I_zz − Σ D_i², F_i = D_i ω_i², G_i = ω_i² I0 + D_i F_i, H_i = 2ζ_iω_i D_i,
        J_i = 2ζ_iω_i I0 + D_i H_i, A = (1/I0)[…]."""
        modal = self.modal_model(n_modes)
        n, w, z = modal.n_modes, modal.frequencies, modal.damping
        D = modal.participation[:, 5]
        I0 = self.total_inertia - D @ D
        F = D * w**2
        G = w**2 * I0 + D * F
        H = 2 * z * w * D
        J = 2 * z * w * I0 + D * H
        N = 2 * n + 2
        A = np.zeros((N, N))
        A[: n + 1, n + 1 :] = I0 * np.eye(n + 1)  # the kinematic rows, I0·I inside the 1/I0
        A[n + 1, 1 : n + 1] = F
        A[n + 1, n + 2 :] = H
        for i in range(n):
            row = n + 2 + i
            A[row, 1 : n + 1] = -D[i] * F
            A[row, 1 + i] = -G[i]
            A[row, n + 2 :] = -D[i] * H
            A[row, n + 2 + i] = -J[i]
        A /= I0
        B = np.zeros((N, 1))
        B[n + 1, 0] = 1.0
        B[n + 2 :, 0] = -D
        B /= I0
        C = np.zeros((2, N))
        C[0, 0] = C[1, n + 1] = 1.0
        return A, B, C, np.zeros((2, 1))

    def statespace_direct(
        self, n_modes: ModeCount = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) from the second-order model: A = [[0, I], [−M⁻¹K, −M⁻¹C]],
        B = [0; M⁻¹e₁]."""
        M, Cd, K = self.hybrid_matrices(n_modes)
        k = M.shape[0]
        Minv = np.linalg.inv(M)
        A = np.block([[np.zeros((k, k)), np.eye(k)], [-Minv @ K, -Minv @ Cd]])
        B = np.vstack([np.zeros((k, 1)), Minv[:, :1]])
        C = np.zeros((2, 2 * k))
        C[0, 0] = C[1, k] = 1.0
        return A, B, C, np.zeros((2, 1))

    def to_statespace(self, n_modes: ModeCount = None) -> control.StateSpace:
        """python-control StateSpace of Eq. 18 (input T_t, outputs θ and θ')."""
        import control

        n = self.modal_model(n_modes).n_modes
        states = (
            ["theta"]
            + [f"q[{i}]" for i in range(n)]
            + ["theta_dot"]
            + [f"q_dot[{i}]" for i in range(n)]
        )
        return control.ss(
            *self.statespace_eq18(n_modes),
            states=states,
            inputs=["torque"],
            outputs=["theta", "theta_dot"],
        )

    # -- frequencies ---------------------------------------------------------------------------
    def system_frequencies(self, n_modes: ModeCount = None) -> np.ndarray:
        """Hub-free (unconstrained) elastic frequencies of the hybrid model, rad/s (rigid mode
        removed): generalized eigenvalues of (K, M) of Eq. 16."""
        M, _, K = self.hybrid_matrices(n_modes)
        lam = scipy.linalg.eigh(K, M, eigvals_only=True)
        return np.sqrt(np.clip(np.sort(lam)[1:], 0.0, None))

    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        """First ``n_modes`` hub-free elastic frequencies of the six-mode hybrid model, Hz."""
        n = require_count(n_modes, "n_modes")
        if n > self.n_modes:
            raise FieldError(
                "n_modes", f"the model has {self.n_modes} modes; raise n_modes to at least {n}"
            )
        return self.system_frequencies()[:n] / (2 * np.pi)

    def mode_descriptions(self, n_modes: int) -> list[str]:
        n = min(require_count(n_modes, "n_modes"), self.n_modes)
        return [f"mast + reflector bending, cantilever mode {i + 1}" for i in range(n)]

    def mode_details(self, n_modes: int) -> dict:
        """Cantilever (hub clamped) frequencies, finite-element and exact; hub-free frequencies
        with every finite-element mode and exact (``frequencies_hz`` is the six-mode model's);
        couplings D_i and the inertia budget (for ``flexsat modes``)."""
        n = min(require_count(n_modes, "n_modes"), self.n_modes)
        beam = TipMassCantilever(
            self.mast_length,
            self.mast_bending_stiffness_value,
            self.mast_mass_per_length,
            self.reflector_mass,
            self.reflector_inertia,
        )
        exact_free = hub_free_frequencies(
            beam, self.attachment_radius, self.hub_inertia_value, 1, n
        )
        return {
            "constrained_hz": (beam.frequencies(n) / (2 * np.pi)).tolist(),
            "constrained_fe_hz": self.modal_model().frequencies_hz[:n].tolist(),
            "system_all_fe_modes_hz": (self.system_frequencies("all")[:n] / (2 * np.pi)).tolist(),
            "exact_unconstrained_hz": (exact_free / (2 * np.pi)).tolist(),
            "coupling_D_sqrt_kg_m": self.coupling()[:n].tolist(),
            "mast_bending_stiffness_N_m2": self.mast_bending_stiffness_value,
            "inertia_convention": self.inertia_convention,
            "inertia_budget_kg_m2": inertia_budget(self),
        }

    # -- control -------------------------------------------------------------------------------
    def pd_gains(self, **kwargs: Any) -> PD:
        """Rigid-body pole placement (Eqs. 20–24): k = I ω_n², kτ = 2ζω_n I with
        I = ``design_inertia``; keyword arguments go to :class:`~flexsat.control.PD`."""
        return PD.from_rigid_poles(
            self.design_inertia,
            2 * np.pi * self.controller_frequency,
            self.controller_damping,
            **kwargs,
        )

    def cable_slew(
        self,
        cable: CableSpring | None = None,
        duration: float = 400.0,
        control_rate: float = 20.0,
        **pd: Any,
    ) -> xr.Dataset:
        """The 60° PD step slew (Eq. 20) with the cable-spring torque on the hub (default a
        constant T_D = 1 mN m), ideal sensors, long enough for the closed loop to settle to
        θ_ss = T_D / k (Eq. 23): the recorded run (the Python loop: the cable is a
        position-dependent input force)."""
        from flexsat.sim.channels import ChannelDisturbance
        from flexsat.sim.config import SimConfig
        from flexsat.sim.disturbances import CableSpring
        from flexsat.sim.engine import simulate

        cable = CableSpring(constant=1e-3) if cable is None else cable  # 1 mN m
        config = SimConfig(
            duration=duration,
            control_rate=control_rate,
            channel_disturbances={
                "torque": ChannelDisturbance(force=cable, force_output="theta", force_name="cable")
            },
        )
        law = self.pd_gains(target=self.slew_angle, **pd)
        return simulate(self.model(), law, config).dataset

    @property
    def slew_angle(self) -> float:
        """60°, the PD and torque-shaping slews ("Proportional - Derivative Control"), rad."""
        return to_si(PUBLISHED["pd_slew_angle"], "rad")


def inertia_budget(case: NPSCase) -> dict[str, float]:
    """Rigid inertia budget about the hub axis, kg m²."""
    return {
        "hub": case.hub_inertia_value,
        "appendage": case.appendage_inertia,
        "appendage_continuous": case.appendage_inertia_exact,
        "I_zz": case.total_inertia,
        "I0_zz": case.cantilevered_inertia(),
        "design": case.design_inertia,
    }


def nps(**overrides: Any) -> NPSCase:
    """Build the NPS FSS case; override any input by name, as a number (SI) or a unit string.

    ``mast_bending_stiffness`` is solved for ``cantilever_frequency`` unless given (then the
    frequency follows from it and ``cantilever_frequency`` may not be given too);
    ``hub_inertia`` is solved from ``design_inertia`` and ``inertia_convention`` unless given.

    >>> case = nps(mast_length="2 m", inertia_convention="total")
    """
    if "mast_bending_stiffness" in overrides and "cantilever_frequency" in overrides:
        raise FieldError(
            "mast_bending_stiffness",
            "give either it or cantilever_frequency (it is solved for that frequency), not both",
        )
    values = read_inputs("nps", _INPUTS, overrides)
    if values["n_elements"] < 2:
        raise FieldError("n_elements", f"must be >= 2, got {values['n_elements']}")
    if values["damping"] >= 1:
        raise FieldError(
            "damping", f"must be < 1 (a ratio of critical damping), got {values['damping']!r}"
        )
    if 2 * values["n_elements"] < values["n_modes"]:
        raise FieldError(
            "n_modes",
            f"the mesh of {values['n_elements']} elements has "
            f"{2 * values['n_elements']} modes; raise n_elements",
        )
    case = NPSCase(**values)
    case._solution  # noqa: B018 -- solve and validate now: one clear message at construction
    return case


__all__ = [
    "DESIGN_INERTIA",
    "INERTIA_CONVENTIONS",
    "NPSCase",
    "PUBLISHED",
    "SOURCE",
    "inertia_budget",
    "nps",
]
