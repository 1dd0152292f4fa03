"""The plants a simulation scenario names: each case's own plant and the ``flexsat.plants``
plug-ins, all built through one protocol (:mod:`flexsat.scenarios.registry`).

The scenario's ``plant:`` section picks one with ``name`` (default: the scenario's ``case``,
whose object builds its plant with ``plant(**options)``); its other keys are the plant's
``Parameters``. A plug-in plant is a class with ``Parameters`` and a classmethod
``from_scenario(parameters, context)`` returning a :class:`flexsat.dynamics.plant.Plant`;
``context`` is a :class:`PlantContext`. :func:`simulation_plants` is the registry the scenario
schema and runner call.
"""

from __future__ import annotations

import functools
import inspect
import typing
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import BaseModel, ConfigDict

from flexsat.catalog import CASES, all_cases, get_case
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from flexsat.dynamics.plant import Plant


@dataclass(frozen=True)
class PlantContext:
    """What a plant is built against: ``case``, the scenario's case name (the benchmark the
    report cites)."""

    case: str


class CasePlantOptions(BaseModel):
    """The keyword arguments of a case's ``plant()``: open-ended here, checked against its
    signature when the plant is built."""

    model_config = ConfigDict(extra="allow")


@dataclass(frozen=True)
class CasePlant:
    """The plant the object of case ``case`` builds (``plant(**options)``)."""

    case: str
    Parameters: ClassVar[type[BaseModel]] = CasePlantOptions

    def from_scenario(self, parameters: BaseModel, context: PlantContext) -> Plant:
        """Build the case and its plant; the options are checked against ``plant()``."""
        if context.case != self.case:
            raise FieldError(
                "name",
                f"{self.case!r} is the plant of case {self.case!r}, not of the "
                f"scenario's case {context.case!r}",
            )
        builder = get_case(self.case).builder().plant
        accepted = inspect.signature(builder).parameters
        options = parameters.model_dump()
        for name in options:
            if name not in accepted:
                raise FieldError(
                    name,
                    f"not an option of the {self.case} plant "
                    f"(its options: {', '.join(accepted) or 'none'})",
                )
        return builder(**options)


@functools.cache
def simulation_cases() -> tuple[str, ...]:
    """Cases whose object has a ``plant`` method, read from the builder's return annotation (or
    the builder itself when it is a class) so that no case is built."""
    names: list[str] = []
    for name, info in all_cases().items():
        builder = info.builder
        try:
            hints = {} if isinstance(builder, type) else typing.get_type_hints(builder)
        except Exception:  # noqa: BLE001 -- a plug-in's unresolvable annotation: it has no plant
            if name in CASES:  # a built-in's is a bug to see
                raise
            continue
        kind = builder if isinstance(builder, type) else hints.get("return")
        if callable(getattr(kind, "plant", None)):
            names.append(name)
    return tuple(names)


def simulation_plants() -> dict[str, Any]:
    """The plants a simulation scenario can name: each case's plant (:class:`CasePlant`, named
    after its case), then the ``flexsat.plants`` plug-ins (read on the first call; a broken or
    colliding one is left out and reported by :func:`flexsat.plugins.broken_plugins`)."""
    from flexsat.scenarios.registry import merge_builtins

    builtins = {name: CasePlant(name) for name in simulation_cases()}
    return merge_builtins(
        "flexsat.plants", builtins, lambda name, plant: f"the plant of the case {name!r}"
    )


__all__ = ["CasePlant", "CasePlantOptions", "PlantContext", "simulation_cases", "simulation_plants"]
