"""A report page as a user sees it: opened in headless Chromium (Debian's ``chromium``, driven
by playwright), with what a reader would notice checked.

:func:`assert_renders` opens ``index.html`` from disk and asserts that the page loads with no
script error and no failed request, has a heading, shows every figure (each ``<img>`` decoded,
with a width), links only to files that exist, and shows no ``nan``/``inf`` where a number
should be (a "no data" value is written as such, issue 21).

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


def assert_renders(browser: Any, index: Path) -> str:
    """Open the report ``index`` in ``browser`` and check it as a reader would (module
    docstring); returns the page's visible text."""
    index = Path(index).resolve()
    assert index.is_file(), index
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    errors: list[str] = []
    failed: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    page.on("requestfailed", lambda request: failed.append(request.url))
    try:
        page.goto(index.as_uri(), wait_until="load")
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
        page.close()
