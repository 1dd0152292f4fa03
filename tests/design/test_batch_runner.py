"""The execution layer of sweeps and Monte Carlo (issue 13, "Execution"): every case of a chunked
run equals the case run alone, the store does not depend on the chunking or the worker count,
an interrupted run resumes to the same store, and bad input is refused by name.

The runs are the TAMU Law II slew of seed 000 Att. 3 §V (3 modes, 2 s at 75 Hz, friction,
encoder quantisation and random torque on: every case draws its own noise), small so the file
stays within seconds per run.
"""

from __future__ import annotations

import os
import socket
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from flexsat.cases import tamu
from flexsat.design.batch_runner import (
    BatchInterrupted,
    HubManeuverBuilder,
    case_seeds,
    maneuver_metrics,
    open_results,
    run_batch,
)
from flexsat.sim import simulate
from flexsat.sim.disturbances import RandomTorque
from flexsat.units import to_si

G1, G2 = to_si("3000 ozf*in/rad", "N*m/rad"), to_si("800 ozf*in*s/rad", "N*m*s/rad")
ALPHA = np.array([0.0, 0.125, 0.25])
U_MAX = np.array([to_si(f"{v} ozf*in", "N*m") for v in (200, 300, 400)])
#: the 3 × 3 sweep over (α, u_max), α the slow index
SWEEP = {"alpha": np.repeat(ALPHA, 3), "u_max": np.tile(U_MAX, 3)}
BASE_SEED = 2026
HISTORIES = ("theta", "torque")


@pytest.fixture(scope="module")
def case():
    return tamu(n_modes=3)


@pytest.fixture(scope="module")
def builder(case):
    return HubManeuverBuilder(
        case.params,
        3,
        case.sim_config(duration=2.0),
        case.angle,
        case.reference_inertia,
        u_max=case.max_torque,
        g1=G1,
        g2=G2,
    )


def _values(store) -> dict[str, np.ndarray]:
    ds = open_results(store)
    return {name: ds[name].values for name in ds.variables}


def _same(a: dict, b: dict) -> None:
    """Bit-identical stores: the same variables with the same bytes (NaN where NaN)."""
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert np.array_equal(a[name], b[name], equal_nan=a[name].dtype.kind == "f"), name


@pytest.fixture(scope="module")
def reference_store(builder, tmp_path_factory):
    """The sweep in one chunk, in-process: the store every other run is compared with."""
    path = tmp_path_factory.mktemp("batch") / "reference.zarr"
    run_batch(builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=1000, histories=HISTORIES)
    return _values(path)


def test_every_case_of_the_sweep_equals_the_case_run_alone(case, reference_store):
    """Case i of the chunked sweep is the TAMU Law II run built directly from the case
    (``TamuCase.law_ii``), alone, with seed s_i: on the batch-independent path (the plant's modal
    coordinates whatever the batch size) the batched core treats every case on its own
    (per-case noise streams, per-case products), so the difference is exactly zero; the lone
    run on the default path (dense: one case is below the modal threshold) agrees to the
    1e-10 the issue asks (the modal change of coordinates is exact to cond(T) · eps)."""
    seeds = case_seeds(BASE_SEED, np.arange(9))
    assert np.array_equal(reference_store["seed"], seeds)
    worst, worst_default = 0.0, 0.0
    for i in range(9):
        law = case.law_ii(G1, G2, alpha=SWEEP["alpha"][i], u_max=SWEEP["u_max"][i])
        run = dict(n_cases=1, seeds=seeds[i : i + 1])
        alone = simulate(
            case.model(), law, case.sim_config(duration=2.0), **run, batch_independent=True
        )
        default = simulate(case.model(), law, case.sim_config(duration=2.0), **run)
        assert default.dataset.attrs["propagation"] == "dense"
        for name, value in maneuver_metrics(alone).items():
            stored = reference_store["metric_" + name][i]
            assert np.array_equal(stored, value[0], equal_nan=True), name
            np.testing.assert_allclose(
                stored,
                maneuver_metrics(default)[name][0],
                rtol=1e-10,
                atol=0,
                equal_nan=True,
                err_msg=name,
            )
        for name in HISTORIES:
            stored = reference_store["history_" + name][i]
            worst = max(worst, float(np.abs(stored - alone.dataset[name].values[0]).max()))
            scale = np.abs(stored).max()
            worst_default = max(
                worst_default, float(np.abs(stored - default.dataset[name].values[0]).max() / scale)
            )
    assert worst == 0.0
    assert worst_default < 1e-10
    # the sweep is a sweep: the cases differ
    assert len(np.unique(reference_store["history_theta"], axis=0)) == 9


