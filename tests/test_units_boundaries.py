"""Units at every public boundary: a number is SI, a pint Quantity or a unit string is converted,
a wrong dimension is a UnitError naming the field, and a Quantity is never stripped of its unit.

For each boundary kind (control laws, simulation settings, maneuvers, case builders; scenario
files in tests/scenarios/test_maneuver.py) the tests claim (a) a Quantity gives the same object
as its SI number, (b) a unit string does too, (c) a wrong dimension is refused naming the
field, (d) a Quantity where no unit is declared is refused. Converted values are compared with
``==`` where the SI conversion factor is exact in binary or identical on both sides, else to
rel=1e-15 (one rounding of pint's factor).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexsat.cases.inputs import Param, read_inputs
from flexsat.cases.tamu import tamu
from flexsat.control.frequency_shaped import frequency_shaped_lqr
from flexsat.control.lqg import LQGController, zoh
from flexsat.control.lqr import lqr
from flexsat.control.lyapunov import LyapunovRegulator, LyapunovTracker
from flexsat.control.pd import PD
from flexsat.dynamics.hub_appendage import HubAppendageParams
from flexsat.maneuvers.torque_shapes import BangBang, PseudoSquare, Sinusoidal, SmoothBangBang
from flexsat.sim.actuators import TorqueActuator
from flexsat.sim.disturbances import BearingFriction, Impulses, RandomTorque
from flexsat.sim.engine import SimConfig, simulate
from flexsat.sim.sensors import Sensors
from flexsat.units import Q_, UnitError, to_si

OZ_IN = 0.028349523125 * 9.80665 * 0.0254  # 1 ozf·in in N·m: ounce (kg) × g0 × inch, all exact


# -- control laws ---------------------------------------------------------------------------------
def test_pd_gain_in_ounce_inches_per_radian_is_converted_not_stripped():
    """The issue's example: 3000 ozf·in/rad is 21.18 N·m/rad; stripped it was 141x too large."""
    pd_q = PD(kp=Q_(3000, "ozf*in/rad"), kd=Q_(900, "ozf*in*s/rad"))
    pd_si = PD(kp=3000 * OZ_IN, kd=900 * OZ_IN)
    assert float(pd_q.kp) == pytest.approx(float(pd_si.kp), rel=1e-15)
    assert float(pd_q.kd) == pytest.approx(float(pd_si.kd), rel=1e-15)
    assert 3000 / float(pd_q.kp) == pytest.approx(141.6, rel=1e-3)  # the factor the issue saw
    pd_s = PD(kp="3000 ozf*in/rad", kd="900 ozf*in*s/rad", target="40 deg")
    assert float(pd_s.kp) == float(pd_q.kp)
    assert float(pd_s.target) == pytest.approx(math.radians(40), rel=1e-15)
    # arrays of gains (a batch) convert as a whole
    batch = PD(kp=Q_([1.0, 2.0], "kN*m/rad"), kd=0.0)
    assert np.array_equal(batch.kp, [1000.0, 2000.0])
    with pytest.raises(UnitError, match=r"^kp: incompatible units \(kilogram given, N\*m/rad"):
        PD(kp="3 kg", kd=0.0)
    with pytest.raises(UnitError, match=r"^target: incompatible units \(second given, rad"):
        PD(kp=1.0, kd=1.0, target=Q_(2, "s"))


def test_pd_from_rigid_poles_converts_inertia_frequency_and_damping():
    wn = 2 * math.pi * 0.06  # a cyclic frequency carries its 2π (seed 001: ω_n = 0.06 Hz)
    inertia = to_si("2128 ozf*in*s**2", "kg*m**2")
    si = PD.from_rigid_poles(inertia, wn, 0.9)
    q = PD.from_rigid_poles(Q_(2128, "ozf*in*s**2"), Q_(0.06, "Hz"), Q_(90, "percent"))
    s = PD.from_rigid_poles("2128 ozf*in*s**2", "0.06 Hz", "90 percent")
    for law in (q, s):
        assert float(law.kp) == pytest.approx(float(si.kp), rel=1e-15)
        assert float(law.kd) == pytest.approx(float(si.kd), rel=1e-15)
    with pytest.raises(
        UnitError,
        match=r"^natural_frequency: incompatible units \(percent given, "
        r"rad/s expected\)",
    ):
        PD.from_rigid_poles(inertia, "100 percent", 0.9)
    with pytest.raises(UnitError, match=r"^inertia: incompatible units \(kilogram given"):
        PD.from_rigid_poles("3 kg", wn, 0.9)


def test_lyapunov_gains_and_appendage_inertia_convert():
    si = LyapunovRegulator(600 * OZ_IN, 1200 * OZ_IN, 0.5, target=math.radians(40))
    q = LyapunovRegulator(
        Q_(600, "ozf*in/rad"), "1200 ozf*in*s/rad", Q_(50, "percent"), target="40 deg"
    )
    for name in ("g1", "g2", "g3", "target"):
        assert float(getattr(q, name)) == pytest.approx(float(getattr(si, name)), rel=1e-15)
    ref = BangBang(angle=1.0, inertia=1.0, u_max=1.0)
    tracker = LyapunovTracker(ref, 1.0, 1.0, appendage_inertia="1 oz*in**2")
    assert tracker.appendage_inertia == pytest.approx(0.028349523125 * 0.0254**2, rel=1e-15)
    with pytest.raises(UnitError, match=r"^g3: incompatible units \(meter given, dimensionless"):
        LyapunovRegulator(1.0, 1.0, "2 m")


