"""Reading a scenario document (flexsat.scenarios.documents): a file or the text itself, UTF-8,
bounded in size, nesting and value count, no duplicate keys or recursive aliases; each problem
is one ScenarioError line naming the document, the key or the line."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from flexsat.scenarios import ScenarioError, default_scenario, load_scenario
from flexsat.scenarios.kind import built_in_kinds, scenario_kinds

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "tamu_40deg.yaml"


def problem(source) -> str:
    """The one problem line of the ScenarioError that loading ``source`` raises."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(source)
    assert len(info.value.problems) == 1, info.value.problems
    return info.value.problems[0]


# -- the source: a file, text or bytes -------------------------------------------------------------
def test_example_file_is_the_packaged_default():
    assert EXAMPLE.read_text() == default_scenario().yaml_text
    assert load_scenario(EXAMPLE).model_dump() == default_scenario().model_dump()


@pytest.mark.parametrize(
    "text, expected",
    [
        ("name: [unclosed", "yaml: "),
        ("- just\n- a list\n", "scenario: must be a YAML mapping"),
        ("missing.yaml", "scenario: cannot read 'missing.yaml'"),
    ],
)
def test_unreadable_scenarios(text, expected):
    with pytest.raises(ScenarioError, match="invalid scenario") as info:
        load_scenario(text)
    assert expected in str(info.value)


def test_utf8_bytes_load_as_their_text():
    text = default_scenario().yaml_text.replace("name: TAMU", "name: Café TAMU")
    scenario = load_scenario(text.encode("utf-8"))
    assert scenario.name.startswith("Café TAMU")
    assert scenario.yaml_text == text


def test_a_file_scenario_remembers_its_folder_and_text(tmp_path, monkeypatch):
    path = tmp_path / "sub" / "slew.yaml"
    path.parent.mkdir()
    path.write_text(default_scenario().yaml_text)
    monkeypatch.chdir(tmp_path)
    from_file = load_scenario(Path("sub") / "slew.yaml")
    assert from_file.folder == path.parent  # relative paths in it start next to it
    assert from_file.yaml_text == path.read_text()
    assert load_scenario(path.read_text()).folder == tmp_path  # text: the working directory


def test_unknown_kind_is_refused_naming_every_kind():
    """The registry's kinds: the default (maneuver) first, then the built-ins by name, then the
    plug-ins' (the example plug-in's pulse_tuning where it is installed)."""
    message = problem(default_scenario().yaml_text + "kind: survey\n")
    kinds = list(scenario_kinds())
    built_in = list(built_in_kinds())
    assert len(built_in) == 13 and kinds[:13] == built_in
    assert built_in == ["maneuver", *sorted(set(built_in) - {"maneuver"})]
    named = ", ".join(repr(k) for k in kinds[:-1])
    assert message == f"kind: must be {named} or {kinds[-1]!r}, got 'survey'"


@pytest.mark.parametrize("kind", ["survey", "[maneuver]"])
def test_a_kind_is_one_of_the_names(kind):
    assert problem(
        default_scenario().yaml_text.replace("\nname:", f"\nkind: {kind}\nname:", 1)
    ).startswith("kind: must be 'maneuver'")


# -- the YAML: bounded, unambiguous ----------------------------------------------------------------
def test_non_utf8_bytes_are_refused(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(default_scenario().yaml_text.encode() + "# café\n".encode("latin-1"))
    assert problem(path) == (
        f"scenario: {str(path)!r} is not UTF-8 text (byte 0xe9 at offset "
        f"{len(default_scenario().yaml_text.encode()) + 5}); save it as UTF-8"
    )


def test_1000_levels_of_nesting_are_refused_before_the_parser_recurses():
    text = default_scenario().yaml_text + "extra: " + "[" * 1000 + "]" * 1000 + "\n"
    assert default_scenario().yaml_text.count("\n") == 18  # so the nesting is on line 19
    assert problem(text) == (
        "scenario: nested deeper than 32 levels at line 19 (flexsat.limits.MAX_NESTING)"
    )


def test_duplicate_keys_are_refused_naming_the_key_and_lines():
    text = default_scenario().yaml_text.replace("seed: 0}", "seed: 0, seed: 7}")
    assert problem(text) == "simulation.seed: duplicate key (lines 8 and 8); give it once"
    assert problem(default_scenario().yaml_text + "\nname: again\n") == (
        "name: duplicate key (lines 3 and 20); give it once"
    )


def test_anchors_and_merge_keys_still_work():
    text = default_scenario().yaml_text.replace(
        'gains: {g1: "600 ozf*in/rad"', 'gains: &law1 {g1: "600 ozf*in/rad"'
    )
    assert load_scenario(text).runs[0].gains.g1 > 0
    merged = "base: &b {duration: 2 s, control_rate: 75 Hz}\nsimulation: {<<: *b, duration: 1 s}\n"
    assert yaml.safe_load(merged)["simulation"]["duration"] == "1 s"
    with pytest.raises(ScenarioError) as info:  # other problems, but no duplicate: an
        load_scenario(merged)  # override of a merged key is YAML's own rule
    assert not [p for p in info.value.problems if "duplicate" in p]


def test_aliases_expanding_beyond_the_limit_are_refused():
    text = "a: &a [" + ", ".join(["1"] * 10) + "]\n"
    for level in "bcde":
        previous = chr(ord(level) - 1)
        text += f"{level}: &{level} [" + ", ".join([f"*{previous}"] * 10) + "]\n"
    assert problem(text) == (
        "d: more than 10,000 values once aliases are expanded (flexsat.limits.MAX_DOCUMENT_NODES)"
    )


def test_oversized_document_is_refused():
    assert problem("#" * 300_000) == (
        "scenario: the document is larger than 256,000 bytes "
        "(flexsat.limits.MAX_DOCUMENT_BYTES); a scenario is a few kB"
    )
