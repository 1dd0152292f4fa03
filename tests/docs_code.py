"""Run the Python of a documentation page as a reader would, and compare what it prints with
what the page shows.

A page's ```` ```python ```` blocks run in order in one namespace (a reader pasting them into
one session), in a scratch folder. A ```` ```text ```` block right after a Python block is the
output the page promises: :func:`assert_same_output` compares it with what the block printed,
word by word, numbers within half a unit of the last digit the page shows (the page rounds;
BLAS kernels differ below that) plus a relative 1e-9.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

_FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


@dataclass
class Block:
    """A Python block of a page, what the page says it prints (None: nothing shown) and what
    it printed."""

    code: str
    shown: str | None
    printed: str = ""


def python_blocks(page: Path) -> list[Block]:
    """The page's Python blocks, each with the text block that follows it, if any."""
    fences = [(m.group(1), m.group(2), m.end()) for m in _FENCE.finditer(page.read_text())]
    text = page.read_text()
    blocks = []
    for i, (lang, body, end) in enumerate(fences):
        if lang != "python":
            continue
        shown = None
        if i + 1 < len(fences) and fences[i + 1][0] == "text":
            between = text[end : text.index("```text", end)]
            if not between.strip():  # the output block follows the code directly
                shown = fences[i + 1][1]
        blocks.append(Block(body, shown))
    return blocks


def run_page(page: Path, workdir: Path) -> list[Block]:
    """Run every Python block of ``page`` in ``workdir``, in one namespace; each block's
    printed output is kept."""
    blocks = python_blocks(page)
    namespace: dict[str, object] = {"__name__": "__docs__"}
    cwd = os.getcwd()
    os.chdir(workdir)
    try:
        for k, block in enumerate(blocks):
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(block.code, f"{page.name}, block {k + 1}", "exec"), namespace)
            block.printed = out.getvalue()
    finally:
        os.chdir(cwd)
    return blocks


def _tolerance(token: str) -> float:
    mantissa = re.split("[eE]", token)[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(re.split("[eE]", token)[1]) if re.search("[eE]", token) else 0
    return 0.5 * 10.0 ** (exponent - decimals)


def assert_same_output(shown: str, printed: str, where: str) -> None:
    """``printed`` reads as ``shown``: the same words, numbers equal to the digits shown."""
    a, b = shown.split(), printed.split()
    assert len(a) == len(b), f"{where}: the page shows\n{shown}\nthe code printed\n{printed}"
    for s, p in zip(a, b):
        ns, np_ = _NUMBER.findall(s), _NUMBER.findall(p)
        assert _NUMBER.sub("#", s) == _NUMBER.sub("#", p), f"{where}: {s!r} vs {p!r}"
        for x, y in zip(ns, np_):
            tol = _tolerance(x) + 1e-9 * abs(float(x))
            assert math.isclose(float(x), float(y), abs_tol=tol), f"{where}: {s!r} vs {p!r}"
