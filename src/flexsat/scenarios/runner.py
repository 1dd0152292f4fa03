"""Running a scenario of any kind: the one loop over the runs its kind plans.

:func:`run_scenario` asks the scenario's kind (:mod:`flexsat.scenarios.kind`) for its runs,
announces each to ``progress``, hands a :class:`~flexsat.scenarios.kind.Simulation` to
:func:`flexsat.sim.simulate` or calls an analysis, sends the outcome back to the kind and
returns the kind's result. Whatever fails in a run is named by the run's field path: a problem
of its values becomes a :class:`~flexsat.scenarios.errors.ScenarioError`, a simulation that
diverges a :class:`~flexsat.sim.SimulationDiverged` whose message starts with the run. Ctrl-C
(:class:`KeyboardInterrupt`, a batch's
:class:`~flexsat.design.batch_runner.BatchInterrupted`) passes through untouched.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from flexsat.scenarios.errors import ScenarioError, locate
from flexsat.scenarios.kind import Run, Simulation, scenario_kind
from flexsat.sim import SimulationDiverged, simulate


def _execute(run: Run, progress: Callable[[str], None] | None) -> Any:
    """The outcome of one run, its failures named by the run's path."""
    if progress is not None and not run.reports_progress:
        progress(run.label)
    try:
        if isinstance(run.task, Simulation):
            task = run.task
            return simulate(task.plant, task.law, task.config, **task.options)
        return run.task(progress=progress) if run.reports_progress else run.task()
    except SimulationDiverged as exc:
        where = f"{run.path}: " if run.path else ""
        raise SimulationDiverged(f"{where}{exc}", exc.cases, exc.time, exc.cause) from None
    except ScenarioError:
        raise
    except ValueError as exc:
        raise ScenarioError([locate(run.path, exc)]) from None


def run_scenario(scenario: Any, progress: Callable[[str], None] | None = None) -> Any:
    """Run every run of ``scenario`` and return its result.

    Parameters
    ----------
    scenario
        A validated document (:func:`flexsat.scenarios.load_scenario`) of any kind.
    progress : callable, optional
        Called with a label as each of the kind's
        :meth:`~flexsat.scenarios.kind.ScenarioKind.steps` starts.

    Returns
    -------
    flexsat.report.page.ReportedResult
        The kind's result (:func:`flexsat.report.write_report` writes its report).

    Raises
    ------
    ScenarioError
        For a problem the kind finds before or between the runs, or a value a run refuses
        (named by the run: ``runs['Law I'].gains.g1: ...``); no result is returned.
    flexsat.sim.SimulationDiverged
        If a run diverges (the message starts with the run, ``runs['Law I']: ...``).
    """
    plan = scenario_kind(scenario.kind).plan(scenario)
    outcome = None
    try:
        while True:
            outcome = _execute(plan.send(outcome), progress)
    except StopIteration as done:
        return done.value
    finally:
        plan.close()


__all__ = ["run_scenario"]
