"""Command line: ``flexsat cases``, ``flexsat modes CASE``, ``flexsat run [SCENARIO]``,
``flexsat validate``, ``flexsat serve``, ``flexsat --version``.

Results (tables, JSON) go to stdout; progress and errors to stderr. Errors in the user's input
print in red and exit with code 2; a simulation that diverges prints why and exits with code 1,
writing no report.

Each command imports what it needs when it runs (numpy, the cases, the simulation, the
reports): ``flexsat --help`` and ``flexsat cases`` load only typer, rich and
:mod:`flexsat.catalog` (tests/test_cli_startup.py, benchmarks/bench_cli.py).

Plug-ins (:mod:`flexsat.plugins`, docs/plugins.md) are read when a command first needs their
group; every one left out (a missing module, an object of the wrong kind, a built-in's name)
is named on stderr as the command ends, whatever its exit code, and never stops it.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer
from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text

from flexsat.catalog import all_cases, get_case
from flexsat.references import cite, references

if TYPE_CHECKING:
    from flexsat.checks import CheckResult
    from flexsat.report.page import ResultTable

app = typer.Typer(
    help="flexsat: integrated structures-and-control design of flexible spacecraft.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()
errors = Console(stderr=True)


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            typer.echo(f"flexsat {version('flexsat')}")
        except PackageNotFoundError:  # a source tree on PYTHONPATH, not installed
            from flexsat import __version__

            typer.echo(f"flexsat {__version__} (not installed)")
        raise typer.Exit()


def _report_broken_plugins() -> None:
    """Name every plug-in the command left out, on stderr (the one place they are reported)."""
    from flexsat.plugins import broken_plugins

    for plugin in broken_plugins():
        errors.print(
            f"warning: {plugin}", style="yellow", markup=False, highlight=False, soft_wrap=True
        )


@app.callback()
def _main(
    context: typer.Context,
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """flexsat: integrated structures-and-control design of flexible spacecraft."""
    # on close: after the command, also when it exits with an error
    context.call_on_close(_report_broken_plugins)


def _fail(message: str) -> NoReturn:
    errors.print(message, style="red", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(code=2)


def parse_value(text: str) -> bool | int | float | str:
    """A ``--set`` value: bool for true/false, int or float if it reads as one, else the string
    (a quantity with units such as ``"30 ozf*in*s**2"``)."""
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    kind: type[int] | type[float]
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_settings(settings: list[str]) -> dict[str, bool | int | float | str]:
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
def cases(
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON to stdout.")] = False,
) -> None:
    """List the benchmark cases (the built-in ones, then the plug-ins')."""
    catalogue = all_cases()
    if as_json:
        typer.echo(
            json.dumps(
                [
                    {
                        "case": i.name,
                        "source": cite(i.source),
                        "references": references([i.source]),
                        "description": i.description,
                    }
                    for i in catalogue.values()
                ],
                indent=2,
            )
        )
        return
    table = Table(title="flexsat cases")
    for column in ("case", "source", "description"):
        table.add_column(column, overflow="fold")
    for info in catalogue.values():
        table.add_row(info.name, cite(info.source), info.description)
    console.print(table)
    _print_references([i.source for i in catalogue.values()])


def _print_references(sources: list[str]) -> None:
    """The full citations of the sources the printed short citations abbreviate."""
    lines = references(sources)
    if lines:
        for line in lines:
            console.print(line, markup=False, highlight=False, soft_wrap=False)


def _modes_data(
    case: Any, case_name: str, n: int, overrides: dict[str, bool | int | float | str]
) -> dict[str, Any]:
    """The case's first ``n`` frequencies (Hz), with its mode descriptions and further tables
    where it has them (see :mod:`flexsat.cases`)."""
    import numpy as np

    data = {
        "case": case_name,
        "overrides": overrides,
        "frequencies_hz": np.asarray(case.frequencies_hz(n)).tolist(),
    }
    if hasattr(case, "mode_descriptions"):
        data["descriptions"] = list(case.mode_descriptions(n))
    if hasattr(case, "mode_details"):
        data.update(case.mode_details(n))
    return data


def _print_modes(data: dict[str, Any]) -> None:
    from flexsat.units import Q_

    columns = {
        "paper_mode_number": "paper mode",
        "frequencies_hz": "frequency (Hz)",
        "published_hz": "published (Hz)",
        "ratio_to_published": "ratio",
        "exact_unconstrained_hz": "exact, hub free (Hz)",
        "constrained_hz": "exact, hub clamped (Hz)",
        "descriptions": "description",
        "published_descriptions": "published description",
    }
    present = [key for key in columns if key in data]
    modes = Table(title=f"{data['case']}: natural frequencies")
    modes.add_column("mode", justify="right")
    for key in present:
        modes.add_column(columns[key], justify="left" if key == "descriptions" else "right")
    for i in range(len(data["frequencies_hz"])):
        cells = [data[k][i] if i < len(data[k]) else "" for k in present]
        modes.add_row(str(i + 1), *(c if isinstance(c, str) else f"{c:.6g}" for c in cells))
    console.print(modes)
    if "inertia_budget_kg_m2" in data:
        budget = Table(title="inertia budget")
        budget.add_column("part")
        for column in ("kg m²", "oz-in-s²"):
            budget.add_column(column, justify="right")
        for part, value in data["inertia_budget_kg_m2"].items():
            budget.add_row(part, f"{value:.5g}", f"{Q_(value, 'kg*m**2').to('ozf*in*s**2').m:.5g}")
        console.print(budget)


@app.command()
def modes(
    case: Annotated[str, typer.Argument(help="Case name (see `flexsat cases`).")],
    n: Annotated[int, typer.Option("--modes", "-n", min=1, help="Number of elastic modes.")] = 5,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            help='Override a case parameter: NAME=VALUE, e.g. hub_inertia="30 ozf*in*s**2".',
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON to stdout.")] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot", help="Write a PNG of the mode shapes (or the frequencies) to this file."
        ),
    ] = None,
) -> None:
    """Natural frequencies of a case, with mode descriptions and published values where the
    case has them."""
    from flexsat.mode_plot import plot_case_modes

    try:
        from flexsat import limits

        limits.check_count(
            n,
            limits.MAX_MODES,
            "--modes",
            "modes asked for",
            "the exact-beam cases solve one transcendental root per mode",
        )
        overrides = parse_settings(settings or [])
        built = get_case(case).builder(**overrides)
        data = _modes_data(built, case, n, overrides)
        if plot is not None:
            plot_case_modes(built, n, plot, f"{case}: first {n} modes")
    except ValueError as exc:
        _fail(str(exc))
    except OSError as exc:
        _fail(f"--plot: cannot write {str(plot)!r} ({exc.strerror or exc})")
    if as_json:
        typer.echo(json.dumps(data, indent=2))
    else:
        _print_modes(data)


