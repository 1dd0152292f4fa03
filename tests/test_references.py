"""Citations that replace the developers' seed file names (flexsat.references)."""

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
