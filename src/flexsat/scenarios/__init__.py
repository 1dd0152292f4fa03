"""Scenario files: YAML documents validated into SI objects, one module per ``kind``.

``kind: maneuver`` (the default, :mod:`flexsat.scenarios.maneuver`) slews a case's hub under
one or more control laws; ``kind: simulation`` (:mod:`flexsat.scenarios.simulation`) runs any
case's plant (three-axis spacecraft, structures with point actuators, a beam in orbit) under a
law reading and writing named channels; ``kind: slew`` (:mod:`flexsat.scenarios.slew`) slews a
flexible spacecraft on a frequency-shaped optimal maneuver with gain-scheduled perturbation
feedback and judges it against the seed 003 goals; ``kind: ppf`` (:mod:`flexsat.scenarios.ppf`)
optimises the PPF gains of the Agrawal–Bang structure (seed 004) and simulates its tip
responses; ``kind: identification``
(:mod:`flexsat.scenarios.identification`) tests a structure, identifies it and updates its
model. :func:`load_scenario` reads any of them;
problems are reported as ``field.path: rule`` lines of one :class:`ScenarioError`, before
anything runs.

Modules: :mod:`~flexsat.scenarios.errors` (the error and its field-path messages),
:mod:`~flexsat.scenarios.fields` (quantities, counts and base models shared by every kind),
:mod:`~flexsat.scenarios.documents` (reading a document and dispatching on its ``kind``),
:mod:`~flexsat.scenarios.maneuver` (the maneuver schema), :mod:`~flexsat.scenarios.laws` (its
control laws), :mod:`~flexsat.scenarios.runner` (preparing and running a maneuver scenario),
:mod:`~flexsat.scenarios.simulation_laws` and :mod:`~flexsat.scenarios.simulation_plants` (the
laws and plants a simulation scenario names, built-in or plug-in, through the protocol of
:mod:`~flexsat.scenarios.registry`) and :mod:`~flexsat.scenarios.identification`.

The names below are imported from their modules on first use, so ``load_scenario`` does not load
the identification stack until a scenario of that kind is read.
"""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    "ScenarioError": "errors",
    "count": "fields",
    "quantity": "fields",
    "DEFAULT_SCENARIO": "documents",
    "default_scenario": "documents",
    "load_scenario": "documents",
    "Scenario": "maneuver",
    "maneuver_cases": "maneuver",
    "ScenarioPlan": "runner",
    "ScenarioResult": "runner",
    "prepare_scenario": "runner",
    "run_scenario": "runner",
    "SimulationScenario": "simulation",
    "SimulationResult": "simulation",
    "run_simulation": "simulation",
    "simulation_cases": "simulation",
    # the registries themselves are the functions of the same name in those modules
    "LawContext": "simulation_laws",
    "PlantContext": "simulation_plants",
    "SlewScenario": "slew",
    "SlewResult": "slew",
    "run_slew": "slew",
    "PPFScenario": "ppf",
    "PPFResult": "ppf",
    "run_ppf": "ppf",
    "StarTrackerScenario": "star_tracker",
    "StarTrackerResult": "star_tracker",
    "run_star_tracker": "star_tracker",
    "TetherScenario": "tether",
    "TetherResult": "tether",
    "run_tether": "tether",
    "run_cmg": "cmg",
    "run_cmg_station": "cmg",
    "BatchScenario": "batch",
    "BatchResult": "batch",
    "run_batch_scenario": "batch",
    "IdentificationResult": "identification",
    "IdentificationScenario": "identification",
    "identification_steps": "identification",
    "run_identification": "identification",
    "summary_table": "identification",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
