r"""Automated search of the perturbation-feedback weights of a three-axis slew toward the goals of
the EPS slew study c. 1989 (the paper's main recommendation, "Perturbation Control - Torquers +
Force Actuators, 10 s Maneuver").

The EPS slew study c. 1989 designs its perturbation feedback (frequency-shaped LQR
with cross weight, Eqs. 22–28,
:func:`~flexsat.control.perturbation_feedback.perturbation_design`) with diagonal weights

.. math::

    Q = \mathrm{diag}(q_\alpha I_3,\ q_\omega I_3,\ q_\eta,\ q_{\dot\eta}), \qquad
    D = \mathrm{diag}(d_\tau I_3,\ d_F)

over δX = [δα, δω, δη, δη̇] and δu₁ = [J⁻¹δτ, δF], chosen by hand, and judges each design by
simulation against two goals ("Simulation Results",
:mod:`flexsat.sim.slew_goals`): the 1-2-3 angle error
at 1.25 T at most 3 % of the commanded angle, and the peak rim deflection after the slew at most
1/10 of the open-loop one. Its 6 s torquers-only case D misses both and the paper recommends
"an optimization of the weighting matrices" (ibid.). This module does that search.

The pieces:

* :class:`SlewWeights` — the diagonal blocks (one number per block, or one per mode / force);
* :class:`SlewEvaluation` — one design + one closed-loop simulation on the truth plant → the goal
  metrics (:func:`slew_run_metrics`, the same extraction as the slew scenarios);
* :func:`slew_objective` — the scalar the search minimises:

  .. math::

      J = \sum_i \max(0,\ v_i + \mu)^2 + w_e E, \quad
      v_\alpha = \frac{e_\alpha}{e_{tol}} - 1, \quad
      v_r = \frac{r_{goal}}{r} - 1, \quad
      E = \frac{\max|\delta\tau|}{\max|\tau_n|} + \frac{\max|F|}{F_{ref}},

  μ the margin: the penalty part is zero exactly when both goals are met with the margin
  (e_α ≤ (1 − μ) e_tol and r ≥ r_goal / (1 − μ)), a squared hinge (continuous first derivative)
  of the violations otherwise. E (the peak torque perturbation against the peak nominal torque,
  the peak force against a reference force) is weighted small (w_e ≈ 0.01) so that it only
  ranks designs of similar violation, and among designs that meet the goals prefers the least
  effort. A design whose Riccati equation has no stabilising solution, or whose simulation
  diverges, scores :data:`FAILURE_PENALTY` (larger than any violation met in practice);
* :func:`tune_slew_weights` — Nelder–Mead (or Powell) on the base-10 logarithms of block
  multipliers (the weights' scale is what matters and spans decades; a multiplier per free
  block keeps the search to a handful of parameters). Derivative-free because each objective
  value is a simulation whose metrics are peaks and maxima over axes (piecewise smooth in the
  weights, with kinks where the arg-max switches), so finite-difference gradients would be
  unreliable and cost n + 1 simulations each; Nelder–Mead is the default because its first
  simplex probes one decade along every block at once (n + 1 evaluations), which for the
  5-parameter problems here finds the useful direction within ~10 simulations, and it stays
  inside the box of ± ``bound`` decades. The search stops as soon as the goals are met with the
  margin (``stop_when_met``), or at the budget.

Result on the EPS, 1 rad about each axis in 6 s, ω_B = 5 rad/s, ζ_B = 0, 45-mode truth,
10-mode design model, 21 linearisation points, 100 Hz, run to 11.5 s (the deflection goal's
window from 1.25 T to the end; ``examples/eps_slew_6s.yaml``), 0.6–0.9 s an evaluation:

* **Torquers only: no diagonal Q/D found.** Nelder–Mead from case D's weights (attitude, rate,
  modes, torque; 150 evaluations, 135 s), then from its best with the mode rates apart (100
  more), plus a grid of modal against torque weights: no design meets both goals. Case D: 96
  mrad, ratio 4.7. The designs trade one goal for the other along a front: the best ratio among
  designs meeting the angle goal is 1.8; a ratio of 6 costs 48 mrad; the best objective
  (attitude 4.388e7, rate 5.806e5, modes 3744, mode rates 641.1, torque 0.07828) reaches 37.4
  mrad and a ratio of 6.2 with a 71 kN m torque perturbation (2 × the peak nominal torque). On
  the grid (attitude and rate 1e3), modal weights 1e4 to 1e8 reach ratios of 11–28 only by
  abandoning the slew (angle errors 0.95–1.24 rad), and modal weights 1e4 with torque 1e-3, or
  1e6 and up with torque ≤ 1, make the closed loop diverge.
  This is not a limit of the torquers: :mod:`flexsat.design.slew_shaping` builds a torquers-only
  slew meeting both goals (0.8 mrad, ratio 1,200, 10 kN m perturbation). It is the structure of
  the perturbation feedback: the nominal's modal disturbance (Eq. 31) enters through the same
  three torques that carry the slew, so the feedback can reject it only by undoing the slew, a
  trade the LQR settles instant by instant; the feedback is causal and infinite-horizon, and no
  weight makes it aim the modes at rest at T, which a correction planned over the whole
  maneuver does.
* **Torquers + the 7 forces, from case E** (case E: 6.1 mrad, ratio 191, 2,818 N): the search
  not stopping at the goals, effort reference 100 N, a 30 % margin on both goals (120
  evaluations, 133 s): attitude 114.6, rate 988.7, modes E's × 126.6, torque 2.413, force
  8.061e-7; 20.9 mrad, ratio 234, peak force 1,638 N, 33 kN m. The deflection goal has ample
  slack; the angle goal binds: lower peak forces (1,516 N) cost 64 mrad, and forces weighted
  1e4 × E's without feedforward bring the peak to 192 N (the paper's E: ≈ 180 N) with 93 mrad.
  About 1.6 kN is the floor of this family with both goals met.
"""

