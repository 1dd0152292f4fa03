"""The ``model:`` problem of a ``design`` scenario: design variables on your own inline
finite-element model (issue 23, deliverable 1).

::

    kind: design
    name: minimum-mass boom with a frequency floor
    model:
      fe: {...}                       # the schema of a simulation scenario's model: fe:
    variables:
      root_width: {section: root, property: width, lower: 5 mm, upper: 60 mm}
      tip: {lumped_mass: 4, start: 0.5 kg, lower: 0.2 kg, upper: 1 kg}
      hub_z: {lumped_mass: 0, property: inertia, axis: z, lower: ..., upper: ...}
    objective: mass
    constraints:
      - {response: frequency_hz_1, min: 3 Hz}
      - {response: separation_hz_1_2, min: 1 Hz}

``model:`` is the ``model:`` section of a simulation or design-study scenario
(:class:`flexsat.scenarios.models.ModelSection`, parsed by it), with an inline ``fe:``
description: a design variable changes element matrices, which a modal model file does not
hold. A variable names

- ``section`` (a key of ``model.fe.sections``: every member using it is one design group) and
  ``property``, a dimension of its shape (tube: ``outer_diameter``, ``thickness``; rectangle:
  ``width``, ``height``; circle: ``diameter``; general: ``area``, ``Iy``, ``Iz``, ``J``), or
- ``material`` (a key of ``model.fe.materials``) and ``property``: ``E`` or ``density``, in
  every member made of it (with ``nu`` given, G = E / (2 (1 + nu)) follows E), or
- ``lumped_mass`` (the node id of an entry of ``model.fe.masses``; one entry at that node) and
  ``property``: ``mass`` (the default) or ``inertia`` with its ``axis`` (x, y, z).

``start`` defaults to the model's own value; ``lower`` and ``upper`` are required. Responses
(:mod:`flexsat.design.structure_problem`): ``mass`` (kg), ``frequency_hz_<k>`` (the k-th
elastic frequency, Hz, k <= ``model.fe.n_modes``), ``separation_hz_<i>_<j>`` (f_j − f_i, Hz).
Every refusal names its field path (``variables.root_width.section: unknown section 'rot'``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.design.structure_problem import (
    MASS_PROPERTIES,
    MATERIAL_PROPERTIES,
    PROPERTY_UNITS,
    SECTION_PROPERTIES,
    MassVariable,
    MaterialVariable,
    SectionShape,
    SectionVariable,
    StructureProblem,
    parse_response,
)
from flexsat.input_checks import FieldError
from flexsat.units import to_si

if TYPE_CHECKING:
    from flexsat.scenarios.models import ModelSection

__all__ = ["model_problem", "response_names"]

_AXES = ("x", "y", "z")


def response_names(scenario: Any) -> list[tuple[str, str]]:
    """(field path, response name) of every response the document names: the objective, each
    constraint's response and the Pareto front's secondary."""
    names = [("objective", scenario.objective)]
    names += [
        (f"constraints[{i}].response", c.response) for i, c in enumerate(scenario.constraints)
    ]
    if scenario.pareto is not None:
        names.append(("pareto.secondary", scenario.pareto.secondary))
    return names


def model_problem(scenario: Any) -> tuple[StructureProblem, dict[str, str], dict[str, str]]:
    """The :class:`~flexsat.design.structure_problem.StructureProblem` of a ``design`` document
    with a ``model:`` section, the SI unit of each variable and of each response.

    Raises
    ------
    FieldError
        At its field path: ``model.file`` (not an inline model), ``variables.<name>.<key>``,
        ``objective``, ``constraints[i].response``, ``pareto.secondary``, ``parameters``.
    """
    section: ModelSection = scenario.model
    for key in ("file", "hub_appendage"):
        if getattr(section, key) is not None:
            raise FieldError(
                f"model.{key}",
                "design variables change element matrices: give the structure as an inline "
                "finite-element model (model.fe); a modal model file or a hub with appendages "
                "has none",
            )
    fe = section.fe
    assert fe is not None  # ModelSection holds exactly one source
    if scenario.parameters:
        raise FieldError(
            "parameters", "apply to a reference problem (problem:); your model is in model.fe"
        )
    if not scenario.variables:
        raise FieldError("variables", "name at least one design variable of the model")
    named = []
    for path, name in response_names(scenario):
        try:
            _, modes = parse_response(name)
        except FieldError as exc:
            raise FieldError(path, exc.rule) from None
        if modes and max(modes) > fe.n_modes:
            raise FieldError(
                path,
                f"{name}: mode {max(modes)} is beyond model.fe.n_modes = {fe.n_modes} "
                "(elastic modes counted from 1)",
            )
        named.append(name)
    shapes = {
        key: SectionShape(
            entry.shape, {p: float(getattr(entry, p)) for p in SECTION_PROPERTIES[entry.shape]}
        )
        for key, entry in fe.sections.items()
    }
    variables = tuple(_variable(name, spec, fe) for name, spec in scenario.variables.items())
    try:
        description = fe.description()
    except FieldError as exc:
        raise FieldError(f"model.fe.{exc.field}", exc.rule) from None
    problem = StructureProblem(description, shapes, variables, tuple(dict.fromkeys(named)))
    units = {v.name: PROPERTY_UNITS[v.property] for v in variables}
    return problem, units, problem.response_units()


def _variable(name: str, spec: Any, fe: Any) -> SectionVariable | MassVariable | MaterialVariable:
    """One variable of the document (SI), refused at ``variables.<name>.<key>``."""
    where = f"variables.{name}"
    given = [k for k in ("section", "material", "lumped_mass") if getattr(spec, k) is not None]
    if len(given) != 1:
        raise FieldError(
            where,
            "name one of: a section of model.fe.sections (section:), a material of "
            "model.fe.materials (material:) or the node of a lumped mass of model.fe.masses "
            f"(lumped_mass:); got {', '.join(given) or 'none'}",
        )
    for key in ("lower", "upper"):
        if getattr(spec, key) is None:
            raise FieldError(f"{where}.{key}", "a variable of your model needs its bounds")
    if spec.material is not None:
        if spec.material not in fe.materials:
            known = ", ".join(fe.materials)
            raise FieldError(f"{where}.material", f"unknown material {spec.material!r} ({known})")
        if spec.property not in MATERIAL_PROPERTIES or spec.axis is not None:
            raise FieldError(
                f"{where}.property", f"a material has E or density, got {spec.property!r}"
            )
        unit = PROPERTY_UNITS[spec.property]
        model_value = getattr(fe.materials[spec.material], spec.property)
        start, lower, upper = _bounds(spec, unit, where, model_value)
        return MaterialVariable(name, spec.material, spec.property, start, lower, upper)
    if spec.section is not None:
        if spec.section not in fe.sections:
            known = ", ".join(fe.sections)
            raise FieldError(f"{where}.section", f"unknown section {spec.section!r} ({known})")
        entry = fe.sections[spec.section]
        allowed = SECTION_PROPERTIES[entry.shape]
        if spec.property not in allowed:
            raise FieldError(
                f"{where}.property",
                f"section {spec.section!r} is a {entry.shape}: one of {', '.join(allowed)}, "
                f"got {spec.property!r}",
            )
        if spec.axis is not None:
            raise FieldError(f"{where}.axis", "applies to a lumped mass's inertia")
        unit = PROPERTY_UNITS[spec.property]
        model_value = getattr(entry, spec.property)
        start, lower, upper = _bounds(spec, unit, where, model_value)
        return SectionVariable(name, spec.section, spec.property, start, lower, upper)
    at = [i for i, m in enumerate(fe.masses) if m.node == spec.lumped_mass]
    if len(at) != 1:
        nodes = ", ".join(str(m.node) for m in fe.masses) or "none"
        raise FieldError(
            f"{where}.lumped_mass",
            f"{'no' if not at else 'more than one'} lumped mass at node {spec.lumped_mass} "
            f"(model.fe.masses are at nodes {nodes})",
        )
    entry = fe.masses[at[0]]
    prop = spec.property or "mass"
    if prop not in MASS_PROPERTIES:
        raise FieldError(f"{where}.property", f"a lumped mass has mass or inertia, got {prop!r}")
    if (prop == "inertia") != (spec.axis is not None):
        raise FieldError(f"{where}.axis", "an inertia names its axis (x, y or z); a mass none")
    if prop == "mass":
        model_value = entry.mass
    else:
        J = np.zeros(3) if entry.inertia is None else np.asarray(entry.inertia, dtype=float)
        a = _AXES.index(spec.axis)
        model_value = float(J[a] if J.ndim == 1 else J[a, a])
    start, lower, upper = _bounds(spec, PROPERTY_UNITS[prop], where, model_value)
    return MassVariable(name, at[0], prop, start, lower, upper, spec.axis)


def _bounds(spec: Any, unit: str, where: str, model_value: Any) -> tuple[float, float, float]:
    """start (the model's value when not given), lower, upper in SI."""
    lower = to_si(spec.lower, unit, f"{where}.lower")
    upper = to_si(spec.upper, unit, f"{where}.upper")
    start = float(model_value) if spec.start is None else to_si(spec.start, unit, f"{where}.start")
    for key, value in (("start", start), ("lower", lower), ("upper", upper)):
        if not value > 0:
            raise FieldError(f"{where}.{key}", f"must be > 0, got {value!r} {unit}")
    if not lower < upper:
        raise FieldError(f"{where}.lower", f"must be < upper, got [{lower}, {upper}] {unit}")
    if not lower <= start <= upper:
        what = "the model's value" if spec.start is None else "start"
        raise FieldError(f"{where}.start", f"{what} {start} {unit} is outside [{lower}, {upper}]")
    return start, lower, upper
