"""The one report writer: every scenario kind's result becomes a folder the same way.

A result (:class:`ReportedResult`) gives its metrics records, its dataset, its figures and the
sections of its page; :func:`write_report` writes ``metrics.json`` and ``results.nc`` (or what
the result's :meth:`~ReportedResult.write_data` writes instead), draws the figures and writes
``index.html`` into a folder published whole or not at all
(:func:`flexsat.report.publish.write_atomically`).
:meth:`~ReportedResult.console_table` is what the command line prints.

``index.html`` is one self-contained file: it opens offline with no file beside it. In order:
the heading, the scenario and its case, the provenance line (flexsat version, date, the
scenario file's SHA-256 and the command; :mod:`flexsat.report.provenance`), the kind's
sections, the controller summary (:meth:`ReportedResult.controller_summaries`,
:mod:`flexsat.report.controller_summary`), the interactive figures
(:meth:`ReportedResult.plots`, drawn by :mod:`flexsat.report.interactive` with BokehJS inlined
in the page's head), the full citations of the published sources the page names
(:func:`flexsat.references.references`) and the scenario as given. A static figure a kind
draws (a PNG file :meth:`ReportedResult.figures` writes) is embedded in the page as a ``data:``
URI; the file stays beside the page for reuse in other documents, as do the data files, for
programs. Metric names are shown with :func:`flexsat.report.display.metric_label` (words and
units), the data files keep the machine names.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from flexsat.report.display import metric_label
from flexsat.report.json_data import NULL_REASONS
from flexsat.report.publish import write_atomically, write_metrics_and_results

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.report.controller_summary import LawSummary
    from flexsat.report.interactive import Plot


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


def metrics_html(records: list[dict[str, Any]], units: dict[str, str] | None = None) -> str:
    """The metrics table of a page: a row per metric, its readable name and unit
    (:func:`~flexsat.report.display.metric_label`, ``units``: the dataset's unit of a metric
    whose name has none), and a column per run."""
    units = units or {}
    return html_table(
        ["metric", *(r["run"] for r in records)],
        [(metric_label(name, units.get(name)), *values) for name, values in metric_rows(records)],
    )


def images_html(files: list[str]) -> str:
    """One ``<figure>`` per image file, in order."""
    esc = html.escape
    return "".join(f'<figure><img src="{esc(f)}" alt="{esc(f)}"></figure>' for f in files)


#: the report pages' style sheet
STYLE = """<style>
body { font-family: sans-serif; margin: 2em auto; max-width: 60em; }
table { border-collapse: collapse; margin-bottom: 1em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }
td:first-child { text-align: left; }
img { max-width: 100%; }
pre { background: #f4f4f4; padding: 1em; overflow-x: auto; }
.provenance { color: #555; font-size: 0.85em; }
ol.references li { margin-bottom: 0.4em; }
</style>"""

#: the media types of the static figures a page embeds, by file suffix
MEDIA_TYPES = {".png": "image/png", ".svg": "image/svg+xml", ".jpg": "image/jpeg"}

_IMAGE_SOURCE = re.compile(r'(<img\b[^>]*?\bsrc=")([^"]+)(")')


def embed_images(body: str, folder: Path) -> str:
    """``body`` with every ``<img src="file">`` whose file is in ``folder`` embedded as a
    ``data:`` URI (base64; the page then needs no file beside it). Other sources are left
    as they are."""

    def embed(match: re.Match[str]) -> str:
        name = html.unescape(match.group(2))
        path = folder / name
        media = MEDIA_TYPES.get(Path(name).suffix.lower())
        if media is None or "/" in name or not path.is_file():
            return match.group(0)
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        return f"{match.group(1)}data:{media};base64,{data}{match.group(3)}"

    return _IMAGE_SOURCE.sub(embed, body)


def references_html(texts: Iterable[str], extra: Sequence[str] = ()) -> str:
    """The page's references: the full citation of every published source ``texts`` name
    (:func:`flexsat.references.references`; HTML is read as its text), then ``extra`` (the
    methods a section cites). Empty when there are none."""
    from flexsat.references import references

    lines = references(html.unescape(t) for t in texts)
    items = [*(line.strip() for line in lines), *extra]
    if not items:
        return ""
    body = "".join(f"<li>{html.escape(item)}</li>" for item in dict.fromkeys(items))
    return f'<h2>References</h2>\n<ol class="references">{body}</ol>\n'


def report_page(
    result: ReportedResult,
    body: str,
    title: str = "flexsat report",
    case: str | None = None,
    *,
    provenance: str = "",
    head: str = "",
) -> str:
    """A report's index.html: the heading, the scenario and its case (``case``, default the
    scenario's) with the case's source, the ``provenance`` line, ``body`` (HTML: sections,
    figures, references), and the scenario as given; ``head`` goes into the page's head (the
    interactive figures' scripts)."""
    esc = html.escape
    case = result.scenario.case if case is None else case
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{esc(title)}: {esc(result.scenario.name)}
</title>
{STYLE}{head}</head>
<body>
<h1>{esc(title)}</h1>
<p><b>Scenario:</b> {esc(result.scenario.name)}<br><b>Case:</b> {esc(case)}
({esc(result.case_source)})</p>
{provenance}{body}
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

    def plots(self, ds: xr.Dataset) -> list[Plot]:
        """The interactive figures (:class:`flexsat.report.interactive.Plot`), in page order,
        shown after the sections with a toggle per run; none by default."""
        return []

    def controller_summaries(self) -> Sequence[LawSummary]:
        """The linear summary of each run's law
        (:func:`flexsat.report.controller_summary.summarise_law`); none by default (a kind
        whose laws and plant have no linear form)."""
        return ()

    def console_table(self) -> ResultTable:
        """What ``flexsat run`` prints: by default the metrics, one column per run."""
        return metrics_table(self.metrics_records())


def page_body(result: ReportedResult, ds: xr.Dataset, figures: list[str]) -> tuple[str, str]:
    """(body, head) of the page of ``result``: the kind's sections, the controller summary, the
    interactive figures and the references; the BokehJS for the head when there are figures."""
    from flexsat.report.controller_summary import CITATIONS, summary_html
    from flexsat.report.interactive import head, render

    sections = result.sections(ds, figures)
    summaries = result.controller_summaries()
    summary = summary_html(summaries)
    plots = result.plots(ds)
    runs = list(dict.fromkeys(c.run for p in plots for c in p.curves if c.run))
    interactive = (
        "<h2>Figures</h2>\n<p>Drag to pan, draw a box or use the wheel (after picking it in the "
        "toolbar) to zoom, hover for values; a click on a legend entry hides its curve, the "
        "boxes show or hide a run in every figure.</p>\n" + render(plots, runs) + "\n"
        if plots
        else ""
    )
    texts = [result.case_source, sections, summary, *(p.title for p in plots)]
    references = references_html(texts, CITATIONS if summaries else ())
    return f"{sections}\n{summary}\n{interactive}{references}", head() if plots else ""


def write_report(
    result: ReportedResult, out_dir: str | Path, *, command: str | None = None
) -> Path:
    """Write the report of ``result`` as the folder ``out_dir``, whole or not at all
    (:func:`flexsat.report.publish.write_atomically`); its ``index.html`` opens with no file
    beside it (module docstring).

    Parameters
    ----------
    result : ReportedResult
        The result of :func:`flexsat.scenarios.run_scenario`, of any kind.
    out_dir : str or Path
        Created if needed; an earlier report there is replaced as a whole (a folder holding
        other files is refused).
    command : str, optional
        The command line that ran the scenario (``flexsat run`` passes its own), for the
        provenance line; default: the Python API.

    Returns
    -------
    Path
        ``out_dir``, resolved.

    Raises
    ------
    flexsat.report.publish.OutputError
        When the folder cannot be written (disk full, read-only, ...); ``out_dir`` is unchanged.
    """
    from flexsat.report.provenance import provenance, provenance_html

    origin = provenance_html(provenance(result.scenario.yaml_text, command))

    def write(folder: Path) -> None:
        ds = result.dataset()
        result.write_data(folder, ds)
        figures = result.figures(folder, ds)
        body, head = page_body(result, ds, figures)
        page = report_page(
            result,
            embed_images(body, folder),
            result.report_title,
            result.report_case(),
            provenance=origin,
            head=head,
        )
        (folder / "index.html").write_text(page, encoding="utf-8")

    return write_atomically(out_dir, write)


__all__ = [
    "MEDIA_TYPES",
    "STYLE",
    "ReportedResult",
    "ResultTable",
    "format_metric",
    "embed_images",
    "html_table",
    "images_html",
    "metric_rows",
    "metrics_html",
    "metrics_table",
    "page_body",
    "references_html",
    "report_page",
    "write_report",
]
