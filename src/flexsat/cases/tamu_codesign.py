r"""TAMU structure–control co-design: appendage thickness with Law II's gains and α at equal
appendage mass, against the settling time of the published 40° slew (issue 23).

The problem is the one A. L. Hale, R. J. Lisowski and W. E. Dahl studied in 1982: a single-axis
slew of a hub with four appendages, with a structural variable of the appendages and the
control weights designed together by a gradient optimiser (reviewed in the integrated-design
survey the project's specification summarises). It is rebuilt here on the TAMU hub
(:func:`flexsat.cases.tamu`: Junkins, Rahman & Bang, Att. 3 of J. L. Junkins, T. C. Pollock and
Z. H. Rahman, "Near-minimum-time maneuvers of flexible spacecraft: theory and experiment",
Texas A&M report, 1990) with Control Law II in place of their LQ regulator. What of their
setup is assumed is listed in docs/design_optimization.md ("TAMU co-design").

Design variables (SI), in order:

- ``thickness_ratio`` s: the appendages' thickness over the published one. Each appendage is a
  flat strip of fixed width, so its bending stiffness and line density scale as
  EI = s³ EI₀, ρ = s ρ₀ (Euler–Bernoulli strip, I = b h³/12, A = b h);
- ``g1`` [N m/rad], ``g2`` [N m s/rad]: Law II's position and rate gains;
- ``alpha``: the smoothed bang-bang reference's rise-time fraction (Att. 3 Eq. 15).

Equal appendage mass (the equality constraint ρ L + m_tip = ρ₀ L + m_tip,0 per appendage) is
eliminated exactly: the tip mass carries what the strip does not,
m_tip(s) = ρ₀ L (1 − s) + m_tip,0, so every design point has the published appendage mass to
rounding (tested) and s is bounded above where the tip mass reaches zero. Torque saturation is
the published 400 oz-in of both the reference (its u_max) and the actuator, which clips the
command as the experiment's did.

Objective: the settling time of the published maneuver is piecewise constant in the design
(it moves in steps of one 75 Hz sample, and the 0.01° encoder adds jumps), so the optimiser
sees a smooth surrogate, the time spent outside the 0.5° band with the band's edge smoothed,

.. math::

    \tilde t_s(x) = \Delta t \sum_k \tfrac12\Big(1 + \tanh\frac{|\theta_k(x) - \theta_f| - b}
    {2 w b}\Big), \qquad b = 0.5°,\ w = \text{band\_width},

on the engine's 75 Hz record of the published loop (least-squares rate filter, 5 oz-in random
torque of seed 0 for every design, the encoder read exactly: its quantisation is a discontinuous
element left out) with the bearing's Coulomb friction regularised over ω_s =
``friction_smoothing`` (default 0.01 rad/s):
τ_f = −c₁ tanh(θ'/ω_s) − c₂ θ' (:class:`~flexsat.sim.disturbances.BearingFriction`; the
published runs use ω_s = 1e-3 rad/s, inside which the bearing is a stiff damper c₁/ω_s that
sticks). It equals the settling time when the response leaves the band once and stays inside
after; each time the response crosses the band before settling it is short by the crossing
time. Its gradient is taken by central differences: the 2n + 1 designs of one gradient are one
batched :func:`flexsat.sim.simulate` call on a
:class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage` (per-case EI, ρ and tip mass),
step h_k = ``fd_step`` · scale_k, truncation O(h²). With the published ω_s the bearing's
stick–slip switches wrinkle the surrogate on the scale of the step (measured at the optimisers'
end points: SLSQP's KKT residual 8e-3, trust-constr's 5e-8 on one BLAS and 0.09 on another);
over 0.01 rad/s the optimum is a smooth one (docs, "TAMU co-design"). The surrogate's
accuracy as a settling-time predictor is measured (:func:`surrogate_rank_correlation`), and
the reported optimum is judged by the real simulated settling time with the published
settings (friction with ω_s = 1e-3 rad/s, 0.01° encoder, least-squares rate, 5 oz-in random
torque, seed 0, 0.5° band) (:func:`settling_comparison`).

Stability: ``decay_rate`` is the decay rate σ = −max ln|λ_i| / Δt of the slowest mode of the
loop's linear part (zero-order-hold plant, least-squares rate filter, Law II; friction,
saturation and the encoder left out; :meth:`TamuCodesign.decay_rates`). The surrogate's
optimum has σ < 0: a loop that only the bearing friction and the torque limit hold (docs).

Mass: with ``mass_mode="fixed_tip"`` the tip mass stays at its published value and the
appendage mass ρ₀ s L + m_tip,0 is a response (exact gradient), for a front of appendage mass
against settling time (:mod:`flexsat.design.pareto`).

The integral of time-weighted squared error
:math:`\int_0^{t_f} t\,(\theta - \theta_f)^2\,dt` (ITSE; R. C. Dorf and R. H. Bishop, *Modern
Control Systems*, 12th ed., Pearson 2011, §5.9) of the same loop is reported as a second
response: it ranks designs by settling time worse (docs).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.stats import spearmanr

from flexsat.cases.tamu import TamuCase, published_reference_inertia, tamu
from flexsat.control import LyapunovTracker
from flexsat.design.describe import DesignFeature, sorted_poles
from flexsat.design.optimization_problem import (
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.dynamics.dispersed_hub import DispersedHubAppendage
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.input_checks import FieldError, require_positive_scalar
from flexsat.maneuvers import SmoothBangBang
from flexsat.sim import simulate
from flexsat.units import FloatArray, to_si

__all__ = [
    "MASS_MODES",
    "PUBLISHED_LAW_II",
    "TamuCodesign",
    "settling_comparison",
    "surrogate_rank_correlation",
]

#: the published Law II design (docs/tamu.md): s = 1, g1 = 3000 oz-in/rad,
#: g2 = 800 oz-in-s/rad, α = 0.2, in SI and in the variables' order
PUBLISHED_LAW_II = (
    1.0,
    to_si("3000 ozf*in/rad", "N*m/rad"),
    to_si("800 ozf*in*s/rad", "N*m*s/rad"),
    0.2,
)

NAMES = ("thickness_ratio", "g1", "g2", "alpha")

#: ``equal``: the tip mass takes up what the strip does not (the published appendage mass at
#: every s); ``fixed_tip``: the published tip mass, the appendage mass a response (ρ₀ s L +
#: m_tip,0), for the front of appendage mass against settling time
MASS_MODES = ("equal", "fixed_tip")


@dataclass
class TamuCodesign:
    """The TAMU co-design problem (module docstring); fields SI.

    Attributes
    ----------
    thickness_bounds : (lower, upper)
        Bounds of s; the upper one must leave a positive tip mass.
    g1_bounds, g2_bounds, alpha_bounds : (lower, upper)
        Bounds of the gains (N m/rad, N m s/rad) and of α (within [0, 1/4]).
    duration : float
        Run length t_f, s (the published runs: 15 s).
    n_modes : int
        Cantilever modes per appendage.
    fd_step : float
        Relative central-difference step of the surrogate's gradient.
    band_width : float
        w: the smoothed band edge's width as a fraction of the 0.5° band.
    friction_smoothing : float
        ω_s, rad/s: the surrogate loop's Coulomb friction regularisation (module docstring).
    mass_mode : {"equal", "fixed_tip"}
        :data:`MASS_MODES`.
    """

    thickness_bounds: tuple[float, float] = (0.6, 1.6)
    g1_bounds: tuple[float, float] = (5.0, 60.0)
    g2_bounds: tuple[float, float] = (1.0, 20.0)
    alpha_bounds: tuple[float, float] = (0.05, 0.24)
    duration: float = 15.0
    n_modes: int = 10
    fd_step: float = 1e-5
    band_width: float = 0.2
    friction_smoothing: float = 1e-2
    mass_mode: str = "equal"
    _case: TamuCase = field(init=False, repr=False)
    _cache: dict[bytes, dict[str, tuple[float, FloatArray]]] = field(
        init=False, repr=False, default_factory=dict
    )
    _plants: tuple[bytes, Any] = field(init=False, repr=False, default=(b"", None))

    def __post_init__(self) -> None:
        require_positive_scalar(self.duration, "duration")
        require_positive_scalar(self.fd_step, "fd_step")
        require_positive_scalar(self.band_width, "band_width")
        require_positive_scalar(self.friction_smoothing, "friction_smoothing")
        if self.mass_mode not in MASS_MODES:
            raise FieldError(
                "mass_mode", f"must be one of {', '.join(MASS_MODES)}, got {self.mass_mode!r}"
            )
        self._case = tamu(n_modes=int(self.n_modes))
        for name in ("thickness_bounds", "g1_bounds", "g2_bounds", "alpha_bounds"):
            lo, hi = getattr(self, name)
            if not 0 <= lo < hi:
                raise FieldError(name, f"must be 0 <= lower < upper, got {(lo, hi)}")
        p = self._case.params
        s_max = 1.0 + p.tip_mass / (p.rho * p.length) if self.mass_mode == "equal" else np.inf
        if self.thickness_bounds[0] <= 0 or self.thickness_bounds[1] >= s_max:
            raise FieldError(
                "thickness_bounds",
                f"must lie in (0, {s_max:.4f}) (above it the tip mass would be negative)",
            )
        if self.alpha_bounds[1] + 0.2 * self.fd_step >= 0.25:
            raise FieldError(
                "alpha_bounds",
                "the upper α plus its difference step must stay below 1/4 (Att. 3 Eq. 15)",
            )

    # -- the vehicle of a design -------------------------------------------------------------
    @property
    def case(self) -> TamuCase:
        return self._case

    @property
    def appendage_mass(self) -> float:
        """ρ₀ L + m_tip,0: the published mass of one appendage, kg."""
        p = self._case.params
        return float(p.rho * p.length + p.tip_mass)

    def structure(self, s: FloatArray) -> dict[str, FloatArray]:
        """EI, ρ and tip mass (SI) of thickness ratios ``s``: at the published appendage mass
        (``mass_mode="equal"``) or with the published tip mass (``"fixed_tip"``)."""
        p = self._case.params
        s = np.asarray(s, dtype=float)
        rho = p.rho * s
        if self.mass_mode == "equal":
            tip = self.appendage_mass - rho * p.length
        else:
            tip = np.full_like(rho, p.tip_mass)
        return {"EI": p.EI * s**3, "rho": rho, "tip_mass": tip}

    def mass(self, s: FloatArray) -> FloatArray:
        """Mass of one appendage, ρ L + m_tip (kg), at thickness ratios ``s``."""
        st = self.structure(np.asarray(s, dtype=float))
        return np.asarray(st["rho"] * self._case.params.length + st["tip_mass"], dtype=float)

    def _plant(self, s: FloatArray) -> DispersedHubAppendage:
        """The dispersed plant of thickness ratios ``s`` (the last one kept: a gradient's
        simulation and its decay rates share the cantilever modes' root finding)."""
        key = np.asarray(s, dtype=float).tobytes()
        if self._plants[0] != key:
            per_case: dict[str, Any] = dict(self.structure(s))  # (n_cases,): per-case fields
            plant = DispersedHubAppendage.from_parameters(
                replace(self._case.params, **per_case), n_modes=int(self.n_modes)
            )
            self._plants = (key, plant)
        return self._plants[1]

    def _batch(self, X: FloatArray, friction: bool, noise: bool, quantised: bool = True) -> Any:
        """One :func:`simulate` of the designs ``X`` (n_cases, 4); ``quantised=False`` keeps
        the least-squares rate filter and the random torque of ``noise`` but reads the encoder
        exactly (the smooth surrogate's loop)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        case, p = self._case, self._case.params
        st = self.structure(X[:, 0])
        plant = self._plant(X[:, 0])
        # the design's rigid inertia with the case's design-to-model ratio (tamu module notes);
        # at equal mass it changes with s only through the strip/tip split
        inertia = np.array(
            [
                published_reference_inertia(replace(p, EI=e, rho=r, tip_mass=m))
                for e, r, m in zip(st["EI"], st["rho"], st["tip_mass"])
            ]
        )
        reference = SmoothBangBang(case.angle, inertia, u_max=case.max_torque, alpha=X[:, 3])
        law = LyapunovTracker(
            reference,
            X[:, 1],
            X[:, 2],
            0.0,
            appendage_inertia=plant.appendage_inertia,
            n_appendages=int(p.n_appendages),
        )
        config = case.sim_config(self.duration, friction=friction, noise=noise)
        if noise and not quantised:
            config = replace(
                config,
                sensors=replace(config.sensors, encoder_resolution=0.0),
                friction=replace(config.friction, smoothing=self.friction_smoothing),
            )
        # every design sees the random-torque stream of seed 0 (the published runs' seed), so
        # that differences between designs are the design's alone
        seeds = np.full(X.shape[0], config.seed)
        return simulate(plant, law, config, seeds=seeds).dataset

    def surrogates(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The smoothed time outside the 0.5° band (s) and the ITSE (rad² s²) of the designs
        ``X`` (n_cases, 4), from one batched run of the surrogate's loop (module docstring)."""
        ds = self._batch(X, friction=True, noise=True, quantised=False)
        t = ds["time"].values
        e = ds["theta"].values - self._case.angle
        band = np.radians(0.5)
        outside = 0.5 * (1.0 + np.tanh((np.abs(e) - band) / (2 * self.band_width * band)))
        soft = np.sum(outside, axis=-1) * (t[1] - t[0])
        itse = np.trapezoid(t * e**2, t, axis=-1)
        return np.asarray(soft, dtype=float), np.asarray(itse, dtype=float)

    def soft_settling(self, X: FloatArray) -> FloatArray:
        """Smoothed time outside the 0.5° band of the designs ``X``, s."""
        return self.surrogates(X)[0]

    def itse(self, X: FloatArray) -> FloatArray:
        """ITSE of the designs ``X``, rad² s²."""
        return self.surrogates(X)[1]

    def decay_rates(self, X: FloatArray) -> FloatArray:
        r"""Decay rate σ (1/s) of the slowest closed-loop mode of the designs ``X`` (n_cases, 4):
        the linear part of the sampled loop (module docstring, "Stability").

        The plant's zero-order-hold equivalent x_{k+1} = A_d x_k + B_d u_k, θ_k = C x_k, under
        Law II's feedback u_k = −g1 θ_k − g2 Σ_j c_j θ_{k−N+1+j} through the published
        least-squares rate filter (N = 8 samples, :func:`~flexsat.sim.sensors.
        least_squares_derivative_weights`), closed on the state (x_k, θ_{k−1}, …, θ_{k−N+1});
        σ = −max_i ln|λ_i| / Δt over its eigenvalues λ_i. Friction, saturation and the encoder
        are the loop's nonlinear parts and are left out; σ < 0 is a loop that only the bearing
        friction and the torque limit can hold."""
        from scipy.linalg import expm

        from flexsat.sim.sensors import least_squares_derivative_weights

        X = np.atleast_2d(np.asarray(X, dtype=float))
        plant = self._plant(X[:, 0])
        A, B = plant.linear_part()
        mats = plant.output_matrices("theta")
        assert mats is not None  # a position output of a linear plant
        C = mats[0]
        config = self._case.sim_config(self.duration)
        dt, n_w = config.dt, int(config.sensors.rate_window)
        w = least_squares_derivative_weights(n_w, int(config.sensors.rate_order), dt)
        n = A.shape[-1]
        out = np.empty(X.shape[0])
        for i in range(X.shape[0]):
            M = np.zeros((n + 1, n + 1))
            M[:n, :n], M[:n, n:] = A[i] * dt, B[i][:, :1] * dt
            E = expm(M)
            g1, g2 = X[i, 1], X[i, 2]
            K = np.zeros(n + n_w - 1)  # u_k = K z_k
            K[:n] = -(g1 + g2 * w[-1]) * C[i][0]
            K[n:] = -g2 * w[-2::-1]
            Z = np.zeros((n + n_w - 1, n + n_w - 1))
            Z[:n, :n] = E[:n, :n]
            Z[:n] += E[:n, n:] @ K[None, :]
            Z[n, :n] = C[i][0]
            Z[n + 1 :, n : n + n_w - 2] = np.eye(n_w - 2)
            out[i] = -np.max(np.log(np.abs(np.linalg.eigvals(Z)))) / dt
        return out

    def first_frequency_hz(self, s: FloatArray) -> FloatArray:
        """First clamped (cantilever) frequency of the appendages, Hz."""
        from flexsat.structures.beam import cantilever_modes_batch

        p = self._case.params
        st = self.structure(np.atleast_1d(s))
        n = st["EI"].size
        modes = cantilever_modes_batch(
            np.full(n, p.length), st["EI"], st["rho"], st["tip_mass"], np.full(n, p.tip_inertia), 1
        )
        return np.asarray(modes.omegas[:, 0] / (2 * np.pi), dtype=float)

    # -- the reference-problem protocol -------------------------------------------------------
    def _scales(self) -> FloatArray:
        return np.array([1.0, PUBLISHED_LAW_II[1], PUBLISHED_LAW_II[2], 0.2])

    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        """``itse`` (rad² s²), ``appendage_mass`` (kg) and ``frequency_hz`` (first clamped
        appendage frequency, Hz), each with its gradient w.r.t. (s, g1, g2, α)."""
        x = np.asarray(x, dtype=float)
        key = x.tobytes()
        if key in self._cache:
            return self._cache[key]
        h = self.fd_step * self._scales()
        n = x.size
        X = np.vstack([x, x + np.diag(h), x - np.diag(h)])
        S, J = self.surrogates(X)
        dJ = (J[1 : n + 1] - J[n + 1 :]) / (2 * h)
        dS = (S[1 : n + 1] - S[n + 1 :]) / (2 * h)
        sig = self.decay_rates(X)
        dsig = (sig[1 : n + 1] - sig[n + 1 :]) / (2 * h)
        f = self.first_frequency_hz(np.array([x[0], x[0] + h[0], x[0] - h[0]]))
        df = np.zeros(n)
        df[0] = (f[1] - f[2]) / (2 * h[0])
        dm = np.zeros(n)
        if self.mass_mode == "fixed_tip":
            dm[0] = self._case.params.rho * self._case.params.length  # ∂(ρ₀ s L)/∂s, exact
        out = {
            "itse": (float(J[0]), dJ),
            "soft_settling": (float(S[0]), dS),
            "appendage_mass": (float(self.mass(x[0])), dm),
            "decay_rate": (float(sig[0]), dsig),
            "frequency_hz": (float(f[0]), df),
        }
        if len(self._cache) > 256:
            self._cache.clear()
        self._cache[key] = out
        return out

    def problem(self) -> DesignProblem:
        """Minimise the ITSE from the published design, within the bounds (no further
        constraint: equal mass is built in, saturation is in the plant)."""
        bounds = (self.thickness_bounds, self.g1_bounds, self.g2_bounds, self.alpha_bounds)
        units = ("", "N*m/rad", "N*m*s/rad", "")
        start = [float(np.clip(v, lo, hi)) for v, (lo, hi) in zip(PUBLISHED_LAW_II, bounds)]
        variables = tuple(
            DesignVariable(n, v, lo, hi, scale=sc, unit=u)
            for n, v, (lo, hi), sc, u in zip(NAMES, start, bounds, self._scales(), units)
        )
        j0 = self.responses(np.array(start))["soft_settling"][0]
        return DesignProblem(
            variables,
            Objective(
                "soft_settling", lambda x: self.responses(x)["soft_settling"], scale=j0, unit="s"
            ),
            (),
        )

    def report_metrics(self, x: FloatArray) -> dict[str, float]:
        """What the ``design`` scenario reports beside the responses: the real simulated
        settling time of ``x`` and of the published design (:func:`settling_comparison`)."""
        c = settling_comparison(self, x)
        return {k: v for k, v in c.items() if "itse" not in k}

    def settling_times(self, X: FloatArray) -> FloatArray:
        """Real simulated 0.5° settling times (s; NaN: not settled in t_f) of the designs
        ``X`` with the published settings (friction, encoder, random torque, seed 0)."""
        ds = self._batch(X, friction=True, noise=True)
        return np.asarray(ds["settling_time_s"].values, dtype=float)

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]:
        """The design ``x`` = (s, g1, g2, α) as a structure and a controller: the appendages'
        first clamped frequencies, EI, line density and tip mass, and Law II's gains and α
        (g3 = 0 as published)."""
        from flexsat.structures.beam import cantilever_modes_batch

        x = np.asarray(x, dtype=float)
        p = self._case.params
        st = self.structure(np.array([x[0]]))
        n = min(3, int(self.n_modes))
        modes = cantilever_modes_batch(
            p.length, st["EI"], st["rho"], st["tip_mass"], p.tip_inertia, n
        )
        # Law II about the final angle once the reference has ended (g3 = 0): u = −g1 θ̃ − g2 θ̇
        # on the linear hub-appendage model, state [θ, q, θ̇, q̇]
        k = int(self.n_modes)
        design = replace(
            p, EI=float(st["EI"][0]), rho=float(st["rho"][0]), tip_mass=float(st["tip_mass"][0])
        )
        A, B = HubAppendage(design, n_modes=k).linear_part()
        gain = np.zeros((1, 2 * (k + 1)))
        gain[0, 0], gain[0, k + 1] = x[1], x[2]
        poles = sorted_poles(np.linalg.eigvals(A - B @ gain))
        return {
            "appendage frequencies": DesignFeature(
                "structure",
                modes.omegas[0] / (2 * np.pi),
                "Hz",
                labels=tuple(f"mode {i}" for i in range(1, n + 1)),
                note="clamped appendage with its tip mass (Euler–Bernoulli)",
            ),
            "appendage EI": DesignFeature(
                "structure",
                st["EI"],
                "N*m**2",
                note="thickness ratio s: EI = s³ EI₀, ρ = s ρ₀, tip mass at equal appendage mass",
            ),
            "appendage line density": DesignFeature("structure", st["rho"], "kg/m"),
            "tip mass": DesignFeature("structure", st["tip_mass"], "kg"),
            "g1": DesignFeature(
                "control",
                np.array([x[1]]),
                "N*m/rad",
                note="Law II: u = −g1 (θ − θ_r) − g2 (θ̇ − θ̇_r), g3 = 0",
            ),
            "g2": DesignFeature("control", np.array([x[2]]), "N*m*s/rad"),
            "alpha": DesignFeature(
                "control",
                np.array([x[3]]),
                "",
                note="rise-time fraction of the smoothed bang-bang reference (Att. 3 Eq. 15)",
            ),
            "closed-loop poles": DesignFeature(
                "control",
                poles,
                "1/s",
                note="eig(A − B K) of the linear hub-appendage model with Law II about the final "
                "angle (K = [g1, 0, …, g2, 0, …]): continuous time, without friction, rate "
                "filter, sampling or saturation",
            ),
        }


