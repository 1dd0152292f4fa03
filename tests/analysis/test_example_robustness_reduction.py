"""examples/robustness_reduction.py runs and prints what docs/robustness_reduction.md shows."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "examples" / "robustness_reduction.py"
DOC = ROOT / "docs" / "robustness_reduction.md"
NUMBER = re.compile(r"[-+]?\d+\.\d+|inf")


def _doc_output() -> list[str]:
    """The ```text block after the line that names the example's command."""
    text = DOC.read_text(encoding="utf-8")
    start = text.index("`python examples/robustness_reduction.py`")
    block = text[start:].split("```text\n", 1)[1].split("```", 1)[0]
    return block.strip("\n").splitlines()


def _mask(line: str) -> tuple[str, list[str]]:
    return NUMBER.sub("#", line), NUMBER.findall(line)


def _close(printed: str, documented: str) -> bool:
    """Equal to one unit of the last printed digit (a value at a rounding edge may round the
    other way with another BLAS kernel; the docs were taken on one machine)."""
    if "inf" in (printed, documented):
        return printed == documented
    decimals = len(documented.split(".")[1])
    return abs(float(printed) - float(documented)) <= 1.01 * 10.0**-decimals


@pytest.fixture(scope="module")
def printed(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.run(
        [sys.executable, str(SCRIPT)],
        cwd=tmp_path_factory.mktemp("example"),
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip("\n").splitlines()


def test_prints_what_the_docs_show(printed: list[str]) -> None:
    documented = _doc_output()
    assert len(printed) == len(documented)
    for got, want in zip(printed, documented):
        (g_words, g_nums), (w_words, w_nums) = _mask(got), _mask(want)
        assert g_words == w_words, (got, want)
        assert all(_close(a, b) for a, b in zip(g_nums, w_nums)), (got, want)


def test_the_guarantees_hold_in_the_printed_numbers(printed: list[str]) -> None:
    """The certified bound is above the sweep's peak, the certified box below the sweep's."""
    text = "\n".join(printed)
    bound, peak = (
        float(x) for x in re.findall(r"sup\|S\| <= ([\d.]+), sweep max \|S\| = ([\d.]+)", text)[0]
    )
    assert peak <= bound
    k_cert, k_sweep = (
        float(x)
        for x in re.search(
            r"certified ±([\d.]+) %, first unstable member found at ±([\d.]+) %", text
        ).groups()
    )
    assert k_cert <= k_sweep