def test_histories_do_not_depend_on_the_chunk_size_across_the_modal_threshold(builder, tmp_path):
    """With histories recorded, 40 cases in one chunk (above the compiled loop's default modal
    threshold, cases × samples × substeps >= 20,000) and in chunks of one (below it) give the
    same store bit for bit: a sweep's chunks always take the batch-independent path."""
    n = 40
    table = {"alpha": np.linspace(0.0, 0.25, n), "u_max": np.full(n, U_MAX[1])}
    one = run_batch(
        builder,
        table,
        tmp_path / "one.zarr",
        base_seed=BASE_SEED,
        chunk_size=n,
        histories=HISTORIES,
    )
    assert one.chunks_run == 1
    run_batch(
        builder,
        table,
        tmp_path / "many.zarr",
        base_seed=BASE_SEED,
        chunk_size=1,
        histories=HISTORIES,
    )
    _same(_values(tmp_path / "one.zarr"), _values(tmp_path / "many.zarr"))


def test_plant_gain_and_maneuver_parameters_batch_in_one_call(case, builder, tmp_path):
    """Cases differing in hub inertia, stiffness, damping, tip mass, gains and maneuver time
    run as one dispersed batch and each equals its own one-case call (exactly) with the sweep's
    settings (``for_table``: the friction substeps of the whole table; ``batch_independent``:
    the propagation of any chunk size, each case in its own modal coordinates)."""
    n = 4
    table = {
        "hub_inertia": case.params.hub_inertia * np.array([0.8, 1.0, 1.2, 1.5]),
        "EI": case.params.EI * np.array([0.9, 1.0, 1.1, 1.2]),
        "damping": np.array([0.002, 0.005, 0.01, 0.02]),
        "tip_mass": case.params.tip_mass * np.array([0.5, 1.0, 1.5, 2.0]),
        "g1": G1 * np.array([0.5, 1.0, 1.5, 2.0]),
        "duration": np.array([3.0, 3.2, 3.4, 3.6]),
        "alpha": np.array([0.05, 0.1, 0.15, 0.2]),
    }
    run_batch(builder, table, tmp_path / "mixed.zarr", base_seed=7, chunk_size=n)
    stored = _values(tmp_path / "mixed.zarr")
    for i in range(n):
        plant, law, config, _ = builder.for_table(table)(
            {k: v[i : i + 1] for k, v in table.items()}, case_seeds(7, [i])
        )
        result = simulate(
            plant, law, config, n_cases=1, seeds=case_seeds(7, [i]), batch_independent=True
        )
        alone = maneuver_metrics(result)
        for name, value in alone.items():
            assert np.array_equal(stored["metric_" + name][i], value[0], equal_nan=True), name
    assert len(np.unique(stored["metric_peak_tip_deflection_m"])) == n


@pytest.mark.parametrize("chunk_size", [1, 7])
def test_store_does_not_depend_on_the_chunk_size(builder, reference_store, tmp_path, chunk_size):
    """Chunks of 1 and 7 cases (7 leaves a ragged last chunk of 2) give the one-chunk store."""
    run_batch(
        builder,
        SWEEP,
        tmp_path / "s.zarr",
        base_seed=BASE_SEED,
        chunk_size=chunk_size,
        histories=HISTORIES,
    )
    _same(_values(tmp_path / "s.zarr"), reference_store)


