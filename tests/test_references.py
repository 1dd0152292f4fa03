"""Citations that replace the developers' seed file names (flexsat.references)."""

import re
import subprocess
from pathlib import Path

from flexsat.references import ATTACHMENTS, SEEDS, cite, references


def test_cite_replaces_each_seed_file_by_authors_and_year():
    text = "seed 000_7bfdb62d2eacc22a.txt, Att. 4 Table 1; seed 002_c3272b32d7cac32e.txt, L3"
    assert cite(text) == "Junkins, Pollock & Rahman 1990, Att. 4 Table 1; Bainum & Reddy 1979, L3"
    assert cite("Blevins (1979), Table 8-1") == "Blevins (1979), Table 8-1"
    assert cite("seed 009_0123456789abcdef.txt") == "seed 009_0123456789abcdef.txt"  # unknown


def test_references_list_the_full_citation_and_the_attached_papers_named():
    lines = references(
        ["seed 000_7bfdb62d2eacc22a.txt, Att. 7 Table 2", "seed 004_680d3fec9e1f8c83.txt, L205"]
    )
    assert lines[0].startswith("Junkins, Pollock & Rahman 1990: J. L. Junkins, T. C. Pollock")
    assert lines[1] == f"  Att. 7: {ATTACHMENTS[7]}"
    assert "Creamer" in lines[1] and "Acta Astronautica" in lines[2]
    assert len(lines) == 3


def test_every_seed_is_cited_with_authors_title_and_year():
    for number, ref in SEEDS.items():
        assert any(str(year) in ref.short for year in range(1970, 2000)), number
        assert len(ref.full) > len(ref.short) + 40, number


def test_references_find_a_source_named_by_its_short_citation():
    lines = references(["Junkins, Pollock & Rahman 1990, Att. 12, L4258", "Bainum & Reddy 1979"])
    assert lines[0].startswith("Junkins, Pollock & Rahman 1990: J. L. Junkins")
    assert lines[1] == f"  Att. 12: {ATTACHMENTS[12]}"
    assert lines[2].startswith("Bainum & Reddy 1979: P. M. Bainum") and len(lines) == 3
    assert references(["Att. 4 of nothing"]) == []  # an attachment only of the Texas A&M report


#: pointers to files outside the repository: the developers' notes (by path or by file name,
#: ``seed003.md``, ``seed000_part2.md``) and seed transcripts, and absolute paths of the machine
#: they were written on
OUTSIDE_FILE = re.compile(
    r"shared/spec|shared/seeds|/work/|\b\d{3}_[0-9a-f]{16}\.txt\b|\bseed\d{3}(_part\d)?\.md\b"
)
#: what ships or is read by users: the package, its documentation and examples
PRODUCT = ("src", "docs", "README.md", "examples", "benchmarks")


def test_outside_file_pattern_matches_each_kind_of_pointer():
    for pointer in (
        "notes ../shared/spec/seed003.md §2.6",
        "shared/seeds/x",
        "/work/main/README.md",
        "seed 000_7bfdb62d2eacc22a.txt, Att. 3",
        "(spec seed003.md §3.2)",
        "`seed000_part2.md` §8",
    ):
        assert OUTSIDE_FILE.search(pointer), pointer
    assert not OUTSIDE_FILE.search("Junkins, Pollock & Rahman 1990, Att. 3 Eq. 12 (L1152)")


def _product_texts() -> list[tuple[str, str]]:
    """(path, text) of every tracked text file of the product (:data:`PRODUCT`)."""
    root = Path(__file__).resolve().parents[1]
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--", *PRODUCT],
        cwd=root,
        capture_output=True,
        check=True,
    ).stdout.decode()
    files = [name for name in listed.split("\0") if name]
    assert any(name.startswith("src/flexsat/") for name in files)  # the listing worked
    out = []
    for name in files:
        try:
            out.append((name, (root / name).read_text(encoding="utf-8")))
        except (UnicodeDecodeError, FileNotFoundError):  # binary, or deleted in the work tree
            continue
    return out


def test_the_product_points_to_no_file_outside_the_repository():
    """Sources are cited by full reference (flexsat.references), never by a path outside."""
    found = []
    for name, text in _product_texts():
        for number, line in enumerate(text.splitlines(), 1):
            if OUTSIDE_FILE.search(line):
                found.append(f"{name}:{number}: {line.strip()}")
    assert found == [], "\n".join(found)


#: the developers' internal names of their sources, which a reader cannot use: the seed numbers
#: (``seed 003``, ``Seed 003's``, ``seeds 003 and 004``, ``seed003``; the transcript-file form
#: ``seed 003_<hex>.txt`` is OUTSIDE_FILE's) and line numbers into their OCR transcripts
#: (``L208``, ``L1302-L1323``, ``L208–L220``, ``L2-L9``). Not flagged: one-digit names such as
#: the factors L1, L2 of the output-feedback weights or an L2 cache, "L" as a length, and random
#: seeds (``seed 0``, ``seed=123``, ``seeds 5 and 6``).
INTERNAL_POINTER = re.compile(r"\b(?i:seeds?)\s*\d{3}\b(?!_)|\bL\d{2,5}\b|\bL\d+\s*[-–]\s*L\d+\b")


def test_internal_pointer_pattern_matches_seed_numbers_and_line_numbers_only():
    for pointer in (
        "seed 003's main recommendation",
        "(seed 000 Att. 12)",
        "Seed 004 publishes no frequency",
        "the robustness sets of seeds 003 and 004",
        "notional (seed003 §3.3)",
        "piezo pairs (seed\n004)",
        "Table 1 (L1302-L1323)",
        "L208–L220",
        "(L21)",
        "Att. 6 L2415/L2495",
        "L2-L9",
        'f"{SOURCE}, L82"',
    ):
        assert INTERNAL_POINTER.search(pointer), pointer
    for legit in (
        "G1 = L1 L1ᵀ, G2 = L2 L2ᵀ",
        "4 MiB L2;",
        "the Agrawal-Bang L-shaped structure",
        "λ = l/L, T̂ = T/(mΩ²L)",
        "(A - l2 * I2) / (l1 - l2)",
        "seed 000_7bfdb62d2eacc22a.txt",  # the transcript-file form cite() still reads
        "Measured (seed 0):",
        "default_rng(seed=123)",
        "runs with seeds 5 and 6 are identical",
    ):
        assert not INTERNAL_POINTER.search(legit), legit


def test_the_product_cites_no_seed_number_and_no_transcript_line():
    """Sources are located by section, table, figure, equation or attachment, which a reader
    holding the paper can use, never by the developers' seed numbers or transcript lines."""
    found = []
    for name, text in _product_texts():
        for match in INTERNAL_POINTER.finditer(text):  # the whole text: "seed\n004" too
            number = text.count("\n", 0, match.start()) + 1
            found.append(f"{name}:{number}: {match.group()!r}")
    assert found == [], "\n".join(found)