def _result_table(data: ResultTable) -> Table:
    """A result's :class:`~flexsat.report.page.ResultTable` for the console (cells are text,
    never markup: run labels are the user's)."""
    table = Table(title=data.title, caption=data.caption)
    for i, column in enumerate(data.columns):
        table.add_column(Text(column), justify="left" if i == 0 else "right")
    for row in data.rows:
        table.add_row(*(Text(cell) for cell in row))
    return table


@app.command()
def run(
    scenario: Annotated[
        Path | None,
        typer.Argument(help="Scenario YAML file; the embedded TAMU 40 deg default when left out."),
    ] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Report folder.")] = Path("out"),
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            min=1,
            help="Sweep or Monte Carlo: run on a local dask cluster of this many worker processes.",
        ),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            "--scheduler",
            help="Sweep or Monte Carlo: run on the dask cluster at this address (tcp://HOST:PORT).",
        ),
    ] = None,
) -> None:
    """Run a scenario and write its report (metrics or identification tables, netCDF, plots,
    HTML)."""
    from flexsat.report.publish import check_output_folder, write_error

    try:  # before any work: a report that cannot be written is known in a second
        check_output_folder(out)
    except OSError as exc:
        _fail(f"--out: {exc}")
    from flexsat.design.batch_store import StoreError
    from flexsat.report import write_report
    from flexsat.scenarios import (
        ScenarioError,
        default_scenario,
        load_scenario,
        run_scenario,
        scenario_kind,
    )
    from flexsat.sim import SimulationDiverged

    try:
        spec = default_scenario() if scenario is None else load_scenario(scenario)
        kind = scenario_kind(spec.kind)
        spec = kind.with_execution(spec, workers, scheduler)
        with _progress(kind.steps(spec)) as say:
            result = run_scenario(spec, progress=say)
    except ScenarioError as exc:
        _fail(str(exc))
    except StoreError as exc:  # a sweep's store: worded as a report that cannot be written
        _fail(f"store: {write_error(exc, exc.store, 'the batch store', exc.outcome)}")
    except SimulationDiverged as exc:  # a result, not an input error: exit 1, nothing written
        errors.print(str(exc), style="red", markup=False, highlight=False)
        raise typer.Exit(code=1) from None
    except KeyboardInterrupt as exc:  # Ctrl-C: say what is kept, exit as an interrupted program
        from flexsat.design.batch_runner import BatchInterrupted

        message = (
            str(exc) if isinstance(exc, BatchInterrupted) else "interrupted: no report written"
        )
        errors.print(message, style="red", markup=False, highlight=False)
        raise typer.Exit(code=130) from None
    console.print(_result_table(result.console_table()))
    command = ["flexsat", "run", *([] if scenario is None else [str(scenario)]), "-o", str(out)]
    command += [] if workers is None else ["--workers", str(workers)]
    command += [] if scheduler is None else ["--scheduler", scheduler]
    try:  # the command as given, for the report's provenance line
        path = write_report(result, out, command=shlex.join(command))
    except OSError as exc:
        _fail(f"--out: {exc}")
    console.print(f"report written to {path / 'index.html'}", markup=False)


