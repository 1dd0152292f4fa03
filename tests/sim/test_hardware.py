"""Hardware in the loop (flexsat.sim.hardware): filters against their exact ZOH, the wheel's
momentum and speed limit, the amplifier's limit, the delay's stability boundary."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from flexsat.control.base import Controller
from flexsat.control.pd import PD
from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.state_space import StateSpacePlant
from flexsat.input_checks import FieldError
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate
from flexsat.sim.hardware import (
    Amplifier,
    AntiAliasFilter,
    Hardware,
    HardwarePlant,
    ReactionWheel,
    delayed_linear_law,
    zoh,
)


class RigidHub(Plant):
    """I θ'' = τ: the rigid body the wheel tests need (momentum I θ')."""

    inputs = (Channel("torque", "N*m"),)
    outputs = (Channel("theta", "rad"), Channel("theta_dot", "rad/s"))
    recorded = ("theta", "theta_dot")

    def __init__(self, inertia: float) -> None:
        self.inertia = inertia

    @property
    def nx(self) -> int:
        return 2

    def linear_part(self):
        return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0 / self.inertia]])

    def output_matrices(self, name):
        row = {"theta": [1.0, 0.0], "theta_dot": [0.0, 1.0]}[name]
        return np.array([row]), np.zeros((1, 1)), np.zeros((1, 1))

    def momentum(self, x):
        return self.inertia * x[..., 1]


class Sequence_(Controller):
    """Plays a given input sequence, reading (and ignoring) ``y``."""

    reads = ("y",)
    writes = ("u",)

    def __init__(self, values):
        self.values, self.k = np.asarray(values, float), 0

    def initial_state(self, n_cases):
        return {"k": np.zeros(n_cases, int)}

    def __call__(self, t, y, state):
        k = int(state["k"][0])
        return self.values[k], {"k": state["k"] + 1}


@pytest.mark.parametrize("kind,order", [("butterworth", 4), ("bessel", 3), ("butterworth", 1)])
def test_filter_is_the_exact_zoh_of_its_state_space(kind, order):
    # y = u exactly (feedthrough only), so the filter is driven by the held input: its states
    # must follow z+ = Φ z + Γ u with (Φ, Γ) the exact ZOH of (A_f, B_f); the engine forms them
    # inside one exponential of the augmented system, so the two agree to round-off
    # (a few ulps times the sample count: 1e-12 of the largest state).
    dt, n = 0.01, 300
    u = np.random.default_rng(1).standard_normal(n + 1)
    plant = StateSpacePlant([[-1.0]], [[1.0]], [[0.0]], [[1.0]], "u", "y")
    flt = AntiAliasFilter("7 Hz", order, kind)
    cfg = SimConfig(n * dt, 1 / dt, hardware=Hardware(filters={"y": flt}))
    run = simulate(plant, Sequence_(u), cfg, record_states=True, compiled=False).dataset
    hp = HardwarePlant(plant, {}, {"y": flt})
    s = hp.hardware_states()["y_filter"]
    Z = run["state"].values[0, :, s : s + order]
    Af, Bf, Cf = flt.matrices()
    Phi, Gam = zoh(Af, Bf, dt)
    z = np.zeros(order)
    ref = [z]
    for k in range(n):
        z = Phi @ z + Gam[:, 0] * u[k]
        ref.append(z)
    ref = np.array(ref)
    assert np.abs(Z - ref).max() <= 1e-12 * np.abs(ref).max()
    # the law reads the filter's output C_f z: the plant's y_filtered row
    y_f = hp.output("y_filtered", run["state"].values[0], np.zeros((n + 1, hp.n_inputs)))
    np.testing.assert_allclose(y_f, ref @ Cf[0], atol=1e-12 * np.abs(ref).max())


def _wheel_run(wheel, I=10.0, target=1.0, duration=20.0, rate=100.0, kp=40.0, kd=40.0):
    law = PD(kp, kd, target=target)
    cfg = SimConfig(duration, rate, hardware=Hardware(actuators={"torque": wheel}))
    return simulate(RigidHub(I), law, cfg, record_states=True).dataset


