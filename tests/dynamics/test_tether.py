"""Tethered subsatellite (issue 14, F21; Vadali & Kim, seed 000 Att. 12, Eq. 4): with the length
held and no thrust the integral of motion V1 of Eq. 8 is constant (V14) and its rate along any
motion is Eq. 9 (plus φ'F̂/λ with thrust); the z, y form of Eq. 10 follows from Eq. 4; the SI
plant is Eq. 4 scaled by Ω, m, L, and the engine's sampled mode (exp_rk4) agrees with its
continuous-law mode (DOP853); a collapsing tether ends a run by name; the paper's scales
(Ω = 0.07068 rad/min at 220 km, 0.630 N per unit force); non-physical inputs are refused by
name."""

import numpy as np
import pytest

from flexsat.control.base import Controller
from flexsat.dynamics.tether import (
    TetheredSubsatellite,
    TetherScales,
    accelerations,
    integral_of_motion,
    integral_of_motion_rate,
    rate_control_accelerations,
)
from flexsat.sim import continuous
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate

D5 = np.radians(5.0)
X0 = np.array([1.0, D5, D5, 0.0, 0.0, 0.0])  # the paper's initial conditions, L4399
RNG = np.random.default_rng(14)


class ConstantInputs(Controller):
    """Holds the tether's two inputs at constants (SI): a static law for either mode."""

    reads = ("length",)

    def __init__(self, first, thrust, control="tension"):
        self.writes = ("tension" if control == "tension" else "reel_rate", "thrust")
        self.first, self.thrust = first, thrust
        self.target = 0.0

    def __call__(self, t, y, state):
        z = np.zeros(np.shape(y["length"]))
        return {self.writes[0]: z + self.first, "thrust": z + self.thrust}, state


def random_states(n=50):
    x = RNG.uniform(-0.6, 0.6, (n, 6))
    x[:, 0] = RNG.uniform(0.05, 1.5, n)
    return x


@pytest.mark.numerics
def test_v14_integral_of_motion_is_constant_with_the_length_held():
    # V14 (L4357-L4363): λ ≡ 1 (rate control, λ' = 0), F̂ = 0, θ = φ = 5° at rest.
    # DOP853 at rtol 1e-12 over two orbits: V1 (~1.1e-2) varies by < 1e-10 absolute.
    tau = np.linspace(0, 4 * np.pi, 801)
    plant = TetheredSubsatellite(control="rate")
    run = continuous.run(
        plant, ConstantInputs(0.0, 0.0, "rate"), tau, np.delete(X0, 3), rtol=1e-12, atol=1e-14
    )
    V1 = plant.output("integral_of_motion", run.states[0])
    assert V1[0] == pytest.approx(0.5 * (3 * np.cos(D5) ** 2 + 4) * np.sin(D5) ** 2, rel=1e-14)
    assert np.ptp(V1) < 1e-10
    # V1 bounds the libration analytically (L4359): 4 sin²φ <= 2 V1 and 3 sin²θ cos²φ <= 2 V1
    theta, phi = run.states[0, :, 1], run.states[0, :, 2]
    assert np.all(4 * np.sin(phi) ** 2 <= 2 * V1[0] + 1e-12)
    assert np.all(3 * (np.sin(theta) * np.cos(phi)) ** 2 <= 2 * V1[0] + 1e-12)


def test_eq9_is_the_rate_of_v1_along_any_motion():
    # Central differences of V1 along Eq. 4's flow against Eq. 9 (+ φ'F̂/λ): the step 1e-5
    # leaves an O(h²) ~ 1e-10 truncation and ~eps/h ~ 1e-11 round-off.
    x = random_states()
    T, F = RNG.uniform(0, 5, len(x)), RNG.uniform(-1, 1, len(x))

    def flow(x):
        return np.concatenate([x[:, 3:], accelerations(x, T, F)], 1)

    def V1(x):
        return integral_of_motion(x[:, 1], x[:, 2], x[:, 4], x[:, 5])

    h = 1e-5
    numeric = (V1(x + h * flow(x)) - V1(x - h * flow(x))) / (2 * h)
    np.testing.assert_allclose(integral_of_motion_rate(x, F), numeric, atol=1e-8)


