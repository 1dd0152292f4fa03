"""Scenario files: YAML documents validated into SI objects, one module per ``kind``.

``kind: maneuver`` (the default, :mod:`flexsat.scenarios.maneuver`) slews a case's hub under
one or more control laws; ``kind: identification`` (:mod:`flexsat.scenarios.identification`)
tests a structure, identifies it and updates its model. :func:`load_scenario` reads either;
problems are reported as ``field.path: rule`` lines of one :class:`ScenarioError`, before
anything runs.

The names below are imported from their modules on first use, so ``load_scenario`` does not load
the identification stack until a scenario of that kind is read.
"""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    "DEFAULT_SCENARIO": "maneuver",
    "Scenario": "maneuver",
    "ScenarioError": "maneuver",
    "ScenarioPlan": "maneuver",
    "ScenarioResult": "maneuver",
    "count": "maneuver",
    "default_scenario": "maneuver",
    "load_scenario": "maneuver",
    "maneuver_cases": "maneuver",
    "prepare_scenario": "maneuver",
    "quantity": "maneuver",
    "run_scenario": "maneuver",
    "IdentificationResult": "identification",
    "IdentificationScenario": "identification",
    "identification_steps": "identification",
    "run_identification": "identification",
    "summary_table": "identification",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
