"""A report page as a user sees it: opened in headless Chromium (Debian's ``chromium``, driven
by playwright), with what a reader would notice checked.

:func:`assert_renders` opens ``index.html`` from disk and asserts that the page loads with no
script error and no failed request, has a heading, shows every figure (each ``<img>`` decoded,
with a width; each interactive figure drawn on a canvas once BokehJS is idle), links only to
files that exist, and shows no ``nan``/``inf`` where a number should be (a "no data" value is
written as such, issue 21).

:func:`open_offline` opens a copy of ``index.html`` alone in an empty folder, in a browser
context with the network switched off and every request that is not the page itself refused
and recorded: what a reader sees who was sent the one file (issue 24, "the report opens offline
with no sibling files").

The browser is started once per test session (:func:`browser`, a pytest fixture registered in
``conftest.py``). Without Chromium or playwright the tests that need it are skipped, unless
``FLEXSAT_BROWSER=required`` (set by ``.ci/run``), where they fail instead: CI must not pass by
skipping them.
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse

import pytest

#: Chromium's flags for a sandbox without a network or a display: no background connections,
#: component updates or sync (each would be refused by the closed network, many at a time)
CHROMIUM_FLAGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)

#: a number a report should never show: a table cell or a sentence's word that reads nan or inf
_NOT_A_NUMBER = re.compile(r"(?<![\w.])[-+]?(nan|inf|infinity)(?![\w])", re.IGNORECASE)


def _unavailable(reason: str) -> None:
    if os.environ.get("FLEXSAT_BROWSER") == "required":
        pytest.fail(f"FLEXSAT_BROWSER=required but {reason}")
    pytest.skip(reason)


def start_browser() -> Iterator[Any]:
    """A headless Chromium for the session (a generator for a pytest fixture)."""
    executable = shutil.which("chromium")
    if executable is None:
        _unavailable("headless Chromium (Debian's chromium) is not installed")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _unavailable("playwright is not installed")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=CHROMIUM_FLAGS)
        try:
            yield browser
        finally:
            browser.close()


def wait_for_figures(page: Any) -> int:
    """Wait until BokehJS (where the page has it) has drawn its documents; the number of
    canvases then on the page (0 without interactive figures)."""
    if page.evaluate("() => window.Bokeh === undefined"):
        return 0
    page.wait_for_function("() => Bokeh.documents.length > 0", timeout=30_000)
    page.locator("canvas").first.wait_for(state="attached", timeout=30_000)  # pierces shadows
    return int(page.locator("canvas").count())


def assert_renders(browser: Any, index: Path, page: Any = None) -> str:
    """Open the report ``index`` in ``browser`` (or in ``page``, already set up: it is left
    open) and check it as a reader would (module docstring); returns the page's visible
    text."""
    index = Path(index).resolve()
    assert index.is_file(), index
    own = page is None
    if own:
        page = browser.new_page(viewport={"width": 1200, "height": 900})
    errors: list[str] = []
    failed: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    page.on("requestfailed", lambda request: failed.append(request.url))
    try:
        page.goto(index.as_uri(), wait_until="load")
        canvases = wait_for_figures(page)
        if page.evaluate("() => window.Bokeh !== undefined"):
            assert canvases > 0, f"{index}: the interactive figures are not drawn"
        assert errors == [], f"script errors in {index}: {errors}"
        assert failed == [], f"requests that failed in {index}: {failed}"
        heading = page.inner_text("h1").strip()
        assert heading, f"{index}: no title"
        images = page.eval_on_selector_all(
            "img",
            "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth])",
        )
        for src, complete, width in images:
            assert complete and width > 0, f"{index}: figure {src} is not shown"
        for href in page.eval_on_selector_all("a[href]", "els => els.map(e => e.href)"):
            url = urlparse(href)
            if url.scheme == "file":
                assert Path(unquote(url.path)).exists(), f"{index}: broken link {href}"
        text = page.inner_text("body")
        shown = _NOT_A_NUMBER.search(text)
        assert shown is None, f"{index}: shows {shown.group(0)!r} where a number should be"
        return text
    finally:
        if own:
            page.close()


def open_offline(browser: Any, index: Path, folder: Path) -> tuple[Any, list[str], str]:
    """Copy ``index`` alone into the empty ``folder`` and open it there with the network off
    (module docstring), checked by :func:`assert_renders`.

    Returns
    -------
    (page, refused, text)
        The open page (close its ``context`` when done), the URLs of the requests refused
        (any the page made beyond itself), and the page's visible text.
    """
    folder.mkdir(parents=True, exist_ok=True)
    assert not any(folder.iterdir()), f"{folder} is not empty"
    alone = folder / "index.html"
    shutil.copyfile(index, alone)
    context = browser.new_context(offline=True, viewport={"width": 1200, "height": 900})
    refused: list[str] = []
    page_url = alone.resolve().as_uri()

    def route(request_route: Any) -> None:
        url = request_route.request.url
        if url == page_url:
            request_route.continue_()
        else:
            refused.append(url)
            request_route.abort()

    context.route("**/*", route)
    page = context.new_page()
    try:
        text = assert_renders(browser, alone, page)
    except BaseException:
        context.close()
        raise
    return page, refused, text
