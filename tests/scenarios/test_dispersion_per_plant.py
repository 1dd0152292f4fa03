"""Every dispersed case equals the same case run alone, for each plant type, in chunks of 1, 7
and all the cases (issue 22, acceptance).

For each plant type a small Monte Carlo of 8 cases varies one physically meaningful field of a
scenario document by its path (an inertia entry, a modulus, a tip mass, a frequency, a law gain
or weight, a gimbal skew angle) and runs in chunks of 1 (eight chunks), 7 (a chunk of 7 and one
of 1) and 8 (every case in one chunk; the acceptance's "1,000": a chunk holding the whole
batch, which is what 1,000 is for a batch of 8). Each plant's case takes 0.05–0.4 s, so 8 cases
run four times (three batches and each case alone) keep a plant to about 10 s; the simulated
durations are shortened from the examples' for the same reason (the guarantee is about the
batch, not the physics of the run).

Every case of a batch over a document is that document run by the one scenario runner
(:mod:`flexsat.scenarios.batch_cases`), so the comparison is bit for bit: the three stores are
identical, and case i's metrics equal those of the target document with the value and the
case's seed written in here by hand (not by the batch code), run alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from flexsat.design.batch_runner import open_results
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.scenarios.batch_cases import case_metrics, document_seeds, noise_seed_path
from flexsat.units import si_factor

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CASES = 8
CHUNKS = (1, 7, CASES)


@dataclass(frozen=True)
class Dispersion:
    """A plant type's Monte Carlo: the target document (an example with ``changes``), its run,
    the varied ``path`` with its distribution ``entry``, where the value sits in the document
    (``keys``, written by hand) and in which unit it is written (None: a plain number), and the
    kind's noise seed field (None: a deterministic kind)."""

    example: str
    run: str
    changes: dict[str, Any]
    path: str
    entry: dict[str, Any]
    keys: tuple[str | int, ...]
    unit: str | None
    seed_path: str | None

    def target(self) -> dict[str, Any]:
        data = yaml.safe_load((EXAMPLES / self.example).read_text())
        for where, value in self.changes.items():
            node = data
            *parents, last = where.split("/")
            for key in parents:
                node = node[int(key) if key.isdigit() else key]
            if value is None:
                del node[last]
            else:
                node[int(last) if last.isdigit() else last] = value
        return data