@contextmanager
def _progress(steps: int) -> Iterator[Callable[[str], None]]:
    """Progress over ``steps`` steps on stderr: a bar on a terminal, one line per step elsewhere
    (logs, CI). Yields the ``progress(label)`` callback the runners call as each step starts;
    every step before it is then complete."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    live = errors.is_terminal
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=errors,
        disable=not live,
    ) as bar:
        task = bar.add_task("starting", total=steps)
        started = 0

        def step(label: str) -> None:
            nonlocal started
            bar.update(task, completed=min(started, steps), description=f"running {label}")
            started += 1
            if not live:
                errors.print(
                    f"[{started}/{steps}] running {label} ...", markup=False, highlight=False
                )

        yield step
        # the runner's own count: a bar that ends short or over shows a miscounted step list
        bar.update(task, completed=started, description="done")
    if not live:
        errors.print(f"done ({started}/{steps} steps)", markup=False, highlight=False)


#: below this console width the table stacks each source under its quantity and shows the case
#: once per group instead of in a column
_WIDE_TABLE = 140
_NUMERIC = ("published", "computed", "published\ncomputed", "rel. error", "tolerance")
_STYLES = {"pass": "green", "discrepancy": "yellow", "fail": "bold red", "error": "bold red"}


def _validation_table(results: list[CheckResult], wide: bool) -> tuple[Table, list[str]]:
    """The validation table and its numbered notes: every non-pass row's explanation (an
    erratum, a model deviation, an unexplained failure, an error) and the checks' remarks."""
    from flexsat.text import format_optional

    table = Table(title="flexsat validate: published numbers, computed live", box=box.SIMPLE_HEAD)
    if wide:
        columns = [
            ("case", False),
            ("quantity", True),
            ("source", True),
            ("published", False),
            ("computed", False),
            ("unit", True),
            ("rel. error", False),
            ("tolerance", True),
            ("result", False),
        ]
    else:  # result first, so that it is never squeezed out; published over computed
        columns = [
            ("result", False),
            ("case: quantity (unit), source", True),
            ("published\ncomputed", True),
            ("rel. error", True),
            ("tolerance", True),
        ]
    for column, wrap in columns:
        table.add_column(
            column,
            overflow="fold",
            no_wrap=not wrap,
            justify="right" if column in _NUMERIC else "left",
            min_width=20 if column.startswith("case:") else None,
        )
    notes: list[str] = []
    case = None
    for r in results:
        c = r.check
        marks = ""
        # a failure's explanation already quotes the check's note
        for text in (r.explanation, c.note if r.status != "fail" else ""):
            if text:
                if text not in notes:
                    notes.append(text)
                marks += f" [{notes.index(text) + 1}]"
        source = cite(c.source)
        result = Text(r.status.upper() if r.failed else r.status, style=_STYLES[r.status])
        published = format_optional(c.published, ".10g")
        computed = format_optional(r.computed, ".7g")
        error, tolerance = format_optional(r.relative_error, "+.1e"), Text(c.tolerance)
        if wide:
            table.add_row(
                Text(c.case),
                Text(c.quantity + marks),
                Text(source),
                published,
                computed,
                Text(c.unit),
                error,
                tolerance,
                result,
            )
            continue
        if c.case != case:
            if case is not None:
                table.add_section()
            table.add_row("", Text(c.case, style="bold"))
            case = c.case
        unit = f" ({c.unit})" if c.unit else ""
        table.add_row(
            result,
            Text.assemble(c.quantity, unit, marks, "\n", (source, "dim")),
            f"{published}\n{computed}",
            error,
            tolerance,
        )
    return table, notes


