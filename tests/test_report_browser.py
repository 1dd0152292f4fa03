"""The browser check of the report pages (tests/report_browser.py) fails on what a reader would
notice: a missing figure, a script error, a broken link, a NaN shown as a number."""

import base64

import pytest

from report_browser import assert_renders

#: a 1 × 1 PNG
PIXEL = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg=="
)


def _page(folder, body):
    (folder / "plot.png").write_bytes(PIXEL)
    (folder / "metrics.json").write_text("[]")
    index = folder / "index.html"
    index.write_text(f"<!doctype html><html><body><h1>Report</h1>{body}</body></html>")
    return index


def test_a_whole_page_passes(tmp_path, browser):
    body = '<img src="plot.png"><a href="metrics.json">data</a><table><td>1.5</td></table>'
    assert "1.5" in assert_renders(browser, _page(tmp_path, body))


@pytest.mark.parametrize(
    "body, complaint",
    [
        ('<img src="missing.png">', "(?i)failed"),
        ('<a href="results.nc">data</a>', "broken link"),
        ("<table><tr><td>settling time</td><td>nan</td></tr></table>", "shows 'nan'"),
        ("<p>peak -inf deg</p>", "shows '-inf'"),
        ("<script>undefined_function()</script>", "script errors"),
    ],
)
def test_what_a_reader_would_notice_fails(tmp_path, browser, body, complaint):
    with pytest.raises(AssertionError, match=complaint):
        assert_renders(browser, _page(tmp_path, body))


@pytest.mark.parametrize(
    "body",
    [
        '<img src="plot.png">',  # beside the page where it was written, not where it is sent
        '<script src="https://cdn.invalid/bokeh.min.js"></script>',  # needs the network
    ],
)
def test_a_page_that_needs_more_than_itself_fails_offline(tmp_path, browser, body):
    from report_browser import open_offline

    folder = tmp_path / "written"
    folder.mkdir()
    index = _page(folder, body)
    with pytest.raises(AssertionError, match="(?i)failed|not shown"):
        open_offline(browser, index, tmp_path / "alone")


def test_a_whole_page_opens_offline(tmp_path, browser):
    from report_browser import open_offline

    folder = tmp_path / "written"
    folder.mkdir()
    data = "data:image/png;base64," + base64.b64encode(PIXEL).decode()
    page, refused, text = open_offline(
        browser, _page(folder, f'<img src="{data}"><p>1.5</p>'), tmp_path / "alone"
    )
    page.context.close()
    assert refused == [] and "1.5" in text
