"""Scenario files: YAML documents validated into SI objects, one kind class per ``kind``.

Each ``kind:`` of scenario file is a class (:class:`~flexsat.scenarios.kind.ScenarioKind`)
that carries the file's schema and plans its runs: ``kind: maneuver`` (the default,
:mod:`flexsat.scenarios.maneuver_kind`) slews a case's hub under one or more control laws;
``kind: simulation`` (:mod:`flexsat.scenarios.simulation`) runs any case's plant under a law
reading and writing named channels; ``slew``, ``ppf``, ``star_tracker``, ``tether``, ``cmg``,
``cmg_station``, ``identification``, ``sweep`` and ``montecarlo`` have a module each. Other
packages add kinds through the entry-point group ``flexsat.kinds`` (docs/kinds.md).
:func:`load_scenario` reads any of them and :func:`run_scenario` runs any of them; problems are
reported as ``field.path: rule`` lines (:class:`~flexsat.scenarios.errors.Problem`) of one
:class:`ScenarioError`, before anything runs.

Modules: :mod:`~flexsat.scenarios.errors` (the error and its field-path problems),
:mod:`~flexsat.scenarios.fields` (quantities, counts and base models shared by every kind),
:mod:`~flexsat.scenarios.kind` (the kind protocol and registry),
:mod:`~flexsat.scenarios.documents` (reading a document and validating it by its kind),
:mod:`~flexsat.scenarios.runner` (the one loop that runs a scenario's runs),
:mod:`~flexsat.scenarios.simulation_laws` and :mod:`~flexsat.scenarios.simulation_plants` (the
laws and plants a simulation scenario names, built-in or plug-in, through the protocol of
:mod:`~flexsat.scenarios.registry`), then one module per kind.

The names below are imported from their modules on first use: importing the package loads
none of the kinds.
"""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    "Problem": "errors",
    "ScenarioError": "errors",
    "count": "fields",
    "quantity": "fields",
    "in_unit": "fields",
    "integer_in": "fields",
    "DEFAULT_SCENARIO": "documents",
    "default_scenario": "documents",
    "load_scenario": "documents",
    "Run": "kind",
    "ScenarioKind": "kind",
    "Simulation": "kind",
    "scenario_kind": "kind",
    "scenario_kinds": "kind",
    "run_scenario": "runner",
    "Scenario": "maneuver",
    "maneuver_cases": "maneuver",
    "ManeuverResult": "maneuver_kind",
    "ScenarioPlan": "maneuver_kind",
    "prepare_scenario": "maneuver_kind",
    "SimulationScenario": "simulation",
    "SimulationResult": "simulation",
    "simulation_cases": "simulation",
    # the registries themselves are the functions of the same name in those modules
    "LawContext": "simulation_laws",
    "PlantContext": "simulation_plants",
    "SlewScenario": "slew",
    "SlewResult": "slew",
    "PPFScenario": "ppf",
    "PPFResult": "ppf",
    "StarTrackerScenario": "star_tracker",
    "StarTrackerResult": "star_tracker",
    "TetherScenario": "tether",
    "TetherResult": "tether",
    "BatchScenario": "batch",
    "BatchResult": "batch",
    "IdentificationResult": "identification",
    "IdentificationScenario": "identification",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
