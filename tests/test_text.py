"""Display formatting (flexsat.text)."""

from flexsat.text import MISSING, format_optional


def test_format_optional_formats_numbers_and_marks_missing_values():
    assert format_optional(0.123456, ".3f") == "0.123"
    assert format_optional(-2e-5, "+.1e") == "-2.0e-05"
    assert format_optional(None, ".3f") == MISSING == "–"
