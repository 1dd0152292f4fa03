"""examples/robust_synthesis.py runs and prints what docs/synthesis.md shows."""

from __future__ import annotations

import re

import pytest

from example_output import assert_same_line, doc_output, run_example

#: the H2/LQR gain mismatch is round-off (its digits differ between BLAS kernels)
ROUND_OFF = re.compile(r"max \|F \+ K\| / max \|K\| = (\S+)$")
#: the CPU time of a design, "(… s CPU)", differs from run to run
TIMING = re.compile(r"\(\d+\.\d+ s CPU\)")


@pytest.fixture(scope="module")
def printed(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    return run_example("robust_synthesis.py", tmp_path_factory.mktemp("example"))


def test_the_example_prints_the_documented_designs(printed):
    documented = doc_output("synthesis.md", "`python examples/robust_synthesis.py")
    assert len(printed) == len(documented)
    for got, doc in zip(printed, documented, strict=True):
        gain = ROUND_OFF.search(got)
        if gain:
            assert ROUND_OFF.search(doc)
            assert float(gain.group(1)) < 1e-9  # the H2 gain is the LQR gain
            continue
        assert_same_line(got, doc, TIMING)
