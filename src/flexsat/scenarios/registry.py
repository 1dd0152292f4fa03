"""What a law or a plant implements to be built from a scenario section, and the registries that
merge the built-in ones with the plug-ins (the ``flexsat.laws`` and ``flexsat.plants`` entry
points, :mod:`flexsat.plugins`).

A *scenario component* is a class (or any object) with

- ``Parameters``: a :class:`pydantic.BaseModel` subclass, the schema of its section (a run's
  ``gains:`` for a law, the ``plant:`` section for a plant); its fields are validated like the
  built-in ones, a problem reported as ``runs['a'].gains.kp: rule``. Use
  :func:`flexsat.scenarios.quantity` for a quantity with units (stored as its SI float);
- ``from_scenario(parameters, context)``: builds the runtime object from the validated
  ``Parameters`` instance and a context (:class:`~flexsat.scenarios.simulation_laws.LawContext`,
  :class:`~flexsat.scenarios.simulation_plants.PlantContext`); a ``ValueError`` whose message
  starts with ``field: `` is reported at that field of the section.

docs/plugins.md describes the protocol for each group with a worked example.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from pydantic import BaseModel

from flexsat.input_checks import FieldError


def component_rule(obj: Any, section_models: tuple[str, ...] = ("Parameters",)) -> str | None:
    """Why ``obj`` is not a scenario component (module docstring), or None.

    ``section_models`` are the attributes that must name a pydantic model (a law may also have
    ``Target``, which may be None).
    """
    for attribute in section_models:
        model = getattr(obj, attribute, None)
        if attribute != "Parameters" and model is None:
            continue
        if not (isinstance(model, type) and issubclass(model, BaseModel)):
            return (
                f"{attribute}: a scenario component needs a pydantic BaseModel subclass "
                f"{attribute!r} (the schema of its section), got {model!r}"
            )
    if not callable(getattr(obj, "from_scenario", None)):
        return "from_scenario: a scenario component needs a from_scenario(parameters, context)"
    return None


def validate_section(
    model: type[BaseModel], values: Any, owner: str, noun: str, section: str
) -> BaseModel:
    """``values`` (a scenario section) validated into ``model``.

    Unknown and missing keys are reported in the built-in laws' words (``kp: not a gain of law
    'pd' (its gains: kp, kd)``, ``kd: required by law 'pd'``) unless the model allows extra
    keys (``model_config["extra"] == "allow"``: a component with open-ended options checks them
    itself); every other problem is pydantic's, located at its field.

    Parameters
    ----------
    model : pydantic model class
        The component's ``Parameters`` (or a law's ``Target``).
    values : mapping
        The section as written (quantities not yet converted).
    owner : str
        What the section belongs to, for messages: ``"law 'pd'"``, ``"plant 'two_mass'"``.
    noun : str
        What one key is called: ``"gain"``, ``"option"``.
    section : str
        The section's key, for a section that is not a mapping.

    Raises
    ------
    ValueError
        ``key: rule`` for an unknown or missing key; pydantic's ValidationError (nested at the
        section's field) for a value its field refuses.
    """
    if not isinstance(values, Mapping):
        raise FieldError(section, f"a mapping of {noun}s, got {values!r}")
    known = list(model.model_fields)
    article = "an" if noun[0] in "aeiou" else "a"
    if model.model_config.get("extra") != "allow":
        for key in values:
            if key not in known:
                raise FieldError(
                    key,
                    f"not {article} {noun} of {owner} (its {noun}s: {', '.join(known) or 'none'})",
                )
    for key, field in model.model_fields.items():
        if field.is_required() and key not in values:
            raise FieldError(key, f"required by {owner}")
    return model.model_validate(dict(values))


def merge_builtins(
    group: str, builtins: Mapping[str, Any], describe: Callable[[str, Any], str]
) -> dict[str, Any]:
    """The built-in components of a kind followed by the plug-ins of entry-point ``group``.

    A plug-in that is not a component (:func:`component_rule`) or takes a built-in's name is
    left out and reported (:func:`flexsat.plugins.broken_plugins`).

    Parameters
    ----------
    group : str
        ``"flexsat.laws"`` or ``"flexsat.plants"``.
    builtins : mapping of str to component
        The built-in components by name.
    describe : callable
        ``describe(name, obj)``: what a built-in is, for a collision message (``"the built-in
        simulation law 'lqr' (flexsat.scenarios.simulation_laws:LQR)"``).
    """
    from flexsat.plugins import entry_point_objects

    models = ("Parameters", "Target") if group == "flexsat.laws" else ("Parameters",)
    reserved = {name: describe(name, obj) for name, obj in builtins.items()}
    plugins = entry_point_objects(group, lambda name, obj: component_rule(obj, models), reserved)
    return {**builtins, **plugins}


__all__ = ["component_rule", "merge_builtins", "validate_section"]