def test_eq10_decoupled_form_follows_from_eq4():
    # z = λ cos φ, y = λ sin φ: z'', y'' by the chain rule from Eq. 4 equal the right-hand sides
    # of Eq. 10, and the identities (11)-(12) hold; exact algebra, round-off only.
    x = random_states()
    T, F = RNG.uniform(0, 5, len(x)), RNG.uniform(-1, 1, len(x))
    lam, th, ph, dl, dth, dph = x.T
    ddl, ddth, ddph = accelerations(x, T, F).T
    c, s = np.cos(ph), np.sin(ph)
    z, y = lam * c, lam * s
    dz, dy = dl * c - lam * s * dph, dl * s + lam * c * dph
    ddz = ddl * c - 2 * dl * s * dph - lam * c * dph**2 - lam * s * ddph
    ddy = ddl * s + 2 * dl * c * dph - lam * s * dph**2 + lam * c * ddph
    np.testing.assert_allclose(
        ddz - z * ((1 + dth) ** 2 - 1 + 3 * np.cos(th) ** 2), -T / lam * z - F / lam * y, atol=1e-12
    )
    np.testing.assert_allclose(ddy + y, -T / lam * y + F / lam * z, atol=1e-12)
    np.testing.assert_allclose(
        ddth + 2 * dz / z * (1 + dth) + 3 * np.cos(th) * np.sin(th), 0, atol=1e-12
    )
    np.testing.assert_allclose(y * dy + z * dz, lam * dl, atol=1e-14)
    np.testing.assert_allclose(z * dy - y * dz, lam**2 * dph, atol=1e-14)


def test_paper_scales():
    # L4397-L4401: 220 km, .07068 rad/min, "nearly 1.48 hours", and the scales derived from them.
    s = TetherScales(mass="22.7 kg", length="20 km", altitude="220 km")
    assert s.orbit_rate * 60 == pytest.approx(0.07068, abs=5e-6)  # printed to 4 figures
    assert s.period / 3600 == pytest.approx(1.48, abs=0.005)
    assert s.force == pytest.approx(0.630, abs=5e-4)
    assert s.impulse == pytest.approx(534.8, abs=0.05)
    assert s.speed == pytest.approx(23.56, abs=5e-3)
    given = TetherScales(mass=22.7, length=2e4, orbit_rate="0.07068 rad/min")
    assert given.orbit_rate == pytest.approx(s.orbit_rate, rel=1e-4)


def test_si_plant_is_eq4_scaled():
    s = TetherScales(mass="22.7 kg", length="20 km", altitude="220 km")
    plant = TetheredSubsatellite(s)
    xhat = random_states(8)
    That, Fhat = RNG.uniform(0, 5, 8), RNG.uniform(-1, 1, 8)
    x = s.state_to_si(xhat)
    u = np.stack([That * s.force, Fhat * s.force], 1)
    xdot = plant.rhs(x, u)
    # d/dt = Ω d/dτ: SI rates are Ω × the nondimensional ones, scaled per coordinate
    expected = s.state_to_si(np.concatenate([xhat[:, 3:], accelerations(xhat, That, Fhat)], 1))
    np.testing.assert_allclose(xdot, expected * s.orbit_rate, rtol=1e-12, atol=1e-18)
    # rate control: [l, θ, φ, θ̇, φ̇], l̇ = u
    rplant = TetheredSubsatellite(s, control="rate")
    x5 = s.state_to_si(xhat[:, [0, 1, 2, 4, 5]])
    rate = xhat[:, 3] * s.speed
    xdot5 = rplant.rhs(x5, np.stack([rate, Fhat * s.force], 1))
    acc = rate_control_accelerations(xhat[:, [0, 1, 2, 4, 5]], xhat[:, 3], Fhat)
    expected5 = s.state_to_si(np.concatenate([xhat[:, [3, 4, 5]], acc], 1))
    np.testing.assert_allclose(xdot5, expected5 * s.orbit_rate, rtol=1e-12, atol=1e-18)
    assert plant.output("length_rate", x).shape == (8,)
    np.testing.assert_allclose(
        rplant.output("length_rate", x5, np.stack([rate, 0 * rate], 1)), rate
    )
    np.testing.assert_allclose(
        plant.output("integral_of_motion", x),
        integral_of_motion(*xhat[:, [1, 2, 4, 5]].T),
        rtol=1e-12,
    )


