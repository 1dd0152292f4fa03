"""The control laws a maneuver run can name (``law:``): the gains each takes, whether it tracks
a reference, and how it builds its controller from the run, the case and the maneuver."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from flexsat.control import (
    PD,
    Controller,
    LQGController,
    LyapunovRegulator,
    LyapunovTracker,
    refine_estimator,
)
from flexsat.input_checks import FieldError
from flexsat.scenarios.fields import given_fields

if TYPE_CHECKING:
    from flexsat.maneuvers import TorqueShape
    from flexsat.scenarios.maneuver import RunSpec


@dataclass(frozen=True)
class CaseContext:
    """What the controllers need from the case and the maneuver."""

    angle: float
    reference_inertia: float
    appendage_inertia: float
    n_appendages: int
    plant: Any = None
    dt: float = 0.0


def _gains(run: RunSpec) -> dict[str, Any]:
    # RunSpec requires the law's gains (or, for pd, poles: _pd reads gains only without them)
    assert run.gains is not None
    return given_fields(run.gains)


def _regulator(run: RunSpec, ctx: CaseContext, reference: TorqueShape | None) -> Controller:
    return LyapunovRegulator(**_gains(run), target=ctx.angle, n_appendages=ctx.n_appendages)


def _tracker(run: RunSpec, ctx: CaseContext, reference: TorqueShape | None) -> Controller:
    assert reference is not None  # RunSpec requires a reference of lyapunov_tracker
    return LyapunovTracker(
        reference,
        **_gains(run),
        appendage_inertia=ctx.appendage_inertia,
        n_appendages=ctx.n_appendages,
    )


def _pd(run: RunSpec, ctx: CaseContext, reference: TorqueShape | None) -> Controller:
    options: dict[str, Any] = {"target": ctx.angle, "reference": reference}
    if run.feedforward is not None:
        options["feedforward"] = run.feedforward
    if run.poles is None:
        return PD(**_gains(run), **options)
    return PD.from_rigid_poles(
        ctx.reference_inertia, run.poles.natural_frequency, run.poles.damping_ratio, **options
    )


def _lqg(run: RunSpec, ctx: CaseContext, reference: TorqueShape | None) -> Controller:
    spec, plant = run.lqg, ctx.plant
    assert spec is not None  # RunSpec requires lqg of law 'lqg'
    A, B, _ = plant.state_space
    n, k = plant.ndof, plant.ndof - 1
    C = np.zeros((2, 2 * n))
    C[0, 0] = C[1, n] = 1.0
    weights = spec.mode_weights
    if not isinstance(weights, float) and len(weights) != k:
        raise FieldError(
            "lqg.mode_weights", f"give one weight or one per mode ({k}), got {len(weights)}"
        )
    modes = np.broadcast_to(np.asarray(weights, float), (k,))
    per_dof = np.concatenate([[spec.rigid_weight], modes])
    Q = np.diag(np.concatenate([per_dof, per_dof]))
    R = np.array([[spec.control_weight]])
    Rn = np.diag(spec.sensor_noise)
    options: dict[str, Any] = dict(target=ctx.angle, reference=reference)
    law = LQGController.design((A, B[:, None], C), Q, R, spec.process_noise, Rn, ctx.dt, **options)
    if spec.refine == "none":
        return law
    # LQGSpec requires keep_modes of refine "truncated"
    keep_modes = (
        k if spec.refine == "weighted" or spec.keep_modes is None else min(spec.keep_modes, k)
    )
    kept = np.r_[0, 1 : keep_modes + 1, n, n + 1 : n + keep_modes + 1]
    refined = refine_estimator(
        A, B[:, None], C, law.K, kept, Rn, truncate=spec.refine == "truncated"
    )
    return LQGController(A, B[:, None], C, refined.gain, refined.L, ctx.dt, **options)


@dataclass(frozen=True)
class _Law:
    gains: tuple[str, ...]
    required: tuple[str, ...]
    reference: Literal["required", "optional", "forbidden"]
    build: Callable[[RunSpec, CaseContext, TorqueShape | None], Controller]
    pd_options: bool = False


#: the laws a maneuver run can name
LawName = Literal["lyapunov_regulator", "lyapunov_tracker", "pd", "lqg"]
MANEUVER_LAWS: dict[LawName, _Law] = {
    "lyapunov_regulator": _Law(("g1", "g2", "g3"), ("g1", "g2"), "forbidden", _regulator),
    "lyapunov_tracker": _Law(("g1", "g2", "g3"), ("g1", "g2"), "required", _tracker),
    "pd": _Law(("kp", "kd"), ("kp", "kd"), "optional", _pd, pd_options=True),
    "lqg": _Law((), (), "optional", _lqg),
}
