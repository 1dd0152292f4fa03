"""Claims of a dispersed hub + appendage batch built as arrays
(flexsat.dynamics.dispersed_hub.DispersedHubAppendage, issue 22): each case equals the same
plant built and run alone (HubAppendage, the scalar frequency solver and Gauss rule) to 1e-12,
and has the same bits whether it runs in a chunk of 1, of 7 or in the whole batch, on the
metrics-only path of a sweep and with histories on the batch-independent path."""

from dataclasses import replace

import numpy as np
import pytest

from flexsat.control import PD
from flexsat.design.batch_runner import HubManeuverBuilder, maneuver_metrics, run_chunk
from flexsat.dynamics.dispersed_hub import DispersedHubAppendage
from flexsat.dynamics.dispersion import DispersedPlant, stack_plants
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.input_checks import FieldError
from flexsat.sim import SimConfig, simulate
from flexsat.units import to_si

N_MODES = 4
N_CASES = 15
HISTORIES = ("theta", "theta_dot", "torque", "root_torque", "tip_deflection", "energy")


def _table(params, n=N_CASES, seed=0):
    rng = np.random.default_rng(seed)
    return {
        "hub_inertia": params.hub_inertia * rng.uniform(0.8, 1.2, n),
        "EI": params.EI * rng.uniform(0.8, 1.2, n),
        "tip_mass": params.tip_mass * rng.uniform(0.5, 1.5, n),
    }


def _builder(tamu_case, **config):
    return HubManeuverBuilder(
        tamu_case.params,
        N_MODES,
        tamu_case.sim_config(duration=3.0, friction=False, noise=False, **config),
        tamu_case.angle,
        tamu_case.reference_inertia,
        u_max=tamu_case.max_torque,
        g1=to_si("3000 ozf*in/rad", "N*m/rad"),
        g2=to_si("800 ozf*in*s/rad", "N*m*s/rad"),
    )


def _chunk(table, lo, hi):
    return {k: v[lo:hi] for k, v in table.items()}


def test_the_batch_is_the_plants_built_alone(tamu_case):
    """The first-order form of every case equals that of ``HubAppendage(params_c)`` to 1e-12 of
    its largest entry: the roots agree to ulps, the closed-form couplings with the scalar Gauss
    rule to ~1e-15, and M⁻¹ (cond ~1e2) carries them into A (measured: 1e-13)."""
    p = tamu_case.params
    table = _table(p)
    batch = DispersedHubAppendage.from_parameters(replace(p, **table), N_MODES, damping=0.01)
    A, B = batch.linear_part()
    assert batch.n_cases == N_CASES and A.shape == (N_CASES, 2 * N_MODES + 2, 2 * N_MODES + 2)
    for c in range(N_CASES):
        alone = HubAppendage(
            replace(p, damping=0.01, **{k: float(v[c]) for k, v in table.items()}), N_MODES
        )
        a, b = alone.linear_part()
        assert np.abs(A[c] - a).max() <= 1e-12 * np.abs(a).max()
        assert np.abs(B[c] - b).max() <= 1e-12 * np.abs(b).max()
        np.testing.assert_allclose(batch.total_inertia[c], alone.total_inertia, rtol=1e-15)
        Q, q = batch.energy_matrix[c], alone.energy_matrix
        assert np.abs(Q - q).max() <= 1e-12 * np.abs(q).max()
        # the case's own plant is a HubAppendage with the batch's integrals
        own = batch.plants[c]
        assert isinstance(own, HubAppendage) and np.array_equal(own.linear_part()[0], A[c])
        np.testing.assert_allclose(
            own.modal_integrals["G"],
            alone.modal_integrals["G"],
            atol=1e-12 * np.abs(alone.modal_integrals["G"]).max(),
        )


def test_each_case_equals_the_plant_run_alone(tamu_case):
    """The histories of every case (PD slew, gyro and strain-gauge noise with the case's seed)
    equal the run of ``HubAppendage(params_c)`` alone to 1e-12 of their largest value: both run
    the dense compiled loop (a short run), the models differ by ~1e-13 (above), and the closed
    loop is stable, so the difference stays at that level."""
    p = tamu_case.params
    table = _table(p, n=6, seed=1)
    batch = DispersedHubAppendage.from_parameters(replace(p, **table), N_MODES, damping=0.01)
    cfg = SimConfig(duration=2.0, substeps=2)
    target = np.linspace(0.2, 0.7, 6)
    seeds = np.arange(6) + 40
    out = simulate(batch, PD(5.0, 20.0, target=target), cfg, seeds=seeds).dataset
    for c in range(6):
        alone = HubAppendage(
            replace(p, damping=0.01, **{k: float(v[c]) for k, v in table.items()}), N_MODES
        )
        one = simulate(alone, PD(5.0, 20.0, target=target[c]), cfg, seeds=seeds[c : c + 1])
        assert one.dataset.attrs["propagation"] == out.attrs["propagation"] == "dense"
        for var in HISTORIES + ("vibration_energy",):
            a, b = out[var].values[c], one.dataset[var].values[0]
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), (c, var)


