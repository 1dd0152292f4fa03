"""The compiled three-axis loop (flexsat.sim.compiled_attitude, flexsat.sim.kernels_attitude):
equal to the Python loop to the round-off of its integrator, a case of a batch equal to the
case run alone bit for bit, batches of rigid and flexible spacecraft with per-case inertia,
frequencies, damping and coupling.

Tolerances. Both loops run the same integrator (the rigid body's RKMK4; the flexible plant's
Krogstad exp_rk4, the compiled one in the modal coordinates x = T z of
flexsat.sim.spacecraft_modal); they differ by the order of the sums (a few ulps per
operation) and, for the flexible plant, by the change of coordinates (cond(T) ulps per step).
Under the damped closed loops below these differences add up at most linearly over the N
integrator steps, so a history differs by at most ``ULPS · N · cond(T) · eps`` of its
largest value, ULPS = 16 ulps per step (a bound, not a fit: measured differences are about
one hundredth of it).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import control as ct
from flexsat.control.attitude_laws import GibbsLyapunovLaw, MRPLaw, QuaternionPD
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.dynamics.dispersion import DispersedPlant, stack_plants
from flexsat.dynamics.plant import Channel
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft
from flexsat.input_checks import FieldError
from flexsat.sim.channels import ChannelActuator, ChannelDisturbance, ChannelSensor
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import SimulationDiverged, simulate
from flexsat.sim.spacecraft_modal import spacecraft_modal_form

sys.path.insert(0, str(Path(__file__).parents[1] / "testing"))
from test_conformance import _flexible  # noqa: E402  (the conformance suite's small spacecraft)

pytestmark = pytest.mark.numerics  # round-off bounds: re-run on other BLAS kernels

EPS = np.finfo(float).eps
ULPS = 16
J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
TARGET = [np.cos(0.3), 0.6 * np.sin(0.3), 0.8 * np.sin(0.3), 0.0]
HISTORIES = ("attitude", "rate", "euler123", "torque_command", "torque", "energy")


def _config(duration=10.0, noisy=False, **kw):
    extra = {}
    if noisy:
        extra = dict(
            channel_sensors={
                "attitude": ChannelSensor(noise=1e-5),
                "rate": ChannelSensor(noise=1e-6, bias=[1e-6, 0.0, -2e-6]),
            },
            channel_disturbances={
                "torque": ChannelDisturbance(
                    random=0.01, impulse_times=[0.5], impulses=[[0.2, -0.1, 0.3]]
                )
            },
        )
    return SimConfig(duration=duration, control_rate=10.0, **extra, **kw)


def _histories(result):
    return {k: result.dataset[k].values for k in result.dataset.data_vars if k in HISTORIES}


def _assert_close(got, want, steps, cond=1.0):
    for k in want:
        scale = max(np.abs(want[k]).max(), 1e-300)
        tol = ULPS * steps * cond * EPS * scale
        err = np.abs(got[k] - want[k]).max()
        assert err <= tol, f"{k}: {err:.3g} > {tol:.3g} (scale {scale:.3g})"


def _steps(result, config):
    return config.n_steps * result.dataset.attrs["substeps"]


def _compensator(target=TARGET):
    """u = −K_p (β_v − β_v,t) − K_d ω_f with ω_f the rate through a first-order filter: a
    linear law with an internal state reading the attitude and rate channels."""
    a, kp, kd = 20.0, 20.0, 60.0
    A = -a * np.eye(3)
    B = np.hstack([np.zeros((3, 4)), a * np.eye(3)])
    C = -kd * np.eye(3)
    D = np.hstack([np.zeros((3, 1)), -kp * np.eye(3), np.zeros((3, 3))])
    return StateSpaceCompensator(
        ct.ss(A, B, C, D),
        [Channel("attitude", "", 4), Channel("rate", "rad/s", 3)],
        [Channel("torque", "N*m", 3)],
        dt=0.1,
        references={"attitude": np.asarray(target)},
    )


LAWS = {
    "mrp_pd": lambda: MRPLaw(K=10.0, P=[50.0, 60.0, 70.0], beta_target=TARGET),
    "quaternion_pd": lambda: QuaternionPD(
        Kp=[20.0, 25.0, 30.0], Kd=60.0, beta_target=TARGET, w_ref=[1e-4, 0.0, 0.0]
    ),
    "gibbs": lambda: GibbsLyapunovLaw(k=60.0, A=10.0, beta_target=TARGET),
    "linear_form": _compensator,
}


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("plant", ["rigid", "flexible"])
def test_compiled_equals_the_python_loop(plant, law):
    p = RigidSpacecraft(J) if plant == "rigid" else _flexible()
    config = _config(noisy=True, channel_actuators={"torque": ChannelActuator(saturation=0.5)})
    x0 = p.state_from(euler123=[0.05, -0.1, 0.02], rate=[0.01, 0.0, -0.01])
    states = law == "mrp_pd"  # the state history too (back from the modal coordinates)
    compiled = simulate(p, LAWS[law](), config, n_cases=3, initial_state=x0, record_states=states)
    python = simulate(
        p, LAWS[law](), config, n_cases=3, initial_state=x0, compiled=False, record_states=states
    )
    assert compiled.dataset.attrs["engine"] == "compiled"
    assert python.dataset.attrs["engine"] == "python"
    cond = 1.0
    if plant == "flexible":
        T = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping).T
        cond = np.linalg.cond(T)
        assert compiled.dataset.attrs["propagation"] == "modal"
    got, want = _histories(compiled), _histories(python)
    assert set(got) == set(want) == set(HISTORIES)
    if states:
        got["state"], want["state"] = (
            compiled.dataset["state"].values,
            python.dataset["state"].values,
        )
    _assert_close(got, want, _steps(python, config), cond)
    for k in python.metrics:  # the same metrics from the same histories
        np.testing.assert_allclose(compiled.metrics[k], python.metrics[k], rtol=1e-9, atol=1e-12)


def test_eps_flexible_with_node_outputs_equals_the_python_loop():
    """The EPS (10 elastic modes, repeated pairs of the symmetric antenna, torquers at the CG
    node loading the modes) under the example's MRP law: every recorded output."""
    from flexsat.cases.eps import eps

    p = eps().plant(n_modes=10)
    law = MRPLaw(K=7200.0, P=[5400.0, 32400.0, 32800.0], beta_target=TARGET)
    config = SimConfig(duration=5.0, control_rate=20.0)
    compiled = simulate(p, law, config, n_cases=1)
    python = simulate(p, law, config, n_cases=1, compiled=False)
    assert compiled.dataset.attrs["engine"] == "compiled"
    T = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping).T
    keys = [k for k in python.dataset.data_vars if python.dataset[k].dims[:2] == ("case", "time")]
    assert any(k.startswith("displacement_") for k in keys)
    got = {k: compiled.dataset[k].values for k in keys}
    want = {k: python.dataset[k].values for k in keys}
    # each displacement's scale: the largest displacement (a small one carries the others'
    # round-off through the shared modal coordinates)
    big = max(np.abs(v).max() for k, v in want.items() if k.startswith("displacement_"))
    for k in keys:
        if k.startswith("displacement_"):
            want[k] = np.concatenate([want[k], [[big]]], axis=1)
            got[k] = np.concatenate([got[k], [[big]]], axis=1)
    _assert_close(got, want, _steps(python, config), np.linalg.cond(T))