def test_wheel_and_hub_momentum_is_conserved():
    # no external torque: the motor and the wheel bearing's friction (viscous and Coulomb) act
    # between wheel and hub, so I θ' + J_w Ω_a keeps its initial value 0. The exact step and
    # the friction's force column both leave it unchanged: round-off only (1e-10 N m s,
    # against momenta of order 1 N m s).
    wheel = ReactionWheel(
        0.05,
        torque_constant=0.1,
        viscous=1e-3,
        coulomb=0.02,
        amplifier=Amplifier("current", current_limit=20.0, bandwidth=200.0, torque_constant=0.1),
    )
    run = _wheel_run(wheel)
    hp = HardwarePlant(RigidHub(10.0), {"torque": wheel}, {})
    h = hp.momentum(run["state"].values[0])
    assert np.abs(run["theta_dot"].values).max() > 0.05  # the hub did slew
    assert np.abs(h).max() < 1e-10
    speed = run["torque_wheel_speed"].values[0]
    assert np.abs(speed).max() > 5.0  # the wheel spun up, and it is recorded


def test_wheel_speed_limit_caps_the_slew():
    # with zero total momentum I θ' + J_w (Ω + θ') = 0, so |θ'| = J_w |Ω| / (I + J_w): the speed
    # limit caps the hub rate at J_w Ω_max / (I + J_w). The limiter acts at the samples, so Ω
    # may pass Ω_max by one sample's acceleration at most, τ_max Δt (1/J_w + 1/I).
    I, Jw, om_max, tau_max, dt = 10.0, 0.05, 100.0, 2.0, 0.01
    amp = Amplifier("current", current_limit=tau_max / 0.1, torque_constant=0.1)
    limited = ReactionWheel(Jw, torque_constant=0.1, max_speed=om_max, amplifier=amp)
    free = ReactionWheel(Jw, torque_constant=0.1, amplifier=amp)
    cap = Jw * om_max / (I + Jw)
    over = tau_max * dt * (1 / Jw + 1 / I)
    run = _wheel_run(limited, target=3.0, duration=30.0)
    ref = _wheel_run(free, target=3.0, duration=30.0)
    rate = np.abs(run["theta_dot"].values[0])
    assert np.abs(ref["theta_dot"].values[0]).max() > 1.5 * cap  # unlimited, it goes faster
    assert cap * (1 - 1e-3) <= rate.max() <= Jw * (om_max + over) / (I + Jw)
    assert np.abs(run["torque_wheel_speed"].values[0]).max() <= om_max + over
    # the slew takes at least θ / cap: 90 % of 3 rad no sooner than 2.7 / cap
    t = run["time"].values
    t90 = t[np.argmax(run["theta"].values[0] >= 2.7)]
    assert t90 >= 2.7 / cap
    assert run.attrs["engine"] == "python"  # the limiter is a state-dependent switch
    law = PD(40.0, 40.0, target=3.0)
    cfg = SimConfig(1.0, 100.0, hardware=Hardware(actuators={"torque": limited}))
    with pytest.raises(ValueError, match="speed limit"):
        simulate(RigidHub(I), law, cfg, compiled=True)
    with pytest.raises(ValueError, match="fractional computation delay"):
        simulate(RigidHub(I), law, replace(cfg, hardware=Hardware(delay=0.5)), compiled=True)


def test_voltage_mode_back_emf_caps_the_wheel_speed():
    # voltage mode, V held at V_max: the wheel runs up to V_max / K_e (no friction), the
    # back-EMF's no-load speed; exact in the limit, reached to 1e-6 after 60 time constants
    amp = Amplifier("voltage", voltage_limit=12.0)
    wheel = ReactionWheel(0.01, torque_constant=0.05, back_emf=0.05, resistance=1.0, amplifier=amp)
    run = _wheel_run(wheel, target=1e3, duration=60.0, kp=1e3, kd=0.0)
    speed = np.abs(run["torque_wheel_speed"].values[0])
    assert speed[-1] == pytest.approx(wheel.no_load_speed, rel=1e-6)
    assert wheel.no_load_speed == pytest.approx(240.0)


