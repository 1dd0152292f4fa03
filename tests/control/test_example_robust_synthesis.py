"""examples/robust_synthesis.py runs and prints what docs/synthesis.md shows."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "examples" / "robust_synthesis.py"
DOC = ROOT / "docs" / "synthesis.md"
NUMBER = re.compile(r"[-+]?\d+\.\d+|inf")
#: the H2/LQR gain mismatch is round-off (its digits differ between BLAS kernels)
ROUND_OFF = re.compile(r"max \|F \+ K\| / max \|K\| = (\S+)$")


def _doc_output() -> list[str]:
    text = DOC.read_text(encoding="utf-8")
    start = text.index("`python examples/robust_synthesis.py")
    block = text[start:].split("```text\n", 1)[1].split("```", 1)[0]
    return block.strip("\n").splitlines()


def _mask(line: str) -> tuple[str, list[str]]:
    """Words without numbers, and the numbers; the CPU time in "(… s CPU)" dropped."""
    line = re.sub(r"\(\d+\.\d+ s CPU\)", "(t s CPU)", line)
    return NUMBER.sub("#", line), NUMBER.findall(line)


def _close(printed: str, documented: str) -> bool:
    """Equal to one unit of the last printed digit (a value at a rounding edge may differ
    between BLAS kernels; the docs were taken on one machine)."""
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


def test_the_example_prints_the_documented_designs(printed):
    documented = _doc_output()
    assert len(printed) == len(documented)
    for got, doc in zip(printed, documented, strict=True):
        gain = ROUND_OFF.search(got)
        if gain:
            assert ROUND_OFF.search(doc)
            assert float(gain.group(1)) < 1e-9  # the H2 gain is the LQR gain
            continue
        (gw, gn), (dw, dn) = _mask(got), _mask(doc)
        assert gw == dw, (got, doc)
        assert all(_close(a, b) for a, b in zip(gn, dn, strict=True)), (got, doc)