@app.command()
def validate(
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON to stdout.")] = False,
    case: Annotated[
        list[str] | None,
        typer.Option("--case", help="Only this case's checks (repeat for several)."),
    ] = None,
    strict: Annotated[
        bool, typer.Option("--strict", help="Also exit with code 1 on a documented discrepancy.")
    ] = False,
) -> None:
    """Recompute every published number the code base reproduces and compare it with the paper:
    case, quantity, source, published and computed values, relative error, tolerance, result.

    A result is pass, discrepancy (a paper erratum or a documented, argued model deviation: the
    code computes the value the explanation gives), fail (outside the tolerance, unexplained)
    or error. Every row that is not a pass carries its explanation. Exits with code 1 if any
    check fails or errs, and with --strict also on a discrepancy."""
    from flexsat import checks as published_checks

    try:
        selected = published_checks.select_checks(case)
    except ValueError as exc:
        _fail(str(exc))
    results = published_checks.run_checks(checks=selected)
    failed = [r for r in results if r.failed]
    explained = [r for r in results if r.status == "discrepancy"]
    if as_json:
        typer.echo(json.dumps([r.as_dict() for r in results], indent=2, ensure_ascii=False))
    else:
        table, notes = _validation_table(results, console.width >= _WIDE_TABLE)
        console.print(table)
        for i, text in enumerate(notes, 1):
            console.print(f"[{i}] {text}", markup=False, highlight=False)
        _print_references([r.check.source for r in results])
        seconds = sum(r.seconds for r in results)
        passed = len(results) - len(failed) - len(explained)
        console.print(
            f"{len(results)} checks: {passed} passed, {len(explained)} discrepancies "
            f"(explained), {len(failed)} failed ({seconds:.1f} s)",
            markup=False,
            highlight=False,
            style="red" if failed else ("yellow" if explained else "green"),
        )
    if failed or (strict and explained):
        raise typer.Exit(code=1)


@app.command()
def serve(
    port: Annotated[int, typer.Option("--port", min=1, max=65535, help="TCP port.")] = 5006,
    address: Annotated[
        str, typer.Option("--address", help="Address to listen on (default this machine only).")
    ] = "127.0.0.1",
    show: Annotated[bool, typer.Option("--show", help="Open the page in a browser.")] = False,
) -> None:
    """Serve the live design dashboard of the TAMU case: tune the law's gains and see the
    maneuver, the tip deflection, the settling time and the loop margins update
    (docs/dashboard.md). Stops on Ctrl-C."""
    try:
        from flexsat.report.dashboard import serve as serve_dashboard
    except ImportError as exc:  # panel is a dependency; a broken install says which module
        _fail(f"flexsat serve needs the dashboard libraries (panel, bokeh): {exc}")

    def ready(url: str) -> None:
        console.print(f"flexsat design dashboard at {url} (Ctrl-C to stop)", markup=False)

    try:
        serve_dashboard(port, address, show, ready=ready)
    except OSError as exc:
        _fail(f"--port: cannot listen on {address}:{port}: {exc.strerror or exc}")
    except KeyboardInterrupt:
        errors.print("dashboard stopped", markup=False, highlight=False)


__all__ = ["app", "parse_settings", "parse_value"]


if __name__ == "__main__":  # python -m flexsat.cli (python -m flexsat is the same)
    app(prog_name="flexsat")