def test_amplifier_limit_and_lag():
    # current mode, 12 A × K_t: the applied torque never exceeds it; the lag's step response
    # after one sample is 1 − exp(−ω_b Δt) of the (clipped) demand
    kt, dt = 0.1, 0.01
    amp = Amplifier("current", current_limit=12.0, bandwidth=5.0, torque_constant=kt)
    law = PD(100.0, 0.0, target=1.0)
    cfg = SimConfig(1.0, 1 / dt, hardware=Hardware(actuators={"torque": amp}))
    run = simulate(RigidHub(10.0), law, cfg, record_states=True).dataset
    i = run["torque_motor_current"].values[0]
    assert np.abs(i).max() <= 12.0 + 1e-12
    assert i[1] == pytest.approx(12.0 * (1 - np.exp(-2 * np.pi * 5.0 * dt)), rel=1e-12)


def _delayed_pd_boundary(I, T, ratio):
    """The largest kp (kd = ratio kp) for which the one-sample-delayed PD loop on I s² is
    stable: the spectral radius of [θ, θ', u_prev]+ = M [θ, θ', u_prev] crosses 1."""

    def radius(kp):
        M = np.array([[1.0, T, T * T / (2 * I)], [0.0, 1.0, T / I], [-kp, -ratio * kp, 0.0]])
        return np.abs(np.roots(np.poly(M))).max()

    lo, hi = 1e-6, 1e6
    for _ in range(200):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return lo, radius


@pytest.mark.parametrize("compiled", [True, False])
def test_one_sample_delay_moves_the_pd_stability_boundary(compiled):
    # the boundary of the discrete characteristic polynomial with the delay state; the run's
    # amplitude decays just below it and grows just above, and the boundary lies below the
    # undelayed one
    I, T, ratio = 1.0, 0.1, 0.5
    k_c, radius = _delayed_pd_boundary(I, T, ratio)

    def M0(kp):
        return np.array(
            [
                [1 - kp * T * T / (2 * I), T - ratio * kp * T * T / (2 * I)],
                [-kp * T / I, 1 - ratio * kp * T / I],
            ]
        )  # noqa: E731

    assert np.abs(np.linalg.eigvals(M0(1.2 * k_c))).max() < 1  # stable without the delay
    plant = RigidHub(I)
    for factor, grows in ((0.97, False), (1.03, True)):
        kp = factor * k_c
        cfg = SimConfig(60.0, 1 / T, hardware=Hardware(delay=1))
        run = simulate(
            plant, PD(kp, ratio * kp, target=0.0), cfg, initial_state=[1e-3, 0.0], compiled=compiled
        ).dataset
        th = np.abs(run["theta"].values[0])
        assert (th[-50:].max() > th[:50].max()) == grows
        # the growth per sample is the spectral radius (last 300 samples' envelope)
        env = np.array([th[i : i + 30].max() for i in range(len(th) - 330, len(th) - 30, 30)])
        rate = np.exp(np.mean(np.diff(np.log(env))) / 30)
        assert rate == pytest.approx(radius(kp), abs=2e-3)
    assert run.attrs["engine"] == ("compiled" if compiled else "python")


def test_delay_compiled_equals_python_and_shift_register():
    # the compiled loop's shift register and the Python loop's FIFO: the same run to round-off
    plant = RigidHub(2.0)
    for d in (1, 3):
        cfg = SimConfig(5.0, 50.0, hardware=Hardware(delay=d))
        law = PD(3.0, 4.0, target=0.5)
        a = simulate(plant, law, cfg, compiled=True).dataset
        b = simulate(plant, law, cfg, compiled=False).dataset
        np.testing.assert_allclose(a["theta"].values, b["theta"].values, atol=1e-13)
        # the applied torque is the PD law of the measurements d samples earlier, 0 before
        u, th, om = (b[k].values[0] for k in ("torque", "theta", "theta_dot"))
        assert np.all(u[:d] == 0)
        np.testing.assert_allclose(u[d:], 3.0 * (0.5 - th[:-d]) - 4.0 * om[:-d], atol=1e-14)