def test_store_does_not_depend_on_the_worker_count(builder, reference_store, tmp_path):
    """Two local worker processes (chunks finishing in any order) give the in-process store."""
    run_batch(
        builder,
        SWEEP,
        tmp_path / "w.zarr",
        base_seed=BASE_SEED,
        chunk_size=2,
        histories=HISTORIES,
        workers=2,
    )
    _same(_values(tmp_path / "w.zarr"), reference_store)


class _StopAfter:
    """A progress callback that interrupts the run (as Ctrl-C would) after ``k`` chunks."""

    def __init__(self, k: int):
        self.k, self.calls = k, []

    def __call__(self, p):
        self.calls.append(p)
        if p.chunks_done >= self.k and len(self.calls) > 1:
            raise KeyboardInterrupt


def test_an_interrupted_run_resumes_to_the_same_store(builder, reference_store, tmp_path):
    """Stopped after 2 of 5 chunks, the store holds exactly those chunks' cases as done; the
    same command again runs the 3 others only and the store equals the uninterrupted one: no
    case missing, none computed twice."""
    path = tmp_path / "r.zarr"
    with pytest.raises(KeyboardInterrupt):
        run_batch(
            builder,
            SWEEP,
            path,
            base_seed=BASE_SEED,
            chunk_size=2,
            histories=HISTORIES,
            progress=_StopAfter(2),
        )
    done = open_results(path)["done"].values
    assert done.sum() == 4 and all(
        done[s : s + 2].all() or not done[s : s + 2].any() for s in range(0, 9, 2)
    )
    progress = []
    summary = run_batch(
        builder,
        SWEEP,
        path,
        base_seed=BASE_SEED,
        chunk_size=2,
        histories=HISTORIES,
        progress=progress.append,
    )
    assert (summary.chunks_skipped, summary.chunks_run) == (2, 3)
    assert progress[0].cases_done == 4 and progress[-1].cases_done == 9
    assert progress[-1].cases_per_s > 0 and progress[-1].eta_s == 0
    _same(_values(path), reference_store)
    # a third run has nothing to do
    assert (
        run_batch(
            builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=2, histories=HISTORIES
        ).chunks_run
        == 0
    )


def test_a_run_resumes_with_another_chunk_size(builder, reference_store, tmp_path):
    """The mask is per case: a run stopped in chunks of 2 resumes in chunks of 4 (the chunks
    not all done are run whole) to the same store."""
    path = tmp_path / "c.zarr"
    with pytest.raises(KeyboardInterrupt):
        run_batch(
            builder,
            SWEEP,
            path,
            base_seed=BASE_SEED,
            chunk_size=2,
            histories=HISTORIES,
            progress=_StopAfter(1),
        )
    summary = run_batch(
        builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=4, histories=HISTORIES
    )
    assert (summary.chunks_skipped, summary.chunks_run) == (0, 3)
    _same(_values(path), reference_store)


class _DiesOnce:
    """The TAMU builder, except that the first chunk to reach it kills its worker process."""

    def __init__(self, builder, marker: Path):
        self.builder, self.marker = builder, marker
        self.parameter_names = builder.parameter_names

    def describe(self):
        return self.builder.describe()

    def __call__(self, parameters, seeds):
        if not self.marker.exists():
            self.marker.write_text("killed")
            os._exit(1)  # the worker dies mid-run, as on a lost node
        return self.builder(parameters, seeds)


def test_a_killed_worker_s_chunk_is_run_again(builder, reference_store, tmp_path):
    """A worker dying while running a chunk loses only that chunk's attempt: the chunk runs
    again on a live worker and the store equals the undisturbed one."""
    marker = tmp_path / "killed"
    path = tmp_path / "k.zarr"
    run_batch(
        _DiesOnce(builder, marker),
        SWEEP,
        path,
        base_seed=BASE_SEED,
        chunk_size=3,
        histories=HISTORIES,
        workers=2,
    )
    assert marker.exists()
    _same(_values(path), reference_store)


