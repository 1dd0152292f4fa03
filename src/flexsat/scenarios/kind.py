"""Scenario kinds: one class per ``kind:`` of scenario file, and the registry that finds them.

A kind is a subclass of :class:`ScenarioKind`. Its :attr:`~ScenarioKind.kind` name is the
registry key; its :attr:`~ScenarioKind.document` (a pydantic model) validates the file; its
:meth:`~ScenarioKind.plan` yields the labelled runs of a scenario and returns the result. What
every kind shares -- progress, naming the failing run, relabelling a diverged simulation, the
report -- is done once, by :func:`flexsat.scenarios.runner.run_scenario` and
:func:`flexsat.report.page.write_report`.

A run (:class:`Run`) is either a :class:`Simulation` -- the (plant, law, configuration) the
runner hands to :func:`flexsat.sim.simulate` -- or, for an analysis without closed-loop
dynamics of its own, a callable. :meth:`~ScenarioKind.plan` is a generator: the runner sends
each run's outcome back, so a later run can depend on an earlier one (a slew designs its
feedback about the nominal maneuver its first run solved)::

    def plan(self, scenario):
        plant = build(scenario)                         # ScenarioError: nothing has run
        outcomes = []
        for index, run in enumerate(scenario.runs):
            outcomes.append((yield Run(run.label, Simulation(plant, law(run), config),
                                       path=f"runs[{run.label!r}]")))
        return MyResult(scenario, outcomes)

The registry (:func:`scenario_kinds`) holds the kinds defined in the modules of
:mod:`flexsat.scenarios` and those other packages declare in the entry-point group
``flexsat.kinds`` (:mod:`flexsat.plugins`); docs/kinds.md shows a plug-in kind.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from collections.abc import Callable, Generator, Mapping
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import BaseModel, ValidationError

from flexsat import plugins
from flexsat.scenarios.errors import Problem, ScenarioError, pydantic_problem

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.dynamics.plant import Plant
    from flexsat.sim.config import SimConfig


@dataclass(frozen=True)
class Simulation:
    """A run with dynamics: ``flexsat.sim.simulate(plant, law, config, **options)``.

    Attributes
    ----------
    plant : flexsat.dynamics.plant.Plant
    law : flexsat.control.Controller
    config : flexsat.sim.SimConfig
    options : mapping
        Further keyword arguments of :func:`flexsat.sim.simulate` (``n_cases``,
        ``initial_state``, ``record_states``, ...).
    """

    plant: Plant
    law: Controller
    config: SimConfig
    options: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Run:
    """One labelled step of a scenario.

    Attributes
    ----------
    label : str
        What the progress display shows (the run's label, ``"nominal maneuver"``, ...).
    task : Simulation or callable
        A simulation, or a callable of no argument (of ``progress`` when
        :attr:`reports_progress`) returning the run's outcome.
    path : str
        The field path that names the run in a problem (``runs['Law I']``); ``""`` is the
        scenario itself.
    reports_progress : bool
        The callable announces its own steps through the ``progress`` keyword it is given, in
        place of the runner's one announcement of :attr:`label`.
    """

    label: str
    task: Simulation | Callable[..., Any]
    path: str = ""
    reports_progress: bool = False


class ScenarioKind:
    """Base of every scenario kind (module docstring).

    Attributes
    ----------
    kind : str
        The ``kind:`` value of its files; the registry key.
    document : type of pydantic.BaseModel
        The schema of its files. It has a ``kind`` field, and ``yaml_text`` and ``folder``
        (:class:`flexsat.scenarios.fields.Document` gives them).
    runs_batches : bool
        Whether ``--workers`` and ``--scheduler`` apply (:meth:`with_execution`).
    """

    kind: ClassVar[str]
    document: ClassVar[type[BaseModel]]
    runs_batches: ClassVar[bool] = False

    def validate(self, data: dict[str, Any]) -> BaseModel:
        """The document of ``data`` (stage 1: schema, units, section rules).

        Raises
        ------
        ScenarioError
            Listing every problem, each with its field path.
        """
        try:
            return self.document.model_validate(data)
        except ValidationError as exc:
            raise ScenarioError(
                [pydantic_problem(e, data, self.document) for e in exc.errors()]
            ) from None

    def steps(self, scenario: Any) -> int:
        """How many progress steps :meth:`plan` announces (its runs, or the steps of a run
        that reports its own progress)."""
        raise NotImplementedError

    def plan(self, scenario: Any) -> Generator[Run, Any, Any]:
        """Yield the scenario's runs (each receives its outcome back) and return the result,
        an object with the protocol of :class:`flexsat.report.page.ReportedResult`.

        Raises
        ------
        ScenarioError
            For a problem found before or between the runs.
        """
        raise NotImplementedError

    def with_execution(self, scenario: Any, workers: int | None, scheduler: str | None) -> Any:
        """The scenario with the command line's ``--workers`` / ``--scheduler`` in place of its
        own; refused by a kind that does not run batches.

        Raises
        ------
        ScenarioError
        """
        if workers is None and scheduler is None:
            return scenario
        batch_kinds = [name for name, cls in scenario_kinds().items() if cls.runs_batches]
        raise ScenarioError(
            [
                Problem(
                    "--workers/--scheduler",
                    f"a {self.kind} scenario runs in this process; they apply to the kinds "
                    + ", ".join(batch_kinds),
                )
            ]
        )


def _kind_classes(module: ModuleType) -> list[type[ScenarioKind]]:
    return [
        obj
        for obj in vars(module).values()
        if isinstance(obj, type)
        and issubclass(obj, ScenarioKind)
        and obj.__module__ == module.__name__
        and isinstance(getattr(obj, "kind", None), str)
    ]


#: the kind of a scenario file that names none
DEFAULT_KIND = "maneuver"


@functools.cache
def built_in_kinds() -> dict[str, type[ScenarioKind]]:
    """The kinds defined in the modules of :mod:`flexsat.scenarios` (each module is imported
    to find them, once per process): :data:`DEFAULT_KIND` first, then by name."""
    import flexsat.scenarios as package

    found: dict[str, type[ScenarioKind]] = {}
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"{package.__name__}.{info.name}")
        for cls in _kind_classes(module):
            found[cls.kind] = cls
    return dict(sorted(found.items(), key=lambda item: (item[0] != DEFAULT_KIND, item[0])))


def _accept(name: str, obj: Any) -> str | None:
    """None for a plug-in kind the registry can hold, else the rule it breaks."""
    if not (isinstance(obj, type) and issubclass(obj, ScenarioKind)):
        return "not a subclass of flexsat.scenarios.kind.ScenarioKind"
    kind = getattr(obj, "kind", None)
    if kind != name:
        return f"its kind is {kind!r}; the entry-point name must be its kind"
    document = getattr(obj, "document", None)
    if not (isinstance(document, type) and issubclass(document, BaseModel)):
        return "its document is not a pydantic model"
    return None


def scenario_kinds() -> dict[str, type[ScenarioKind]]:
    """Every scenario kind by name: the built-in ones (:func:`built_in_kinds`), then those of
    the entry-point group ``flexsat.kinds``; a plug-in that cannot be loaded is left out and
    listed by :func:`flexsat.plugins.broken_plugins`."""
    built_in = built_in_kinds()
    reserved = {
        name: f"the built-in kind {name!r} ({cls.__module__}:{cls.__qualname__})"
        for name, cls in built_in.items()
    }
    return {
        **built_in,
        **plugins.entry_point_objects("flexsat.kinds", accept=_accept, reserved=reserved),
    }


def scenario_kind(name: Any) -> ScenarioKind:
    """The kind ``name`` (an instance of its class).

    Raises
    ------
    ScenarioError
        For a name that is no kind; the message lists the kinds there are.
    """
    kinds = scenario_kinds()
    if not isinstance(name, str) or name not in kinds:
        known = [repr(k) for k in kinds]
        raise ScenarioError(
            [Problem("kind", f"must be {', '.join(known[:-1])} or {known[-1]}, got {name!r}")]
        )
    return kinds[name]()


__all__ = [
    "DEFAULT_KIND",
    "Run",
    "ScenarioKind",
    "Simulation",
    "built_in_kinds",
    "scenario_kind",
    "scenario_kinds",
]
