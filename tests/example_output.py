"""Run an example script and compare what it prints with the ```text block its docs page shows.

Shared by the tests of the Python examples (examples/frequency_domain.py,
robust_synthesis.py, robustness_reduction.py): the page's block after the line naming the
example's command, each line compared by its words (numbers masked) and its numbers, equal to
one unit of the last digit the page prints (a value on a rounding edge may round the other way
with another BLAS kernel; the pages were written on one machine).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NUMBER = re.compile(r"[-+]?\d+\.\d+|inf")


def doc_output(page: str, command: str) -> list[str]:
    """The lines of the ```text block after ``command`` on docs/``page``."""
    text = (ROOT / "docs" / page).read_text(encoding="utf-8")
    start = text.index(command)
    block = text[start:].split("```text\n", 1)[1].split("```", 1)[0]
    return block.strip("\n").splitlines()


def run_example(script: str, cwd: Path, *args: str, timeout: float = 600) -> list[str]:
    """The lines examples/``script`` prints, run headless with this tree's sources."""
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip("\n").splitlines()


def mask(line: str, timing: re.Pattern[str] | None = None) -> tuple[str, list[str]]:
    """A line's words with its numbers masked, and the numbers; a run time matched by
    ``timing`` dropped first."""
    if timing is not None:
        line = timing.sub("(t)", line)
    return NUMBER.sub("#", line), NUMBER.findall(line)


def close(printed: str, documented: str) -> bool:
    """Equal to one unit of the documented number's last digit (module docstring)."""
    if "inf" in (printed, documented):
        return printed == documented
    decimals = len(documented.split(".")[1])
    return abs(float(printed) - float(documented)) <= 1.01 * 10.0**-decimals


def assert_same_line(printed: str, documented: str, timing: re.Pattern[str] | None = None) -> None:
    """The same words and, number by number, :func:`close`."""
    (pw, pn), (dw, dn) = mask(printed, timing), mask(documented, timing)
    assert pw == dw, (printed, documented)
    assert len(pn) == len(dn) and all(close(a, b) for a, b in zip(pn, dn)), (printed, documented)