def _batch_law(kind, n):
    K = np.linspace(8.0, 14.0, n)
    if kind == "mrp_pd":
        return MRPLaw(K=K, P=[50.0, 60.0, 70.0], beta_target=TARGET)
    return _compensator()


@pytest.mark.parametrize("kind", ["mrp_pd", "linear_form"])
@pytest.mark.parametrize("plant", ["rigid", "flexible"])
def test_a_case_of_a_batch_is_the_case_run_alone_bit_for_bit(plant, kind):
    """Chunks of 1, 7 and the whole batch of 17 (three groups of lanes, the last one part
    full), each case with its own gain, seed and initial rate."""
    n = 17
    p = RigidSpacecraft(J) if plant == "rigid" else _flexible()
    config = _config(duration=3.0, noisy=True)
    x0 = np.array([p.state_from(rate=[0.01 * i, -0.002, 0.0]) for i in range(n)])
    seeds = 100 + np.arange(n)
    law = _batch_law(kind, n)
    full = simulate(p, law, config, n_cases=n, seeds=seeds, initial_state=x0)
    assert full.dataset.attrs["engine"] == "compiled"
    for size in (1, 7):
        for c0 in range(0, n, size):
            c1 = min(n, c0 + size)
            sub = MRPLaw(K=law.K[c0:c1], P=law.P, beta_target=TARGET) if kind == "mrp_pd" else law
            part = simulate(
                p, sub, config, n_cases=c1 - c0, seeds=seeds[c0:c1], initial_state=x0[c0:c1]
            )
            for k, v in _histories(part).items():
                assert np.array_equal(v, full.dataset[k].values[c0:c1]), (k, size, c0)


