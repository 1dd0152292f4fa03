"""Command line: ``flexsat cases``, ``flexsat modes CASE``, ``flexsat run [SCENARIO]``.

Errors in the user's input print in red on stderr and exit with code 2.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, NoReturn

import numpy as np
import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

from flexsat.cases import CASES, get_case
from flexsat.cases.tamu import inertia_budget
from flexsat.report import metric_rows, write_report
from flexsat.scenario import ScenarioError, default_scenario, load_scenario, run_scenario
from flexsat.structures.beam import hub_free_frequencies
from flexsat.units import Q_

app = typer.Typer(
    help="flexsat: integrated structures-and-control design of flexible spacecraft.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()
errors = Console(stderr=True)


def _fail(message: str) -> NoReturn:
    errors.print(message, style="red", markup=False, highlight=False)
    raise typer.Exit(code=2)


def parse_value(text: str):
    """A ``--set`` value: bool for true/false, int or float if it reads as one, else the string
    (a quantity with units such as ``"30 ozf*in*s**2"``)."""
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_settings(settings: list[str]) -> dict:
    """``["NAME=VALUE", ...]`` to a dict of case overrides (values through :func:`parse_value`).

    Raises
    ------
    ValueError
        For an item without ``=`` or without a name.
    """
    overrides = {}
    for item in settings:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"--set: expected NAME=VALUE, got {item!r}")
        overrides[name.strip()] = parse_value(value.strip())
    return overrides


@app.command()
def cases() -> None:
    """List the benchmark cases."""
    table = Table(title="flexsat cases")
    for column in ("case", "source", "description"):
        table.add_column(column, overflow="fold")
    for info in CASES.values():
        table.add_row(info.name, info.source, info.description)
    console.print(table)


def _modes_data(case_name: str, n: int, overrides: dict) -> dict:
    """Frequencies (Hz) of the first ``n`` elastic modes, exact (distributed model) and of the
    assumed-modes model, and the inertia budget (kg m²)."""
    case = get_case(case_name).builder(**overrides)
    model = case.model()
    if n > model.n_modes:
        raise ValueError(f"--modes: the model has {model.n_modes} modes; "
                         f"raise it with --set n_modes={n}")
    hz = 1 / (2 * np.pi)
    p = model.params
    exact = hub_free_frequencies(p.beam(), p.hub_radius, p.hub_inertia, p.n_appendages, n)
    return {
        "case": case_name,
        "overrides": overrides,
        "model_modes": model.n_modes,
        "exact_unconstrained_hz": (hz * exact).tolist(),
        "unconstrained_hz": (hz * model.frequencies()[:n]).tolist(),
        "constrained_hz": (hz * model.frequencies(constrained=True)[:n]).tolist(),
        "inertia_budget_kg_m2": inertia_budget(case),
    }


def _print_modes(data: dict) -> None:
    modes = Table(title=f"{data['case']}: natural frequencies ({data['model_modes']}-mode model)")
    for column in ("mode", "hub free, exact (Hz)", "hub free, model (Hz)",
                   "hub clamped, exact = model (Hz)"):
        modes.add_column(column, justify="right")
    rows = zip(data["exact_unconstrained_hz"], data["unconstrained_hz"], data["constrained_hz"])
    for i, (exact, free, clamped) in enumerate(rows, 1):
        modes.add_row(str(i), f"{exact:.6g}", f"{free:.6g}", f"{clamped:.6g}")
    budget = Table(title="inertia budget")
    budget.add_column("part")
    for column in ("kg m²", "oz-in-s²"):
        budget.add_column(column, justify="right")
    for part, value in data["inertia_budget_kg_m2"].items():
        budget.add_row(part, f"{value:.5g}", f"{Q_(value, 'kg*m**2').to('ozf*in*s**2').m:.5g}")
    console.print(modes, budget)


@app.command()
def modes(
    case: Annotated[str, typer.Argument(help="Case name (see `flexsat cases`).")],
    n: Annotated[int, typer.Option("--modes", "-n", min=1, help="Number of elastic modes.")] = 5,
    settings: Annotated[list[str] | None, typer.Option(
        "--set", help='Override a case parameter: NAME=VALUE, e.g. hub_inertia="30 ozf*in*s**2".'
    )] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON to stdout.")] = False,
) -> None:
    """Natural frequencies (hub free and hub clamped) and inertia budget of a case."""
    try:
        data = _modes_data(case, n, parse_settings(settings or []))
    except ValueError as exc:
        _fail(str(exc))
    if as_json:
        typer.echo(json.dumps(data, indent=2))
    else:
        _print_modes(data)


def _metrics_table(records: list[dict]) -> Table:
    table = Table(title="metrics")
    table.add_column("metric")
    for record in records:
        table.add_column(Text(record["run"]), justify="right")  # labels are not markup
    for metric, values in metric_rows(records):
        table.add_row(metric, *values)
    return table


@app.command()
def run(
    scenario: Annotated[Path | None, typer.Argument(
        help="Scenario YAML file; the embedded TAMU 40 deg default when left out.")] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Report folder.")] = Path("out"),
) -> None:
    """Run a scenario, print its metrics and write the report (metrics, netCDF, plots, HTML)."""
    try:
        spec = default_scenario() if scenario is None else load_scenario(scenario)
        result = run_scenario(spec, progress=lambda label: console.print(f"running {label} ...", markup=False))
    except ScenarioError as exc:
        _fail(str(exc))
    console.print(_metrics_table(result.metrics_records()))
    try:
        path = write_report(result, out)
    except OSError as exc:
        _fail(f"--out: cannot write the report to {str(out)!r} ({exc.strerror or exc})")
    console.print(f"report written to {path / 'index.html'}", markup=False)


__all__ = ["app", "parse_settings", "parse_value"]
