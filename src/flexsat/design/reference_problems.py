r"""Reference design problems: one with a closed-form optimum, one structure + control.

1. **Minimum-mass cantilever tube with a first-frequency floor** (Euler–Bernoulli beam).
   A clamped-free tube of length L, outer diameter D and wall t has

   .. math::

       m = \rho L \pi t (D - t), \qquad
       \omega_1 = \frac{(\beta_1 L)^2}{L^2}\sqrt{\frac{E}{\rho}\frac{I}{A}}, \qquad
       \frac{I}{A} = \frac{D^2 + (D - 2t)^2}{16},

   β₁L = 1.8751040687… the first root of cos βL cosh βL = −1 (S. S. Rao, *Vibration of
   Continuous Systems*, Wiley 2007, §11.5; the tube's I and A: W. C. Young and R. G. Budynas,
   *Roark's Formulas for Stress and Strain*, 7th ed., Table A.1). Minimise m subject to
   ω₁ >= ω_min, t_min <= t <= t_max, D_min <= D <= D_max. Mass grows with D and t, ω₁ grows
   with D and falls with t, so (when the bounds allow) the wall sits at t_min and the frequency
   floor is met exactly: D* = t_min + sqrt(8 r² − t_min²) with r² = (ω_min L² / (β₁L)²)² ρ / E,
   and the multipliers (minimisation convention, ∇m + λ ∇(ω_min − ω₁) + μ ∇(t_min − t) = 0)
   are λ = (∂m/∂D)/(∂ω₁/∂D), μ = ∂m/∂t − λ ∂ω₁/∂t (:func:`cantilever_tube_optimum`).

2. **Hub with booms, single axis: wall thickness and diameter against an LQ slew cost**
   (:class:`HubBoomCodesign`). A hub of inertia J_h pinned about z carries identical tube booms
   with tip masses; in the hub-coupled (antisymmetric) motion each boom sees the hub inertia
   shared out, so one boom on J_h / (number of booms) is modelled (the symmetric modes do not
   couple to the hub torque and are left out). FE frames (in-plane bending: uy, rz per node;
   hub: rz) give the rigid rotation mode φ₀ = r / sqrt(rᵀMr) (r the rigid rotation field) and
   the lowest elastic modes (Fox–Kapoor and Nelson derivatives, :mod:`flexsat.analysis.
   fe_sensitivity`). The modal plant η̈ + 2ζΩη̇ + Ω²η = Φ_hᵀ u (u the hub torque) is regulated
   from a hub-angle error θ₀ at rest with weights on hub angle, hub rate and the elastic tip
   deflection d = y_tip − x_tip θ_hub; J_LQ = tr(S X₀) and its gradient come from
   :func:`flexsat.analysis.riccati_sensitivity.lq_cost_gradient` (∂J/∂A, ∂J/∂B, ∂J/∂Q by one
   adjoint Lyapunov solve; ∂J/∂X₀ = S) chained through ∂A, ∂B, ∂Q, ∂X₀ of the two section
   dimensions. Minimise J_LQ + w_m · (structural mass) subject to f₁ >= f_min.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, NamedTuple

import numpy as np
from scipy.optimize import brentq

from flexsat.analysis.fe_sensitivity import (
    FEModalDerivatives,
    TubeSection,
    fe_modal_derivatives,
    fe_parameter_matrices,
)
from flexsat.analysis.riccati_sensitivity import chain_gradient, lq_cost_gradient
from flexsat.analysis.sampled_sensitivity import (
    smooth_peak,
    soft_settling,
    terminal_energy,
    terminal_error,
)
from flexsat.design.describe import DesignFeature, sorted_poles
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.design.sampled_loop import loop_gradient, sampled_lq_loop
from flexsat.input_checks import FieldError, require_positive_scalar
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section
from flexsat.units import FloatArray

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "CANTILEVER_BETA1_L",
    "CantileverTube",
    "HubBoomCodesign",
    "ModalPlant",
    "cantilever_tube_optimum",
]

#: first root of cos(x) cosh(x) = −1 (clamped-free beam), to machine precision
CANTILEVER_BETA1_L = float(
    brentq(
        lambda b: np.cos(b) * np.cosh(b) + 1.0, 1.5, 2.5, xtol=1e-15, rtol=4 * np.finfo(float).eps
    )
)


# -- 1. cantilever tube ------------------------------------------------------------------------
@dataclass(frozen=True)
class CantileverTube:
    """Minimum-mass clamped-free tube with a first-frequency floor (SI; see the module notes).

    Variables, in order: wall ``t`` (m), outer diameter ``D`` (m), started at the upper bounds.
    """

    length: float = 2.0
    youngs_modulus: float = 70e9
    density: float = 2700.0
    omega_min: float = 2 * np.pi * 20.0
    thickness_bounds: tuple[float, float] = (1e-3, 10e-3)
    diameter_bounds: tuple[float, float] = (25e-3, 0.2)

    def __post_init__(self) -> None:
        for name in ("length", "youngs_modulus", "density", "omega_min"):
            require_positive_scalar(getattr(self, name), name)
        for name in ("thickness_bounds", "diameter_bounds"):
            lo, hi = getattr(self, name)
            if not 0 < lo < hi:
                raise FieldError(name, f"must be 0 < lower < upper, got {(lo, hi)}")
        if 2 * self.thickness_bounds[1] >= self.diameter_bounds[0]:
            raise FieldError("diameter_bounds", "the lower diameter must exceed twice the wall")

    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        """mass (kg) and ω₁ (rad/s) with their gradients w.r.t. (t, D)."""
        t, D = float(x[0]), float(x[1])
        rho, L = self.density, self.length
        c = CANTILEVER_BETA1_L**2 / L**2 * np.sqrt(self.youngs_modulus / rho)
        sq = np.sqrt((D**2 + (D - 2 * t) ** 2) / 16.0)
        mass = rho * L * np.pi * t * (D - t)
        dmass = rho * L * np.pi * np.array([D - 2 * t, t])
        omega = c * sq
        domega = c / (8.0 * sq) * np.array([-(D - 2 * t), D - t])
        return {"mass": (mass, dmass), "omega": (omega, domega)}

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]:
        """The tube's first bending frequency (Hz, Euler–Bernoulli, module notes) and its
        section (wall, outer diameter, I/A) at ``x`` = (t, D)."""
        t, D = float(x[0]), float(x[1])
        omega = self.responses(np.array([t, D]))["omega"][0]
        return {
            "first bending frequency": DesignFeature(
                "structure",
                np.array([omega / (2 * np.pi)]),
                "Hz",
                note="clamped-free Euler–Bernoulli tube, (β₁L)² √(EI/(ρA)) / (2π L²)",
            ),
            "I/A": DesignFeature(
                "structure",
                np.array([(D**2 + (D - 2 * t) ** 2) / 16.0]),
                "m**2",
                note="(D² + (D − 2t)²)/16 of the thin-walled tube",
            ),
        }

    def problem(self) -> DesignProblem:
        (tl, tu), (dl, du) = self.thickness_bounds, self.diameter_bounds
        return DesignProblem(
            variables=(
                DesignVariable("t", tu, tl, tu, scale=tl, unit="m"),
                DesignVariable("D", du, dl, du, scale=du / 4, unit="m"),
            ),
            objective=Objective("mass", lambda x: self.responses(x)["mass"], unit="kg"),
            constraints=(
                Constraint(
                    "frequency floor",
                    lambda x: _floor(self.omega_min, self.responses(x)["omega"]),
                    scale=self.omega_min,
                    unit="rad/s",
                ),
            ),
        )


def _floor(bound: float, value: tuple[float, FloatArray]) -> tuple[float, FloatArray]:
    """bound − value <= 0, with its gradient."""
    return bound - value[0], -value[1]


def cantilever_tube_optimum(tube: CantileverTube) -> dict[str, float]:
    """Closed-form optimum of :class:`CantileverTube`: t, D, mass, λ (frequency), μ (t_min).

    Valid when D* lies inside the diameter bounds (refused by name otherwise).
    """
    t = tube.thickness_bounds[0]
    r2 = (tube.omega_min * tube.length**2 / CANTILEVER_BETA1_L**2) ** 2 * (
        tube.density / tube.youngs_modulus
    )
    D = t + np.sqrt(8 * r2 - t**2)
    if not tube.diameter_bounds[0] < D < tube.diameter_bounds[1]:
        raise FieldError("diameter_bounds", f"the closed-form D* = {D:.6g} m lies outside them")
    r = tube.responses(np.array([t, D]))
    dm, dw = r["mass"][1], r["omega"][1]
    lam = dm[1] / dw[1]
    return {
        "t": t,
        "D": float(D),
        "mass": r["mass"][0],
        "frequency floor": float(lam),
        "t >= lower": float(dm[0] - lam * dw[0]),
    }


# -- 2. hub with booms -------------------------------------------------------------------------
class ModalPlant(NamedTuple):
    """The hub-boom modal plant (A, B, C, Q), ω, their derivative stacks (P, ...) w.r.t. the
    section dimensions, and the rigid-mode state x₀ of the hub at θ₀ with its derivative."""

    A: FloatArray
    B: FloatArray
    C: FloatArray
    Q: FloatArray
    omega: FloatArray
    dA: FloatArray
    dB: FloatArray
    dC: FloatArray
    dQ: FloatArray
    domega: FloatArray
    x0: FloatArray
    dx0: FloatArray


@dataclass(frozen=True)
class HubBoomCodesign:
    """Single-axis hub with tube booms: (t, D) against J_LQ + w_m · mass, f₁ >= f_min.

    Attributes (SI)
    ----------
    length : boom length, m;  elements : frames per boom
    youngs_modulus, density : boom material
    hub_inertia : J_h, kg m² (whole hub);  booms : number of identical booms
    tip_mass : kg per boom
    damping : modal damping ratio of the elastic modes
    elastic_modes : elastic modes kept in the plant
    weights : (hub angle, 1/rad²; hub rate, s²/rad²; tip deflection, 1/m²) per second
    control_weight : R, 1/(N m)² per second
    initial_angle : θ₀, rad
    mass_weight : w_m, cost per kg
    frequency_min_hz : f_min, Hz
    thickness_bounds, diameter_bounds : m
    start : (t, D), m
    maneuver : also report the sampled slew's metrics (below)
    control_rate : Hz;  maneuver_time : T, s (a whole number of samples)
    peak_order : p of the smooth peak torque;  settling_band : b, rad
    settling_width : w, the relative width of the band's smoothed edge

    With ``maneuver`` the responses also hold the metrics of a slew of the hub from rest at 0
    to θ_f = θ₀, run on the engine (:func:`flexsat.design.sampled_loop.sampled_lq_loop`)
    under the discrete LQR law u_k = −K(x_k − x_f) of the ZOH model at ``control_rate``
    (weights Q h and R h, Q = Cᵀ diag(weights) C as for J_LQ) over T: ``residual_energy``
    ½Σ(η̇ᵢ² + ωᵢ²ηᵢ²) of the elastic modes at T (J), ``pointing_error_sq`` (θ_hub(T) − θ_f)²
    (rad²), ``peak_torque`` the p-norm of the torque samples (N m; the true peak lies in
    [‖u‖_p (NT)^(−1/p), ‖u‖_p]) and ``soft_settling`` the smoothed time outside the band
    |θ_hub − θ_f| ≤ b (s; :mod:`flexsat.analysis.sampled_sensitivity`). u is the torque on
    one boom's share J_h / booms of the hub (the half-model). Their gradients come from the
    discrete adjoint (:func:`flexsat.design.sampled_loop.loop_gradient`) chained through the
    same ∂A, ∂B, ∂C, ∂Q, ∂x₀ stacks as J_LQ, plus the metrics' own weights (Ω² in the energy,
    the hub row of the modes in θ_hub).
    """

    #: the responses of the sampled slew (with ``maneuver``)
    MANEUVER_RESPONSES: ClassVar[tuple[str, ...]] = (
        "residual_energy",
        "pointing_error_sq",
        "peak_torque",
        "soft_settling",
    )

    length: float = 1.2
    elements: int = 6
    youngs_modulus: float = 70e9
    density: float = 2700.0
    hub_inertia: float = 0.4
    booms: int = 4
    tip_mass: float = 0.2
    damping: float = 0.005
    elastic_modes: int = 3
    weights: tuple[float, float, float] = (100.0, 1.0, 1e4)
    control_weight: float = 1.0
    initial_angle: float = 0.5
    mass_weight: float = 20.0
    frequency_min_hz: float = 6.0
    thickness_bounds: tuple[float, float] = (0.5e-3, 3e-3)
    diameter_bounds: tuple[float, float] = (10e-3, 60e-3)
    start: tuple[float, float] = (2e-3, 40e-3)
    maneuver: bool = False
    control_rate: float = 50.0
    maneuver_time: float = 3.0
    peak_order: int = 16
    settling_band: float = float(np.radians(0.5))
    settling_width: float = 0.2
    _memo: dict[bytes, dict[str, tuple[float, FloatArray]]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in (
            "length",
            "youngs_modulus",
            "density",
            "hub_inertia",
            "tip_mass",
            "damping",
            "control_weight",
            "initial_angle",
            "mass_weight",
            "frequency_min_hz",
            "control_rate",
            "maneuver_time",
            "settling_band",
            "settling_width",
        ):
            require_positive_scalar(getattr(self, name), name)
        steps = self.maneuver_time * self.control_rate
        if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
            raise FieldError(
                "maneuver_time", f"must be a whole number of {1 / self.control_rate:g} s samples"
            )
        if not isinstance(self.maneuver, bool):
            raise FieldError("maneuver", f"must be true or false, got {self.maneuver!r}")
        if (
            isinstance(self.peak_order, bool)
            or not isinstance(self.peak_order, int)
            or self.peak_order < 2
            or self.peak_order % 2
        ):
            raise FieldError("peak_order", f"must be an even integer >= 2, got {self.peak_order!r}")
        for name in ("elements", "booms", "elastic_modes"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise FieldError(name, f"must be an integer >= 1, got {value!r}")
        if len(self.weights) != 3 or not all(np.isfinite(w) and w >= 0 for w in self.weights):
            raise FieldError("weights", f"must be three finite numbers >= 0, got {self.weights}")
        if self.weights[0] == 0:
            raise FieldError("weights", "the hub-angle weight must be > 0 (detectability)")

    def structure(self, t: float, D: float) -> Structure:
        """The half-model: hub node 0 (rz) and one boom along x, in-plane bending only."""
        s = Structure("hub with boom")
        n = self.elements
        s.add_node(0, (0.0, 0.0, 0.0))
        for i in range(1, n + 1):
            s.add_node(i, (self.length * i / n, 0.0, 0.0))
        material = Material(self.youngs_modulus, self.density)
        for i in range(n):
            s.add_frame(i, i + 1, material, Section.tube(D, t))
        s.add_mass(0, 0.0, inertia=(0.0, 0.0, self.hub_inertia / self.booms))
        s.add_mass(n, self.tip_mass)
        for i in range(n + 1):  # out-of-plane and axial dofs are not modelled
            s.clamp(i, ("ux", "uz", "rx", "ry"))
        s.clamp(0, ("uy",))  # the hub is pinned
        return s

    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        """J_LQ, structural mass (kg, one boom with its tip mass) and f₁ (Hz), with gradients
        w.r.t. (t, D)."""
        key = np.asarray(x, dtype=float).tobytes()
        if key not in self._memo:
            self._memo.clear()
            self._memo[key] = self._evaluate(float(x[0]), float(x[1]))
        return self._memo[key]

    def modal_plant(self, x: FloatArray) -> ModalPlant:
        """The modal plant at design x = (t, D) with its derivative stacks (the J_LQ and
        maneuver responses are built on it)."""
        return self._modal(float(x[0]), float(x[1]))[0]

    def _modal(self, t: float, D: float) -> tuple[ModalPlant, FEModalDerivatives]:
        s = self.structure(t, D)
        group = tuple(range(self.elements))
        params = [TubeSection("thickness", group, D, t), TubeSection("outer_diameter", group, D, t)]
        ne = self.elastic_modes
        d = fe_modal_derivatives(s, params, list(range(1, ne + 1)), rigid_body_modes=1)
        mats = fe_parameter_matrices(s, params)
        asm = d.assembly
        P, N = len(params), ne + 1
        # rigid rotation field r (rz = 1, uy = x) and its mass-normalised mode
        r = np.zeros(asm.n_dofs)
        for node, dof in asm.dofs:
            r[asm.index(node, dof)] = 1.0 if dof == "rz" else (self.length * node / self.elements)
        Jt = float(r @ (asm.M @ r))
        dJt = np.array([float(r @ (dM @ r)) for dM in mats.dM])
        phi = np.column_stack([r / np.sqrt(Jt), d.modes])
        dphi = np.concatenate(
            [(-0.5 * Jt**-1.5 * dJt)[:, None, None] * r[None, :, None], d.mode_gradient], axis=2
        )
        omega = np.concatenate([[0.0], d.omegas])
        domega = np.concatenate([np.zeros((P, 1)), d.omega_gradient], axis=1)
        hub, tip = asm.index(0, "rz"), asm.index(self.elements, "uy")
        A, B, C = self._plant(omega, phi, hub, tip)
        dA, dB, dC = (
            np.stack(m)
            for m in zip(*(self._plant(omega, phi, hub, tip, domega[k], dphi[k]) for k in range(P)))
        )
        W = np.diag(self.weights)
        Q = C.T @ W @ C
        dQ = np.stack([dC[k].T @ W @ C + C.T @ W @ dC[k] for k in range(P)])
        x0 = np.zeros(2 * N)
        x0[0] = self.initial_angle * np.sqrt(Jt)  # η₀ with θ_hub = θ₀, elastic modes at rest
        dx0 = np.zeros((P, 2 * N))
        dx0[:, 0] = self.initial_angle * 0.5 / np.sqrt(Jt) * dJt
        return ModalPlant(A, B, C, Q, omega, dA, dB, dC, dQ, domega, x0, dx0), d

    def _evaluate(self, t: float, D: float) -> dict[str, tuple[float, FloatArray]]:
        plant, d = self._modal(t, D)
        A, B, Q, dA, dB, dQ, x0, dx0 = (
            plant.A,
            plant.B,
            plant.Q,
            plant.dA,
            plant.dB,
            plant.dQ,
            plant.x0,
            plant.dx0,
        )
        P = dA.shape[0]
        X0 = np.outer(x0, x0)
        dX0 = np.stack([np.outer(dx0[k], x0) + np.outer(x0, dx0[k]) for k in range(P)])
        g = lq_cost_gradient(A, B, Q, np.array([[self.control_weight]]), X0)
        dJ = chain_gradient([(g.dA, dA), (g.dB, dB), (g.dQ, dQ), (g.S, dX0)])
        out = {
            "lq_cost": (g.cost, dJ),
            "mass": (d.mass, d.mass_gradient),
            "frequency_hz": (float(d.frequencies_hz[0]), d.frequency_hz_gradient[:, 0]),
        }
        if self.maneuver:
            out.update(self._maneuver(plant))
        return out

    def _maneuver(self, m: ModalPlant) -> dict[str, tuple[float, FloatArray]]:
        """The sampled slew from rest to θ_f = θ₀ under the discrete LQR law and its metrics
        with their adjoint gradients (class docstring)."""
        h = 1.0 / self.control_rate
        steps = int(round(self.maneuver_time * self.control_rate))
        n = m.A.shape[0]
        N = n // 2
        R = np.array([[self.control_weight * h]])
        loop = sampled_lq_loop(m.A, m.B, m.Q * h, R, h, steps, np.zeros(n), m.x0)
        c, dc = m.C[0], m.dC[:, 0, :]  # hub angle θ_hub = cᵀx
        theta_f = self.initial_angle
        W = np.zeros((n, n))  # ½η̇ᵀη̇ + ½ηᵀΩ²η of the elastic modes
        W[np.arange(1, N), np.arange(1, N)] = m.omega[1:] ** 2
        W[np.arange(N + 1, n), np.arange(N + 1, n)] = 1.0
        dW = np.zeros((m.domega.shape[0], n, n))
        dW[:, np.arange(1, N), np.arange(1, N)] = 2 * m.omega[1:] * m.domega[:, 1:]
        X, U = loop.X, loop.U
        metrics = {
            "residual_energy": terminal_energy(X, U, W),
            "pointing_error_sq": terminal_error(X, U, c, theta_f),
            "peak_torque": smooth_peak(X, U, self.peak_order),
            "soft_settling": soft_settling(
                X, U, c, theta_f, self.settling_band, self.settling_width, h
            ),
        }
        out = {}
        for name, mv in metrics.items():
            g = loop_gradient(loop, mv)
            pairs: list[tuple[npt.ArrayLike, npt.ArrayLike]] = [
                (g.dA, m.dA),
                (g.dB, m.dB),
                (g.dQ * h, m.dQ),
                (g.dr[None], m.dx0[:, None]),
            ]
            if "W" in mv.weights:
                pairs.append((mv.weights["W"], dW))
            if "c" in mv.weights:
                pairs.append((mv.weights["c"][None], dc[:, None]))
            out[name] = (mv.value, chain_gradient(pairs))
        return out

    def _plant(
        self,
        omega: FloatArray,
        phi: FloatArray,
        hub: int,
        tip: int,
        domega: FloatArray | None = None,
        dphi: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Modal (A, B, C), or their derivatives when (domega, dphi) are given (A, B and C are
        affine in ω², ω and Φ, so the derivative is the same assembly of the derivatives)."""
        N = omega.size
        zeta = np.full(N, self.damping)
        zeta[0] = 0.0
        if domega is None or dphi is None:
            stiff, damp, shape, eye = omega**2, 2 * zeta * omega, phi, np.eye(N)
        else:
            stiff, damp, shape, eye = 2 * omega * domega, 2 * zeta * domega, dphi, np.zeros((N, N))
        zero = np.zeros((N, N))
        A = np.block([[zero, eye], [-np.diag(stiff), -np.diag(damp)]])
        B = np.concatenate([np.zeros(N), shape[hub]])[:, None]
        x_tip = self.length
        deflection = shape[tip] - x_tip * shape[hub]  # zero for the rigid mode
        z = np.zeros(N)
        C = np.array(
            [
                np.concatenate([shape[hub], z]),
                np.concatenate([z, shape[hub]]),
                np.concatenate([deflection, z]),
            ]
        )
        return A, B, C

    def objective_value(self, x: FloatArray) -> tuple[float, FloatArray]:
        """J_LQ + w_m · mass and its gradient."""
        r = self.responses(x)
        return (
            r["lq_cost"][0] + self.mass_weight * r["mass"][0],
            r["lq_cost"][1] + self.mass_weight * r["mass"][1],
        )

    def problem(self) -> DesignProblem:
        (tl, tu), (dl, du) = self.thickness_bounds, self.diameter_bounds
        f0 = self.objective_value(np.array(self.start))[0]
        return DesignProblem(
            variables=(
                DesignVariable("t", self.start[0], tl, tu, scale=1e-3, unit="m"),
                DesignVariable("D", self.start[1], dl, du, scale=1e-2, unit="m"),
            ),
            objective=Objective("LQ cost + mass penalty", self.objective_value, scale=abs(f0)),
            constraints=(
                Constraint(
                    "first frequency floor",
                    lambda x: _floor(self.frequency_min_hz, self.responses(x)["frequency_hz"]),
                    scale=self.frequency_min_hz,
                    unit="Hz",
                ),
            ),
        )

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]:
        """The design ``x`` = (t, D) as a structure and a controller: the elastic frequencies
        and the rigid inertia of the half-model, and the LQ regulator of the modal plant (the
        plant :meth:`responses` costs) with its gain K (u = −K x, x = (η, η̇), η the modal
        coordinates of the rigid mode and the mass-normalised elastic modes) and its
        closed-loop poles eig(A − B K)."""
        t, D = float(x[0]), float(x[1])
        s = self.structure(t, D)
        group = tuple(range(self.elements))
        params = [TubeSection("thickness", group, D, t), TubeSection("outer_diameter", group, D, t)]
        ne = self.elastic_modes
        d = fe_modal_derivatives(s, params, list(range(1, ne + 1)), rigid_body_modes=1)
        asm = d.assembly
        r = np.zeros(asm.n_dofs)
        for node, dof in asm.dofs:
            r[asm.index(node, dof)] = 1.0 if dof == "rz" else (self.length * node / self.elements)
        Jt = float(r @ (asm.M @ r))
        phi = np.column_stack([r / np.sqrt(Jt), d.modes])
        omega = np.concatenate([[0.0], d.omegas])
        hub, tip = asm.index(0, "rz"), asm.index(self.elements, "uy")
        A, B, C = self._plant(omega, phi, hub, tip)
        Q = C.T @ np.diag(self.weights) @ C
        x0 = np.zeros(2 * (ne + 1))
        x0[0] = self.initial_angle * np.sqrt(Jt)
        lq = lq_cost_gradient(A, B, Q, np.array([[self.control_weight]]), np.outer(x0, x0))
        K = np.asarray(lq.K, dtype=float)[0]
        poles = sorted_poles(np.linalg.eigvals(A - B @ lq.K))
        coords = ["η0 (rigid)", *(f"η{i}" for i in range(1, ne + 1))]
        return {
            "elastic frequencies": DesignFeature(
                "structure",
                d.frequencies_hz,
                "Hz",
                labels=tuple(f"mode {i}" for i in range(1, ne + 1)),
                note="FE half-model (one boom on J_h / booms), pinned hub",
            ),
            "rigid inertia": DesignFeature(
                "structure",
                np.array([Jt]),
                "kg*m**2",
                note="rᵀ M r of the half-model about the hub axis",
            ),
            "LQ gain": DesignFeature(
                "control",
                K,
                "",
                labels=(*coords, *(f"rate of {c}" for c in coords)),
                note="u = −K x on the modal state (mass-normalised coordinates)",
            ),
            "closed-loop poles": DesignFeature(
                "control", poles, "1/s", note="eig(A − B K) of the modal plant"
            ),
        }