def _dispersed_flexible(n):
    """n cases of the small flexible spacecraft: inertia ±5 %, frequencies ±10 %, damping
    and coupling varied per case."""
    base = _flexible()
    rng = np.random.default_rng(7)
    w = np.sqrt(base.stiffness)
    return [
        base.with_parameters(
            inertia=base.inertia * (1 + 0.05 * rng.uniform(-1, 1)),
            frequencies=w * (1 + 0.1 * rng.uniform(-1, 1, w.size)),
            damping=0.005 * np.exp(0.3 * rng.standard_normal(w.size)),
            coupling=base.coupling * (1 + 0.2 * rng.uniform(-1, 1)),
        )
        for _ in range(n)
    ]


def test_dispersed_flexible_batch_cases_equal_the_cases_alone():
    n = 9
    plants = _dispersed_flexible(n)
    batch = stack_plants(plants)
    assert isinstance(batch, DispersedPlant) and batch.n_cases == n
    config = _config(duration=3.0, noisy=True)
    law = MRPLaw(K=10.0, P=[50.0, 60.0, 70.0], beta_target=TARGET)
    seeds = 10 + np.arange(n)
    result = simulate(batch, law, config, n_cases=n, seeds=seeds)
    assert result.dataset.attrs["engine"] == "compiled"
    got = _histories(result)
    for size in (1, 7):
        for c0 in range(0, n, size):
            c1 = min(n, c0 + size)
            part_plant = plants[c0] if c1 - c0 == 1 else stack_plants(plants[c0:c1])
            part = simulate(part_plant, law, config, n_cases=c1 - c0, seeds=seeds[c0:c1])
            for k, v in _histories(part).items():
                assert np.array_equal(v, got[k][c0:c1]), (k, size, c0)
    # and each case equals its plant on the Python loop
    for i in (0, n - 1):
        alone = simulate(plants[i], law, config, n_cases=1, seeds=seeds[i : i + 1], compiled=False)
        p = plants[i]
        cond = np.linalg.cond(
            spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping).T
        )
        _assert_close(
            {k: v[i : i + 1] for k, v in got.items()},
            _histories(alone),
            _steps(alone, config),
            cond,
        )


def test_stacked_rigid_spacecraft_is_one_plant_with_an_inertia_per_case():
    inertias = [J * s for s in (0.9, 1.0, 1.1)]
    batch = stack_plants([RigidSpacecraft(Ji) for Ji in inertias])
    assert type(batch) is RigidSpacecraft and batch.n_cases == 3
    np.testing.assert_array_equal(batch.inertia, np.stack(inertias))
    law = LAWS["mrp_pd"]()
    config = _config(duration=5.0)
    result = simulate(batch, law, config, n_cases=3)
    assert result.dataset.attrs["engine"] == "compiled"
    for i, Ji in enumerate(inertias):
        alone = simulate(RigidSpacecraft(Ji), law, config, n_cases=1)
        for k, v in _histories(alone).items():
            assert np.array_equal(v, result.dataset[k].values[i : i + 1]), k


def test_with_parameters_keeps_the_plant_and_checks_the_new_ones():
    p = _flexible()
    same = p.with_parameters()
    for a, b in zip(p.linear_part(), same.linear_part()):
        np.testing.assert_allclose(b, a, rtol=1e-14, atol=1e-14 * np.abs(a).max())
    w = np.sqrt(p.stiffness)
    q = p.with_parameters(frequencies=2 * w, damping=0.02)
    np.testing.assert_allclose(q.stiffness, 4 * p.stiffness, rtol=1e-15)
    np.testing.assert_allclose(q.damping, 0.08 * w, rtol=1e-15)
    with pytest.raises(FieldError, match="frequencies"):
        p.with_parameters(frequencies=-w)
    with pytest.raises(FieldError, match="frequencies"):
        p.with_parameters(frequencies=w[:1])
    with pytest.raises(FieldError, match="damping"):
        p.with_parameters(damping=-0.1)
    with pytest.raises(FieldError, match="inertia"):
        p.with_parameters(inertia=np.diag([1.0, 1.0, 3.0]))  # triangle inequality
    with pytest.raises(FieldError, match="coupling"):
        p.with_parameters(coupling=100 * p.coupling)  # J − ΔᵀΔ not positive definite


