"""The planned torque histories of slew scenarios (``shaping: {kind: planned, ...}``,
:mod:`flexsat.scenarios.slew`): the section's schema, the plan of a run (kept per nominal
setup) and its note for the report; the plant's force channels a ``forces`` field names.

The plan itself is :func:`flexsat.design.planned_slew.planned_slew`: the nominal plus a
sine-series correction of the torque (and, with ``forces``, of the plant's point forces)
bringing the design modes to rest at T at the least energy
:math:`\\int_0^T \\lVert\\Delta\tau\rVert^2 + w_F\\lVert F\rVert^2 dt` (or the least peak)
within the limits, by successive linearisation (EPS slew study c. 1989 for the goals and the
plant; the method is flexsat's, docs/eps.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import model_validator

from flexsat.input_checks import FieldError
from flexsat.scenarios.errors import Problem, ScenarioError, item_path
from flexsat.scenarios.fields import SchemaSection, in_unit, integer_in

if TYPE_CHECKING:
    from flexsat.design.planned_slew import PlannedSlew
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew
    from flexsat.scenarios.slew import SlewRunSpec
    from flexsat.sim import SimConfig

__all__ = ["PlannedShapingSpec", "force_channels", "plan_for_run", "plan_note"]


class PlannedShapingSpec(SchemaSection):
    """A torque history planned over the whole maneuver (:mod:`flexsat.design.planned_slew`):
    the nominal plus the sine-series correction bringing the design modes to rest at T at the
    least energy (or peak torque) within the torque limit."""

    kind: Literal["planned"]
    basis: Annotated[int, integer_in(1, 200)] = 30
    objective: Literal["energy", "peak"] = "energy"
    torque_limit: Annotated[float | None, in_unit("N*m", positive=True)] = None
    samples: Annotated[int | None, integer_in(2, 100_000, optional=True)] = None
    iterations: Annotated[int, integer_in(0, 20)] = 4
    feedback: bool = True
    forces: Literal["none", "all"] | list[str] = "none"
    force_limit: Annotated[float | None, in_unit("N", positive=True)] = None
    force_weight: Annotated[float, in_unit("m**2", positive=True)] = 1.0

    @model_validator(mode="after")
    def _force_fields(self) -> Self:
        if self.forces == "none":
            for name in ("force_limit", "force_weight"):
                if name in self.model_fields_set:
                    raise FieldError(name, "given without forces planned (shaping.forces)")
        return self


def force_channels(forces: str | list[str], where: str, plant: FlexibleSpacecraft) -> list[str]:
    """Force channels of ``plant`` named by a scenario's ``forces`` field (``none``, ``all``
    or a list of ``69X`` or ``force_69X``); a name the plant lacks is refused at ``where``."""
    available = [c.name for c in plant.inputs if c.name.startswith("force_")]
    if forces == "none":
        return []
    if forces == "all":
        return available
    names: list[str] = []
    for name in forces:
        channel = name if name.startswith("force_") else f"force_{name}"
        if channel not in available:
            raise ScenarioError(
                [
                    Problem(
                        where,
                        f"{name!r} is not a force of the plant (its forces: "
                        f"{', '.join(c[len('force_') :] for c in available)})",
                    )
                ]
            )
        names.append(channel)
    return names


def plan_for_run(
    run: SlewRunSpec,
    index: int,
    plant: FlexibleSpacecraft,
    kept: dict[str, Any],
    nominal: ThreeAxisSlew,
    config: SimConfig,
) -> PlannedSlew:
    """The run's planned torque history on the case's plant (kept in ``kept["plans"]``)."""
    from flexsat.design.planned_slew import planned_slew

    plans = kept.setdefault("plans", {})
    spec = run.shaping
    assert spec is not None
    if run.label not in plans:
        forces = force_channels(
            spec.forces, f"runs{item_path(index, run.label)}.shaping.forces", plant
        )
        try:
            plans[run.label] = planned_slew(
                plant,
                kept["design_plant"],
                nominal,
                config,
                spec.basis,
                spec.objective,
                spec.torque_limit,
                spec.samples,
                spec.iterations,
                forces=forces,
                force_limit=spec.force_limit,
                force_weight=spec.force_weight,
            )
        except FieldError as exc:
            names = {"n_basis": "basis", "n_samples": "samples", "config": "simulation"}
            field = names.get(exc.field, exc.field)
            raise FieldError(
                field if field == "simulation" else f"shaping.{field}", exc.rule
            ) from None
    plan: PlannedSlew = plans[run.label]
    return plan


def plan_note(label: str, plan: PlannedSlew, given_limit: float | None) -> str:
    """What a planned run's optimum is and which constraint binds (for the report);
    ``given_limit`` the run's ``shaping.torque_limit``."""
    peaks = ", ".join(f"{a} {p:,.0f}" for a, p in zip("xyz", plan.peak_torques, strict=True))
    text = (
        f"{label}: torque planned over the maneuver ({plan.objective} objective, "
        f"{plan.shaped.coefficients.shape[1]} sines per axis, {plan.rank} independent terminal "
        f"conditions); planned peak torques {peaks} N m; terminal residual by iteration "
        + " → ".join(f"{r:.2g}" for r in plan.iterates)
        + "."
    )
    if plan.torque_limit is not None and plan.force_limit is None:
        limit = float(plan.torque_limit[0])
        if not plan.feasible:
            text += (
                f" The torque limit {limit:,.0f} N m cannot be met: the least peak torque "
                f"meeting the terminal conditions is {plan.least_peak:.3g} × the limit "
                f"({plan.least_peak * limit:,.0f} N m); the plan flown is the last iterate."
            )
        else:
            largest = float(plan.multipliers.max()) if plan.multipliers.size else 0.0
            held = " (the least peak with its margin)" if plan.objective == "peak" else ""
            text += (
                f" Torque limit {limit:,.0f} N m{held}: {plan.active} sampled limits active "
                f"(largest multiplier {largest:.3g} (N m)² s per limit), KKT residual "
                f"{plan.kkt_residual:.1e}."
            )
    elif plan.force_limit is not None:  # with or without a torque limit
        limits = []
        if plan.torque_limit is not None:
            limits.append(f"torque {float(plan.torque_limit[0]):,.0f} N m")
        if plan.force_limit is not None:
            limits.append(f"force {plan.force_limit:,.0f} N")
        named = " and ".join(limits)
        if not plan.feasible:
            text += (
                f" The limits ({named}) cannot be met: the least peak meeting the terminal "
                f"conditions is {plan.least_peak:.3g} × the limits"
                + (
                    f" ({plan.least_peak * float(plan.torque_limit[0]):,.0f} N m of torque)"
                    if plan.torque_limit is not None
                    else ""
                )
                + "; the plan flown is the last iterate."
            )
        else:
            largest = float(plan.multipliers.max()) if plan.multipliers.size else 0.0
            held = " (the least peak with its margin)" if plan.objective == "peak" else ""
            text += (
                f" Limits {named}{held}: {plan.active} sampled limits active "
                f"(largest multiplier {largest:.3g} (N m)² s per limit), KKT residual "
                f"{plan.kkt_residual:.1e}."
            )
    if plan.force_channels:
        text += (
            " Planned point forces, peaks "
            + ", ".join(
                f"{name[len('force_') :]} {p:,.0f}"
                for name, p in zip(plan.force_channels, plan.peak_forces, strict=True)
            )
            + f" N; torque correction energy {plan.torque_energy:.3g} N² m² s."
        )
    if plan.objective == "peak" and plan.feasible and np.isfinite(plan.least_peak):
        # in units of the given limit, in N m without one (PlannedSlew.least_peak)
        least = plan.least_peak * (1.0 if given_limit is None else given_limit)
        text += f" Least peak of the first linearisation: {least:,.0f} N m."
    return text
