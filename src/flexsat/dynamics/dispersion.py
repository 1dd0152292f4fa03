"""A batch of plants with the same channels and different parameters, one case each.

A Monte Carlo set may vary inertias, stiffnesses and damping per case. :func:`stack_plants`
builds a :class:`DispersedPlant` from one plant per case: its linear part (A, B) and output
matrices carry a leading case axis, and the engine propagates each case with its own
propagators (batched products), so case i of the batch is plant i run alone.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.plant import Plant
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from flexsat.units import FloatArray


class DispersedPlant(Plant):
    """Plants ``plants[i]`` as the cases of one batch (module docstring).

    Parameters
    ----------
    plants : sequence of Plant
        Same ``inputs``, ``outputs``, ``nx``, ``noise_channels`` and nonlinear structure (force
        matrix shape); parameters may differ.

    Raises
    ------
    ValueError
        Naming the field that differs between the plants, or a non-finite matrix entry.
    """

    def __init__(self, plants: Iterable[Plant]) -> None:
        plants = tuple(plants)
        if not plants or not all(isinstance(p, Plant) for p in plants):
            raise FieldError("plants", "give one or more Plant instances")
        first = plants[0]
        for i, p in enumerate(plants[1:], 1):
            for field in (
                "inputs",
                "outputs",
                "nx",
                "noise_channels",
                "recorded",
                "nonlinear",
                "maneuver",
            ):
                a, b = getattr(first, field), getattr(p, field)
                if (tuple(a) if isinstance(a, tuple) else a) != (
                    tuple(b) if isinstance(b, tuple) else b
                ):
                    raise FieldError(
                        field,
                        f"plants[{i}] has {field} {_show(b)}, plants[0] "
                        f"has {_show(a)}; a dispersed batch needs the same "
                        f"channels and state",
                    )
            fa, fb = first.force_matrix, p.force_matrix
            if (fa is None) != (fb is None) or (
                fa is not None and fb is not None and fa.shape != fb.shape
            ):
                raise FieldError(
                    "force_matrix",
                    f"plants[{i}] has a different nonlinear force structure from plants[0]",
                )
            if getattr(p, "step", None) is not None:
                raise FieldError(
                    "step",
                    f"plants[{i}] has its own integrator; a dispersed batch "
                    "is propagated by the exponential integrators",
                )
        self.plants = plants
        self.inputs = tuple(first.inputs)
        self.outputs = tuple(first.outputs)
        self.recorded = tuple(first.recorded)
        self.maneuver = first.maneuver
        self.noise_channels = tuple(first.noise_channels)
        self.nonlinear = bool(first.nonlinear)
        self.integrator = getattr(first, "integrator", "etd2rk")
        for extra in ("recorded_measurements", "recorded_disturbances"):  # planar plants' extras
            if hasattr(first, extra):
                setattr(self, extra, tuple(getattr(first, extra)))
        for name, M in (("A", self._linear[0]), ("B", self._linear[1])):
            bad = np.argwhere(~np.isfinite(M).reshape(len(plants), -1).all(axis=1))
            if bad.size:
                raise FieldError(
                    name,
                    f"plants[{int(bad[0, 0])}] has a non-finite entry in "
                    f"its linear part; check its dispersed parameters",
                )

    @property
    def nx(self) -> int:
        return self.plants[0].nx

    @property
    def n_cases(self) -> int:
        return len(self.plants)

    @cached_property
    def _linear(self) -> tuple[FloatArray, FloatArray]:
        parts = [p.linear_part() for p in self.plants]
        return np.stack([a for a, _ in parts]), np.stack([b for _, b in parts])

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B) with a leading case axis: (n_cases, n_x, n_x), (n_cases, n_x, m)."""
        return self._linear

    @cached_property
    def force_matrix(self) -> FloatArray | None:
        matrices = [p.force_matrix for p in self.plants]
        if any(m is None for m in matrices):  # all or none: checked at construction
            return None
        return np.stack([m for m in matrices if m is not None])

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """Each case's force from its own plant; x (..., n_cases, n_x)."""
        return np.stack(
            [p.nonlinear_force(x[..., i, :], u[..., i, :]) for i, p in enumerate(self.plants)],
            axis=-2,
        )

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        mats = [p.output_matrices(name) for p in self.plants]
        given = [m for m in mats if m is not None]
        if len(given) < len(mats):
            return None
        C, D = (np.stack([np.asarray(m[i], float) for m in given]) for i in range(2))
        return C, D, _stack_optional([m[2] for m in given])

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        """Output ``name`` per case, x (..., n_cases, n_x)."""
        return np.stack(
            [
                p.output(
                    name, x[..., i, :], u[..., i, :], None if f_in is None else f_in[..., i, :]
                )
                for i, p in enumerate(self.plants)
            ],
            axis=x.ndim - 2,
        )

    def _per_case(self, method: str, x: FloatArray) -> FloatArray | None:
        values = [getattr(p, method)(x[..., i, :]) for i, p in enumerate(self.plants)]
        if any(v is None for v in values):
            return None
        return np.stack(values, axis=x.ndim - 2)

    def energy(self, x: FloatArray) -> FloatArray | None:
        return self._per_case("energy", x)

    def momentum(self, x: FloatArray) -> FloatArray | None:
        return self._per_case("momentum", x)

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray | None:
        """Each case's dE/dt from its own plant; x (..., n_cases, n_x), u (..., n_cases, m)."""
        values = [p.power(x[..., i, :], u[..., i, :]) for i, p in enumerate(self.plants)]
        given = [v for v in values if v is not None]
        if len(given) < len(values):
            return None
        return np.stack(given, axis=x.ndim - 2)

    def initial_state(self, n_cases: int) -> FloatArray:
        return np.stack([p.initial_state(1)[0] for p in self.plants])

    def __getattr__(self, name: str) -> Callable[[FloatArray, FloatArray | None], FloatArray]:
        # per-case extras of the planar plants (vibration_energy): only when every plant has it
        if name == "vibration_energy" and all(
            hasattr(p, name) for p in self.__dict__.get("plants", ())
        ):

            def vibration_energy(x: FloatArray, energy: FloatArray | None = None) -> FloatArray:
                return np.stack(
                    [
                        getattr(p, name)(x[..., i, :], None if energy is None else energy[..., i])
                        for i, p in enumerate(self.plants)
                    ],
                    axis=x.ndim - 2,
                )

            return vibration_energy
        raise AttributeError(name)