def test_fractional_delay_between_whole_ones():
    # a delay of f samples: the previous command over f Δt. At f → 0 and 1 it joins the
    # undelayed and one-sample runs; in between the response lies between them.
    plant = RigidHub(2.0)
    law = PD(3.0, 4.0, target=0.5)
    runs = {
        d: simulate(plant, law, SimConfig(5.0, 20.0, hardware=Hardware(delay=d)))
        .dataset["theta"]
        .values[0]
        for d in (0.0, 1e-9, 0.5, 1.0 - 1e-9, 1.0)
    }
    np.testing.assert_allclose(runs[1e-9], runs[0.0], atol=1e-8)
    np.testing.assert_allclose(runs[1.0 - 1e-9], runs[1.0], atol=1e-8)
    mid = runs[0.5][1:40]
    lo = np.minimum(runs[0.0], runs[1.0])[1:40]
    hi = np.maximum(runs[0.0], runs[1.0])[1:40]
    assert np.all((mid >= lo - 1e-12) & (mid <= hi + 1e-12))


def test_delayed_linear_law_shifts_the_feedforward():
    from flexsat.control.linear_form import run_linear_law

    law = PD(3.0, 4.0, target=0.5).linear_form(0.1, np.arange(20) * 0.1, 1)
    d = delayed_linear_law(law, 2)
    y = np.random.default_rng(0).standard_normal((20, 1, 2))
    u0 = run_linear_law(law, y)
    u2 = run_linear_law(d, y)
    np.testing.assert_allclose(u2[2:], u0[:-2], atol=1e-14)
    assert np.all(u2[:2] == 0)


def test_bad_hardware_is_refused_naming_the_field():
    with pytest.raises(FieldError, match="order"):
        AntiAliasFilter(10.0, 0)
    with pytest.raises(FieldError, match="kind"):
        AntiAliasFilter(10.0, 2, "chebyshev")
    with pytest.raises(FieldError, match="corner"):
        AntiAliasFilter(-1.0)
    with pytest.raises(FieldError, match="mode"):
        Amplifier("torque")
    with pytest.raises(FieldError, match="wheel.inertia"):
        ReactionWheel(0.0)
    with pytest.raises(FieldError, match="voltage mode"):
        Hardware(actuators={"torque": Amplifier("voltage")})
    with pytest.raises(FieldError, match="delay"):
        Hardware(delay=-1)
    with pytest.raises(FieldError, match="hardware"):
        SimConfig(1.0, hardware="wheel")  # type: ignore[arg-type]
    cfg = SimConfig(1.0, 10.0, hardware=Hardware(filters={"nope": AntiAliasFilter(1.0)}))
    with pytest.raises(FieldError, match="nope"):
        simulate(RigidHub(1.0), PD(1.0, 1.0), cfg)
    cfg = replace(cfg, hardware=Hardware(filters={"theta_dot": AntiAliasFilter(1.0)}))
    run = simulate(RigidHub(1.0), PD(1.0, 1.0, target=0.1), cfg).dataset
    assert np.isfinite(run["theta"].values).all()


def test_modal_form_of_filters_on_a_hybrid_plant():
    # the filters' companion blocks (tests/sim/test_hardware_models.py) join the plant's modal
    # form; the compiled loop in these coordinates equals the Python loop's dense step to
    # round-off (cond(T) eps: 1e-12 rad against 0.7 rad of slew)
    from flexsat.cases.tamu import tamu

    case = tamu()
    hw = case.hardware()
    hp = HardwarePlant(case.model(), hw.actuators, hw.filters)
    assert hp.modal_form() is not None
    law = case.law_ii(0.5, 0.3, 0.2, alpha=np.array([0.1, 0.2]))  # g3: the filter is read
    cfg = replace(case.sim_config(3.0), hardware=hw)
    a = simulate(case.model(), law, cfg, batch_independent=True).dataset
    b = simulate(case.model(), law, cfg, compiled=False).dataset
    assert a.attrs["engine"] == "compiled" and b.attrs["engine"] == "python"
    np.testing.assert_allclose(a["theta"].values, b["theta"].values, atol=1e-12)
    np.testing.assert_allclose(
        a["vibration_energy"].values, b["vibration_energy"].values, atol=1e-12
    )