def test_runs_off_the_kernel_take_the_python_loop_and_say_why():
    p = RigidSpacecraft(J)
    law = LAWS["mrp_pd"]()
    limited = _config(channel_actuators={"torque": ChannelActuator(rate_limit=1.0)})
    assert simulate(p, law, limited).dataset.attrs["engine"] == "python"
    with pytest.raises(ValueError, match="torque: actuator rate limit or bias"):
        simulate(p, law, limited, compiled=True)
    moving = _flexible()
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft

    translating = FlexibleSpacecraft(moving.modal, translation=True)
    assert simulate(translating, law, _config(duration=1.0)).dataset.attrs["engine"] == "python"


@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning", "ignore:invalid:RuntimeWarning")
def test_divergence_and_the_gibbs_singularity_raise_as_on_the_python_loop():
    p = RigidSpacecraft(J)
    wild = MRPLaw(K=1e9, P=1e9, beta_target=TARGET)
    config = _config(duration=2.0)
    with pytest.raises(SimulationDiverged) as compiled:
        simulate(p, wild, config)
    with pytest.raises(SimulationDiverged) as python:
        simulate(p, wild, config, compiled=False)
    assert compiled.value.cases == python.value.cases and compiled.value.time == python.value.time
    assert compiled.value.cause == python.value.cause
    # a diverging case of a large batch is reported from the compiled loop itself, by its
    # batch index (the other cases settle)
    gains = np.full(40, 10.0)
    gains[27] = 1e9
    law = MRPLaw(
        K=gains, P=np.where(gains > 1e3, 1e9, 50.0)[:, None] * np.ones(3), beta_target=TARGET
    )
    with pytest.raises(SimulationDiverged) as batch:
        simulate(p, law, config, n_cases=40)
    assert batch.value.cases == (27,)
    upside = p.state_from(attitude=[0.0, 0.0, 0.0, 1.0])  # 180° from the identity target
    with pytest.raises(FieldError, match="attitude"):
        simulate(p, GibbsLyapunovLaw(k=1.0, A=1.0), config, initial_state=upside)


@pytest.mark.parametrize("plant", ["eps_proportional", "coupled_non_proportional"])
def test_energy_in_modal_coordinates_is_the_plants_energy(plant):
    """½ ω_rᵀ J ω_r + ½ z_eᵀ Q_e z_e (SpacecraftModes.elastic_energy, what the compiled loop
    records instead of changing back to x) against the plant's own energy of x = T z, on
    random states: the EPS's free-free modes (each mode its own pair: Q_e diagonal) and the
    coupled spacecraft (non-proportional damping: Q_e a matrix). The two differ by the
    round-off of x = T z and of the sums, a few cond(T) · eps of the energy per coordinate:
    bound 16 · n · cond(T) · eps · E (E > 0: the kinetic and strain energies are positive
    definite, no cancellation)."""
    from flexsat.cases.eps import eps

    p = eps().plant(n_modes=10) if plant == "eps_proportional" else _flexible()
    modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
    assert modes.elastic_energy.ndim == (1 if plant == "eps_proportional" else 2)
    Qe = modes.elastic_energy
    Qe = np.diag(Qe) if Qe.ndim == 1 else Qe
    z = np.random.default_rng(3).standard_normal((50, p.nx))
    wr, ze = z[:, 2:7:2], z[:, 7:]
    got = 0.5 * (np.sum(wr * (wr @ p.inertia), -1) + np.sum(ze * (ze @ Qe), -1))
    want = p.energy(z @ modes.T.T)
    tol = 16 * p.nx * np.linalg.cond(modes.T) * EPS * want
    assert np.all(np.abs(got - want) <= tol), np.max(np.abs(got - want) / want)