def test_unknown_parameter_names_the_name_and_the_known_ones(builder, tmp_path):
    with pytest.raises(ValueError, match=r"unknown parameter 'hub_inertai'.*hub_inertia"):
        run_batch(builder, {"hub_inertai": [1.0, 2.0]}, tmp_path / "x.zarr")
    assert not (tmp_path / "x.zarr").exists()


@pytest.mark.parametrize(
    "column, values, rule",
    [
        ("alpha", [0.1, 0.3], r"alpha: .*\[0, 1/4\]"),
        ("g3", [0.0, -5.0], r"g3: must be > -4"),
        ("hub_inertia", [0.3, -1.0], r"hub_inertia: must be > 0"),
        ("friction_coulomb", [0.1, -1.0], r"friction_coulomb.*must be >= 0"),
        ("saturation", [1.0, 0.0], r"saturation.*must be > 0"),
        ("encoder_resolution", [1e-4, -1e-4], r"encoder_resolution.*must be >= 0"),
        ("strain_noise", [0.0, -0.01], r"strain_noise.*must be >= 0"),
        ("random_torque", [-0.01, 0.0], r"random_torque.*must be >= 0"),
        # the TAMU rate is the encoder's least-squares derivative: a gyro noise would change nothing
        ("gyro_noise", [0.0, 0.01], r"gyro_noise.*'ls_filter', not 'gyro'"),
    ],
)
def test_a_bad_value_is_refused_before_anything_runs(builder, tmp_path, column, values, rule):
    """The builder's rules (Att. 3 Eq. 15's α range, Eq. 11's g3 > −n, a positive inertia, a
    friction coefficient >= 0, a torque limit > 0, a resolution and noise levels >= 0) apply to
    the whole table first: no store is made."""
    with pytest.raises(ValueError, match=rule):
        run_batch(builder, {column: np.array(values)}, tmp_path / "x.zarr")
    assert not (tmp_path / "x.zarr").exists()


def test_an_existing_scheduler_gives_the_same_store(builder, reference_store, tmp_path):
    """``scheduler=`` an already running cluster's address: the same store."""
    from distributed import LocalCluster

    with LocalCluster(
        processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        run_batch(
            builder,
            SWEEP,
            tmp_path / "e.zarr",
            base_seed=BASE_SEED,
            chunk_size=4,
            histories=HISTORIES,
            scheduler=cluster.scheduler_address,
        )
    _same(_values(tmp_path / "e.zarr"), reference_store)


def test_a_scheduler_that_does_not_answer_is_refused_within_10_s(builder, tmp_path):
    with socket.socket() as s:  # a free port: nothing listens there
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=f"scheduler: no dask scheduler answered at '{address}'"):
        run_batch(builder, SWEEP, tmp_path / "x.zarr", scheduler=address)
    assert time.perf_counter() - t0 < 10.0


@pytest.mark.parametrize(
    "change",
    [
        {"setup_text": "another scenario"},
        {"base_seed": 1},
        {"table": {"alpha": SWEEP["alpha"], "u_max": SWEEP["u_max"][::-1]}},
    ],
)
def test_a_store_of_another_setup_is_refused(builder, tmp_path, change):
    """A store is resumed only by its own setup: another scenario text, base seed or parameter
    table is refused before anything runs, and the store is left as it was."""
    path = tmp_path / "s.zarr"
    run_batch(builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=9, setup_text="tamu sweep")
    before = _values(path)
    kwargs = {"base_seed": BASE_SEED, "setup_text": "tamu sweep", "chunk_size": 9}
    table = change.pop("table", SWEEP)
    kwargs.update(change)
    with pytest.raises(ValueError, match="holds the results of a different setup"):
        run_batch(builder, table, path, **kwargs)
    _same(_values(path), before)