PLANTS = {
    # rigid three-axis: the EPS as a rigid body, its MRP PD attitude gain (noisy rate sensor)
    "rigid three-axis, EPS": Dispersion(
        "eps_rigid_gibbs_slew.yaml",
        "MRP PD",
        {"simulation": {"duration": "30 s", "control_rate": "10 Hz"}},
        "runs['MRP PD'].gains.K",
        {"distribution": "normal", "mean": "3600 N*m", "sd": "200 N*m"},
        ("runs", 0, "gains", "K"),
        "N*m",
        "simulation.seed",
    ),
    # rigid three-axis from a user's FE model (rigid: true), a principal moment of the hub
    "rigid three-axis, own FE spacecraft": Dispersion(
        "own_spacecraft_slew.yaml",
        "MRP PD",
        {"plant": {"rigid": True}, "simulation": {"duration": "10 s", "control_rate": "20 Hz"}},
        "model.fe.masses[0].inertia[2]",
        {"distribution": "normal", "mean": "1.8 kg*m**2", "sd": "0.05 kg*m**2"},
        ("model", "fe", "masses", 0, "inertia", 2),
        "kg*m**2",
        "simulation.seed",
    ),
    # flexible three-axis, a user's FE model: the booms' modulus (the FE model re-solved per case)
    "flexible three-axis, own FE spacecraft": Dispersion(
        "own_spacecraft_slew.yaml",
        "MRP PD",
        {"simulation": {"duration": "10 s", "control_rate": "20 Hz"}},
        "model.fe.materials.aluminium.E",
        {"distribution": "normal", "mean": "70 GPa", "sd": "3 GPa"},
        ("model", "fe", "materials", "aluminium", "E"),
        "GPa",
        "simulation.seed",
    ),
    # flexible three-axis, the EPS with 10 modes: the attitude gain
    "flexible three-axis, EPS": Dispersion(
        "eps_flexible_slew.yaml",
        "MRP PD",
        {"simulation": {"duration": "10 s", "control_rate": "20 Hz"}},
        "runs['MRP PD'].gains.K",
        {"distribution": "normal", "mean": "7200 N*m", "sd": "300 N*m"},
        ("runs", 0, "gains", "K"),
        "N*m",
        "simulation.seed",
    ),
    # structural: the Agrawal-Bang L structure, the LQR's control weight
    "structural, Agrawal-Bang": Dispersion(
        "agrawal_bang_lqr.yaml",
        "LQR",
        {"simulation": {"duration": "2 s", "control_rate": "200 Hz"}},
        "runs.LQR.gains.input_weights",
        {"distribution": "lognormal", "median": 1.0, "gsd": 1.5},
        ("runs", 0, "gains", "input_weights"),
        None,
        "simulation.seed",
    ),
    # structural, a user's clamped FE model: the tip mass of a cantilevered tube
    "structural, own clamped FE tube": Dispersion(
        "own_spacecraft_slew.yaml",
        "LQR",
        {
            "model": {
                "fe": {
                    "nodes": [{"id": k, "xyz": [f"{0.2 * k} m", 0, 0]} for k in range(6)],
                    "materials": {"al": {"E": "70 GPa", "nu": 0.33, "density": "2700 kg/m**3"}},
                    "sections": {
                        "tube": {"shape": "tube", "outer_diameter": "30 mm", "thickness": "1 mm"}
                    },
                    "elements": [
                        {"nodes": [k, k + 1], "material": "al", "section": "tube"} for k in range(5)
                    ],
                    "masses": [{"node": 5, "mass": "500 g"}],
                    "clamps": [{"node": 0}],
                    "n_modes": 4,
                    "damping": 0.01,
                }
            },
            "plant": {
                "actuators": [{"name": "force", "node": 5, "axis": "z"}],
                "sensors": [{"name": "tip", "node": 5, "axis": "z"}],
            },
            "initial": {"state": [1e-3, 0, 0, 0, 0, 0, 0, 0]},
            "actuators": {"force": {"saturation": "5 N"}},
            "simulation": {"duration": "1 s", "control_rate": "200 Hz"},
            "runs": [{"label": "LQR", "law": "lqr", "gains": {"state_weights": 1}}],
        },
        "model.fe.masses[0].mass",
        {"distribution": "normal", "mean": "500 g", "sd": "50 g"},
        ("model", "fe", "masses", 0, "mass"),
        "g",
        "simulation.seed",
    ),
    # hybrid hub + appendage: the NPS PD slew's bandwidth (gyro noise: seeded cases)
    "hybrid, NPS": Dispersion(
        "nps_pd_slews.yaml",
        "PD step",
        {},
        "runs['PD step'].poles.natural_frequency",
        {"distribution": "normal", "mean": "0.06 Hz", "sd": "0.003 Hz"},
        ("runs", 0, "poles", "natural_frequency"),
        "Hz",
        "simulation.seed",
    ),
    # hybrid hub + appendage: the TAMU hub inertia (a random torque: seeded cases)
    "hybrid, TAMU": Dispersion(
        "tamu_40deg.yaml",
        "Law I",
        {"simulation/duration": "5 s"},
        "case_overrides.hub_inertia",
        {"distribution": "normal", "mean": "50 ozf*in*s**2", "sd": "2 ozf*in*s**2"},
        ("case_overrides", "hub_inertia"),
        "ozf*in*s**2",
        "simulation.seed",
    ),
    # beam in orbit: Bainum's LQR control weight
    "beam in orbit, Bainum": Dispersion(
        "bainum_orbit_lqr.yaml",
        "LQR",
        {"simulation": {"duration": "300 s", "control_rate": "2 Hz"}},
        "runs.LQR.gains.input_weights",
        {"distribution": "uniform", "low": 0.5, "high": 2.0},
        ("runs", 0, "gains", "input_weights"),
        None,
        "simulation.seed",
    ),
    # CMG spacecraft: the pyramid's skew angle under the preferred gimbal set
    "CMG cluster": Dispersion(
        "cmg_preferred_angles.yaml",
        "x, preferred set (V4)",
        {"runs/1/duration": "1 s"},
        "cluster.skew",
        {"distribution": "normal", "mean": "54.74 deg", "sd": "2 deg"},
        ("cluster", "skew"),
        "deg",
        None,
    ),
    # tether: Vadali & Kim's coupled controller, its out-of-plane gain K4 (one orbit)
    "tether": Dispersion(
        "tether_retrieval.yaml",
        "controller 2, K4 = 2 (Figs. 4-5)",
        {"simulation/orbits": 1},
        "runs['controller 2, K4 = 2 (Figs. 4-5)'].gains.K4",
        {"distribution": "normal", "mean": 2.0, "sd": 0.2},
        ("runs", 0, "gains", "K4"),
        None,
        None,
    ),
}