@pytest.mark.parametrize("plant", ["rigid", "flexible"])
def test_a_case_of_a_batch_of_1000_is_the_case_run_alone_bit_for_bit(plant):
    """The batch of 1,000 (125 groups of lanes on every core, in blocks) against chunks of 1
    and 7 cut from it at the start, the middle and the end: bit for bit. The flexible plant
    shares its propagators (E, F) between the lanes."""
    n = 1000
    p = RigidSpacecraft(J) if plant == "rigid" else _flexible()
    config = _config(duration=1.0, noisy=True)
    x0 = np.array([p.state_from(rate=[1e-5 * i, -0.002, 0.0]) for i in range(n)])
    seeds = 100 + np.arange(n)
    law = _batch_law("mrp_pd", n)
    full = _histories(simulate(p, law, config, n_cases=n, seeds=seeds, initial_state=x0))
    for c0, c1 in ((0, 1), (0, 7), (497, 504), (500, 501), (993, 1000), (999, 1000)):
        sub = MRPLaw(K=law.K[c0:c1], P=law.P, beta_target=TARGET)
        part = simulate(
            p, sub, config, n_cases=c1 - c0, seeds=seeds[c0:c1], initial_state=x0[c0:c1]
        )
        for k, v in _histories(part).items():
            assert np.array_equal(v, full[k][c0:c1]), (k, c0, c1)


def _metrics_only_cases(plant):
    """A batch whose cases settle at different times (the pointing settling time is a number,
    not NaN, for most) with noisy sensors and random torques."""
    n = 17
    p = RigidSpacecraft(J) if plant == "rigid" else _flexible()
    x0 = np.array([p.state_from(rate=[0.002 * i, -0.002, 0.0]) for i in range(n)])
    law = MRPLaw(K=np.linspace(80.0, 140.0, n), P=[50.0, 60.0, 70.0], beta_target=TARGET)
    config = _config(duration=40.0, noisy=True)
    return p, law, config, x0, 100 + np.arange(n)


@pytest.mark.parametrize("plant", ["rigid", "flexible"])
def test_metrics_only_equals_the_metrics_of_the_full_run(plant):
    """simulate(metrics_only=True) accumulates the channel metrics in the loop
    (compiled_attitude.run_metrics): the same loop on the same states as the full run, so
    the peaks of the rigid body's channels and its pointing metrics are the same numbers bit
    for bit (the same formulas on the same states). Round-off differences: a root mean square
    sums the squares in the loop where NumPy's mean sums pairwise (relative n_t · eps); the
    flexible plant's outputs are the rows C T z summed in the loop where the full run sums
    them by a matrix product (ULPS · n · cond(T) · eps of the largest value of the metric)."""
    p, law, config, x0, seeds = _metrics_only_cases(plant)
    full = simulate(p, law, config, n_cases=len(seeds), seeds=seeds, initial_state=x0)
    lean = simulate(
        p, law, config, n_cases=len(seeds), seeds=seeds, initial_state=x0, metrics_only=True
    )
    assert lean.dataset.attrs["histories"] == "none"
    assert lean.dataset.attrs["engine"] == "compiled"
    assert not any("time" in lean.dataset[k].dims for k in lean.dataset.data_vars)
    assert list(lean.metrics) == list(full.metrics)
    assert np.isfinite(full.metrics["pointing_settling_time_s"]).sum() >= 10
    n_t = config.n_steps + 1
    cond = 1.0
    if plant == "flexible":
        cond = np.linalg.cond(
            spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping).T
        )
    for k, want in full.metrics.items():
        got = lean.metrics[k]
        if k.startswith("rms_"):
            np.testing.assert_allclose(got, want, rtol=n_t * EPS, atol=0)
        elif plant == "rigid" or k.endswith(("_deg", "_s")):
            if k.endswith("_deg") and plant == "flexible":  # β from the rows T[:4] z
                tol = ULPS * p.nx * cond * EPS * np.degrees(2.0)
                np.testing.assert_allclose(got, want, rtol=0, atol=tol)
            else:
                np.testing.assert_array_equal(got, want, err_msg=k)
        else:
            tol = ULPS * p.nx * cond * EPS * np.abs(want).max()
            np.testing.assert_allclose(got, want, rtol=0, atol=tol, err_msg=k)


