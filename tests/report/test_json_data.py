"""The one JSON conversion of report data (flexsat.report.json_data) and, over a small run of
every kind's example, a metrics.json (and summary.json / identification.json) that a strict
JSON reader accepts: no NaN or Infinity token, every null it wrote for a non-finite number
with its reason (issue 21)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.report import write_report
from flexsat.report.json_data import NULL_REASONS, dumps, json_ready
from flexsat.scenarios import load_scenario, run_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _strict(text: str):
    """Parse as a strict reader does: NaN, Infinity and -Infinity are no JSON."""
    return json.loads(text, parse_constant=lambda token: pytest.fail(f"{token} in JSON"))


def test_non_finite_numbers_become_null_with_their_reason():
    data = {
        "run": "a",
        "mean": np.float64("nan"),
        "peak": math.inf,
        "low": -np.inf,
        "ok": np.float32(1.5),
        "count": np.int64(3),
        "series": np.array([1.0, np.nan, 2.0]),
        "nested": [{"x": math.nan}],
    }
    out = _strict(dumps(data))
    assert out["mean"] is None and out["peak"] is None and out["low"] is None
    assert out["ok"] == 1.5 and out["count"] == 3
    assert out["series"] == [1.0, None, 2.0]
    assert out["nested"] == [{"x": None, NULL_REASONS: {"x": "not a number (NaN): no data"}}]
    assert out[NULL_REASONS] == {
        "mean": "not a number (NaN): no data",
        "peak": "+infinity",
        "low": "-infinity",
        "series": "[1] not a number (NaN): no data",
    }


def test_a_reason_the_result_states_is_kept():
    data = {"rate": math.nan, "std": None, NULL_REASONS: {"rate": "nothing accepted"}}
    assert json_ready(data)[NULL_REASONS] == {"rate": "nothing accepted"}
    assert NULL_REASONS not in json_ready({"a": 1.0})  # only when something is null for it


def test_no_nan_token_can_be_written(monkeypatch):
    # a float subclass is still a float to the conversion
    class Measured(float):
        pass

    assert json_ready({"x": Measured("nan")}) == {
        "x": None,
        NULL_REASONS: {"x": "not a number (NaN): no data"},
    }
    # and were the conversion bypassed, the writer itself refuses the token (allow_nan=False)
    import flexsat.report.json_data as json_data

    monkeypatch.setattr(json_data, "json_ready", lambda value: value)
    with pytest.raises(ValueError, match="Out of range float values"):
        json_data.dumps({"x": math.nan})


# -- every kind -------------------------------------------------------------------------------
def _set(data, path, value):
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value


def _small_tamu(folder: Path) -> None:
    data = yaml.safe_load((EXAMPLES / "tamu_40deg.yaml").read_text())
    data["simulation"]["duration"] = "0.5 s"
    data["model"]["n_modes"] = 3
    (folder / "tamu_40deg.yaml").write_text(yaml.safe_dump(data, sort_keys=False))


def _example(name: str, changes: dict, folder: Path) -> Path:
    data = yaml.safe_load((EXAMPLES / name).read_text())
    for path, value in changes.items():
        _set(data, path, value)
    if "runs" in data and isinstance(data["runs"], list):
        data["runs"] = data["runs"][:2]
    if data.get("kind") in ("sweep", "montecarlo"):
        _small_tamu(folder)
        data["store"] = "store.zarr"
    path = folder / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


#: one example of each kind and the changes that make it a small run (a second or a few)
KINDS = {
    "maneuver": ("nps_pd_slews.yaml", {("simulation", "duration"): "0.5 s"}),
    "simulation": ("free_free_beam_impulse.yaml", {("simulation", "duration"): "0.05 s"}),
    "ppf": ("agrawal_bang_ppf.yaml", {("simulation", "duration"): "0.5 s"}),
    "cmg": (
        "cmg_preferred_angles.yaml",
        {("runs", 0, "duration"): "0.5 s", ("runs", 1, "duration"): "0.5 s"},
    ),
    "cmg_station": ("space_station_cmg.yaml", {("simulation", "orbits"): 0.05}),
    "slew": (
        "eps_slew_6s.yaml",
        {
            ("plant", "n_modes"): 12,
            ("controller", "linearization_points"): 3,
            ("maneuver", "duration"): "1 s",
            ("simulation", "duration"): "1.25 s",
        },
    ),
    "tether": (
        "tether_retrieval.yaml",
        {("simulation", "orbits"): 0.1, ("simulation", "samples_per_orbit"): 200},
    ),
    "star_tracker": (
        "star_tracker.yaml",
        {("runs", 0, "attitudes"): 3, ("runs", 1, "attitudes"): 3},
    ),
    "identification": (
        "tamu_grid_identification.yaml",
        {
            ("hammer", "duration"): "2 s",
            ("video", "duration"): "0.5 s",
            ("wheels", "duration"): "40 s",
            ("wheels", "segment"): 256,
            ("identification", "era_order"): 10,
            ("identification", "bootstrap_samples"): 0,
            ("truth", "modes"): 10,
        },
    ),
    "sweep": (
        "tamu_trade_surfaces.yaml",
        {("parameters", "alpha", "n"): 2, ("parameters", "u_max", "n"): 2},
    ),
    "montecarlo": ("tamu_montecarlo.yaml", {("cases",): 4, ("execution", "chunk_size"): 4}),
    "design": (
        "tamu_codesign_pareto.yaml",
        {("pareto", "points"): 2, ("pareto", "starts"): 1, ("pareto", "store"): "front.zarr"},
    ),
    "design_study": (
        "eps_design_stages.yaml",
        {
            ("cache",): "stage-cache",
            ("model", "n_modes"): 12,
            ("modes", "n_modes"): 6,
            ("simulation", "duration"): "10 s",
            ("simulation", "control_rate"): "10 Hz",
        },
    ),
}


def _nulls_have_reasons(node, where="") -> None:
    """Every null the conversion wrote for a non-finite number is explained: a mapping with
    null_reasons names only keys it holds."""
    if isinstance(node, dict):
        for key in node.get(NULL_REASONS, {}):
            assert key in node, f"{where}: a reason for the absent {key}"
        for key, value in node.items():
            _nulls_have_reasons(value, f"{where}.{key}")
    elif isinstance(node, list):
        for index, value in enumerate(node):
            _nulls_have_reasons(value, f"{where}[{index}]")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_writes_strict_json(kind, tmp_path):
    name, changes = KINDS[kind]
    scenario = load_scenario(_example(name, changes, tmp_path))
    assert scenario.kind == kind
    out = write_report(run_scenario(scenario), tmp_path / "report")
    written = [p for p in out.iterdir() if p.suffix == ".json"]
    assert {p.name for p in written} & {"metrics.json", "summary.json", "identification.json"}
    for path in written:
        _nulls_have_reasons(_strict(path.read_text()), path.name)
