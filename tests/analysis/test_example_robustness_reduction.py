"""examples/robustness_reduction.py runs and prints what docs/robustness_reduction.md shows."""

from __future__ import annotations

import re

import pytest

from example_output import assert_same_line, doc_output, run_example


@pytest.fixture(scope="module")
def printed(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    return run_example("robustness_reduction.py", tmp_path_factory.mktemp("example"))


def test_prints_what_the_docs_show(printed: list[str]) -> None:
    documented = doc_output("robustness_reduction.md", "`python examples/robustness_reduction.py`")
    assert len(printed) == len(documented)
    for got, want in zip(printed, documented, strict=True):
        assert_same_line(got, want)


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
