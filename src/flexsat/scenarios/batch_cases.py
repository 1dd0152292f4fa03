r"""The cases of a sweep or Monte Carlo over any scenario: values written into copies of the
target document, each copy run by :func:`flexsat.scenarios.runner.run_scenario`.

A batch whose ``parameters:`` are field paths of its target scenario
(:mod:`flexsat.scenarios.document_paths`) varies that document, whatever its kind::

    kind: sweep
    name: PPF filter damping
    scenario: agrawal_bang_ppf.yaml
    run: 1a paper                       # one run of the target (leave out: all its runs)
    parameters:
      ppf.zeta_f: {values: [0.05, 0.1, 0.2]}
      simulation.duration: {values: ["20 s", "40 s"]}

Case i is the target document with ``runs`` cut down to the named run, each parameter's value
written at its path as a quantity string in the parameter's own unit (the unit its entry is
written in, e.g. ``"52.3 ozf*in*s**2"``; a plain SI number where the entry has no unit), and
the case's noise seed written into the kind's seed field (``simulation.seed``, else a top-level
``seed``) where the kind has one. That document is validated by the target's kind and run by
the one runner, so a case is the scenario run alone with those values: the same document
through the same code, bit for bit.

Seeds. Case i's seed is :func:`flexsat.design.batch_seeds.case_seeds`' :math:`s_i \in
[0, 2^{63})` folded into a scenario's seed range :math:`[0, 2^{32})`
(:data:`flexsat.limits.MAX_SEED`) by keeping its 32 high bits, :math:`s_i \gg 31`: a function of
the base seed and i alone, so results do not depend on the chunking or the workers. (Two of
n cases share a 32-bit seed with probability about :math:`n^2 / 2^{33}`: 1 % at 10,000.)

Checks before any case runs (:meth:`DocumentCases.check`):

* every path leads into the target document (else refused by name with the nearest paths), and
  holds a number or a quantity whose dimension is the parameter's;
* **every** case's document is validated by the target's kind (stage 1: schema, units, section
  rules), a problem named by the parameter, the case index and the rule: 5.5–6 ms a case
  measured for the NPS slew and the space station (a minute for 10,000 cases, against 0.2–3 s
  a case to run them);
* the **extreme draws** — for each parameter the case of its least and of its greatest value —
  are also planned up to their first run (stage 2: the kind builds the plant and designs the
  laws, where rules such as a positive definite inertia satisfying the triangle inequality or a
  positive stiffness are checked), so a distribution whose tails make the plant unphysical is
  refused before any case runs. A rule broken only by an interior combination of values is
  found when its case runs, named the same way.

Metrics (:func:`case_metrics`): the numbers of the kind's
:meth:`~flexsat.report.page.ReportedResult.metrics_records` (``metrics.json``): with one run,
each under its own name (``settling_time_s``); with several, under ``runs['label'].name``. A
flag is 0 or 1, a missing value (None) NaN; text is left out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, get_args

import numpy as np
import yaml
from pydantic import BaseModel

from flexsat.input_checks import FieldError
from flexsat.scenarios.document_paths import (
    nearest_paths,
    parse_path,
    read_value,
    with_values,
)
from flexsat.scenarios.errors import Problem, ScenarioError, locate
from flexsat.scenarios.kind import scenario_kind

if TYPE_CHECKING:
    from flexsat.report.page import ReportedResult

#: the chunk size of a batch over a document that gives none: its cases take 0.2–5 s each
#: (one scenario run each, docs/sweeps.md), so 10 a chunk keeps the progress, the resumable
#: part and the tasks for several workers fine-grained (the Law II fast path's 1,000 is one
#: compiled call of about a second)
DOCUMENT_CHUNK_SIZE = 10

#: the keys of a parameter's entry that hold its values (the others: a name, a count)
_VALUE_KEYS = ("mean", "sd", "low", "high", "median", "gsd", "values")


def is_document_path(name: str) -> bool:
    """Whether a ``parameters:`` key is a field path of the target (it has a ``.`` or a
    ``[``) rather than a name of the Law II fast path."""
    return "." in name or "[" in name


def _unit_of(text: str, field: str) -> tuple[str, str] | None:
    """(the unit as written, its SI unit) of a quantity string, None for a plain number. A
    cyclic frequency keeps the hertz as its SI unit: pint's base unit of Hz is 1/s, which
    :func:`flexsat.units.to_si_array` would not tell from rad/s, so a value in rad/s among
    values in Hz would lose its 2π."""
    from flexsat.units import parse_quantity

    q = parse_quantity(text, field)
    if q.dimensionless and q.units == q.to_base_units().units:
        return None
    written = f"{q.units:~C}"
    return written, "Hz" if str(q.units) == "hertz" else f"{q.to_base_units().units:~C}"


def written_unit(entry: Mapping[str, Any], field: str) -> tuple[str, str] | None:
    """(unit, SI unit) of the first quantity string among a parameter entry's values; None
    when they are all plain numbers (SI)."""
    for key in _VALUE_KEYS:
        values = entry.get(key)
        for value in values if isinstance(values, list) else [values]:
            if isinstance(value, str):
                unit = _unit_of(value, f"{field}.{key}")
                if unit is not None:
                    return unit
    return None


@dataclass(frozen=True)
class DocumentParameter:
    """One varied field: its ``path`` (the table's column), the SI ``unit`` of the table's
    values, and the ``written`` unit its values go into the document in (None: a plain SI
    number)."""

    path: str
    unit: str
    written: str | None

    def value(self, si: float) -> float | str:
        """The document's value for the SI value ``si``: ``"52.3 ozf*in*s**2"`` or a number."""
        from flexsat.units import si_factor

        if self.written is None:
            return float(si)
        return f"{float(si) / si_factor(self.written)!r} {self.written}"


def document_parameter(path: str, entry: Mapping[str, Any], data: object) -> DocumentParameter:
    """The parameter at ``path`` of the target document ``data``, its unit from its
    ``entry``, its dimension checked against the document's value there.

    Raises
    ------
    FieldError
        ``parameters[path]``: a path that is not in the document (nearest paths named), a value
        there that is not a number or a quantity, a unit of another dimension.
    """
    from flexsat.units import parse_quantity

    field = f"parameters.{path}"
    parse_path(path, field)
    current = read_value(data, path, field)
    unit = written_unit(entry, field)
    if isinstance(current, bool) or not isinstance(current, (int, float, str, type(None))):
        raise FieldError(field, f"{path} holds {current!r}, not a number or a quantity")
    doc_unit = None
    if isinstance(current, str):
        try:
            doc_unit = _unit_of(current, path)
        except FieldError:
            raise FieldError(
                field, f"{path} holds {current!r}, not a number or a quantity"
            ) from None
    if unit is not None and doc_unit is not None:
        mine = parse_quantity(f"1 {unit[0]}", field).dimensionality
        theirs = parse_quantity(f"1 {doc_unit[0]}", field).dimensionality
        if mine != theirs:
            raise FieldError(
                field,
                f"values in {unit[0]} ({mine}) where the scenario's {path} is {current!r} "
                f"({theirs}): give them in a unit of its dimension",
            )
    if unit is not None:
        return DocumentParameter(path, unit[1], unit[0])
    if doc_unit is None:
        return DocumentParameter(path, "", None)
    # plain numbers are SI, read by the kind's schema in the field's own SI unit: labelled
    # with the base unit of the document's value (1/s for a value in Hz, as for one in rad/s)
    base = parse_quantity(current, field).to_base_units().units  # type: ignore[arg-type]
    return DocumentParameter(path, f"{base:~C}", None)


def noise_seed_path(document: type[BaseModel]) -> str | None:
    """The field of a kind's document that holds the noise seed: ``simulation.seed`` if its
    ``simulation`` section has a ``seed``, else a top-level ``seed``; None if it has neither
    (a deterministic kind)."""
    fields = document.model_fields
    if "simulation" in fields:
        annotation = fields["simulation"].annotation
        for model in (annotation, *get_args(annotation)):
            if isinstance(model, type) and issubclass(model, BaseModel):
                if "seed" in model.model_fields:
                    return "simulation.seed"
    return "seed" if "seed" in fields else None


def document_seeds(base_seed: int, cases: np.ndarray) -> np.ndarray:
    """The seeds written into the case documents (module docstring: s_i >> 31), int64."""
    from flexsat.design.batch_seeds import case_seeds

    return case_seeds(base_seed, cases) >> 31


def case_metrics(result: ReportedResult) -> dict[str, float]:
    """The case's scalar metrics from its result's records (module docstring)."""
    from flexsat.report.json_data import NULL_REASONS

    records = result.metrics_records()
    out: dict[str, float] = {}
    for record in records:
        prefix = "" if len(records) == 1 else f"runs[{record['run']!r}]."
        for key, value in record.items():
            if key in ("run", NULL_REASONS):
                continue
            if value is None:
                out[prefix + key] = math.nan
            elif isinstance(value, (bool, int, float, np.number, np.bool_)):
                out[prefix + key] = float(value)
    return out


@dataclass(frozen=True)
class DocumentCases:
    """The case builder of a batch over a target document (module docstring), handed to
    :func:`flexsat.design.batch_runner.run_batch`, which calls :meth:`check` on the table, then
    :meth:`run_chunk` on dask workers.

    Attributes
    ----------
    kind : str
        The target's kind.
    data : dict
        The target document as parsed (its runs cut down to ``run``).
    folder : Path
        The target's folder (relative paths in it start there).
    parameters : tuple of DocumentParameter
    seed_path : str or None
        The kind's noise seed field (:func:`noise_seed_path`).
    requirements : tuple of str
        Metrics the batch's requirements read: a case without one is refused by name.
    """

    kind: str
    data: dict[str, Any]
    folder: Path
    parameters: tuple[DocumentParameter, ...]
    seed_path: str | None
    requirements: tuple[str, ...] = ()

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The table's columns: the parameters' paths."""
        return tuple(p.path for p in self.parameters)

    def describe(self) -> str:
        """The builder's settings as text (part of the store's fingerprint)."""
        return repr(self)

    def document(self, values: Mapping[str, float], seed: int) -> dict[str, Any]:
        """Case document: the target with ``values`` (SI, by path) and ``seed`` written in."""
        written: dict[str, Any] = {p.path: p.value(values[p.path]) for p in self.parameters}
        if self.seed_path is not None:
            written[self.seed_path] = int(seed)
        return with_values(self.data, written)

    def scenario(self, values: Mapping[str, float], seed: int) -> BaseModel:
        """The case's validated scenario, as :func:`flexsat.scenarios.load_scenario` gives it
        for the case document's text.

        Raises
        ------
        ScenarioError
            The kind's problems of the case document.
        """
        from flexsat.scenarios.documents import load_scenario

        text = yaml.safe_dump(self.document(values, seed), sort_keys=False, allow_unicode=True)
        scenario = load_scenario(text)
        scenario._folder = self.folder  # type: ignore[attr-defined]  # a fields.Document
        return scenario

    def problems(
        self, index: int, values: Mapping[str, float], exc: ScenarioError
    ) -> list[Problem]:
        """The problems of case ``index`` named by the parameters they concern (the parameter
        whose path a problem's path starts with, or ``parameters``), with the case's values."""
        shown = ", ".join(f"{p.path} = {p.value(values[p.path])}" for p in self.parameters)
        out = []
        for problem in exc.problems:
            mine = [
                p.path
                for p in self.parameters
                if problem.path.startswith(p.path) or p.path.startswith(problem.path or "\0")
            ]
            where = f"parameters.{mine[0]}" if len(mine) == 1 else "parameters"
            rule = f"case {index} ({shown}): {problem}"
            if len(mine) == 1 and problem.rule.startswith("unknown key"):
                near = nearest_paths(mine[0], self.data)
                rule += f"; nearest fields: {', '.join(near)}" if near else ""
            out.append(Problem(where, rule))
        return out

    def check(self, table: Mapping[str, np.ndarray]) -> None:
        """Validate every case's document and plan the extreme draws up to their first run
        (module docstring), before any case runs.

        Raises
        ------
        ScenarioError
            Naming the parameter, the case index and the rule.
        """
        n = len(next(iter(table.values())))
        extremes = sorted(
            {0}
            | {int(np.argmin(table[p.path])) for p in self.parameters}
            | {int(np.argmax(table[p.path])) for p in self.parameters}
        )
        kind = scenario_kind(self.kind)
        seen: set[tuple[float, ...]] = set()
        for index in range(n):
            values = {p.path: float(table[p.path][index]) for p in self.parameters}
            key = tuple(values.values())
            if key in seen:  # a grid repeats no point, a design rarely: each document once
                continue
            seen.add(key)
            try:
                if index in extremes:
                    self._plan_first_run(index, values, self.scenario(values, 0))
                else:  # the document as parsed: the schema of its text, without the YAML
                    kind.validate(self.document(values, 0))
            except ScenarioError as exc:
                raise ScenarioError(self.problems(index, values, exc)) from None

    def _plan_first_run(self, index: int, values: Mapping[str, float], scenario: Any) -> None:
        """Everything the kind does before its first run (plant, laws), nothing run."""
        plan = scenario_kind(self.kind).plan(scenario)
        try:
            next(plan)
        except StopIteration:
            pass
        except ScenarioError:
            raise
        except ValueError as exc:
            raise ScenarioError([locate("", exc)]) from None
        finally:
            plan.close()

    def run_chunk(
        self,
        extract: Any,
        parameters: Mapping[str, np.ndarray],
        start: int,
        base_seed: int,
        histories: tuple[str, ...] = (),
    ) -> dict[str, np.ndarray]:
        """Run the cases ``start .. start + n`` one by one: {``metric_`` name: (n,)}, an empty
        ``time`` and the ``seed`` (n,) each case ran with.

        Raises
        ------
        ScenarioError
            A case the kind refuses, named by its index and values; a required metric the
            kind's result does not have.
        flexsat.sim.SimulationDiverged
            A case that diverged, named by its index (:func:`flexsat.sim.engine.offset_cases`).
        """
        from flexsat.scenarios.runner import run_scenario
        from flexsat.sim import SimulationDiverged
        from flexsat.sim.engine import offset_cases

        if histories:
            raise FieldError("histories", "a batch over a scenario document keeps metrics only")
        n = len(next(iter(parameters.values())))
        seeds = document_seeds(base_seed, np.arange(start, start + n))
        rows = []
        for k in range(n):
            values = {p.path: float(parameters[p.path][k]) for p in self.parameters}
            try:
                result = run_scenario(self.scenario(values, int(seeds[k])))
            except SimulationDiverged as exc:
                raise offset_cases(exc, k) from None
            except ScenarioError as exc:
                raise ScenarioError(self.problems(start + k, values, exc)) from None
            rows.append(extract(result))
            if list(rows[-1]) != list(rows[0]):
                raise FieldError(
                    "parameters",
                    f"case {start + k} has the metrics {', '.join(rows[-1])}, case {start} "
                    f"{', '.join(rows[0])}: the kind's result changes with the values",
                )
        missing = [m for m in self.requirements if m not in rows[0]]
        if missing:
            raise FieldError(
                f"requirements.{missing[0]}",
                f"unknown metric; the run's metrics: {', '.join(rows[0])}",
            )
        out = {f"metric_{name}": np.array([r[name] for r in rows]) for name in rows[0]}
        out["time"] = np.empty(0)
        out["seed"] = seeds
        return out


def target_runs(data: dict[str, Any], run: str | None, kind: str) -> dict[str, Any]:
    """The target document with its ``runs`` cut down to the run labelled ``run`` (all of them
    if None).

    Raises
    ------
    FieldError
        ``run``: a label that is no run of the target, or a kind without labelled runs.
    """
    if run is None:
        return data
    runs = data.get("runs")
    items = [r for r in runs if isinstance(r, dict)] if isinstance(runs, list) else []
    labels = [str(r["label"]) for r in items if "label" in r]
    if not labels:
        raise FieldError("run", f"a {kind} scenario has no labelled runs; leave run out")
    if run not in labels:
        raise FieldError(
            "run", f"{run!r} is not a run of the scenario (its runs: {', '.join(labels)})"
        )
    return {**data, "runs": [r for r in items if r.get("label") == run]}


def document_cases(
    target: Any,
    run: str | None,
    parameters: Mapping[str, Mapping[str, Any]],
    requirements: tuple[str, ...],
) -> DocumentCases:
    """The case builder of a batch over the loaded ``target`` scenario (any kind but a batch).

    Raises
    ------
    ScenarioError
        A target that runs batches itself, a run that is not one of its runs, a path that is
        not a field of it (nearest named) or a unit of another dimension.
    """
    from flexsat.scenarios.documents import parse_document

    kind = scenario_kind(target.kind)
    if kind.runs_batches:
        raise ScenarioError(
            [
                Problem(
                    "scenario",
                    f"a {target.kind} scenario is a batch itself; a sweep or Monte Carlo varies "
                    "a scenario of another kind (a batch of batches is one batch: give all its "
                    "parameters here)",
                )
            ]
        )
    try:
        data = target_runs(parse_document(target.yaml_text), run, target.kind)
        varied = tuple(document_parameter(path, entry, data) for path, entry in parameters.items())
    except FieldError as exc:
        raise ScenarioError([locate("", exc)]) from None
    return DocumentCases(
        kind=target.kind,
        data=data,
        folder=target.folder,
        parameters=varied,
        seed_path=noise_seed_path(type(target)),
        requirements=requirements,
    )


__all__ = [
    "DOCUMENT_CHUNK_SIZE",
    "DocumentCases",
    "DocumentParameter",
    "case_metrics",
    "document_cases",
    "document_parameter",
    "document_seeds",
    "is_document_path",
    "noise_seed_path",
    "target_runs",
    "written_unit",
]
