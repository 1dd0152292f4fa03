"""The in-process modal model cache of ``model:`` sections (flexsat.scenarios.modal_cache): a
batch that varies no structural field solves the structure once, one that varies the structure
solves each distinct structure once, a changed file is a new model, the cache is bounded and
stays in its process; and an unphysical structure in a distribution is refused by name before
any case runs."""

from __future__ import annotations

import pickle
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.batch_runner import open_results
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.modal_cache import MODAL_MODELS, ModalModelCache, section_key
from flexsat.structures.fem import Assembly

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _own_spacecraft(folder: Path) -> None:
    """examples/own_spacecraft_slew.yaml, its slew cut to 5 s (the cache, not the slew, is
    tested), as target.yaml in ``folder``."""
    data = yaml.safe_load((EXAMPLES / "own_spacecraft_slew.yaml").read_text())
    data["simulation"]["duration"] = "5 s"
    (folder / "target.yaml").write_text(yaml.safe_dump(data, sort_keys=False))


def _sweep(folder: Path, path: str, values: list, chunk_size: int = 1) -> dict:
    _own_spacecraft(folder)
    study = {
        "kind": "sweep",
        "name": f"sweep of {path}",
        "scenario": "target.yaml",
        "parameters": {path: {"values": values}},
        "execution": {"chunk_size": chunk_size},
        "store": "sweep.zarr",
    }
    (folder / "sweep.yaml").write_text(yaml.safe_dump(study, sort_keys=False))
    run_scenario(load_scenario(folder / "sweep.yaml"))
    ds = open_results(folder / "sweep.zarr")
    return {str(k): ds[k].values for k in ds.data_vars if str(k).startswith("metric_")}


@pytest.fixture
def solves(monkeypatch):
    """Count the finite-element modal solves (Assembly.modes calls), from an empty cache."""
    calls = []
    solve = Assembly.modes

    def counted(self, *args, **kwargs):
        calls.append(args)
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(Assembly, "modes", counted)
    MODAL_MODELS.clear()
    yield calls
    MODAL_MODELS.clear()


def test_a_law_gain_sweep_solves_the_structure_once(tmp_path, solves):
    """Four attitude gains, a chunk each: the extreme draws' plans and the four cases all build
    the plant from one model: one modal solve, every other build a hit."""
    metrics = _sweep(tmp_path, "runs['MRP PD'].gains.K", ["10 N*m", "15 N*m", "20 N*m", "25 N*m"])
    assert len(solves) == 1
    info = MODAL_MODELS.info()
    assert info.misses == 1 and info.hits >= 4 and info.size == 1
    peak = metrics["metric_peak_rate"]
    assert len(set(peak.tolist())) == 4  # the gain reaches every case


def test_a_modulus_sweep_solves_each_structure_once(tmp_path, solves):
    """Two moduli: two structures, two solves (the extreme draws are the two cases: their plans
    solve, their runs hit); the stiffer boom has the higher first frequency."""
    _sweep(tmp_path, "model.fe.materials.aluminium.E", ["70 GPa", "140 GPa", "70 GPa"])
    assert len(solves) == 2
    assert MODAL_MODELS.info().size == 2


def test_a_cached_model_gives_the_solved_model_s_results(tmp_path, solves):
    """The same sweep with the cache in use (one solve) and with the cache emptied before every
    build (a solve each time) stores the same numbers, bit for bit."""
    path, values = "runs['MRP PD'].gains.K", ["10 N*m", "20 N*m"]
    (tmp_path / "warm").mkdir()
    (tmp_path / "cold").mkdir()
    warm = _sweep(tmp_path / "warm", path, values)
    assert len(solves) == 1
    get = MODAL_MODELS.get

    def uncached(key, build):
        MODAL_MODELS.clear()
        return get(key, build)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(MODAL_MODELS, "get", uncached)
        cold = _sweep(tmp_path / "cold", path, values)
    assert len(solves) >= 1 + 4  # two plans and two cases, each solved again
    assert sorted(warm) == sorted(cold)
    for name in warm:
        assert np.array_equal(warm[name], cold[name], equal_nan=True), name


def test_a_changed_file_is_a_new_model(tmp_path, solves):
    """A netCDF model file rewritten with other content under the same name: another key, the
    new model read; the same content again: a hit."""
    text = yaml.safe_load((EXAMPLES / "own_spacecraft_slew.yaml").read_text())
    first = load_scenario(yaml.safe_dump(text)).model.modal_model(tmp_path)
    first.save(tmp_path / "model.nc")
    section = load_scenario(yaml.safe_dump({**text, "model": {"file": "model.nc"}})).model
    a = section.modal_model(tmp_path)
    assert section.modal_model(tmp_path) is a
    text["model"]["fe"]["materials"]["aluminium"]["E"] = "80 GPa"
    load_scenario(yaml.safe_dump(text)).model.modal_model(tmp_path).save(tmp_path / "model.nc")
    b = section.modal_model(tmp_path)
    assert b is not a and b.frequencies[6] > a.frequencies[6]  # the stiffer file's model
    np.testing.assert_array_equal(a.frequencies, first.frequencies)