from __future__ import annotations

import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_nonneg,
    require_numeric,
    require_positive,
)
from flexsat.sim.slew_goals import SlewGoals, slew_goal_metrics
from flexsat.units import FloatArray

if TYPE_CHECKING:
    import xarray

    from flexsat.control.base import Controller
    from flexsat.control.perturbation_feedback import PerturbationDesign
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew
    from flexsat.sim.config import SimConfig
    from flexsat.sim.recording import SimResult

__all__ = [
    "BLOCKS",
    "FAILURE_PENALTY",
    "SlewEvaluation",
    "SlewWeights",
    "TuningResult",
    "goal_violations",
    "nominal_histories",
    "open_loop_deflection",
    "rim_nodes",
    "slew_objective",
    "slew_run_metrics",
    "tune_slew_weights",
]

#: the diagonal blocks of Q (attitude, rate, modes, mode_rates) and D (torque, force)
BLOCKS = ("attitude", "rate", "modes", "mode_rates", "torque", "force")

#: objective of a design that fails (no stabilising Riccati solution, or a diverged simulation):
#: above the violations of any design met on the EPS (D's 6 s penalty is ≈ 55)
FAILURE_PENALTY = 1.0e4

#: the search methods of :func:`tune_slew_weights` (scipy.optimize.minimize names)
METHODS = ("nelder-mead", "powell")


# -- weights -------------------------------------------------------------------------------------
def _block(value, name: str, positive: bool) -> tuple[float, ...] | None:
    if value is None:
        return None
    rule = "> 0 (D is inverted)" if positive else ">= 0"
    try:  # a Quantity is refused here (weights are SI numbers), not stripped of its unit
        w = np.atleast_1d(require_numeric(value, name, "weight"))
    except FieldError as exc:
        raise FieldError(
            name, f"one weight or a list of them, finite and {rule}: {exc.rule}"
        ) from None
    if w.ndim != 1 or w.size == 0 or np.any(w < 0) or (positive and np.any(w <= 0)):
        raise FieldError(name, f"one weight or a list of them, finite and {rule}, got {value!r}")
    return tuple(float(x) for x in w)


