"""The documentation site (mkdocs.yml) covers every guide and every public module.

``make docs`` builds the site strictly (in CI); these tests catch what a strict build does not:
a guide written into docs/ but left out of the navigation, and a module added to the package
but to no API reference page (its docstrings would never be published).
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "flexsat"
DOCS = ROOT / "docs"


def _nav_pages(node: object) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, list):
        return [page for item in node for page in _nav_pages(item)]
    if isinstance(node, dict):
        return [page for value in node.values() for page in _nav_pages(value)]
    return []


def _config() -> dict:
    return yaml.safe_load((ROOT / "mkdocs.yml").read_text())


def test_every_page_in_docs_is_in_the_navigation_and_every_entry_exists():
    nav = _nav_pages(_config()["nav"])
    pages = sorted(str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md"))
    assert sorted(nav) == pages
    assert len(set(nav)) == len(nav)


def test_every_public_module_has_its_api_reference_entry():
    documented = set()
    for page in (DOCS / "api").glob("*.md"):
        documented |= set(re.findall(r"^::: (flexsat(?:\.\w+)+)$", page.read_text(), re.M))
    public = {
        "flexsat." + ".".join(path.relative_to(SRC).with_suffix("").parts)
        for path in SRC.rglob("*.py")
        if not any(part.startswith("_") for part in path.relative_to(SRC).parts)
    }
    assert public - documented == set(), "modules missing from docs/api"
    assert documented - public == set(), "docs/api names modules that do not exist"


def test_the_site_is_built_strictly_from_the_sources_with_numpy_docstrings():
    config = _config()
    assert config["strict"] is True
    (handler,) = [p["mkdocstrings"] for p in config["plugins"] if isinstance(p, dict)]
    python = handler["handlers"]["python"]
    assert python["paths"] == ["src"]
    assert python["options"]["docstring_style"] == "numpy"


#: a Markdown link or autolink with a scheme: it leaves the repository
_EXTERNAL = re.compile(r"\]\(\s*<?[a-zA-Z][a-zA-Z0-9+.-]*:|<[a-zA-Z][a-zA-Z0-9+.-]*://")


def test_no_link_points_outside_the_repository():
    """The site and the README link only to their own pages and files (issue 24): a reader
    offline, or years later, finds every one."""
    pages = [*DOCS.rglob("*.md"), ROOT / "README.md"]
    outside = [
        f"{page.relative_to(ROOT)}:{n}: {line.strip()}"
        for page in pages
        for n, line in enumerate(page.read_text().splitlines(), 1)
        if _EXTERNAL.search(line)
    ]
    assert outside == []
    assert _EXTERNAL.search("[spec](https://example.org/x)")
    assert _EXTERNAL.search("see <http://example.org>")
    assert not _EXTERNAL.search("[the tutorial](tutorial.md#1-the-structure)")