def test_an_unknown_history_names_the_recorded_ones(builder, tmp_path):
    with pytest.raises(ValueError, match=r"histories: 'thetaa' is not a recorded variable.*theta"):
        run_batch(builder, SWEEP, tmp_path / "h.zarr", histories=("thetaa",), retries=0)


def test_a_run_killed_while_laying_out_its_store_leaves_none_and_the_next_run_starts_afresh(
    builder, reference_store, tmp_path, monkeypatch
):
    """The store is laid out in ``.<name>.partial`` and renamed into place when complete. A
    failure between its two writes (as a kill would leave it) leaves no store, so the same command
    is not refused as "another setup"; a partial folder left by a killed run is replaced."""
    path = tmp_path / "s.zarr"
    writes = xr.Dataset.to_zarr

    def killed_at_the_second_write(self, store, *args, mode=None, **kwargs):
        if mode == "r+":
            raise KeyboardInterrupt
        return writes(self, store, *args, mode=mode, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(xr.Dataset, "to_zarr", killed_at_the_second_write)
        with pytest.raises(KeyboardInterrupt):
            run_batch(builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=3, histories=HISTORIES)
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    (tmp_path / ".s.zarr.partial").mkdir()  # what a SIGKILL at that moment leaves
    (tmp_path / ".s.zarr.partial" / "half-written").write_text("")
    run_batch(builder, SWEEP, path, base_seed=BASE_SEED, chunk_size=3, histories=HISTORIES)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]
    _same(_values(path), reference_store)


def test_ctrl_c_says_how_many_cases_the_store_keeps(builder, tmp_path):
    path = tmp_path / "i.zarr"
    with pytest.raises(BatchInterrupted) as info:
        run_batch(
            builder,
            SWEEP,
            path,
            base_seed=BASE_SEED,
            chunk_size=2,
            histories=HISTORIES,
            progress=_StopAfter(2),
        )
    assert (info.value.cases_done, info.value.n_cases) == (4, 9)
    assert str(info.value) == (
        f"interrupted: 4 of 9 cases are done and kept in the store "
        f"{str(path)!r}; run the same command again to resume"
    )


def test_friction_dispersed_per_case_does_not_depend_on_the_chunking(case, builder, tmp_path):
    """Bearing friction (Att. 3 Eq. 23) as a per-case parameter: the integrator substeps are
    fixed from the whole table's stiffest friction before the table is cut into chunks
    (``for_table``: ceil(Δt/1.5 · max (c1/ε + c2) / I_hub), the bound of the damping rate
    (c1/ε + c2)(M⁻¹)_θθ), so chunks of 1, 2 and 5 cases give the same store bit for bit; the
    bound is at least what the engine asks for the stiffest case on the model."""
    from flexsat.sim.config import stable_substeps

    nominal = builder.config.friction
    n = 5
    table = {
        "alpha": np.full(n, 0.1),
        "u_max": np.full(n, U_MAX[1]),
        "friction_coulomb": nominal.coulomb * np.array([0.0, 0.5, 1.0, 2.0, 4.0]),
        "friction_viscous": nominal.viscous * np.array([1.0, 3.0, 0.0, 1.0, 2.0]),
    }
    stores = []
    for chunk in (1, 2, n):
        run_batch(builder, table, tmp_path / f"f{chunk}.zarr", base_seed=3, chunk_size=chunk)
        stores.append(_values(tmp_path / f"f{chunk}.zarr"))
    for other in stores[1:]:
        _same(other, stores[0])
    substeps = builder.for_table(table).config.substeps
    slope = nominal.coulomb * 4.0 / nominal.smoothing + nominal.viscous * 2.0
    assert substeps == max(
        builder.config.substeps,
        int(np.ceil(builder.config.dt / 1.5 * slope / case.params.hub_inertia)),
    )
    stiffest = type(nominal)(nominal.coulomb * 4.0, nominal.viscous * 2.0, nominal.smoothing)
    engine = stable_substeps(case.model(), stiffest, builder.config.dt, builder.config.substeps)
    assert substeps >= engine > builder.config.substeps
    # the friction decides: the cases differ
    assert len(np.unique(stores[0]["metric_peak_rate_error_deg_s"])) == n