def _diagonal(values: tuple[float, ...], size: int, name: str) -> FloatArray:
    if len(values) == 1:
        return np.full(size, values[0])
    if len(values) != size:
        raise FieldError(name, f"one weight or {size} of them, got {len(values)}")
    return np.asarray(values)


def _check_range(weights: SlewWeights, q: FloatArray, d: FloatArray) -> None:
    """Refuse weights spanning more than :data:`flexsat.limits.MAX_WEIGHT_RANGE`, naming the
    block whose extreme value lies farther (in decades) from 1."""
    values = np.concatenate([q, d])
    positive = values[values > 0]
    low, high = positive.min(), positive.max()
    if high <= limits.MAX_WEIGHT_RANGE * low:
        return
    # weights are SI numbers of natural scale 1: the one farther from 1 is out of place
    extreme = high if abs(np.log10(high)) >= abs(np.log10(low)) else low
    block = next(
        name for name in BLOCKS if getattr(weights, name) and extreme in getattr(weights, name)
    )
    raise FieldError(
        block,
        f"the weights span {high / low:.3g} (from {low:.3g} to {high:.3g}), above "
        f"{limits.MAX_WEIGHT_RANGE:.0e} (flexsat.limits.MAX_WEIGHT_RANGE: the smaller "
        "would be below the rounding of the larger)",
    )


@dataclass(frozen=True)
class SlewWeights:
    """Diagonal weights of a perturbation design (module docstring): Q over [δα (rad), δω
    (rad/s), η, η̇] and D over [J⁻¹δτ (rad/s²), F (N)], SI numbers. Each block is one number
    (filling the block) or one per component; ``mode_rates`` defaults to ``modes``; ``force``
    is needed only with forces."""

    attitude: Any
    rate: Any
    modes: Any
    torque: Any
    mode_rates: Any = None
    force: Any = None

    def __post_init__(self) -> None:
        for name in BLOCKS:
            value = _block(getattr(self, name), name, positive=name in ("torque", "force"))
            if value is None and name not in ("mode_rates", "force"):
                raise FieldError(name, "required")
            object.__setattr__(self, name, value)

    def diagonals(self, n_modes: int, n_forces: int = 0) -> tuple[FloatArray, FloatArray]:
        """(diag Q, diag D) for a design model of ``n_modes`` modes and ``n_forces`` forces."""
        rates = self.modes if self.mode_rates is None else self.mode_rates
        q = np.concatenate(
            [
                _diagonal(self.attitude, 3, "attitude"),
                _diagonal(self.rate, 3, "rate"),
                _diagonal(self.modes, n_modes, "modes"),
                _diagonal(rates, n_modes, "mode_rates"),
            ]
        )
        d = _diagonal(self.torque, 3, "torque")
        if n_forces:
            if self.force is None:
                raise FieldError("force", "required when the design uses forces")
            d = np.concatenate([d, _diagonal(self.force, n_forces, "force")])
        _check_range(self, q, d)
        return q, d

    def scaled(self, factors: Mapping[str, float]) -> SlewWeights:
        """These weights with blocks multiplied by ``factors`` (block name -> factor > 0); an
        unset ``mode_rates`` follows ``modes`` unless scaled itself."""
        changes = {}
        for name, factor in factors.items():
            if name not in BLOCKS:
                raise FieldError("factors", f"unknown block {name!r}; blocks: {', '.join(BLOCKS)}")
            values = getattr(self, name)
            if values is None and name == "mode_rates":
                values = self.modes
            if values is None:
                raise FieldError("factors", f"block {name!r} is not set in these weights")
            changes[name] = tuple(float(factor) * x for x in values)
        return replace(self, **changes)

    def as_dict(self) -> dict[str, float | list[float]]:
        """Plain numbers by block (a one-element block as a float), unset blocks left out: the
        ``weights`` mapping of a slew scenario run."""
        out = {}
        for name in BLOCKS:
            values = getattr(self, name)
            if values is not None:
                out[name] = values[0] if len(values) == 1 else list(values)
        return out


