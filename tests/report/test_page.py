"""The one report writer (:mod:`flexsat.report.page`): tables escape every text and read back
cell for cell through an HTML parser; metrics show 4 significant digits and ``n/a``; the console
table transposes when runs outnumber metrics; :func:`write_report` writes the metrics, the
dataset and the page of any :class:`ReportedResult`, each read back equal, and nothing when the
result fails while being written."""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from html.parser import HTMLParser
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from flexsat.report.page import (
    ReportedResult,
    format_metric,
    html_table,
    images_html,
    metric_rows,
    metrics_table,
    report_page,
    write_report,
)
from flexsat.report.provenance import without_provenance


class Cells(HTMLParser):
    """The text of every table cell, row by row (an independent reading of the table)."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.rows, self._cell = [], None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.rows[-1].append(self._cell)
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data


def test_html_table_escapes_and_reads_back_cell_for_cell():
    headings = ["metric", "<b>run</b>", "a & b"]
    rows = [["<script>alert(1)</script>", 1.5, None], ['"quoted"', "x<y", 3]]
    text = html_table(headings, rows)
    assert "<script>" not in text and "<b>" not in text
    parser = Cells()
    parser.feed(text)
    assert parser.rows == [headings, [str(c) for c in rows[0]], [str(c) for c in rows[1]]]


@pytest.mark.parametrize(
    "value, shown",
    [(None, "n/a"), (1234.5678, "1235"), (0.000123456, "0.0001235"), (-2.0, "-2"), (1e9, "1e+09")],
)
def test_metrics_show_four_significant_digits(value, shown):
    assert format_metric(value) == shown


RECORDS = [
    {"run": "Law I", "settling_time_s": 12.3456, "peak_torque": None},
    {"run": "Law II", "settling_time_s": 7.0, "peak_torque": 0.5},
]


def test_metrics_table_has_a_row_per_metric_and_a_column_per_run():
    table = metrics_table(RECORDS)
    assert table.columns == ("metric", "Law I", "Law II")
    assert table.rows == (("settling_time_s", "12.35", "7"), ("peak_torque", "n/a", "0.5"))
    assert metric_rows(RECORDS) == [
        ("settling_time_s", ["12.35", "7"]),
        ("peak_torque", ["n/a", "0.5"]),
    ]


def test_metrics_table_transposes_when_the_runs_outnumber_the_metrics():
    records = [{"run": f"case {i}", "error": 0.1 * i} for i in range(3)]
    table = metrics_table(records)
    assert table.columns == ("", "error")
    assert table.rows == (("case 0", "0"), ("case 1", "0.1"), ("case 2", "0.2"))


def test_images_are_figures_in_order_and_escaped():
    text = images_html(["a.png", 'b"c.png'])
    assert text.index("a.png") < text.index("b&quot;c.png") and text.count("<figure>") == 2


@dataclass(frozen=True)
class Result(ReportedResult):
    """The smallest result: two runs of one metric and a time history."""

    scenario: object
    case_source: str = "a <source>"
    fail: bool = False

    def metrics_records(self):
        return [{"run": "a", "x": 1.0}, {"run": "b", "x": None}]

    def dataset(self):
        t = np.linspace(0.0, 1.0, 5)
        return xr.Dataset(
            {"y": (("run", "time"), np.vstack([t, t**2]))}, coords={"run": ["a", "b"], "time": t}
        )

    def sections(self, ds, figures):
        if self.fail:
            raise RuntimeError("drawing failed")
        return html_table(["metric", "a", "b"], [("y max", *ds["y"].max("time").values)])


SCENARIO = SimpleNamespace(name="<Test> & co", case="tamu", yaml_text="kind: x\nname: <Test>\n")


def test_write_report_writes_metrics_dataset_and_page(tmp_path):
    result = Result(SCENARIO)
    folder = write_report(result, tmp_path / "out")
    assert json.loads((folder / "metrics.json").read_text()) == result.metrics_records()
    with xr.open_dataset(folder / "results.nc") as ds:
        xr.testing.assert_equal(ds.load(), result.dataset())
    page = (folder / "index.html").read_text()
    # the page as report_page writes it, but for the provenance line (the date varies)
    assert without_provenance(page) == report_page(
        result, result.sections(result.dataset(), []) + "\n\n", "flexsat report", "tamu"
    )
    assert page.count('<p class="provenance">') == 1
    # the scenario's name, case source and text are escaped, never markup
    assert "&lt;Test&gt; &amp; co" in page and "<Test>" not in page
    assert "a &lt;source&gt;" in page and "name: &lt;Test&gt;" in page
    # the console's default: the metrics table (two runs of one metric: a row per run)
    assert result.console_table().rows == (("a", "1"), ("b", "n/a"))


def test_a_result_failing_while_written_leaves_no_report(tmp_path):
    with pytest.raises(RuntimeError, match="drawing failed"):
        write_report(Result(SCENARIO, fail=True), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_embedded_images_decode_to_the_files_bytes(tmp_path):
    # a page needs no file beside it: a figure file in the folder becomes a data: URI that
    # decodes to the very bytes of the file; sources that are not files of the folder stay
    import base64
    import re

    from flexsat.report.page import embed_images

    data = bytes(range(256)) * 3
    (tmp_path / "a b.png").write_bytes(data)
    body = (
        '<figure><img src="a b.png" alt="x"></figure><img src="missing.png">'
        '<img src="../a b.png"><img alt="y" src="notes.txt">'
    )
    (tmp_path / "notes.txt").write_text("not an image")
    out = embed_images(body, tmp_path)
    uris = re.findall(r'src="data:image/png;base64,([^"]+)"', out)
    assert [base64.b64decode(u) for u in uris] == [data]
    for kept in ('src="missing.png"', 'src="../a b.png"', 'src="notes.txt"'):
        assert kept in out


def test_references_give_the_full_citation_of_every_source_named():
    from flexsat.references import SEEDS
    from flexsat.report.page import references_html

    # names as a page holds them: HTML-escaped ("&amp;"), a source named twice is cited once
    text = references_html(
        ["Junkins, Pollock &amp; Rahman 1990, Att. 3", "<p>EPS slew study c. 1989</p>"],
        ["A. Author, a method, 2020", "A. Author, a method, 2020"],
    )
    for number in ("000", "003"):
        assert html.escape(SEEDS[number].full, quote=True) in text
    assert "Near-Minimum-Time Maneuvers of Flexible Vehicles: Analytical" in text  # Att. 3
    assert text.count("<li>") == 4
    assert references_html(["no source here"]) == ""


def test_metrics_table_shows_names_and_units():
    from flexsat.report.page import metrics_html

    parser = Cells()
    parser.feed(metrics_html(RECORDS + [], {"peak_torque": "N m"}))
    assert parser.rows == [
        ["metric", "Law I", "Law II"],
        ["Settling time (s)", "12.35", "7"],
        ["Peak torque (N m)", "n/a", "0.5"],  # no unit in the name: the dataset's
    ]


@dataclass(frozen=True)
class PlottedResult(Result):
    """Result with an interactive figure of its two runs and a controller summary."""

    def plots(self, ds):
        from flexsat.report.interactive import Curve, Plot

        t = ds["time"].values
        curves = tuple(Curve(r, r, t, ds["y"].sel(run=r).values) for r in ("a", "b"))
        return [Plot("y against time", "time (s)", "y (m)", curves)]

    def controller_summaries(self):
        from flexsat.report.controller_summary import LawSummary

        return (LawSummary("a", "SomeLaw", reason="it is nonlinear"),)


def test_the_page_orders_sections_summary_figures_references_and_scenario(tmp_path):
    plain = (write_report(Result(SCENARIO), tmp_path / "plain") / "index.html").read_text()
    assert "Bokeh" not in plain  # no interactive figure: no BokehJS either
    page = (write_report(PlottedResult(SCENARIO), tmp_path / "out") / "index.html").read_text()
    head, body = page.split("</head>\n<body>\n<h1>")
    assert "Bokeh" in head and '"text":"y against time"' in body
    order = [
        '<p class="provenance">',
        "<td>y max</td>",
        "<h2>Controller summary</h2>",
        "No linear summary: it is nonlinear.",
        "<h2>Figures</h2>",
        '"labels":["a","b"]',  # a toggle per run
        "<h2>References</h2>",
        "Seiler, A. Packard and P. Gahinet",  # the summary's methods, cited in full
        "<h2>Scenario</h2>",
    ]
    at = [body.index(text) for text in order]
    assert at == sorted(at)