def test_sampled_mode_matches_the_continuous_law_mode():
    # A constant tension of 3 (the equilibrium value at λ = 1) and no thrust, held: the
    # sampled mode's exp_rk4 (fourth order) with 2000 steps of Δτ = π/1000 over one orbit has
    # a global error ~ (Δτ)⁴ × O(1) ≈ 1e-10 against DOP853 at rtol 1e-12.
    plant = TetheredSubsatellite()
    law = ConstantInputs(3.0, 0.0)
    config = SimConfig(duration=2 * np.pi, control_rate=1000 / np.pi, substeps=1)
    sampled = simulate(plant, law, config, initial_state=X0, record_states=True)
    ref = continuous.run(plant, law, [0.0, 2 * np.pi], X0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sampled.dataset["state"].values[0, -1], ref.x_end[0], atol=1e-8)
    # the same run through simulate's continuous-law mode records the same end state
    cont = simulate(
        plant,
        law,
        SimConfig(duration=2 * np.pi, control_rate=1000 / np.pi, law_mode="continuous"),
        initial_state=X0,
        record_states=True,
    )
    np.testing.assert_allclose(cont.dataset["state"].values[0, -1], ref.x_end[0], atol=1e-9)
    assert cont.dataset.attrs["engine"] == "continuous"


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(mass=0.0), "mass: must be > 0"),
        (dict(mass="-1 kg"), "mass: must be > 0"),
        (dict(length="0 km"), "length: must be > 0"),
        (dict(altitude="-5 km"), "altitude: must be >= 0"),
        (dict(orbit_rate=0.0), "orbit_rate: must be > 0"),
        (dict(orbit_rate=1e-3, altitude=1e5), "not both"),
        (dict(mass="3 m"), "mass"),
    ],
)
def test_bad_scales_are_refused_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        TetherScales(**kwargs)


def test_non_physical_lengths_and_modes_are_refused():
    plant = TetheredSubsatellite()
    with pytest.raises(ValueError, match="length: the tether length must be > 0"):
        plant.state_from(length=-1.0)
    with pytest.raises(ValueError, match="length: the tether length must be > 0"):
        plant.state_from(length="0 m")
    with pytest.raises(ValueError, match="length: the initial tether length is required"):
        plant.state_from(pitch=0.1)
    with pytest.raises(ValueError, match="control: must be one of"):
        TetheredSubsatellite(control="thrust")
    still = ConstantInputs(0.0, 0.0)
    with pytest.raises(ValueError, match=r"initial_state: length: the tether collapsed"):
        continuous.run(plant, still, [0, 1], [0.0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="times: must be a strictly monotonic"):
        continuous.run(plant, still, [1.0, 1.0], X0)
    # reeling in at λ' = -1 from λ = 3e-4 collapses the tether at τ = 2e-4: reported, not
    # integrated past
    with pytest.raises(ValueError, match=r"length: the tether collapsed .* at t = 0.0002 s"):
        continuous.run(
            TetheredSubsatellite(control="rate"),
            ConstantInputs(-1.0, 0.0, "rate"),
            [0, 1.0],
            [3e-4, D5, D5, 0, 0],
        )
    x = plant.state_from(length="2 km", pitch="5 deg", roll="-3 deg")
    np.testing.assert_allclose(x, [2000.0, D5, np.radians(-3), 0, 0, 0])


def test_the_rest_state_is_the_deployed_tether_not_a_collapsed_one():
    """initial_state (what simulate starts from by default) is the tether at its reference
    length along the local vertical, at rest: the state state_from(length=L) builds, which a
    zero length would not be (state_from refuses it)."""
    from flexsat.dynamics.tether import TetheredSubsatellite, TetherScales

    scales = TetherScales(mass=22.7, length=20e3, orbit_rate=0.07068 / 60)
    for control in ("tension", "rate"):
        plant = TetheredSubsatellite(scales, control=control)
        x0 = plant.initial_state(3)
        assert x0.shape == (3, plant.nx)
        np.testing.assert_array_equal(x0, np.broadcast_to(plant.state_from(length=20e3), x0.shape))
        with pytest.raises(ValueError, match="length"):
            plant.state_from(length=0.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(length=[1.0, 2.0]), r"length: "),
        (dict(mass="1 m"), r"mass: incompatible units"),
        (dict(altitude=["1 km", "2 km"]), r"altitude: must be one altitude"),
        (dict(altitude="1e10 m"), r"altitude: .* beyond the Earth's Hill sphere"),
        (dict(altitude="1e308 m"), r"altitude: "),
        (dict(mass=1e-300, length=1e-300, orbit_rate=1e-300), r"mass: .* beyond a float's range"),
    ],
)
def test_scales_refuse_shapes_units_and_ranges_by_name(kwargs, message):
    # a length array was a TypeError, 1e308 m of altitude an OverflowError (issue 21)
    with pytest.raises(ValueError, match=message):
        TetherScales(**kwargs)
