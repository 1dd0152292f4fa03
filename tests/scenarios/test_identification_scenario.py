"""Identification scenarios (``kind: identification``): schema, validation, run."""

import pytest
import yaml

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.identification import SUMMARY_COLUMNS, IdentificationScenario


def test_example_loads_with_si_values(identification_example):
    s = load_scenario(yaml.safe_dump(identification_example()))
    assert isinstance(s, IdentificationScenario)
    assert s.video.focal_length == pytest.approx(0.008)
    assert s.video.pixel_size == pytest.approx(27e-6)
    assert s.hammer.impulse == 0.5 and s.wheels.torque_rms == 0.05
    assert s.video.cameras[1].position == pytest.approx((2.0732, 0.5525, 2.4))
    cfg = s.config()
    assert cfg.a_priori_scale == {"clamp verticals": 1.15}
    assert cfg.rig.cameras()[0].fx == pytest.approx(0.008)


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"kind": "survey"}, "kind: must be 'maneuver', 'cmg', "),
        ({"hammer__force": 3}, "hammer.force: unknown key (allowed: node, direction, impulse"),
        ({"wheels__axes": ["x"]}, "wheels.axes: one torque axis per wheel node (3), got 1"),
        (
            {"wheels__torque_constants": [1.0]},
            "wheels.torque_constants: one factor per wheel (3), got 1",
        ),
        (
            {"video__cameras": [{"position": [0, 0, 1], "aim": [0, 0, 0]}]},
            "video.cameras: List should have at least 2 items",
        ),
        ({"video__focal_length": "8 kg"}, "video.focal_length"),
        (
            {"video__cameras": [{"position": [0, 0], "aim": [0, 0, 0]}] * 2},
            "video.cameras[0].position: must be 3 quantities",
        ),
        ({"truth__damping": [0.01, -0.1]}, "truth.damping[1]"),
        (
            {"identification__update": "creamer_junkins"},
            "identification.update: the wheels' torque constants are identified from the FRF",
        ),
    ],
)
def test_schema_errors_name_the_field(changes, message, identification_example):
    with pytest.raises(ScenarioError) as exc:
        load_scenario(yaml.safe_dump(identification_example(**changes)))
    assert message in str(exc.value)


@pytest.mark.parametrize(
    "changes, message",
    [
        (
            {"a_priori__stiffness_scale": {"clamp": 1.1}},
            "a_priori.stiffness_scale: unknown substructure 'clamp'",
        ),
        ({"sensors__targets": [1, 2, 21]}, "sensors.targets: node 21 is clamped"),
        ({"hammer__node": 99}, "hammer.node: node 99 is not a node of tamu_grid"),
        ({"case": "tamu", "case_overrides": {}}, "case: 'tamu' has no substructures to update"),
        ({"case_overrides": {"EI": -1.0}}, "case_overrides: EI: must be > 0"),
    ],
)
def test_case_dependent_errors_before_anything_runs(changes, message, identification_example):
    s = load_scenario(yaml.safe_dump(identification_example(**changes)))
    with pytest.raises(ScenarioError) as exc:
        run_scenario(s)
    assert message in str(exc.value)


def test_run_recovers_the_clamp_and_summarises(identification_example):
    s = load_scenario(yaml.safe_dump(identification_example(fast=True)))
    seen = []
    result = run_scenario(s, progress=seen.append)
    assert seen and result.case_source
    assert abs(result.campaign.scalings["clamp verticals"]["updated"] - 1) < 0.01
    table = result.console_table()
    assert table.columns == ("mode", *SUMMARY_COLUMNS) and len(table.rows) == 5
    assert all(len(row) == len(table.columns) for row in table.rows)


def test_blind_camera_is_a_video_error(identification_example):
    data = identification_example(fast=True)
    for cam in data["video"]["cameras"]:
        cam["aim"] = ["20 m", "20 m", "0 m"]
    with pytest.raises(ScenarioError, match="video.rig: some targets fall outside"):
        run_scenario(load_scenario(yaml.safe_dump(data)))


