"""Star-tracker scenarios (kind: star_tracker): the example file runs the issue's two cases
(clean, and 2 false stars with 20 % missing) through ``flexsat run``; each mistake is reported
as ``field.path: rule`` before anything runs."""

from pathlib import Path

import numpy as np
import pytest

from flexsat.scenarios import ScenarioError, StarTrackerScenario, load_scenario, run_scenario
from flexsat.scenarios.star_tracker import build_tracker

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "star_tracker.yaml"

SMALL = """
kind: star_tracker
name: small star tracker
catalog: {source: synthetic, magnitude_limit: 6.5, seed: 0}
cameras:
  - {field_of_view: "12 deg", n_pixels: 4096, pixel_pitch: "5.5 um", centroid_noise: 0.1}
  - {field_of_view: "12 deg", n_pixels: 4096, pixel_pitch: "5.5 um", centroid_noise: 0.1,
     mounting: ["0 deg", "90 deg", "0 deg"]}
identification: {tolerance: "5 arcsec", min_triplets: 3, min_fields: 2}
runs:
  - {label: clean, attitudes: 40, seed: 1}
  - {label: noisy, attitudes: 40, seed: 2, false_stars: 2, missing_fraction: 0.2}
"""


def test_the_example_loads_with_the_papers_rule():
    spec = load_scenario(EXAMPLE)
    assert isinstance(spec, StarTrackerScenario)
    assert spec.identification.tolerance == pytest.approx(5 * np.pi / 648000)
    assert (spec.identification.min_triplets, spec.identification.min_fields) == (3, 2)
    assert [r.attitudes for r in spec.runs] == [1000, 1000]
    assert spec.cameras[1].mounting[1] == pytest.approx(np.pi / 2)


def test_a_small_scenario_runs_and_identifies_every_attitude():
    result = run_scenario(load_scenario(SMALL))
    rows = {r["run"]: r for r in result.metrics_records()}
    assert set(rows) == {"clean", "noisy"}
    for r in rows.values():
        assert r["attitudes"] == 40 and r["wrong_accepted"] == 0
        assert r["identification_rate"] == 1.0  # 40 of 40 (1,000 attitudes: tests/identify)
        for axis in "xyz":
            assert r[f"error_std_{axis}_arcsec"] < 5  # the paper's sub-5″
    assert result.dataset()["error"].shape == (2, 40, 3)


def test_flexsat_run_dispatches_kind_star_tracker(tmp_path):
    from typer.testing import CliRunner

    from flexsat.cli import app

    path = tmp_path / "st.yaml"
    path.write_text(SMALL.replace("attitudes: 40", "attitudes: 10"))
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "identification_rate" in result.output
    assert (out / "index.html").is_file() and (out / "sky_2.png").is_file()


def test_a_hipparcos_catalogue_is_read_relative_to_the_scenario(tmp_path):
    # three stars 120° apart: the catalogue loads, but no pair fits in a field of view
    line = (
        "H|{hip:12d}| |00 00 00.00|+00 00 00.0| 1.00| |H|{ra:012.8f}|{de:+012.8f}|"
        + "|".join([""] * 68)
        + "\n"
    )
    stars = (line.format(hip=i, ra=120.0 * (i - 1), de=0.0) for i in (1, 2, 3))
    (tmp_path / "hip_main.dat").write_text("".join(stars))
    text = SMALL.replace(
        "{source: synthetic, magnitude_limit: 6.5, seed: 0}",
        "{source: hipparcos, path: hip_main.dat}",
    )
    (tmp_path / "st.yaml").write_text(text)
    with pytest.raises(ScenarioError, match="catalog: no two of its 3 stars"):
        build_tracker(load_scenario(tmp_path / "st.yaml"))
    (tmp_path / "hip_main.dat").write_text("")  # an empty catalogue
    with pytest.raises(ScenarioError, match="catalog: hip_main.dat holds 0 usable stars"):
        build_tracker(load_scenario(tmp_path / "st.yaml"))


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ('tolerance: "5 arcsec"', 'tolerance: "1 arcsec"'),
            r"identification.tolerance: 1″ is below 3√2 σ",
        ),
        (('tolerance: "5 arcsec"', 'tolerance: "5 s"'), "identification.tolerance"),
        (("min_fields: 2", "min_fields: 3"), "cameras: identification.min_fields = 3"),
        (("min_triplets: 3", "min_triplets: 0"), "identification.min_triplets"),
        (("attitudes: 40, seed: 1", "attitudes: 0, seed: 1"), r"runs.*attitudes"),
        (("missing_fraction: 0.2", "missing_fraction: 1.0"), r"runs.*missing_fraction"),
        (("false_stars: 2", "false_stars: -2"), r"runs.*false_stars"),
        (("{label: noisy", "{label: clean"), "runs: duplicate label 'clean'"),
        (("source: synthetic", "source: tycho"), "catalog.source"),
        (("source: synthetic", "source: hipparcos"), "catalog.path: give the hip_main.dat path"),
        (("centroid_noise: 0.1}", "centroid_noise: -0.1}"), r"cameras.*centroid_noise"),
        (
            (
                'field_of_view: "12 deg", n_pixels: 4096, pixel_pitch: "5.5 um", '
                "centroid_noise: 0.1}",
                'field_of_view: "150 deg", n_pixels: 4096, pixel_pitch: "5.5 um", '
                "centroid_noise: 0.1}",
            ),
            r"cameras.*below 120°",
        ),
        (
            ('mounting: ["0 deg", "90 deg", "0 deg"]', 'mounting: ["0 deg", "90 deg"]'),
            r"cameras.*mounting: must be 3",
        ),
        (("seed: 0}", "seed: 0, colour: red}"), "catalog.colour"),
    ],
)
def test_schema_mistakes_are_named(change, message):
    old, new = change
    assert old in SMALL
    with pytest.raises(ScenarioError, match=message):
        spec = load_scenario(SMALL.replace(old, new))
        build_tracker(spec)


def test_a_crowded_run_is_refused_before_any_run_starts(monkeypatch):
    # the second run's 1,000 false stars per field would give ~1.7e7 candidate matches a field:
    # refused by name before the first (clean) run is identified
    import flexsat.attitude.star_tracker as star_tracker

    started = []
    monkeypatch.setattr(star_tracker, "monte_carlo", lambda *a, **k: started.append(a))
    spec = load_scenario(SMALL.replace("false_stars: 2", "false_stars: 1000"))
    with pytest.raises(ScenarioError, match=r"runs\['noisy'\]\.false_stars: 1000 per field") as e:
        run_scenario(spec)
    assert started == [] and len(e.value.problems) == 1


def test_a_sky_beyond_the_star_limit_is_refused_by_name():
    with pytest.raises(ScenarioError, match=r"catalog\.magnitude_limit: .*MAX_CATALOG_STARS"):
        build_tracker(load_scenario(SMALL.replace("magnitude_limit: 6.5", "magnitude_limit: 30")))