def test_filter_phase_lag_appears_in_the_sampled_data_margins():
    # a filter on both measured channels multiplies the loop by H: at the crossover ω_c the
    # phase margin falls by −∠H(jω_c). |H(jω_c)| = 1 − O((ω_c/ω_f)^4) ≈ 1 − 6e-6 leaves ω_c
    # in place, and the zero-order hold's aliasing is of order ω_c/ω_s ~ 2e-3 of the lag: the
    # prediction holds to 1 % of the lag (it is 7e-4° of 4° here)
    import control as ct
    from flexsat.analysis.frequency_domain import build_loop
    from flexsat.analysis.margins import loop_margins
    from flexsat.control.state_space_export import discrete_law
    from flexsat.dynamics.linear_model import plant_state_space

    plant, dt = RigidHub(1.0), 0.01
    K = discrete_law(PD(1.0, 1.4, target=0.0), dt)
    m0 = loop_margins(build_loop(plant_state_space(plant), K, "torque"))
    flt = AntiAliasFilter(5.0, 2)
    Ph = plant_state_space(HardwarePlant(plant, {}, {"theta": flt, "theta_dot": flt}))
    rows = [Ph.output_labels.index(k) for k in ("theta_filtered", "theta_dot_filtered")]
    P1 = ct.ss(
        Ph.A, Ph.B, Ph.C[rows], Ph.D[rows], inputs=["torque"], outputs=["theta", "theta_dot"]
    )
    m1 = loop_margins(build_loop(P1, K, "torque"))
    lag = np.degrees(
        np.angle(flt.frequency_response(np.array([m0.gain_crossover_rad_s / (2 * np.pi)]))[0])
    )
    assert lag < -3.0
    assert m1.phase_margin_deg - m0.phase_margin_deg == pytest.approx(lag, abs=0.01 * abs(lag))
    assert m1.gain_crossover_rad_s == pytest.approx(m0.gain_crossover_rad_s, rel=1e-4)


def test_hardware_pickles_and_reuses_its_plant():
    # a config travels to batch workers by pickle; the augmented plant is built once per plant
    import pickle

    from flexsat.cases.tamu import tamu

    case = tamu()
    hw = case.hardware()
    model = case.model()
    assert hw.plant_for(model) is hw.plant_for(model)
    back = pickle.loads(pickle.dumps(SimConfig(1.0, hardware=hw)))
    assert back.hardware == hw
    assert back.hardware.plant_for(model).nx == hw.plant_for(model).nx


def test_wheel_on_a_flexible_plant_compiled_and_python():
    # any plant: a wheel with its amplifier's lag and Coulomb friction on the TAMU hub +
    # appendages; the compiled loop (dense step) equals the Python loop to round-off and the
    # momentum of hub, appendages and wheel stays 0 (1e-10 N m s, against ~5 N m s of wheel)
    from flexsat.cases.tamu import tamu

    case = tamu()
    model = case.model()
    amp = Amplifier(
        "current", gain=1.2, current_limit="12 A", bandwidth=300.0,
        torque_constant="52.77 ozf*in/A", dac_range="10 V",
    )  # fmt: skip
    wheel = ReactionWheel(
        "0.05 kg*m^2", torque_constant="52.77 ozf*in/A", viscous=1e-3, coulomb=0.05, amplifier=amp
    )
    law = case.law_ii(21.2, 5.65, alpha=0.2)
    hw = Hardware(actuators={"torque": wheel})
    cfg = case.sim_config(5.0, friction=False, noise=False, hardware=hw)
    a = simulate(model, law, cfg, record_states=True).dataset
    b = simulate(model, law, cfg, compiled=False, record_states=True).dataset
    assert (a.attrs["engine"], b.attrs["engine"]) == ("compiled", "python")
    np.testing.assert_allclose(a["theta"].values, b["theta"].values, atol=1e-12)
    h = hw.plant_for(model).momentum(a["state"].values[0])
    assert np.abs(a["torque_wheel_speed"].values).max() > 50.0
    assert np.abs(h).max() < 1e-10
