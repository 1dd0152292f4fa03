"""The tutorial (docs/tutorial.md) runs as printed: its Python blocks in order in one session,
each output it shows equal to what the block prints (tests/docs_code.py: numbers to the digits
the page shows)."""

from __future__ import annotations

from pathlib import Path

import pytest

from docs_code import assert_same_output, python_blocks, run_page

PAGE = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"


def test_the_tutorial_shows_what_its_code_prints(tmp_path):
    blocks = run_page(PAGE, tmp_path)
    assert len(blocks) >= 8
    shown = [b for b in blocks if b.shown is not None]
    assert len(shown) == len(blocks), "every block of the tutorial shows its output"
    for k, block in enumerate(blocks, 1):
        assert_same_output(block.shown, block.printed, f"docs/tutorial.md block {k}")


def test_the_output_check_fails_on_a_changed_number_or_word():
    """The comparison is not vacuous: a digit beyond the page's rounding or a word differs."""
    assert_same_output("PM  39.4 deg", "PM 39.43 deg", "same to the digits shown")
    with pytest.raises(AssertionError):
        assert_same_output("PM  39.4 deg", "PM 39.5 deg", "a number")
    with pytest.raises(AssertionError):
        assert_same_output("settled after 4.38 s", "diverged after 4.38 s", "a word")
    with pytest.raises(AssertionError):
        assert_same_output("[4.54 4.38]", "[4.54 4.38 4.3]", "a count")


def test_every_python_block_is_found(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```python\nprint(1)\n```\n\n```text\n1\n```\n\n```python\nx = 2\n```\n")
    blocks = python_blocks(page)
    assert [b.code for b in blocks] == ["print(1)\n", "x = 2\n"]
    assert blocks[0].shown == "1\n" and blocks[1].shown is None