def _stack_optional(parts: list[FloatArray | None]) -> FloatArray | None:
    """The per-case matrices stacked on a leading case axis; None (the output does not depend
    on that argument) where every case has None, zeros for the cases with None otherwise."""
    given = [np.asarray(p, float) for p in parts if p is not None]
    if not given:
        return None
    return np.stack([np.zeros_like(given[0]) if p is None else np.asarray(p, float) for p in parts])


def _show(value: object) -> str:
    if isinstance(value, tuple) and value and hasattr(value[0], "name"):
        return "(" + ", ".join(c.name for c in value) + ")"
    return repr(value)


def stack_plants(plants: Iterable[Plant]) -> Plant:
    """One plant whose case i is ``plants[i]``: a :class:`DispersedPlant`, or a batch that runs
    faster than one.

    - Plants of one type with a ``stacked`` class method (a plant batched over its own
      parameters, the :class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` with its own
      integrator) give what that method returns.
    - Hub + appendage plants of one structure (the same number of modes, appendages and
      stiffening) become a :class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage`:
      their integrals stacked into per-case arrays, which the compiled loop's metrics-only
      path takes.
    """
    plants = tuple(plants)
    kind = type(plants[0]) if plants else None
    stacked = getattr(kind, "stacked", None)
    if stacked is not None and all(type(p) is kind for p in plants):
        return stacked(plants)
    from flexsat.dynamics.hub_appendage import HubAppendage

    if plants and all(type(p) is HubAppendage for p in plants):
        first = plants[0]
        assert isinstance(first, HubAppendage)
        shape = (first.n_modes, first.stiffening, first.params.n_appendages)
        if all((p.n_modes, p.stiffening, p.params.n_appendages) == shape for p in plants):  # type: ignore[attr-defined]
            from flexsat.dynamics.dispersed_hub import DispersedHubAppendage

            return DispersedHubAppendage.from_plants(plants)  # type: ignore[arg-type]
    return DispersedPlant(plants)


__all__ = ["DispersedPlant", "stack_plants"]