@pytest.mark.parametrize("plant", ["rigid", "flexible", "dispersed"])
def test_metrics_only_a_case_of_a_batch_is_the_case_run_alone_bit_for_bit(plant):
    """The in-loop metrics of chunks of 1 and 7 cut from a batch of 17 (and the dispersed
    flexible batch of 9, each chunk its own stack of plants) equal the batch's bit for bit."""
    if plant == "dispersed":
        plants = _dispersed_flexible(9)
        law = MRPLaw(K=10.0, P=[50.0, 60.0, 70.0], beta_target=TARGET)
        config = _config(duration=20.0, noisy=True)
        seeds = 10 + np.arange(9)
        full = simulate(stack_plants(plants), law, config, seeds=seeds, metrics_only=True)
    else:
        p, law, config, x0, seeds = _metrics_only_cases(plant)
        full = simulate(
            p, law, config, n_cases=len(seeds), seeds=seeds, initial_state=x0, metrics_only=True
        )
    assert full.dataset.attrs["histories"] == "none"
    n = len(seeds)
    for size in (1, 7):
        for c0 in range(0, n, size):
            c1 = min(n, c0 + size)
            if plant == "dispersed":
                part_plant = plants[c0] if c1 - c0 == 1 else stack_plants(plants[c0:c1])
                part = simulate(
                    part_plant,
                    law,
                    config,
                    n_cases=c1 - c0,
                    seeds=seeds[c0:c1],
                    metrics_only=True,
                )
            else:
                sub = MRPLaw(K=law.K[c0:c1], P=law.P, beta_target=TARGET)
                part = simulate(
                    p,
                    sub,
                    config,
                    n_cases=c1 - c0,
                    seeds=seeds[c0:c1],
                    initial_state=x0[c0:c1],
                    metrics_only=True,
                )
            for k, v in part.metrics.items():
                np.testing.assert_array_equal(v, full.metrics[k][c0:c1], err_msg=f"{k} {c0}")


def test_metrics_only_with_a_linear_law_and_a_diverging_case():
    """A linear-form law (no target attitude: no pointing metrics, as the full run) and a
    diverging case: the metrics path hands the batch to the full run, which raises as the
    Python loop does."""
    p = RigidSpacecraft(J)
    config = _config(duration=5.0, noisy=True)
    full = simulate(p, _compensator(), config, n_cases=3)
    lean = simulate(p, _compensator(), config, n_cases=3, metrics_only=True)
    assert lean.dataset.attrs["histories"] == "none"
    assert list(lean.metrics) == list(full.metrics)
    for k in full.metrics:  # rms: the running sum against NumPy's pairwise mean
        np.testing.assert_allclose(lean.metrics[k], full.metrics[k], rtol=51 * EPS, atol=0)
    wild = MRPLaw(K=1e9, P=1e9, beta_target=TARGET)
    with pytest.raises(SimulationDiverged):
        simulate(p, wild, _config(duration=2.0), metrics_only=True)


@pytest.mark.parametrize("plant", ["rigid", "eps"])
def test_one_substep_is_within_the_round_off_bound_of_32(plant):
    """SimConfig(substeps=1), the user's option for these slews (docs/performance.md): the
    linear part of the flexible plant is exact at any step, the gyroscopic force and the
    rigid body's kinematics are integrated to fourth order in |ω| h (|ω| h ~ 2e-3 here). The
    histories of one substep per control period agree with those of 32 within the round-off
    bound of the 32-substep run itself, ULPS · N · cond(T) · eps of each history's largest
    value (N its 32 n_steps integrator steps): the truncation error of the single step is
    below the round-off of the reference (measured: 2e-12 of the largest displacement for the
    EPS with 45 modes, 10 s at 20 Hz)."""
    from flexsat.cases.eps import eps

    if plant == "rigid":
        p, cond = RigidSpacecraft(J), 1.0
        law = MRPLaw(K=np.linspace(8.0, 14.0, 3), P=[50.0, 60.0, 70.0], beta_target=TARGET)
        kw = dict(duration=20.0, control_rate=10.0)
    else:
        p = eps().plant(n_modes=10)
        cond = np.linalg.cond(
            spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping).T
        )
        law = MRPLaw(K=7200.0, P=[5400.0, 32400.0, 32800.0], beta_target=TARGET)
        kw = dict(duration=5.0, control_rate=20.0)
    one = simulate(p, law, SimConfig(substeps=1, **kw), n_cases=3)
    ref = simulate(p, law, SimConfig(substeps=32, **kw), n_cases=3)
    assert one.dataset.attrs["substeps"] == 1 and ref.dataset.attrs["substeps"] == 32
    keys = [k for k in ref.dataset.data_vars if ref.dataset[k].dims[:2] == ("case", "time")]
    got = {k: one.dataset[k].values for k in keys}
    want = {k: ref.dataset[k].values for k in keys}
    _assert_close(got, want, _steps(ref, SimConfig(**kw)), cond)