@pytest.mark.parametrize("chunks", [(1,), (7,), (N_CASES,)])
def test_a_sweep_case_has_the_same_bits_in_any_chunk(tamu_case, chunks):
    """The sweep's route (``HubManeuverBuilder`` chunks through ``run_chunk``, the metrics-only
    path): hub inertia, EI and tip mass per case, metrics bit for bit those of the whole
    batch in chunks of 1, 7 and 15; and the batch equals each plant run alone to 1e-12."""
    b = _builder(tamu_case)
    table = _table(tamu_case.params)
    whole = run_chunk(b, maneuver_metrics, table, 0, 0)
    size = chunks[0]
    parts = [
        run_chunk(b, maneuver_metrics, _chunk(table, lo, lo + size), lo, 0)
        for lo in range(0, N_CASES, size)
    ]
    metrics = [k for k in whole if k.startswith("metric_")]
    assert len(metrics) == 7
    for name in metrics + ["seed"]:
        values = whole[name]
        joined = np.concatenate([part[name] for part in parts])
        assert np.array_equal(joined, values, equal_nan=True), name
    if size == N_CASES:  # against each case built and run alone (the scalar model)
        p = tamu_case.params
        for c in (0, 6, 14):
            alone = HubAppendage(replace(p, **{k: float(v[c]) for k, v in table.items()}), N_MODES)
            plant, law, cfg, _ = b(_chunk(table, c, c + 1), np.array([c]))
            one = simulate(alone, law, cfg, n_cases=1, metrics_only=True).metrics
            for name, value in one.items():
                np.testing.assert_allclose(
                    whole[f"metric_{name}"][c], value[0], rtol=1e-12, atol=1e-15
                )


def test_histories_have_the_same_bits_in_any_chunk(tamu_case):
    """With histories (``batch_independent=True``, the batch-independent path: each case in
    its own modal coordinates) and strain-gauge noise on, every history of a case in chunks of
    1 and 7 equals the whole batch's bit for bit."""
    b = _builder(tamu_case)
    table = _table(tamu_case.params, n=9, seed=2)
    table["strain_noise"] = np.full(9, 1e-3)
    seeds = np.arange(9) * 7 + 3

    def run(lo, hi):
        plant, law, cfg, x0 = b(_chunk(table, lo, hi), seeds[lo:hi])
        return simulate(
            plant, law, cfg, n_cases=hi - lo, seeds=seeds[lo:hi], batch_independent=True
        ).dataset

    whole = run(0, 9)
    for size in (1, 7):
        for lo in range(0, 9, size):
            part = run(lo, min(9, lo + size))
            for var in HISTORIES:
                assert np.array_equal(part[var].values, whole[var].values[lo : lo + size]), var


def test_the_sweep_takes_the_metrics_only_loop(tamu_case):
    """A dispersed chunk runs the compiled metrics-only loop (no history), each case in its
    own modal coordinates."""
    b = _builder(tamu_case)
    table = _table(tamu_case.params, n=3)
    plant, law, cfg, _ = b(table, np.arange(3))
    assert isinstance(plant, DispersedHubAppendage)
    out = simulate(plant, law, cfg, n_cases=3, metrics_only=True).dataset
    assert out.attrs["engine"] == "compiled" and out.attrs["histories"] == "none"
    assert out.attrs["propagation"] == "modal"


def test_stacked_hub_plants_become_one_array_batch(tamu_case):
    """``stack_plants`` of hub + appendage plants stacks their integrals (no modes solved
    again): the same plants as cases, the same first-order form bit for bit."""
    p = tamu_case.params
    plants = [HubAppendage(replace(p, hub_inertia=h * p.hub_inertia), N_MODES) for h in (1, 1.2)]
    batch = stack_plants(plants)
    assert isinstance(batch, DispersedHubAppendage)
    assert batch.plants[1] is plants[1]
    for c, plant in enumerate(plants):
        assert np.array_equal(batch.linear_part()[0][c], plant.linear_part()[0])
        assert np.array_equal(batch.linear_part()[1][c], plant.linear_part()[1])
    with pytest.raises(FieldError, match="nx"):  # refused as before, by the general batch
        stack_plants([plants[0], HubAppendage(p, N_MODES + 1)])
    assert type(stack_plants([plants[0], plants[0].__class__(p, N_MODES)])) is not DispersedPlant