def _monte_carlo(plant: Dispersion, chunk_size: int) -> str:
    return yaml.safe_dump(
        {
            "kind": "montecarlo",
            "name": f"dispersed {plant.path}",
            "scenario": "target.yaml",
            "run": plant.run,
            "parameters": {plant.path: plant.entry},
            "cases": CASES,
            "seed": 3,
            "execution": {"chunk_size": chunk_size},
            "store": "mc.zarr",
        },
        sort_keys=False,
    )


def _store(folder: Path) -> dict[str, np.ndarray]:
    ds = open_results(folder / "mc.zarr")
    return {str(name): ds[name].values for name in ds.variables}


def _alone(plant: Dispersion, si_value: float, seed: int) -> dict[str, float]:
    """The metrics of the target's run with the value and the seed written in by hand."""
    data = plant.target()
    data["runs"] = [r for r in data["runs"] if r["label"] == plant.run]
    node: Any = data
    for key in plant.keys[:-1]:
        node = node[key]
    node[plant.keys[-1]] = (
        float(si_value)
        if plant.unit is None
        else f"{float(si_value) / si_factor(plant.unit)!r} {plant.unit}"
    )
    if plant.seed_path is not None:
        data["simulation"]["seed"] = seed
    return case_metrics(run_scenario(load_scenario(yaml.safe_dump(data, sort_keys=False))))


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PLANTS))
def test_every_dispersed_case_equals_the_case_run_alone(name, tmp_path):
    plant = PLANTS[name]
    target = yaml.safe_dump(plant.target(), sort_keys=False)
    assert noise_seed_path(type(load_scenario(target))) == plant.seed_path
    stores = []
    for size in CHUNKS:
        folder = tmp_path / f"chunks_{size}"
        folder.mkdir()
        (folder / "target.yaml").write_text(target)
        (folder / "mc.yaml").write_text(_monte_carlo(plant, size))
        result = run_scenario(load_scenario(folder / "mc.yaml"))
        assert result.chunks_run == -(-CASES // size)
        stores.append(_store(folder))
    first = stores[0]
    assert first["done"].all()
    for other, size in zip(stores[1:], CHUNKS[1:]):
        assert sorted(other) == sorted(first)
        for key in first:  # bit for bit, NaN where NaN
            assert np.array_equal(other[key], first[key], equal_nan=first[key].dtype.kind == "f"), (
                size,
                key,
            )
    values = first[f"param_{plant.path}"]
    assert len(set(values.tolist())) == CASES  # every case has its own value
    seeds = document_seeds(3, np.arange(CASES))
    assert np.array_equal(first["seed"], seeds)
    metrics = {k[len("metric_") :]: v for k, v in first.items() if k.startswith("metric_")}
    assert metrics
    # the value reaches the results: some metric differs between the cases
    assert any(len(set(v[np.isfinite(v)].tolist())) > 1 for v in metrics.values())
    for i in range(CASES):
        alone = _alone(plant, values[i], int(seeds[i]))
        assert sorted(alone) == sorted(metrics), i
        for metric, value in alone.items():
            assert np.array_equal(metrics[metric][i], value, equal_nan=True), (i, metric)
