"""Slew scenarios (kind: slew): seed 003's three-axis slews of the Earth Pointing Satellite,
the paper's claims on the examples, the report, and each mistake
reported as ``field.path: rule`` before anything runs."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from flexsat.report import write_report
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from report_browser import assert_renders

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: a cheap slew: 12 elastic modes in the plant, 4 in the controller, a 6 s maneuver
SMALL = """
kind: slew
name: small slew
case: eps
plant: {n_modes: 12}
maneuver:
  target: {euler123: ["0.5 rad", "0.5 rad", "0.5 rad"]}
  duration: "6 s"
  break_frequency: "5 rad/s"
controller: {modes: 4, linearization_points: 7}
simulation: {duration: "7.5 s", control_rate: "50 Hz"}
runs:
  - label: torquers
    weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50}
    break_frequency: "5 rad/s"
  - label: decoupled forces
    weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50, force: 1.0e-5}
    break_frequency: "5 rad/s"
    forces: [69X, 63X, 66Y, 66Z, 60Y, 60Z]
    decouple: true
    shaping_damping: 1
    feedforward: time-varying
"""


@pytest.fixture(scope="module")
def ten_seconds():
    return run_scenario(load_scenario(EXAMPLES / "eps_slew_10s.yaml"))


@pytest.fixture(scope="module")
def six_seconds():
    return run_scenario(load_scenario(EXAMPLES / "eps_slew_6s.yaml"))


def _rows(result) -> dict:
    return {r["run"]: r for r in result.metrics_records()}


def test_the_nominal_alone_reaches_the_target_on_the_flexible_plant(ten_seconds):
    # the rebuilt EPS has exact free-free modes: its rigid rotation does not feel the
    # vibration, so the nominal torque alone ends on (1, 1, 1) rad (to the hold's O(h²)
    # error, measured 2e-6 rad); the paper's DISCOS plant drifted (L833-L852)
    rows = _rows(ten_seconds)
    assert rows["open loop"]["angle_error_mrad"] < 0.01
    assert ten_seconds.nominal.boundary_error() < 1e-9


def test_case_a_meets_the_angle_goal_and_lowers_the_peak_deflection_during_the_slew(ten_seconds):
    # seed 003 case A (L873-L900): Euler errors within 30 mrad at 12.5 s, peak deformation
    # during the slew reduced against open loop (the paper: 1.5-2×; here 1.08×)
    a = _rows(ten_seconds)["A: torquers"]
    assert a["angle_goal_met"] and a["angle_error_mrad"] < 30.0
    assert a["deflection_ratio_slew"] > 1.0
    assert a["deflection_ratio_after"] > 1.0


def test_the_forces_of_case_b_cut_the_rim_deflections_tenfold(ten_seconds):
    # case B (L905-L937): the large antenna's rim response reduced 5× (paper) against open
    # loop; with the 7 point forces the deflection goal is met (here 176:1 from 12.5 s, 11:1
    # during the slew)
    b = _rows(ten_seconds)["B: torquers + forces"]
    assert b["angle_goal_met"]
    assert b["deflection_goal_met"] and b["deflection_ratio_after"] >= 10.0
    assert b["deflection_ratio_slew"] > 5.0


def test_the_10s_torquer_cases_miss_the_deflection_goal(ten_seconds):
    # the paper claims every 10 s case meets the 10:1 goal (L1013-L1019); with torquers at the
    # CG and the published weights this model does not: the vibration left at 12.5 s is
    # reduced 4-5.5×, not 10× (closing note of issue 11)
    rows = _rows(ten_seconds)
    for label in (
        "A: torquers",
        "C: no feedforward",
        "C: constant feedforward",
        "C: time-varying feedforward",
    ):
        assert rows[label]["angle_goal_met"], label
        assert not rows[label]["deflection_goal_met"], label
        assert 2.0 < rows[label]["deflection_ratio_after"] < 10.0, label


def test_case_d_misses_the_angle_goal_as_published(six_seconds):
    # case D (L974-L990): 6 s, torquers only, D = 1000: "Euler error 10-20 % at 7.5 s" (fails
    # the goal); here 9.6 % (96 mrad)
    d = _rows(six_seconds)["D: torquers"]
    assert not d["angle_goal_met"]
    assert 60.0 < d["angle_error_mrad"] < 200.0


def test_case_e_forces_do_better_than_case_d(six_seconds):
    # case E (L994-L1008): with forces, a smaller error than D and a large deflection
    # reduction (the paper: 7 % and 100:1; here both goals are met)
    rows = _rows(six_seconds)
    e, d = rows["E: torquers + forces"], rows["D: torquers"]
    assert e["angle_error_mrad"] < d["angle_error_mrad"]
    assert e["deflection_ratio_after"] > 10 * d["deflection_ratio_after"]


def test_a_small_slew_runs_and_writes_its_report(tmp_path, browser):
    result = run_scenario(load_scenario(SMALL))
    assert result.labels == ("open loop", "torquers", "decoupled forces")
    ds = result.dataset()
    for name in (
        "nominal_torque",
        "nominal_euler123",
        "euler123_error",
        "torque_perturbation",
        "rim_deflection_69",
        "angle_error_mrad",
        "deflection_ratio_after",
    ):
        assert name in ds, name
    assert ds["euler123_error"].dims == ("run", "time", "euler123_component")
    # the decoupled forces exert no net moment about the centre of mass: W F = 0 to round-off
    truth = load_scenario(SMALL)
    from flexsat.cases import eps

    plant = eps().plant(n_modes=12)
    names = [c.name for c in plant.inputs[1:]]
    F = np.stack([ds[n].sel(run="decoupled forces").values for n in names], -1)
    moment = F @ plant.force_moments.T
    assert np.abs(moment).max() <= 1e-12 * np.abs(F).max() * np.abs(plant.force_moments).max()
    assert np.abs(ds["force_88X"].sel(run="decoupled forces").values).max() == 0.0
    assert truth.runs[1].decouple
    out = write_report(result, tmp_path / "report")
    for name in ("index.html", "metrics.json", "results.nc"):
        assert (out / name).is_file(), name
    page = (out / "index.html").read_text()
    # the paper's figures, interactive, inside the page: a figure per panel
    titles = [p.title for p in result.plots(ds)]
    rims = [n for n in ds.data_vars if str(n).startswith("rim_deflection_")]
    assert len([t for t in titles if t.startswith("rim deflection")]) == len(rims)
    forces = [
        n
        for n in map(str, ds.data_vars)
        if n.startswith("force_") and not n.endswith("_command") and np.any(ds[n].values)
    ]
    assert 0 < len([t for t in titles if t.startswith("point force")]) == len(forces)
    for title in ("nominal maneuver: torque", "Euler-angle error: x", "rim deflection: node"):
        assert any(t.startswith(title) for t in titles), title
    assert all(f'"text":"{t}"' in page for t in titles)
    assert "PASS" in page or "FAIL" in page
    assert "rim" in assert_renders(browser, out / "index.html").lower()
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as saved:
        assert list(saved.run.values) == list(result.labels)


@pytest.mark.parametrize(
    "change, message",
    [
        (
            (
                "maneuver:\n  target: {euler123",
                "maneuver:\n  target: {attitude: [1, 1, 0, 0]}\n  dummy: {euler123",
            ),
            "maneuver.dummy",
        ),
        (
            (
                'target: {euler123: ["0.5 rad", "0.5 rad", "0.5 rad"]}',
                "target: {attitude: [1, 1, 0, 0]}",
            ),
            "target.attitude: must be a unit quaternion",
        ),
        (('duration: "6 s"', 'duration: "-6 s"'), "maneuver.duration"),
        (
            (
                '  break_frequency: "5 rad/s"\ncontroller',
                '  break_frequency: "0 rad/s"\ncontroller',
            ),
            "maneuver.break_frequency",
        ),
        (
            ('simulation: {duration: "7.5 s"', 'simulation: {duration: "7 s"'),
            r"simulation.duration: must reach 1.25 × the maneuver duration \(7.5 s\)",
        ),
        (("label: torquers", "label: open loop"), "label: 'open loop' names the nominal torque"),
        (("shaping_damping: 1", "shaping_damping: -1"), "shaping_damping"),
        (("force: 1.0e-5}", "}"), "weights.force: required when the run uses forces"),
        (("forces: [69X, 63X, 66Y, 66Z, 60Y, 60Z]", "forces: none"), "decouple: needs forces"),
    ],
)
def test_schema_mistakes_are_named(change, message):
    old, new = change
    assert old in SMALL
    with pytest.raises(ScenarioError, match=message):
        load_scenario(SMALL.replace(old, new))


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ("forces: [69X, 63X", "forces: [99X, 63X"),
            r"runs\['decoupled forces'\].*'99X' is not a force of the plant",
        ),
        (
            ("controller: {modes: 4", "controller: {modes: 13"),
            "controller.modes: at most the plant's 12 elastic modes",
        ),
        (
            ("plant: {n_modes: 12}", "plant: {n_modes: 12, colour: red}"),
            "plant.colour: not an option",
        ),
        (("plant: {n_modes: 12}", "plant: {model: rigid}"), "plant: .* a slew needs a flexible"),
        (
            ("modes: 1, torque: 50}\n    break", "modes: [1, 2], torque: 50}\n    break"),
            r"runs\['torquers'\].*weights.modes: one weight or 4 of them",
        ),
    ],
)
def test_mistakes_found_while_building_are_named_before_any_run(change, message):
    old, new = change
    assert old in SMALL
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(SMALL.replace(old, new)))


def test_the_searched_weights_meet_the_6s_goals_with_forces_only(six_seconds):
    # F18 (the paper's main recommendation): the weights found by
    # flexsat.design.slew_weights.tune_slew_weights meet both 6 s goals with the 7 forces, at
    # a smaller peak force than case E; with the torquers alone the best design found misses
    # both (the argument is in flexsat.design.slew_shaping)
    rows = _rows(six_seconds)
    forces, torquers = rows["tuned: torquers + forces"], rows["tuned: torquers"]
    assert forces["angle_goal_met"] and forces["deflection_goal_met"]
    assert forces["peak_force_N"] < rows["E: torquers + forces"]["peak_force_N"]
    assert not torquers["angle_goal_met"] and not torquers["deflection_goal_met"]
    assert torquers["angle_error_mrad"] < rows["D: torquers"]["angle_error_mrad"]