def settling_comparison(problem: TamuCodesign, x: FloatArray) -> dict[str, float]:
    """The design ``x`` beside the published Law II design, simulated the same way: settling
    time (published settings) and ITSE of each, and the optimum's appendage mass."""
    X = np.vstack([np.asarray(x, dtype=float), np.array(PUBLISHED_LAW_II)])
    ts = problem.settling_times(X)
    J = problem.itse(X)
    mass = problem.mass(X[:, 0])
    return {
        "settling_time_s": float(ts[0]),
        "published_settling_time_s": float(ts[1]),
        "itse": float(J[0]),
        "published_itse": float(J[1]),
        "appendage_mass_kg": float(mass[0]),
        "published_appendage_mass_kg": problem.appendage_mass,
    }


def surrogate_rank_correlation(
    problem: TamuCodesign, n_designs: int = 60, seed: int = 0
) -> dict[str, float]:
    """Spearman rank correlations of the surrogate (``spearman``) and of the ITSE
    (``spearman_itse``) with the real settling time over random designs within the bounds
    (unsettled runs ranked last), and the median |surrogate − settling time| of the settled
    ones (s): how well each orders and predicts the settling time."""
    if n_designs < 3:
        raise FieldError("n_designs", f"must be >= 3, got {n_designs}")
    rng = np.random.default_rng(seed)
    bounds = np.array(
        [problem.thickness_bounds, problem.g1_bounds, problem.g2_bounds, problem.alpha_bounds]
    )
    X = bounds[:, 0] + rng.random((n_designs, 4)) * (bounds[:, 1] - bounds[:, 0])
    S, J = problem.surrogates(X)
    ts = problem.settling_times(X)
    settled = np.isfinite(ts)
    ranked = np.where(settled, ts, 2 * problem.duration)
    return {
        "spearman": float(spearmanr(S, ranked).statistic),
        "spearman_itse": float(spearmanr(J, ranked).statistic),
        "median_error_s": float(np.median(np.abs(S[settled] - ts[settled]))),
        "n_designs": float(n_designs),
        "settled_fraction": float(np.isfinite(ts).mean()),
    }