def test_recorded_tests_from_universal_files(tmp_path, recorded_scenario):
    """``records``: measured tests as UFF 58 files, paths relative to the scenario file; the
    update recovers the clamp within 1 % and the wheels' torque constants (true 0.9, 1.1, 1.0)
    within 1 %, with no truth to compare in the tables."""
    s = load_scenario(recorded_scenario(tmp_path))
    assert s.recorded and s.folder == tmp_path
    result = run_scenario(s)
    c = result.campaign
    assert c.modes["true_hz"] == [None] * len(c.modes["era_hz"])
    assert abs(c.scalings["clamp verticals"]["updated"] - 1) < 0.01
    for v, k in zip(c.wheel_gains.values(), (0.9, 1.1, 1.0)):
        assert v["true"] is None and abs(v["identified"] / k - 1) < 0.01
    assert result.console_table().rows[0][1] == "–"


def test_recorded_tests_without_video(tmp_path, recorded_scenario):
    """The video record is optional: modes are then paired by frequency and the report says
    there are no measured shapes."""
    from flexsat.report import write_report

    path = recorded_scenario(tmp_path)
    data = yaml.safe_load(path.read_text())
    del data["records"]["video"]
    path.write_text(yaml.safe_dump(data))
    result = run_scenario(load_scenario(path))
    assert result.campaign.mac_updated.size == 0 and result.campaign.video_realization is None
    assert abs(result.campaign.scalings["clamp verticals"]["updated"] - 1) < 0.01
    out = write_report(result, tmp_path / "report")
    assert (out / "mac.png").exists()


def test_recorded_scenario_errors(tmp_path, identification_example):
    data = identification_example()
    data["records"] = {"hammer": "h.uff", "wheels": "w.uff"}
    with pytest.raises(ScenarioError, match="sensors: describes a simulated test; with 'records'"):
        load_scenario(yaml.safe_dump(data))
    for name in ("truth", "sensors", "hammer", "video", "wheels"):
        data.pop(name)
    s = load_scenario(yaml.safe_dump(data))
    with pytest.raises(ScenarioError, match=r"records.hammer: cannot read .*h.uff"):
        run_scenario(s)
    data.pop("records")
    with pytest.raises(ScenarioError, match="sensors: required to simulate the tests"):
        load_scenario(yaml.safe_dump(data))


@pytest.mark.parametrize(
    "section, values, expected",
    [
        (
            "wheels",
            {"duration": "1e9 s"},
            "wheels.duration: samples (duration × sample_rate) = 5e+10, "
            "above the limit 2,000,000 (flexsat.limits); shorten the "
            "test or lower the sample rate",
        ),
        ("hammer", {"sample_rate": "-200 Hz"}, "hammer.sample_rate: must be > 0, got -200"),
        (
            "video",
            {"field_rate": "1e12 Hz"},
            "video.duration: samples (duration × field_rate) = 4.5e+12, above the limit 2,000,000",
        ),
        (
            "identification",
            {"bootstrap_samples": 1e9},
            "identification.bootstrap_samples: must be an integer in [0, 1000], got 1000000000.0",
        ),
    ],
)
def test_identification_tests_beyond_the_limits_are_refused_at_load(
    section, values, expected, identification_example
):
    data = identification_example()
    data[section].update(values)
    with pytest.raises(ScenarioError) as info:
        load_scenario(yaml.safe_dump(data))
    assert len(info.value.problems) == 1 and info.value.problems[0].startswith(expected)


def test_identification_seed_is_bounded(identification_example):
    data = dict(identification_example(), seed=1e29)
    with pytest.raises(
        ScenarioError,
        match=r"seed: must be an integer in \[0, 4294967295\], got "
        r"1e\+29",
    ):
        load_scenario(yaml.safe_dump(data))