# -- metrics (shared with the slew scenarios) ----------------------------------------------------
def nominal_histories(nominal: ThreeAxisSlew, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The nominal torque (N m) and 1-2-3 angles (rad) at times t: the maneuver over [0, T],
    then rest at the target (zero torque)."""
    T = nominal.duration
    inside = np.clip(t, 0.0, T)
    torque = np.where((t > T)[:, None], 0.0, nominal.torque(inside))
    return torque, nominal.euler123(inside)


def rim_nodes(dataset: xarray.Dataset) -> list[str]:
    """Nodes of a run's dataset with displacement outputs along all three axes
    (``displacement_66X``, ``…Y``, ``…Z`` -> ``66``), in output order."""
    variables = [str(n) for n in dataset.data_vars]
    names = [n[len("displacement_") : -1] for n in variables if n.startswith("displacement_")]
    return [
        n for n in dict.fromkeys(names) if all(f"displacement_{n}{a}" in dataset for a in "XYZ")
    ]


def _stack(results: Sequence[SimResult], name: str) -> FloatArray:
    return np.stack([r.dataset[name].isel(case=0).values for r in results])


def _rim_deflection(results: Sequence[SimResult]) -> FloatArray:
    """(n_runs, n_t, n_rim, 3) rim displacements of single-case runs."""
    nodes = rim_nodes(results[0].dataset)
    if not nodes:
        raise FieldError(
            "results",
            "the plant records no rim displacements (outputs "
            "displacement_<node>X/Y/Z), so the deflection goal cannot be judged",
        )
    return np.stack(
        [np.stack([_stack(results, f"displacement_{n}{a}") for a in "XYZ"], -1) for n in nodes], -2
    )


def slew_run_metrics(
    results: Sequence[SimResult],
    nominal: ThreeAxisSlew,
    goals: SlewGoals = SlewGoals(),
    deflection_open: npt.ArrayLike | None = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The goal metrics (:func:`~flexsat.sim.slew_goals.slew_goal_metrics`) of single-case
    slew runs on one time grid.

    Parameters
    ----------
    results : sequence of flexsat.sim.SimResult
        One case each, recording ``euler123``, ``torque``, the rim displacements
        (:func:`rim_nodes`) and any ``force_*`` inputs.
    nominal : object
        The nominal maneuver (``duration``, ``target`` quaternion, ``torque(t)``,
        ``euler123(t)``).
    goals : SlewGoals
    deflection_open : (1, n_t, n_rim, 3) array, optional
        Open-loop rim displacements (:func:`open_loop_deflection`); default: the first run is
        the open loop.

    Returns
    -------
    (dict, dict)
        Metrics (n_runs,) by name and their units.
    """
    from flexsat.dynamics.attitude import dcm_to_euler123, quaternion_to_dcm

    if len(results) == 0:
        raise FieldError("results", "at least one run")
    t = results[0].dataset["time"].values
    deflection = _rim_deflection(results)
    if deflection_open is None:
        deflection_open = deflection[:1]
    elif np.shape(deflection_open) != (1,) + deflection.shape[1:]:
        raise FieldError(
            "deflection_open",
            f"shape must be (1,) + {deflection.shape[1:]} (the "
            f"runs' time grid and rim points), got {np.shape(deflection_open)}",
        )
    variables = [str(n) for n in results[0].dataset.data_vars]
    force_names = [n for n in variables if n.startswith("force_") and not n.endswith("_command")]
    return slew_goal_metrics(
        t,
        nominal.duration,
        _stack(results, "euler123"),
        dcm_to_euler123(quaternion_to_dcm(nominal.target)),
        deflection,
        deflection_open,
        torque=_stack(results, "torque"),
        torque_nominal=nominal_histories(nominal, t)[0][None],
        forces=np.stack([_stack(results, n) for n in force_names], -1) if force_names else None,
        goals=goals,
    )


def open_loop_deflection(
    truth: FlexibleSpacecraft, nominal: ThreeAxisSlew, config: SimConfig
) -> FloatArray:
    """(1, n_t, n_rim, 3) rim displacements of the nominal torque alone on ``truth`` (the
    open-loop reference of the deflection goal), held as the feedback laws hold it
    (:class:`~flexsat.control.perturbation_feedback.NominalTorque`)."""
    from flexsat.control import NominalTorque
    from flexsat.sim import simulate

    return _rim_deflection([simulate(truth, NominalTorque(nominal, config.dt), config, n_cases=1)])


# -- one evaluation ------------------------------------------------------------------------------
class SlewEvaluation:
    """One perturbation design and its closed-loop slew on the truth plant → the goal metrics.

    Parameters
    ----------
    truth : FlexibleSpacecraft
        The simulated plant (e.g. the 45-mode EPS), with rim displacement outputs.
    design_plant : FlexibleSpacecraft
        The design model: the truth's first modes (``truth.reduced(n)``).
    nominal : ThreeAxisSlew
        The rigid nominal maneuver (:func:`~flexsat.maneuvers.three_axis_slew`).
    config : flexsat.sim.SimConfig
        Must run through ``goals.evaluation`` × T.
    goals : SlewGoals
    deflection_open : (1, n_t, n_rim, 3) array, optional
        The open-loop reference on ``config``'s grid; computed when not given
        (:func:`open_loop_deflection`).
    n_points : int
        Linearisation times of the gain schedule.

    Notes
    -----
    Calling it with weights, ω_B, ζ_B, forces, decoupling and feedforward returns the metrics
    of :func:`slew_run_metrics` as floats, plus ``peak_nominal_torque_Nm`` and
    ``deflection_ratio_goal`` (what :func:`slew_objective` needs).
    """

    def __init__(
        self,
        truth: FlexibleSpacecraft,
        design_plant: FlexibleSpacecraft,
        nominal: ThreeAxisSlew,
        config: SimConfig,
        goals: SlewGoals = SlewGoals(),
        deflection_open: npt.ArrayLike | None = None,
        n_points: int = 11,
    ) -> None:
        for name, plant in (("truth", truth), ("design_plant", design_plant)):
            if not hasattr(plant, "n_modes") or not hasattr(plant, "inputs"):
                raise FieldError(name, f"must be a FlexibleSpacecraft, got {type(plant).__name__}")
        if design_plant.n_modes > truth.n_modes:
            raise FieldError(
                "design_plant",
                f"at most the truth's {truth.n_modes} modes, got {design_plant.n_modes}",
            )
        missing = [
            a for a in ("duration", "target", "torque", "euler123") if not hasattr(nominal, a)
        ]
        if missing:
            raise FieldError("nominal", f"lacks {', '.join(missing)} (a ThreeAxisSlew has them)")
        if not isinstance(goals, SlewGoals):
            raise FieldError("goals", f"must be a SlewGoals, got {type(goals).__name__}")
        T = float(nominal.duration)
        if config.duration < goals.evaluation * T * (1 - 1e-9):
            raise FieldError(
                "config.duration",
                f"must reach {goals.evaluation:g} T = "
                f"{goals.evaluation * T:g} s where the goals are evaluated, got "
                f"{config.duration:g} s",
            )
        self.truth, self.design_plant, self.nominal = truth, design_plant, nominal
        self.config, self.goals = config, goals
        self.n_points = require_count(n_points, "n_points")
        if deflection_open is None:
            deflection_open = open_loop_deflection(truth, nominal, config)
        self.deflection_open = np.asarray(deflection_open, float)
        grid = np.linspace(0.0, T, 2001)
        self.peak_nominal_torque = float(np.abs(nominal.torque(grid)).max())

    def forces(self, forces: str | Sequence[str]) -> list[str]:
        """Force channel names of the design plant (``"all"``, or names with or without the
        ``force_`` prefix)."""
        available = [c.name for c in self.design_plant.inputs if c.name.startswith("force_")]
        if isinstance(forces, str):
            if forces == "all":
                return available
            forces = [forces]
        names = []
        for name in forces:
            channel = name if name.startswith("force_") else f"force_{name}"
            if channel not in available:
                raise FieldError(
                    "forces",
                    f"{name!r} is not a force of the design plant (its "
                    f"forces: {', '.join(c[6:] for c in available) or 'none'})",
                )
            names.append(channel)
        return names

    def design(
        self,
        weights: SlewWeights,
        omega_b: float,
        zeta_b: float = 0.0,
        forces: str | Sequence[str] = (),
        decouple: bool = False,
    ) -> PerturbationDesign:
        """The :class:`~flexsat.control.perturbation_feedback.PerturbationDesign` of these
        weights."""
        from flexsat.control import perturbation_design

        if not isinstance(weights, SlewWeights):
            raise FieldError("weights", f"must be SlewWeights, got {type(weights).__name__}")
        names = self.forces(forces)
        q, d = weights.diagonals(self.design_plant.n_modes, len(names))
        return perturbation_design(
            self.design_plant,
            self.nominal,
            q,
            d,
            omega_b,
            zeta_b,
            self.n_points,
            forces=names,
            decouple=decouple,
        )

    def __call__(
        self,
        weights: SlewWeights,
        omega_b: float,
        zeta_b: float = 0.0,
        forces: str | Sequence[str] = (),
        decouple: bool = False,
        feedforward: str = "constant",
    ) -> dict[str, float | bool]:
        design = self.design(weights, omega_b, zeta_b, forces, decouple)
        return self.run(design.controller(self.config.dt, feedforward, plant=self.truth))

    def run(self, law: Controller) -> dict[str, float | bool]:
        """The metrics of any law on the truth plant (``__call__`` for a design's law; e.g. an
        open-loop :class:`~flexsat.control.perturbation_feedback.NominalTorque` of another
        torque history, judged against this nominal)."""
        from flexsat.sim import simulate

        result = simulate(self.truth, law, self.config, n_cases=1)
        metrics, _ = slew_run_metrics([result], self.nominal, self.goals, self.deflection_open)
        out = {k: (bool(v[0]) if v.dtype == bool else float(v[0])) for k, v in metrics.items()}
        out["peak_nominal_torque_Nm"] = self.peak_nominal_torque
        out["deflection_ratio_goal"] = float(self.goals.deflection_ratio)
        return out


# -- objective -----------------------------------------------------------------------------------
def goal_violations(metrics: Mapping) -> tuple[float, float]:
    """(v_α, v_r) = (angle error / tolerance − 1, ratio goal / ratio − 1): ≤ 0 where a goal is
    met (module docstring)."""
    for key in (
        "angle_error_mrad",
        "angle_tolerance_mrad",
        "deflection_ratio_after",
        "deflection_ratio_goal",
    ):
        if key not in metrics:
            raise FieldError("metrics", f"lacks {key!r} (the metrics of a SlewEvaluation)")
    ratio = float(metrics["deflection_ratio_after"])
    v_angle = float(metrics["angle_error_mrad"]) / float(metrics["angle_tolerance_mrad"]) - 1.0
    v_ratio = float(metrics["deflection_ratio_goal"]) / ratio - 1.0 if ratio > 0 else np.inf
    return v_angle, v_ratio


def _effort(metrics: Mapping, force_scale: float) -> float:
    effort = float(metrics.get("peak_torque_perturbation_Nm", 0.0)) / float(
        metrics.get("peak_nominal_torque_Nm", 1.0)
    )
    return effort + float(metrics.get("peak_force_N", 0.0)) / force_scale


def slew_objective(
    metrics: Mapping | None,
    margin: float = 0.05,
    effort_weight: float = 0.01,
    force_scale: float = 1000.0,
) -> float:
    r"""J = Σ max(0, v_i + μ)² + w_e E (module docstring); ``None`` metrics (a failed design)
    score :data:`FAILURE_PENALTY`.

    Parameters
    ----------
    metrics : mapping or None
        From :class:`SlewEvaluation`.
    margin : float
        μ in [0, 1): the goals must be met by this fraction.
    effort_weight : float
        w_e ≥ 0.
    force_scale : float
        F_ref, N (> 0): the peak force counted as one unit of effort.
    """
    margin = float(require_nonneg(margin, "margin"))
    if margin >= 1.0:
        raise FieldError("margin", f"must be in [0, 1), got {margin}")
    effort_weight = float(require_nonneg(effort_weight, "effort_weight"))
    force_scale = float(require_positive(force_scale, "force_scale", "N"))
    if metrics is None:
        return FAILURE_PENALTY
    penalty = sum(max(0.0, v + margin) ** 2 for v in goal_violations(metrics))
    if not np.isfinite(penalty):
        return FAILURE_PENALTY
    return min(penalty + effort_weight * _effort(metrics, force_scale), FAILURE_PENALTY)


def _met(metrics: Mapping | None, margin: float) -> bool:
    return metrics is not None and all(v + margin <= 0.0 for v in goal_violations(metrics))


# -- search --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TuningResult:
    """The outcome of :func:`tune_slew_weights`.

    Attributes
    ----------
    weights : SlewWeights
        The best weights found (least objective).
    metrics : dict
        Their goal metrics (:class:`SlewEvaluation`).
    objective : float
    met : bool
        Both goals met with the margin.
    multipliers : dict of str to float
        The best weights' block multipliers against the initial weights.
    history : tuple of dict
        Every evaluation in order: ``multipliers``, ``weights``, ``metrics`` (None when the
        design failed), ``objective``, ``failure`` (the error message or None).
    seconds : float
        Wall time of the search.
    method : str
    """

    weights: SlewWeights
    metrics: dict | None
    objective: float
    met: bool
    multipliers: dict
    history: tuple = field(repr=False)
    seconds: float = 0.0
    method: str = "nelder-mead"

    @property
    def evaluations(self) -> int:
        return len(self.history)


class _Stop(Exception):
    """Ends the scipy search early (goals met, or the budget spent)."""


def tune_slew_weights(
    evaluation: SlewEvaluation,
    initial: SlewWeights,
    free: Sequence[str] = ("attitude", "rate", "modes", "torque"),
    budget: int = 60,
    *,
    omega_b: float,
    zeta_b: float = 0.0,
    forces: str | Sequence[str] = (),
    decouple: bool = False,
    feedforward: str = "constant",
    margin: float = 0.05,
    effort_weight: float = 0.01,
    force_scale: float = 1000.0,
    step: float = 1.0,
    bound: float = 4.0,
    stop_when_met: bool = True,
    method: str = "nelder-mead",
) -> TuningResult:
    r"""Search block multipliers of ``initial`` that meet the slew goals (module docstring).

    The parameters are x_b = log₁₀ m_b, one per free block, the weights ``initial`` with each
    free block multiplied by m_b; x starts at 0 (the initial weights) and stays in
    [−``bound``, ``bound``]. Minimises :func:`slew_objective`.

    Parameters
    ----------
    evaluation : SlewEvaluation
    initial : SlewWeights
        The starting weights (e.g. the paper's case D).
    free : sequence of str
        The blocks to scale (:data:`BLOCKS`; ``mode_rates`` scales the modal-rate block apart
        from ``modes``, ``force`` needs forces).
    budget : int
        At most this many evaluations (each one design and one simulation).
    omega_b, zeta_b, forces, decouple, feedforward
        As for :meth:`SlewEvaluation.__call__`, fixed during the search.
    margin, effort_weight, force_scale
        Of :func:`slew_objective`.
    step : float
        Initial step, decades (> 0): the first simplex / Powell directions.
    bound : float
        Box half-width, decades (> 0).
    stop_when_met : bool
        Stop at the first evaluation meeting both goals with the margin; False spends the
        budget minimising the objective (so the effort among designs that meet the goals).
    method : {"nelder-mead", "powell"}

    Raises
    ------
    ValueError
        Naming the field: unknown or repeated free blocks, ``force`` free without forces, a
        block unset in ``initial``, budget < 1, step or bound ≤ 0, an unknown method or
        feedforward, unknown forces.
    """
    from scipy.optimize import minimize

    from flexsat.control.perturbation_feedback import FEEDFORWARD

    if not isinstance(evaluation, SlewEvaluation):
        raise FieldError("evaluation", f"must be a SlewEvaluation, got {type(evaluation).__name__}")
    if not isinstance(initial, SlewWeights):
        raise FieldError("initial", f"must be SlewWeights, got {type(initial).__name__}")
    free = tuple(free)
    if not free or len(set(free)) != len(free) or any(b not in BLOCKS for b in free):
        raise FieldError("free", f"distinct block names among {', '.join(BLOCKS)}, got {free!r}")
    names = evaluation.forces(forces)
    if "force" in free and not names:
        raise FieldError("free", "'force' needs forces (forces=...)")
    if names and initial.force is None:
        raise FieldError("initial.force", "required when the design uses forces")
    budget = require_count(budget, "budget")
    step = float(require_positive(step, "step"))
    bound = float(require_positive(bound, "bound"))
    if method not in METHODS:
        raise FieldError("method", f"one of {', '.join(METHODS)}, got {method!r}")
    if feedforward not in FEEDFORWARD:
        raise FieldError("feedforward", f"one of {', '.join(FEEDFORWARD)}, got {feedforward!r}")
    slew_objective(None, margin, effort_weight, force_scale)  # checks the three up front
    require_positive(omega_b, "omega_b", "rad/s")
    require_nonneg(zeta_b, "zeta_b")

    history: list[dict] = []
    cache: dict[tuple, float] = {}
    start = _time.perf_counter()

    def objective(x: FloatArray) -> float:
        x = np.clip(np.asarray(x, float), -bound, bound)
        key = tuple(np.round(x, 10))
        if key in cache:
            return cache[key]
        if len(history) >= budget:
            raise _Stop
        multipliers = {b: float(10.0**xi) for b, xi in zip(free, x)}
        weights = initial.scaled(multipliers)
        metrics, failure = None, None
        try:
            # a diverging trial overflows before the engine stops it: scored, not reported
            with np.errstate(over="ignore", invalid="ignore"):
                metrics = evaluation(weights, omega_b, zeta_b, names, decouple, feedforward)
        except ValueError as exc:  # no stabilising Riccati solution, or a diverged run
            failure = str(exc)
        value = slew_objective(metrics, margin, effort_weight, force_scale)
        history.append(
            {
                "multipliers": multipliers,
                "weights": weights,
                "metrics": metrics,
                "objective": value,
                "failure": failure,
            }
        )
        cache[key] = value
        if stop_when_met and _met(metrics, margin):
            raise _Stop
        return value

    n = len(free)
    bounds = [(-bound, bound)] * n
    try:
        if method == "nelder-mead":
            simplex = np.vstack([np.zeros(n), step * np.eye(n)])
            minimize(
                objective,
                np.zeros(n),
                method="Nelder-Mead",
                bounds=bounds,
                options={
                    "initial_simplex": simplex,
                    "maxfev": 10 * budget,
                    "xatol": 1e-2,
                    "fatol": 1e-6,
                },
            )
        else:
            minimize(
                objective,
                np.zeros(n),
                method="Powell",
                bounds=bounds,
                options={
                    "direc": step * np.eye(n),
                    "maxfev": 10 * budget,
                    "xtol": 1e-2,
                    "ftol": 1e-6,
                },
            )
    except _Stop:
        pass
    # a design meeting the goals beats one that misses them by less than its effort term
    best = min(history, key=lambda h: (not _met(h["metrics"], margin), h["objective"]))
    return TuningResult(
        best["weights"],
        best["metrics"],
        best["objective"],
        _met(best["metrics"], margin),
        best["multipliers"],
        tuple(history),
        _time.perf_counter() - start,
        method,
    )