@pytest.mark.parametrize("base", [0, 1, 2026, 2**32, 2**63 - 1, 2**127 + 5])
def test_case_seeds_are_numpy_s_spawned_seed_sequences(base):
    """s_i = SeedSequence(b, spawn_key=(i,)).generate_state(1, uint64)[0] >> 1 (the module's
    definition), computed for all cases at once, equals numpy's per-case objects exactly,
    including the largest spawn word and a base of four 32-bit words."""
    idx = np.r_[0:300, 2**31, 2**32 - 1, 123_456_789]
    expected = [
        int(np.random.SeedSequence(base, spawn_key=(int(i),)).generate_state(1, np.uint64)[0]) >> 1
        for i in idx
    ]
    assert case_seeds(base, idx).tolist() == expected
    assert case_seeds(base, [2**32]).tolist() == [  # beyond one word: numpy's own objects
        int(np.random.SeedSequence(base, spawn_key=(2**32,)).generate_state(1, np.uint64)[0]) >> 1
    ]


def test_sensor_and_actuator_parameters_give_each_case_its_lone_run(case, builder, tmp_path):
    """The hardware of Att. 3 §V as sweep parameters: torque limit, encoder resolution, strain
    gauge noise and random torque. Case i equals, bit for bit, the TAMU Law II run alone with
    its own hardware in the SimConfig and seed s_i (the limit and the noise levels are per case
    in one batched call, the resolution splits the chunk into calls: every case is on its own
    either way). Chunks of 1 and 4 give the same store although the chunk of 4 is split into
    three calls, one of them over cases 0 and 2."""
    oz_in = to_si("1 ozf*in", "N*m")
    res = np.radians(0.01)
    table = {
        "saturation": oz_in * np.array([300.0, 350.0, 400.0, 500.0]),
        "encoder_resolution": np.array([res, 0.0, res, 2 * res]),
        "strain_noise": np.array([0.0, 0.01, 0.02, 0.0]),
        "random_torque": oz_in * np.array([0.0, 5.0, 10.0, 2.0]),
    }
    run_batch(
        builder,
        table,
        tmp_path / "four.zarr",
        base_seed=BASE_SEED,
        chunk_size=4,
        histories=HISTORIES,
    )
    run_batch(
        builder,
        table,
        tmp_path / "one.zarr",
        base_seed=BASE_SEED,
        chunk_size=1,
        histories=HISTORIES,
    )
    stored = _values(tmp_path / "four.zarr")
    _same(stored, _values(tmp_path / "one.zarr"))
    base = case.sim_config(duration=2.0)
    seeds = case_seeds(BASE_SEED, np.arange(4))
    for i in range(4):
        config = replace(
            base,
            actuator=replace(base.actuator, saturation=table["saturation"][i]),
            sensors=replace(
                base.sensors,
                encoder_resolution=table["encoder_resolution"][i],
                strain_noise=table["strain_noise"][i],
            ),
            random_torque=RandomTorque(table["random_torque"][i]),
        )
        alone = simulate(
            case.model(),
            case.law_ii(G1, G2),
            config,
            n_cases=1,
            seeds=seeds[i : i + 1],
            batch_independent=True,
        )
        for name, value in maneuver_metrics(alone).items():
            assert np.array_equal(stored["metric_" + name][i], value[0], equal_nan=True), name
        for name in HISTORIES:
            assert np.array_equal(stored["history_" + name][i], alone.dataset[name].values[0])
    # the hardware decides: the cases differ, and the 300 oz-in limit is reached
    assert len(np.unique(stored["history_theta"], axis=0)) == 4
    assert np.abs(stored["history_torque"][0]).max() == table["saturation"][0]
