"""examples/hardware_in_the_loop.py runs and prints the tables docs/tamu.md and docs/nps.md show.

Each printed row is matched by its first two cells (the run and the hardware or cable torque) to
the row of the same name on either page, and every printed cell must equal the page's: the same
words, and numbers within one unit of the last printed digit (a value on a rounding edge may
fall the other way on another BLAS kernel; the pages were written on one machine).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "examples" / "hardware_in_the_loop.py"
PAGES = (ROOT / "docs" / "tamu.md", ROOT / "docs" / "nps.md")


def _cells(line: str) -> list[str]:
    cells = [c.strip().replace("\u2212", "-") for c in line.strip().strip("|").split("|")]
    # the pages write a zero cable torque as "0", the script as "0 mN m"
    return ["0" if c == "0 mN m" else c for c in cells]


def _rows(text: str) -> dict[tuple[str, str], list[str]]:
    rows = {}
    for line in text.splitlines():
        if line.startswith("|") and not line.startswith("|---"):
            cells = _cells(line)
            rows[(cells[0], cells[1])] = cells[2:]
    return rows


def _same(printed: str, documented: str) -> bool:
    try:
        value, page = float(printed), float(documented)
    except ValueError:
        return printed == documented
    decimals = len(documented.split(".")[1]) if "." in documented else 0
    return abs(value - page) <= 1.01 * 10.0**-decimals


def test_the_example_prints_what_the_pages_show():
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run(
        [sys.executable, str(SCRIPT)], capture_output=True, text=True, env=env, timeout=600
    )
    assert out.returncode == 0, out.stderr
    printed = {k: v for k, v in _rows(out.stdout).items() if k[0] != "run"}
    documented = {}
    for page in PAGES:
        documented.update(_rows(page.read_text(encoding="utf-8")))
    assert len(printed) == 21  # 15 TAMU rows (3 laws x 5 settings) and 6 NPS rows
    for key, cells in printed.items():
        assert key in documented, f"row {key} is not on the pages"
        page_cells = documented[key][: len(cells)]
        assert all(_same(p, d) for p, d in zip(cells, page_cells, strict=True)), (
            key,
            cells,
            page_cells,
        )