def _double_integrator():
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    B = np.array([[0.0], [1.0]])
    C = np.eye(2)
    return A, B, C


def test_lqg_period_and_target_convert_and_weight_matrices_refuse_quantities():
    A, B, C = _double_integrator()
    K, L = np.array([[1.0, 1.7]]), np.eye(2)
    si = LQGController(A, B, C, K, L, 0.01, target=math.radians(10))
    q = LQGController(A, B, C, K, L, Q_(10, "ms"), target="10 deg")
    assert q.dt == pytest.approx(si.dt, rel=1e-15)
    assert float(q.target) == pytest.approx(float(si.target), rel=1e-15)
    assert np.array_equal(zoh(A, B, "10 ms")[1], zoh(A, B, q.dt)[1])
    with pytest.raises(UnitError, match=r"^dt: incompatible units \(hertz given, s expected\)"):
        LQGController(A, B, C, K, L, "100 Hz")
    # a weight matrix has no single unit: a Quantity there is refused, not stripped
    with pytest.raises(UnitError, match=r"^Q: takes a plain number here \(no unit is declared"):
        lqr(A, B, Q_(np.eye(2), "N*m"), np.eye(1))
    with pytest.raises(UnitError, match=r"^Q: takes a plain number here"):
        LQGController.design(
            (A, B, C), Q_(np.eye(2), "N*m"), np.eye(1), np.eye(1), np.eye(2), 0.01, gains="discrete"
        )


def test_frequency_shaped_break_frequency_converts_with_its_two_pi():
    A, B, _ = _double_integrator()
    si = frequency_shaped_lqr(A, B, np.eye(2), np.eye(1), 2 * math.pi * 0.5)
    q = frequency_shaped_lqr(A, B, np.eye(2), np.eye(1), "0.5 Hz")
    assert q.break_frequency == pytest.approx(si.break_frequency, rel=1e-15)
    with pytest.raises(UnitError, match=r"^break_frequency: incompatible units \(second given"):
        frequency_shaped_lqr(A, B, np.eye(2), np.eye(1), "2 s")


# -- simulation settings, sensors, actuators, disturbances --------------------------------------
def test_sim_config_converts_duration_rate_and_band_and_stores_si():
    c = SimConfig(duration=Q_(0.5, "min"), control_rate="0.075 kHz", settling_band="0.5 deg")
    assert c.duration == 30.0 and type(c.duration) is float
    assert c.control_rate == pytest.approx(75.0, rel=1e-15)
    assert c.settling_band == pytest.approx(math.radians(0.5), rel=1e-15)
    assert SimConfig(
        duration=1.0, control_rate=Q_(150 * math.pi, "rad/s")
    ).control_rate == pytest.approx(75.0, rel=1e-15)  # an angular rate reads as cycles: ÷ 2π
    with pytest.raises(
        UnitError,
        match=r"^duration: incompatible units \(degree given, s "
        r"expected\)",
    ):
        SimConfig(duration="15 deg")
    with pytest.raises(UnitError, match=r"^substeps: takes a plain number here"):
        SimConfig(duration=1.0, substeps=Q_(4, "s"))


def test_sensors_actuator_and_disturbances_convert_and_store_si():
    s = Sensors(encoder_resolution="0.01 deg", gyro_noise=Q_(1, "deg/s"), strain_noise="1 ozf*in")
    assert s.encoder_resolution == pytest.approx(math.radians(0.01), rel=1e-15)
    assert s.gyro_noise == pytest.approx(math.radians(1), rel=1e-15)
    assert s.strain_noise == pytest.approx(OZ_IN, rel=1e-15)
    a = TorqueActuator(saturation=Q_(400, "ozf*in"), torque_constant_ratio="105 percent")
    assert a.saturation == pytest.approx(400 * OZ_IN, rel=1e-15)
    assert a.torque_constant_ratio == pytest.approx(1.05, rel=1e-15)
    assert TorqueActuator().saturation == math.inf  # no limit stays allowed
    f = BearingFriction(
        coulomb="20 ozf*in", viscous=Q_(0.001, "ozf*in*s/rad"), smoothing="1e-3 rad/s"
    )
    assert f.coulomb == pytest.approx(20 * OZ_IN, rel=1e-15)
    assert f.viscous == pytest.approx(0.001 * OZ_IN, rel=1e-15)
    assert RandomTorque(std="5 ozf*in").std == pytest.approx(5 * OZ_IN, rel=1e-15)
    imp = Impulses(times=Q_([500, 1500], "ms"), impulses=["1 N*m*s", Q_(2, "N*m*s")])
    assert imp.times == (0.5, 1.5) and imp.impulses == (1.0, 2.0)
    for make, message in [
        (lambda: Sensors(gyro_noise="1 deg"), r"^gyro_noise: incompatible units"),
        (lambda: TorqueActuator(saturation="400 ozf"), r"^saturation: incompatible units"),
        (lambda: BearingFriction(coulomb=Q_(2, "N")), r"^coulomb: incompatible units"),
        (lambda: RandomTorque(std="5 percent"), r"^std: incompatible units \(percent given"),
        (
            lambda: Impulses(times=["1 s"], impulses=["1 N*m"]),
            r"^impulses.impulses: incompatible units",
        ),
    ]:
        with pytest.raises(UnitError, match=message):
            make()


