"""Every published system has a documentation page with its comparison to the paper
(docs/systems.md, issue 24): every case of the catalogue has a row, every link of the table
reaches a section of a page that holds a comparison table, and every group of
``flexsat validate`` is named there with its number of rows."""

from __future__ import annotations

import re
import unicodedata
from collections import Counter
from pathlib import Path

import pytest

from flexsat.catalog import CASES
from flexsat.checks import builtin_checks

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGE = DOCS / "systems.md"
#: a column that holds the paper's values (or the exact/benchmark values a paper printed)
PUBLISHED_COLUMN = re.compile(
    r"published|paper|printed|Table \d|NAFEMS|exact|Att\. \d|Eq\. \d", re.IGNORECASE
)


def slug(heading: str) -> str:
    """Python-Markdown's toc anchor of a heading (its default slugify)."""
    text = unicodedata.normalize("NFKD", heading).encode("ascii", "ignore").decode()
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def sections(page: Path) -> dict[str, str]:
    """anchor -> text of the section under that heading (to the next heading of its level or
    above)."""
    lines = page.read_text().splitlines()
    heads = [
        (i, len(m.group(1)), m.group(2))
        for i, line in enumerate(lines)
        if (m := re.match(r"^(#+) (.*)$", line))
    ]
    out = {}
    for k, (i, level, title) in enumerate(heads):
        end = next((j for j, lv, _ in heads[k + 1 :] if lv <= level), len(lines))
        out[slug(title)] = "\n".join(lines[i + 1 : end])
    return out


def rows(table_heading: str) -> list[list[str]]:
    """The rows of the first table after the line starting with ``table_heading``."""
    text = PAGE.read_text()
    start = text.index(table_heading)
    table = re.search(r"((?:^\|.*\|\n)+)", text[start:], re.M).group(1).splitlines()
    return [[c.strip() for c in line.strip("|").split("|")] for line in table[2:]]


CASE_ROWS = rows("| system | `flexsat cases` name")
OTHER_ROWS = rows("| system | source | comparison")


def test_every_catalogue_case_has_one_row():
    named = [re.fullmatch(r"`(\w+)`", row[1]).group(1) for row in CASE_ROWS]
    assert sorted(named) == sorted(CASES)


@pytest.mark.parametrize(
    "link",
    sorted(
        {
            link
            for row in CASE_ROWS + OTHER_ROWS
            for link in re.findall(r"\]\(([^)]+)\)", "|".join(row))
        }
    ),
)
def test_every_comparison_link_reaches_a_section_with_the_papers_values(link):
    page, _, anchor = link.partition("#")
    if page == "identification.md":  # a method on the grid, compared with its own truth
        assert (DOCS / page).is_file()
        return
    assert anchor, f"{link}: point at the comparison's section"
    found = sections(DOCS / page)
    assert anchor in found, f"{page} has no section #{anchor} (it has {sorted(found)})"
    section = found[anchor]
    if page == "agrawal_bang.md":  # the paper prints no number: its facts are listed instead
        assert "No dimension, material, frequency, damping or piezo constant" in section
        return
    # the tables of the section: a column or a row holds the paper's values
    tables = re.findall(r"((?:^\|.*\|\n?)+)", section, re.M)
    assert tables, f"{link}: no table in the section"
    assert any(PUBLISHED_COLUMN.search(t) for t in tables), f"{link}: no paper values in {tables}"


def test_every_validate_group_is_named_with_its_row_count():
    shown: dict[str, int] = {}
    for row in CASE_ROWS + OTHER_ROWS:
        for group, count in re.findall(r"`(\w+)` \((\d+)\)", row[-1]):
            assert group not in shown, f"{group} named twice"
            shown[group] = int(count)
    # the built-in checks (a plug-in's checks are its package's: docs/plugins.md)
    assert shown == dict(Counter(check.case for check in builtin_checks()))


def test_the_slug_is_the_one_mkdocs_writes():
    assert slug("3.5 Published vs computed") == "35-published-vs-computed"
    assert slug("Closed loop (Eq. 59, Table 4)") == "closed-loop-eq-59-table-4"
    assert slug("Validation rows (V1–V8)") == "validation-rows-v1v8"
