"""``flexsat serve`` benchmark: how fast the dashboard answers a gain change (issue 24 target:
updated plots in <= 1 s on the TAMU case).

Two measurements, each over N gain changes (g1 stepped through 2000 ... 6000 oz-in/rad, each
value different from the last so every change is a real update):

1. **server side**, in-process (Panel without a server): the time from setting the g1 widget's
   value to the end of its update, which runs the 15 s maneuver through ``simulate`` (compiled
   loop), the margins of the sampled loop (``build_loop``, ``loop_margins``, ``disk_margin``),
   the loop gain on 400 frequencies, and refills the four plots' data sources and the readout.
   Wall and CPU time (``time.process_time``) of each update, and the split reported by the
   evaluation (maneuver, margins).
2. **browser round trip**: ``flexsat serve --port P`` started as a user starts it, the page
   opened in headless Chromium (playwright, Debian's ``/usr/bin/chromium``), then for each
   change: type the gain into its field, press Enter, and wait until the page shows the next
   update count (the readout and the plots' data arrive in the same websocket patch). Wall
   time from the key press to the updated page.

Usage: ``.venv/bin/python benchmarks/bench_serve.py [--changes 20] [--no-browser]``. Prints a
markdown table; a plain script, never collected by pytest.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import socket
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 1.0


def _values(n: int) -> list[float]:
    """n gains, oz-in/rad, none equal to its predecessor or to the 3000 start."""
    return [2000.0 + 4000.0 * ((7 * k) % n + 0.5) / n for k in range(n)]


def server_side(n: int) -> dict[str, list[float]]:
    from flexsat.report.dashboard import Dashboard
    from flexsat.report.dashboard_model import TamuDesign

    start = time.perf_counter()
    design = TamuDesign()
    board = Dashboard(design)  # the first update loads (or compiles) the loop
    setup = time.perf_counter() - start
    out: dict[str, list[float]] = {"wall": [], "cpu": [], "simulate": [], "margins": []}
    for g1 in _values(n):
        wall, cpu = time.perf_counter(), time.process_time()
        board.gains["g1"].value = g1
        out["wall"].append(time.perf_counter() - wall)
        out["cpu"].append(time.process_time() - cpu)
        evaluation = design.evaluate(board.point())
        out["simulate"].append(evaluation.simulate_s)
        out["margins"].append(evaluation.margins_s)
    out["setup"] = [setup]
    return out


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def browser_round_trip(n: int) -> dict[str, list[float]]:
    from playwright.sync_api import sync_playwright

    sys.path.insert(0, str(ROOT / "tests"))
    from report_browser import CHROMIUM_FLAGS

    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "OMP_NUM_THREADS": "1"}
    started = time.perf_counter()
    server = subprocess.Popen(
        [sys.executable, "-m", "flexsat", "serve", "--port", str(port)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    url = f"http://127.0.0.1:{port}/"
    out: dict[str, list[float]] = {"round_trip": [], "server_ms": []}
    try:
        while True:
            try:
                urllib.request.urlopen(url, timeout=5).close()
                break
            except OSError:
                if server.poll() is not None or time.perf_counter() - started > 300:
                    raise RuntimeError("flexsat serve did not start") from None
                time.sleep(0.2)
        out["start"] = [time.perf_counter() - started]
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(
                executable_path="/usr/bin/chromium", args=list(CHROMIUM_FLAGS)
            )
            page = browser.new_page(viewport={"width": 1300, "height": 1000})
            opened = time.perf_counter()
            page.goto(url, wait_until="load")
            count = page.locator("#update-count")
            count.wait_for(timeout=60_000)
            out["first_page"] = [time.perf_counter() - opened]
            field = page.get_by_label(re.compile(r"^g1, position gain"))
            for k, g1 in enumerate(_values(n), start=2):
                field.fill(f"{g1:g}")
                clock = time.perf_counter()
                field.press("Enter")
                page.locator("#update-count", has_text=re.compile(rf"^{k}$")).wait_for(
                    timeout=30_000
                )
                out["round_trip"].append(time.perf_counter() - clock)
                shown = page.locator("#update-ms").inner_text()
                out["server_ms"].append(float(shown.split()[0]))
            browser.close()
    finally:
        server.terminate()
        server.wait(timeout=30)
    return out


def _row(label: str, values: list[float], scale: float = 1e3, unit: str = "ms") -> str:
    v = [scale * x for x in values]
    return (
        f"| {label} | {min(v):.0f} {unit} | {statistics.median(v):.0f} {unit} | "
        f"{max(v):.0f} {unit} |"
    )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--changes", type=int, default=20, help="gain changes per measurement")
    p.add_argument("--no-browser", action="store_true", help="server side only")
    args = p.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, ")
    print(f"python {platform.python_version()}; {args.changes} gain changes\n")
    server = server_side(args.changes)
    print("| what | best | median | worst |")
    print("|---|---|---|---|")
    print(_row("server update, wall", server["wall"]))
    print(_row("server update, CPU", server["cpu"]))
    print(_row("  of which the maneuver (simulate)", server["simulate"]))
    print(_row("  of which the margins and loop gain", server["margins"]))
    worst = max(server["wall"])
    if not args.no_browser:
        browser = browser_round_trip(args.changes)
        print(_row("browser round trip (key press to updated page)", browser["round_trip"]))
        print(_row("  server update as the page reports it", browser["server_ms"], scale=1.0))
        print(_row("start: `flexsat serve` to first answer", browser["start"], 1.0, "s"))
        print(_row("first page load to readout", browser["first_page"], 1.0, "s"))
        worst = max(worst, max(browser["round_trip"]))
    print(f"\nworst answer to a gain change {worst:.3f} s (target <= {TARGET_S:g} s): ", end="")
    print("met" if worst <= TARGET_S else "NOT met")


if __name__ == "__main__":
    main()