@pytest.mark.parametrize(
    ("changes", "damping", "field"),
    [
        ({"EI": np.array([1.0, 2.0]), "tip_mass": np.array([0.1, 0.2, 0.3])}, None, "EI"),
        ({"EI": np.array([[1.0, 2.0]])}, None, "EI"),
        ({"EI": np.array([1.0, 2.0])}, np.ones((2, 3)), "damping"),
        ({"EI": np.array([1.0, 2.0])}, np.array([0.01, -0.01]), "damping"),
    ],
)
def test_bad_cases_are_refused_by_name(tamu_case, changes, damping, field):
    p = tamu_case.params
    params = replace(p, **{k: v * getattr(p, k) for k, v in changes.items()})
    with pytest.raises(FieldError, match=field) as err:
        DispersedHubAppendage.from_parameters(params, N_MODES, damping=damping)
    assert err.value.field == field


def test_an_unphysical_case_is_refused_naming_the_field(tamu_case):
    p = tamu_case.params
    with pytest.raises(ValueError, match="EI"):
        replace(p, EI=np.array([1.0, -1.0]) * p.EI)


def test_the_python_loop_and_the_stiffening_batch(tamu_case):
    """The Python loop runs the batch too (its energies and outputs per case from the batch's
    arrays): it equals the compiled loop to 1e-12 (the two loops' products round differently,
    round-off carried by a stable loop). With the rotational stiffening (nonlinear, the Python
    loop; G by the Gauss rule) each case equals the stiffening plant run alone to 1e-12."""
    p = tamu_case.params
    table = _table(p, n=3, seed=3)
    cfg = SimConfig(duration=1.0)
    law = PD(5.0, 20.0, target=[0.3, 0.5, 0.7])
    batch = DispersedHubAppendage.from_parameters(replace(p, **table), N_MODES, damping=0.01)
    fast = simulate(batch, law, cfg).dataset
    slow = simulate(batch, law, cfg, compiled=False).dataset
    assert slow.attrs["engine"] != fast.attrs["engine"]
    for var in HISTORIES + ("vibration_energy", "root_moment"):
        if var in fast:
            a, b = fast[var].values, slow[var].values
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), var
    stiff = DispersedHubAppendage.from_parameters(
        replace(p, **table), N_MODES, stiffening=True, damping=0.01
    )
    out = simulate(stiff, law, cfg).dataset
    for c in range(3):
        alone = HubAppendage(
            replace(p, damping=0.01, **{k: float(v[c]) for k, v in table.items()}),
            N_MODES,
            stiffening=True,
        )
        one = simulate(alone, PD(5.0, 20.0, target=law.target[c]), cfg).dataset
        for var in HISTORIES:
            a, b = out[var].values[c], one[var].values[0]
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), (c, var)


@pytest.mark.parametrize("friction", [False, True])
def test_each_case_in_its_modal_coordinates_equals_the_dense_run(tamu_case, friction):
    """Each case's own modal coordinates (``batch_independent``) against the dense per-case
    propagators, states recorded (the change back x = T_c z per case), a random torque and
    optionally the bearing friction (per-case force columns): equal to 1e-12 of each history's
    largest value (the modal form is exact to cond(T) eps, ~1e-13 here)."""
    from flexsat.sim import BearingFriction, RandomTorque

    p = tamu_case.params
    batch = DispersedHubAppendage.from_parameters(
        replace(p, hub_inertia=p.hub_inertia * np.array([0.9, 1.0, 1.2])), N_MODES, damping=0.01
    )
    cfg = SimConfig(
        duration=1.0,
        random_torque=RandomTorque(0.01),
        friction=BearingFriction(0.05, 0.001) if friction else BearingFriction(),
        substeps=4,
    )
    law = PD(5.0, 20.0, target=[0.3, 0.5, 0.7])
    modal = simulate(batch, law, cfg, record_states=True, batch_independent=True).dataset
    dense = simulate(batch, law, cfg, record_states=True).dataset
    assert (modal.attrs["propagation"], dense.attrs["propagation"]) == ("modal", "dense")
    for var in ("state",) + HISTORIES + ("vibration_energy",):
        a, b = modal[var].values, dense[var].values
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), var