def test_simulate_initial_angle_converts():
    """An initial angle in degrees gives the run of the angle in radians (same floats after
    conversion): the named initial values of ``plant.state_from`` take units."""
    plant = tamu(n_modes=2).model()
    law = PD(kp=5.0, kd=20.0)
    config = SimConfig(duration=0.2)
    si = simulate(plant, law, config, initial_state=plant.state_from(theta=math.radians(1)))
    q = simulate(plant, law, config, initial_state=plant.state_from(theta=Q_(1, "deg")))
    assert np.array_equal(si.dataset["theta"].values, q.dataset["theta"].values)
    assert si.dataset["theta"].values[0, 0] == math.radians(1)
    with pytest.raises(UnitError, match=r"^theta: incompatible units"):
        plant.state_from(theta="1 m")
    with pytest.raises(UnitError, match=r"^initial_state: takes a plain number here"):
        simulate(plant, law, config, initial_state=Q_(np.zeros(plant.nx), "rad"))


# -- maneuvers ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "shape, extra",
    [
        (BangBang, {}),
        (SmoothBangBang, {"alpha": 0.2}),
        (PseudoSquare, {"rise_time": 1.0}),
        (Sinusoidal, {}),
    ],
)
def test_torque_shapes_convert_every_parameter(shape, extra):
    si = shape(
        angle=math.radians(40),
        inertia=to_si("2128 ozf*in*s**2", "kg*m**2"),
        u_max=400 * OZ_IN,
        theta0=math.radians(5),
        **extra,
    )
    quantities = {
        k: Q_(v * 1000, "ms") if k == "rise_time" else Q_(100 * v, "percent")
        for k, v in extra.items()
    }
    q = shape(
        angle=Q_(40, "deg"),
        inertia="2128 ozf*in*s**2",
        u_max="400 ozf*in",
        theta0="5 deg",
        **quantities,
    )
    for name in ("angle", "inertia", "u_max", "duration", "theta0", *extra):
        assert float(getattr(q, name)) == pytest.approx(float(getattr(si, name)), rel=1e-15), name
    t = float(si.duration) / 3
    assert q(Q_(t * 1000, "ms")).theta == pytest.approx(
        si(t).theta, rel=1e-14
    )  # t: one ms→s rounding
    with pytest.raises(UnitError, match=r"^duration: incompatible units \(degree given, s"):
        shape(
            angle=1.0,
            inertia=1.0,
            duration="15 deg",
            **(
                {"alpha": 0.1}
                if shape is SmoothBangBang
                else {"rise_time": 1.0}
                if shape is PseudoSquare
                else {}
            ),
        )
    with pytest.raises(UnitError, match=r"^inertia: incompatible units \(kilogram given"):
        shape(angle=1.0, inertia="3 kg", u_max=1.0, **extra)


# -- case builders and their inputs ---------------------------------------------------------------
def test_case_inputs_convert_quantities_and_refuse_them_where_no_unit_fits():
    lb = to_si("1 lb", "kg")
    assert tamu(tip_mass=Q_(2, "lb")).tip_mass == pytest.approx(2 * lb, rel=1e-15)
    assert tamu(tip_mass="2 lb").tip_mass == tamu(tip_mass=Q_(2, "lb")).tip_mass
    assert tamu(damping=Q_(0.4, "percent")).damping == pytest.approx(0.004, rel=1e-15)
    with pytest.raises(UnitError, match=r"^tip_mass: incompatible units \(second given, kg"):
        tamu(tip_mass="3 s")
    with pytest.raises(UnitError, match=r"^damping: incompatible units \(meter given"):
        tamu(damping=Q_(1, "m"))
    with pytest.raises(UnitError, match=r"^n_modes: takes a plain number here"):
        tamu(n_modes=Q_(3, "m"))
    values = read_inputs("demo", {"x": Param(1.0)}, {"x": Q_(25, "percent")})
    assert values["x"] == 0.25
    params = HubAppendageParams(
        hub_inertia="50 ozf*in*s**2",
        n_appendages=4,
        hub_radius="5 in",
        length=Q_(46, "in"),
        EI=1.0,
        rho=1.0,
        damping=("1 percent", 0.02),
    )
    assert params.length == pytest.approx(46 * 0.0254, rel=1e-15)
    assert params.damping == (0.01, 0.02)
