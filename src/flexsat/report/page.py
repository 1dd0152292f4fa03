"""The one report writer: every scenario kind's result becomes a folder the same way.

A result (:class:`ReportedResult`) gives its metrics records, its dataset, its figures and the
sections of its page; :func:`write_report` writes ``metrics.json`` and ``results.nc`` (or what
the result's :meth:`~ReportedResult.write_data` writes instead), draws the figures and writes
``index.html`` -- the heading, the scenario and its case, the sections, the scenario as given --
into a folder published whole or not at all (:func:`flexsat.report.publish.write_atomically`).
:meth:`~ReportedResult.console_table` is what the command line prints.
"""

from __future__ import annotations

import html
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from flexsat.report.json_data import NULL_REASONS
from flexsat.report.publish import write_atomically, write_metrics_and_results

if TYPE_CHECKING:
    import xarray as xr


def format_metric(value: float | None) -> str:
    """A metric for display: 4 significant digits, ``n/a`` for None (not settled/applicable)."""
    return "n/a" if value is None else f"{value:.4g}"


def html_table(headings: Iterable[object], rows: Iterable[Iterable[object]]) -> str:
    """An HTML table: a heading row, then one row per item of ``rows`` (cells shown with
    ``str``, every text escaped)."""
    esc = html.escape
    head = "".join(f"<th>{esc(str(h))}</th>" for h in headings)
    body = "".join(
        "<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def metric_rows(records: list[dict[str, Any]]) -> list[tuple[str, list[str]]]:
    """Metrics table, one row per metric and one formatted column per run of ``records``."""
    names = [key for key in records[0] if key not in ("run", NULL_REASONS)]
    return [(name, [format_metric(r[name]) for r in records]) for name in names]


def images_html(files: list[str]) -> str:
    """One ``<figure>`` per image file, in order."""
    esc = html.escape
    return "".join(f'<figure><img src="{esc(f)}" alt="{esc(f)}"></figure>' for f in files)


#: the report pages' style sheet
STYLE = """<style>
body { font-family: sans-serif; margin: 2em auto; max-width: 60em; }
table { border-collapse: collapse; margin-bottom: 1em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }
td:first-child { text-align: left; font-family: monospace; }
img { max-width: 100%; }
pre { background: #f4f4f4; padding: 1em; overflow-x: auto; }
</style>"""


def report_page(
    result: ReportedResult, body: str, title: str = "flexsat report", case: str | None = None
) -> str:
    """A report's index.html: the heading, the scenario and its case (``case``, default the
    scenario's) with the case's source, ``body`` (HTML), and the scenario as given."""
    esc = html.escape
    case = result.scenario.case if case is None else case
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{esc(title)}: {esc(result.scenario.name)}
</title>
{STYLE}</head>
<body>
<h1>{esc(title)}</h1>
<p><b>Scenario:</b> {esc(result.scenario.name)}<br><b>Case:</b> {esc(case)}
({esc(result.case_source)})</p>
{body}
<h2>Scenario</h2>
<pre>{esc(result.scenario.yaml_text)}</pre>
</body></html>
"""


@dataclass(frozen=True)
class ResultTable:
    """A table for the console: a title, column headings, rows of text, an optional caption.
    The first column names the row; the others hold numbers."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    caption: str | None = None


def metrics_table(records: list[dict[str, Any]]) -> ResultTable:
    """One column per run and a row per metric; transposed when the runs outnumber the metrics
    (a batch's table: a row per metric of the cases and per requirement), so that it fits."""
    names = [key for key in records[0] if key not in ("run", NULL_REASONS)]
    if len(records) > len(names):
        rows = tuple(
            (str(record["run"]), *(format_metric(record[n]) for n in names)) for record in records
        )
        return ResultTable("metrics", ("", *names), rows)
    rows = tuple((metric, *values) for metric, values in metric_rows(records))
    return ResultTable("metrics", ("metric", *(str(r["run"]) for r in records)), rows)


class ReportedResult:
    """The protocol of every scenario result (a base class giving the defaults).

    A subclass has ``scenario`` (the document: ``name``, ``yaml_text``, ``case`` unless it
    overrides :meth:`report_case`) and ``case_source``, and defines :meth:`metrics_records`,
    :meth:`dataset` and :meth:`sections`; :meth:`figures`, :meth:`write_data` and
    :meth:`console_table` have defaults.
    """

    #: the heading of the report page
    report_title: ClassVar[str] = "flexsat report"

    scenario: Any
    case_source: str

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run: ``"run"`` (the label) and its metrics (None: no
        value, not settled, not applicable)."""
        raise NotImplementedError

    def dataset(self) -> xr.Dataset:
        """Everything the run produced, as one :class:`xarray.Dataset` (``results.nc``)."""
        raise NotImplementedError

    def report_case(self) -> str:
        """The case the page names."""
        return self.scenario.case

    def write_data(self, folder: Path, ds: xr.Dataset) -> None:
        """The data files of the report: ``metrics.json`` and ``results.nc`` (``ds``)."""
        write_metrics_and_results(self, folder, ds)

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        """Draw the figures into ``folder``; their file names, in page order."""
        return []

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        """The page's HTML between the heading and the scenario text (``figures``: the files
        :meth:`figures` wrote)."""
        raise NotImplementedError

    def console_table(self) -> ResultTable:
        """What ``flexsat run`` prints: by default the metrics, one column per run."""
        return metrics_table(self.metrics_records())


def write_report(result: ReportedResult, out_dir: str | Path) -> Path:
    """Write the report of ``result`` as the folder ``out_dir``, whole or not at all
    (:func:`flexsat.report.publish.write_atomically`).

    Parameters
    ----------
    result : ReportedResult
        The result of :func:`flexsat.scenarios.run_scenario`, of any kind.
    out_dir : str or Path
        Created if needed; an earlier report there is replaced as a whole (a folder holding
        other files is refused).

    Returns
    -------
    Path
        ``out_dir``, resolved.

    Raises
    ------
    flexsat.report.publish.OutputError
        When the folder cannot be written (disk full, read-only, ...); ``out_dir`` is unchanged.
    """

    def write(folder: Path) -> None:
        ds = result.dataset()
        result.write_data(folder, ds)
        figures = result.figures(folder, ds)
        page = report_page(
            result, result.sections(ds, figures), result.report_title, result.report_case()
        )
        (folder / "index.html").write_text(page, encoding="utf-8")

    return write_atomically(out_dir, write)


__all__ = [
    "STYLE",
    "ReportedResult",
    "ResultTable",
    "format_metric",
    "html_table",
    "images_html",
    "metric_rows",
    "metrics_table",
    "report_page",
    "write_report",
]
