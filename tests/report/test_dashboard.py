"""``flexsat serve``, the live design dashboard (flexsat.report.dashboard): the page's widgets
drive the maneuver and the margins, first in-process (Panel without a server), then as a user
meets it: the command started on a free port and the page driven in headless Chromium."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import flexsat
from flexsat.report.dashboard import DISPLAY_UNITS, SWEEP_POINTS, Dashboard, readout_html
from flexsat.report.dashboard_model import TamuDesign, design_point, sweep_values
from flexsat.units import si_factor

SRC = Path(flexsat.__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def design():
    return TamuDesign()


def _cell(html: str, ident: str) -> str:
    found = re.search(rf'id="{ident}">([^<]*)<', html)
    assert found, f"no #{ident} in {html}"
    return found.group(1)


def test_a_widget_change_updates_the_readouts_and_the_plots(design):
    board = Dashboard(design)
    first = board.readout.object
    assert _cell(first, "update-count") == "1"
    board.gains["g1"].value = 5000.0
    second = board.readout.object
    assert _cell(second, "update-count") == "2"
    expected = design.evaluate(design_point(g1="5000 ozf*in/rad"))
    assert _cell(second, "settling-time") == f"{expected.settling_time_s:.3f} s"
    assert _cell(second, "phase-margin") == f"{expected.margins.phase_margin_deg:.2f} deg"
    assert _cell(second, "settling-time") != _cell(first, "settling-time")
    angle = board.sources["angle"].data
    assert len(angle["t"]) == expected.time_s.size
    # the plot is in degrees and the tip in inches (the papers' units), from the SI histories
    assert angle["theta"][-1] == pytest.approx(expected.angle_rad[-1] * 180 / 3.141592653589793)
    tip = board.sources["tip"].data["tip"]
    assert tip[-1] == pytest.approx(expected.tip_deflection_m[-1] / si_factor("in"))


def test_the_widgets_hold_the_gains_in_the_papers_units(design):
    board = Dashboard(design)
    point = board.point()
    assert board.gains["g1"].value == pytest.approx(3000.0)
    assert point.g1 == pytest.approx(3000.0 * si_factor(DISPLAY_UNITS["g1"][0]))
    assert point.g2 == pytest.approx(800.0 * si_factor(DISPLAY_UNITS["g2"][0]))


def test_a_law_enables_only_the_gains_it_uses(design):
    board = Dashboard(design)
    board.law.value = "law_i"
    assert board.gains["alpha"].disabled and not board.gains["g3"].disabled
    board.law.value = "pd"
    assert board.gains["g3"].disabled and not board.gains["alpha"].disabled


def test_a_refused_gain_shows_its_message_and_no_numbers(design):
    board = Dashboard(design)
    board.gains["g1"].value = -10.0
    shown = board.readout.object
    assert _cell(shown, "maneuver-error").startswith("g1: must be &gt;= 0")
    assert _cell(shown, "settling-time") == "no maneuver"
    assert "nan" not in shown.lower()
    assert board.sources["angle"].data["t"].size == 0


def test_a_sweep_fills_its_plots_and_reports_its_progress(design):
    board = Dashboard(design)
    board.sweep_gain.value = "g2"
    board.run_sweep()
    data = board.sources["sweep"].data
    expected = sweep_values(board.point(), "g2", SWEEP_POINTS) / si_factor("ozf*in*s/rad")
    np.testing.assert_allclose(data["x"], expected, rtol=1e-12)  # the page's units
    assert len(data["settling"]) == len(data["pm"]) == SWEEP_POINTS
    assert board.progress.value == SWEEP_POINTS
    assert re.search(
        rf"sweep of g2 done: {SWEEP_POINTS} of {SWEEP_POINTS} in", board.sweep_status.object
    )


def test_a_sweep_that_cannot_start_says_why(design):
    board = Dashboard(design)
    board.gains["g1"].value = 0.0
    board.run_sweep()
    assert "g1: a sweep about g1 = 0 needs a value &gt; 0" in board.sweep_status.object
    assert len(board.sources["sweep"].data["x"]) == 0


def test_an_unstable_loop_shows_why_it_has_no_margins(design):
    e = design.evaluate(design_point(g1="1e7 ozf*in/rad"))
    shown = readout_html(e, 3, 12.0)
    assert "unstable" in _cell(shown, "phase-margin")


# -- the command in a browser ----------------------------------------------------------------
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def served():
    """``flexsat serve --port P`` on a free port; its URL once it answers (the first start
    compiles the simulation loop: up to a few minutes on a cold numba cache)."""
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(SRC), "OMP_NUM_THREADS": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "flexsat", "serve", "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    url = f"http://127.0.0.1:{port}/"
    try:
        deadline = time.monotonic() + 300
        while True:
            if process.poll() is not None:
                pytest.fail(f"flexsat serve exited: {process.communicate()[1]}")
            try:
                with urllib.request.urlopen(url, timeout=5) as answer:
                    assert answer.status == 200
                break
            except OSError:
                if time.monotonic() > deadline:
                    pytest.fail("flexsat serve did not answer within 300 s")
                time.sleep(0.5)
        yield url
    finally:
        process.terminate()
        process.wait(timeout=30)


def test_a_port_in_use_is_an_error_naming_the_option():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        env = {**os.environ, "PYTHONPATH": str(SRC)}
        done = subprocess.run(
            [sys.executable, "-m", "flexsat", "serve", "--port", str(port)],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
        )
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"--port: cannot listen on 127.0.0.1:{port}"), done.stderr
    assert "Traceback" not in done.stderr


def test_the_served_page_answers_a_gain_change(served, browser, tmp_path):
    """Acceptance (issue 24): start it, change a gain, see the settling time and a margin
    change; no script error, no failed request (the page needs no network); a screenshot."""
    page = browser.new_page(viewport={"width": 1300, "height": 1000})
    errors: list[str] = []
    failed: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
    page.on("requestfailed", lambda request: failed.append(request.url))
    try:
        page.goto(served, wait_until="load")
        count = page.locator("#update-count")
        count.wait_for(timeout=60_000)
        before = {k: page.locator(f"#{k}").inner_text() for k in ("settling-time", "phase-margin")}
        assert re.fullmatch(r"\d+\.\d{3} s", before["settling-time"]), before
        assert before["phase-margin"].endswith(" deg"), before
        g1 = page.get_by_label(DISPLAY_UNITS["g1"][1])
        g1.fill("5000")
        g1.press("Enter")
        # the readout says how many updates it has shown (the locator pierces Bokeh's shadow DOM)
        page.locator("#update-count", has_text=re.compile(r"^2$")).wait_for(timeout=30_000)
        after = {k: page.locator(f"#{k}").inner_text() for k in ("settling-time", "phase-margin")}
        expected = TamuDesign().evaluate(design_point(g1="5000 ozf*in/rad"))
        assert after["settling-time"] == f"{expected.settling_time_s:.3f} s"
        assert after["phase-margin"] == f"{expected.margins.phase_margin_deg:.2f} deg"
        assert after["settling-time"] != before["settling-time"]
        assert after["phase-margin"] != before["phase-margin"]
        # a sweep in the background: the page shows its progress and ends done
        page.get_by_role("button", name=f"sweep {SWEEP_POINTS} values").click()
        status = page.locator("#sweep-status", has_text=re.compile(r"\bdone:"))
        status.wait_for(timeout=120_000)
        assert f"{SWEEP_POINTS} of {SWEEP_POINTS}" in status.inner_text()
        page.screenshot(path=str(tmp_path / "dashboard.png"), full_page=True)
        assert (tmp_path / "dashboard.png").stat().st_size > 10_000
        assert errors == [], errors
        assert failed == [], failed
    finally:
        page.close()