def test_the_key_is_the_content():
    """Key order does not matter, a value and a file's bytes do."""
    assert section_key({"a": 1.0, "b": [1, 2]}) == section_key({"b": [1, 2], "a": 1.0})
    assert section_key({"a": 1.0}) != section_key({"a": 1.0000000000000002})


def test_the_cache_is_bounded_and_keeps_the_most_recent(tmp_path):
    cache = ModalModelCache(max_entries=2)
    built = []

    def build(name):
        def make():
            built.append(name)
            return name

        return make

    for key in ("a", "b", "a", "c", "a", "b"):  # c evicts b (a was used since); b is rebuilt
        cache.get(key, build(key))
    assert built == ["a", "b", "c", "b"]
    assert cache.info().size == 2 and cache.info().hits == 2


def test_a_failed_build_is_not_stored():
    cache = ModalModelCache()

    def fail():
        raise ValueError("no model")

    with pytest.raises(ValueError, match="no model"):
        cache.get("k", fail)
    assert cache.info().size == 0 and cache.info().misses == 0


def test_the_cache_is_never_pickled():
    with pytest.raises(TypeError, match="never pickled"):
        pickle.dumps(MODAL_MODELS)


# -- unphysical structures refused before any case runs ------------------------------------------
def _monte_carlo(folder: Path, path: str, entry: dict, cases: int, seed: int) -> Path:
    _own_spacecraft(folder)
    study = {
        "kind": "montecarlo",
        "name": f"dispersed {path}",
        "scenario": "target.yaml",
        "parameters": {path: entry},
        "cases": cases,
        "seed": seed,
        "store": "mc.zarr",
    }
    (folder / "mc.yaml").write_text(yaml.safe_dump(study, sort_keys=False))
    return folder / "mc.yaml"


def _draws(path: str, entry: dict, unit: str, cases: int, seed: int) -> np.ndarray:
    from flexsat.design.parameter_space import space_from_spec

    return space_from_spec({path: entry}, {path: unit}).sample(cases, seed).values[path]


def test_a_hub_inertia_violating_the_triangle_inequality_is_refused_by_name(tmp_path):
    """The hub's first principal moment normal about 2.0 kg m² (sd 0.8) with the others 1.6 and
    1.8: a draw above 3.4 or below 0.2 is an inertia no body has. The first such case is named
    with the parameter and the rule before any case runs (no store is made)."""
    path = "model.fe.masses[0].inertia[0]"
    entry = {"distribution": "normal", "mean": "2.0 kg*m**2", "sd": "0.8 kg*m**2"}
    draws = _draws(path, entry, "kg*m**2", 40, 2)
    bad = np.flatnonzero((draws > 3.4) | (draws < 0.2))
    assert bad.size and draws[bad[0]] > 0  # a positive moment: the triangle is the rule broken
    with pytest.raises(
        ScenarioError,
        match=rf"parameters\.{re.escape(path)}: case {bad[0]} \({re.escape(path)} = "
        r"[\d.]+ kg\*m\*\*2\): model\.fe\.masses\[0\]\.inertia: principal moments .* violate the "
        r"triangle inequality I1 \+ I2 >= I3",
    ):
        run_scenario(load_scenario(_monte_carlo(tmp_path, path, entry, 40, 2)))
    assert not (tmp_path / "mc.zarr").exists()


def test_a_negative_modulus_in_a_distribution_s_tail_is_refused_by_name(tmp_path):
    """The booms' modulus normal about 70 GPa with a 60 GPa sd: the first negative draw is
    named with the parameter and the material's rule before any case runs."""
    path = "model.fe.materials.aluminium.E"
    entry = {"distribution": "normal", "mean": "70 GPa", "sd": "60 GPa"}
    draws = _draws(path, entry, "kg/m/s**2", 40, 0)
    first = int(np.flatnonzero(draws <= 0)[0])
    with pytest.raises(
        ScenarioError,
        match=rf"parameters\.{re.escape(path)}: case {first} \({re.escape(path)} = "
        r"-[\d.]+ GPa\): model\.fe\.materials\.aluminium\.E: must be > 0",
    ):
        run_scenario(load_scenario(_monte_carlo(tmp_path, path, entry, 40, 0)))
    assert not (tmp_path / "mc.zarr").exists()
