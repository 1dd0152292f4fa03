"""Every plant and every control law of flexsat through the conformance suite
(:mod:`flexsat.testing`): one test per (subject, check), a check that does not apply skipped by
the subject's declaration.

The plants are built from the published cases where one exists (TAMU hub + appendages, NPS
hybrid model, Draper/RPL, Agrawal & Bang's piezo beam, Bainum's beam in orbit, the TAMU grid,
the EPS, the tether, the CMG pyramid, the space station, the vibration test's state-space model,
the example plug-in's carts) and each law on the plant it is written for.
:func:`test_every_plant_and_law_of_the_package_is_a_subject` fails when a concrete Plant or
Controller subclass of flexsat is in neither PLANTS / LAWS nor the commented NOT_SUBJECTS.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil

import numpy as np
import pytest

import flexsat
from eigenaxis_slew import EigenaxisSlew
from flexsat.control.base import Controller
from flexsat.dynamics.plant import Plant
from flexsat.testing import controller_checks, plant_checks
from flexsat.testing.checks import CHECK_RATE

pytestmark = pytest.mark.numerics  # round-off bounds: re-run on other BLAS kernels


def _tamu(**kw):
    from flexsat.cases.tamu import tamu

    return tamu(n_modes=3, **kw)


def _nps_plant():
    from flexsat.cases.nps import nps

    return nps().model(n_modes=3)


def _coupled_modal():
    """Two elastic modes with rotational participation (a small flexible spacecraft), forces
    and displacement outputs at two nodes."""
    from flexsat.structures.modal_model import ModalModel

    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = J
    participation = np.zeros((2, 6))
    participation[:, 3:] = [[3.0, 0.5, 0.0], [0.0, 4.0, 1.0]]
    return ModalModel(
        node_ids=[1, 2],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0]],
        frequencies=2 * np.pi * np.array([0.4, 0.9]),
        damping=0.005,
        shapes=0.1 * np.random.default_rng(3).standard_normal((2, 2, 6)),
        rigid_mass=rigid,
        participation=participation,
    )


def _flexible():
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft

    return FlexibleSpacecraft(
        _coupled_modal(), forces=[(1, "y"), (2, "x")], displacements=[(1, "y")]
    )


def _dispersed():
    from flexsat.dynamics.dispersion import stack_plants

    return stack_plants([_tamu(hub_inertia=f"{h} kg*m**2").model() for h in (6.0, 7.0, 8.0)])


def _dispersed_flexible():
    """The generic batch (a DispersedPlant): flexible spacecraft differing in one frequency."""
    from flexsat.dynamics.dispersion import stack_plants

    nominal = _flexible()
    base = np.sqrt(nominal.stiffness)
    return stack_plants([nominal.with_parameters(frequencies=base * s) for s in (0.95, 1.0, 1.05)])


def _tamu_hardware():
    """Law II through the TAMU drive, anti-alias filter and one-sample delay (the law wrapped,
    the plant with the hardware states appended), as the engine runs it."""
    from flexsat.cases.tamu import tamu_hardware

    case = _tamu()
    law, model = case.law_ii(1.0, 2.0, 0.5), case.model()
    plant, wrapped, *_ = tamu_hardware().apply(model, law, {}, {}, {})
    return wrapped, plant


def _wheel_array():
    """A rigid spacecraft driven by a four-wheel pyramid (the wheel speeds appended)."""
    from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft
    from flexsat.sim.wheel_array import ReactionWheelArray, WheelArrayPlant, pyramid_axes

    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    array = ReactionWheelArray(pyramid_axes(np.deg2rad(54.74)), 0.05)
    return WheelArrayPlant(RigidSpacecraft(J), "torque", array)


PLANTS = {
    "tamu_hub_appendage": lambda: _tamu().model(),
    "tamu_stiffening": lambda: _tamu(stiffening=True).model(),
    "nps_modal_hybrid": _nps_plant,
    "draper_rpl_structural": lambda: (
        __import__("flexsat.cases.draper_rpl", fromlist=["x"]).draper_rpl().plant(n_modes=3)
    ),
    "agrawal_bang_structural": lambda: (
        __import__("flexsat.cases.agrawal_bang", fromlist=["x"]).agrawal_bang().plant(3)
    ),
    "bainum_linear_structural": lambda: (
        __import__("flexsat.cases.bainum", fromlist=["x"])
        .bainum()
        .linear_plant([-0.5, 0.5, 0.25], 2)
    ),
    "bainum_beam_in_orbit": lambda: (
        __import__("flexsat.cases.bainum", fromlist=["x"]).bainum().plant([-0.5, 0.5, 0.25], 2)
    ),
    "tamu_grid_structural": lambda: (
        __import__("flexsat.cases.tamu_grid", fromlist=["x"]).tamu_grid().plant(n_modes=4)
    ),
    "rigid_spacecraft": lambda: __import__(
        "flexsat.dynamics.rigid_spacecraft", fromlist=["x"]
    ).RigidSpacecraft(np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])),
    "flexible_spacecraft": _flexible,
    "cmg_spacecraft": lambda: __import__(
        "flexsat.dynamics.cmg_actuator", fromlist=["x"]
    ).CmgSpacecraft(np.diag([100.0, 120.0, 150.0]), 1.0),
    "tether_tension": lambda: __import__(
        "flexsat.dynamics.tether", fromlist=["x"]
    ).TetheredSubsatellite(),
    "tether_rate": lambda: __import__(
        "flexsat.dynamics.tether", fromlist=["x"]
    ).TetheredSubsatellite(control="rate"),
    "dispersed_tamu": _dispersed,
    "dispersed_flexible_spacecraft": _dispersed_flexible,
    "gimbal_cluster": lambda: __import__(
        "flexsat.dynamics.gimbal_cluster", fromlist=["x"]
    ).GimbalCluster(),
    "space_station": lambda: _station().plant,
    "station_with_gimbals": lambda: __import__(
        "flexsat.dynamics.station_gimbals", fromlist=["x"]
    ).StationWithGimbals(_station().plant),
    "vibration_test_state_space": lambda: _vibration_plant(),
    "tamu_with_hardware": lambda: _tamu_hardware()[1],
    "rigid_with_wheel_array": lambda: _wheel_array(),
    "plugin_two_mass_spring": lambda: __import__(
        "flexsat_example_plugin.plant", fromlist=["x"]
    ).TwoMassSpring(1.0, 2.0, 4.0, 0.1),
}


def _station():
    """The station's pitch and roll/yaw LQR design on the paper's data (the published case)."""
    from flexsat.cases.space_station_cmg import PAPER_STATION, design

    return design(PAPER_STATION)


def _vibration_plant():
    """The modal-survey plant of :func:`flexsat.sim.vibration_test.simulate_test`: the small
    flexible spacecraft's two modes driven by forces at both nodes, displacement, velocity and
    acceleration sensors (the last with a feed-through D)."""
    from flexsat.dynamics.plant import Channel
    from flexsat.dynamics.state_space import StateSpacePlant
    from flexsat.identify.excitation import sensor_matrices

    sensors = [
        Channel.at(kind, node, axis)
        for kind, node, axis in (("displacement", 1, "y"), ("velocity", 2, "x"))
        + (("acceleration", 1, "y"),)
    ]
    forces = [Channel.at("force", 1, "y"), Channel.at("force", 2, "x")]
    matrices = sensor_matrices(_coupled_modal(), sensors, forces)
    return StateSpacePlant(*matrices, "excitation", "sensors")


def _tether_working_point(plant):
    """A deployed tether (1 m, the default scales' unit length): its rest state (zero length)
    is degenerate for the laws, which divide by the length."""
    return plant.state_from(length=1.0)


#: working points of plants whose rest state is not one (by key)
REST_STATES = {"tether_tension": _tether_working_point, "tether_rate": _tether_working_point}


def _marks(kind, key, check):
    if check.skip is not None:
        return pytest.mark.skip(reason=check.skip)
    return ()


@functools.cache
def _plant(key):
    """The plant of PLANTS[key], built once (collection and the coverage test share it)."""
    return PLANTS[key]()


def _all_plant_checks():
    params = []
    for key in PLANTS:
        plant = _plant(key)
        rest = REST_STATES.get(key, lambda p: None)(plant)
        params += [
            pytest.param(key, check, id=f"{key}-{check.name}", marks=_marks("plant", key, check))
            for check in plant_checks(plant, rest_state=rest)
        ]
    return params


@pytest.mark.parametrize("key, check", _all_plant_checks())
def test_plant(key, check):
    check()


# -- laws, each on the plant it is written for -----------------------------------------------------
DT = 1.0 / CHECK_RATE  # the checks' control period (a discrete law is designed for it)


def _tamu_lqg(**kw):
    from flexsat.control import LQGController
    from flexsat.dynamics.second_order import SecondOrderModel

    case = _tamu()
    som = SecondOrderModel.from_hub_appendage(case.model())
    n, k = som.n_states, som.n_dof
    Q = np.eye(n)
    Q[0, 0], Q[k, k] = 100.0, 10.0
    law = LQGController.design(som, Q, 1.0, 1.0, np.diag([1e-8, 1e-6]), dt=DT, **kw)
    return law, case.model()


def _nps_frequency_shaped():
    from flexsat.cases.nps import nps
    from flexsat.control import frequency_shaped_lqr, kalman

    plant = _nps_plant()
    sys = plant.to_statespace()
    w = np.full(sys.A.shape[0], 0.1)
    L = kalman(sys.A, sys.B, sys.C, 0.1, np.diag([1e-7, 5e-6])).gain
    design = frequency_shaped_lqr(sys.A, sys.B, np.diag(w), 7.0, 2.0)
    assert nps  # the case the plant comes from
    return design.controller(sys.C, L, DT, target=np.radians(30.0)), plant


def _scheduled():
    from flexsat.control.scheduled import ScheduledStateFeedback

    gains = np.random.default_rng(4).uniform(0.5, 2.0, size=(4, 1, 2))
    return ScheduledStateFeedback(
        [0.0, 0.3, 0.6, 0.9], gains, ["theta", "theta_dot"]
    ), _tamu().model()


def _compensator():
    import control as ct
    from flexsat.control.state_space_compensator import StateSpaceCompensator

    lead = ct.ss([[-4.0]], [[1.0, 0.5]], [[-3.0]], [[-5.0, -20.0]])
    law = StateSpaceCompensator(
        lead, ["theta", "theta_dot"], "torque", dt=DT, references={"theta": 0.2}
    )
    return law, _tamu().model()


def _ppf():
    from flexsat.cases.agrawal_bang import agrawal_bang
    from flexsat.control.ppf import PPFBank, PPFController, PPFModel

    case = agrawal_bang()
    modal = case.modal_model(3)
    bank = PPFBank.tuned(
        PPFModel.from_pairs(modal.frequencies, modal.damping, case.piezo_pairs(3)), 0.1
    )
    return PPFController(bank, np.full(9, 1e3), dt=DT), case.plant(3)


def _tether(kind: str, key: str):
    from flexsat.cases.tether import EXAMPLES, make_law
    from flexsat.dynamics.tether import TetheredSubsatellite

    e = EXAMPLES[key]
    return make_law(e.law, e.gains, e.final_length), TetheredSubsatellite(control=kind)


def _perturbation(kind: str):
    from flexsat.control.perturbation_feedback import NominalTorque, perturbation_design

    plant = _flexible()
    nominal = EigenaxisSlew(plant.inertia, [1.0, 1.0, 1.0], 1.0, 2.0)
    if kind == "nominal":
        return NominalTorque(nominal, DT), plant
    design = perturbation_design(plant, nominal, np.r_[[1000.0] * 6, [100.0] * 4], [50.0] * 3, 2.5)
    return design.controller(DT), plant


def _attitude(name: str, plant_key: str):
    from flexsat.control.attitude_laws import GibbsLyapunovLaw, MRPLaw, QuaternionPD

    target = np.array([np.cos(0.2), np.sin(0.2), 0.0, 0.0])
    law = {
        "gibbs": lambda: GibbsLyapunovLaw(k=12.0, A=3.6, beta_target=target),
        "mrp": lambda: MRPLaw(K=7.2, P=12.0, beta_target=target),
        "quaternion_pd": lambda: QuaternionPD(Kp=7.2, Kd=12.0, beta_target=target),
    }[name]()
    return law, PLANTS[plant_key]()


def _attitude_lqg(plant_key: str, coordinates: str):
    """The three-axis LQG on the attitude-error linearisation of the plant, turning to the
    attitude laws' target."""
    from flexsat.control import AttitudeLQG
    from flexsat.dynamics import linearize_attitude

    plant = PLANTS[plant_key]()
    lin = linearize_attitude(plant, coordinates)
    n = lin.A.shape[0]
    Q = np.diag([1600.0] * 3 + [10.0] * 3 + [1.0] * (n - 6))
    Rn = np.diag([1e-6] * 3 + [1e-4] * 3)
    target = np.array([np.cos(0.2), np.sin(0.2), 0.0, 0.0])
    return AttitudeLQG.design(
        lin, Q, 1e-3 * np.eye(3), 1e-2 * np.eye(3), Rn, DT, None, target
    ), plant


def _tamu_law(kind: str):
    case = _tamu()
    if kind == "lyapunov_i":
        return case.law_i(1.0, 2.0, 0.5), case.model()
    return case.law_ii(1.0, 2.0, 0.5), case.model()


def _pd(**kw):
    from flexsat.control import PD

    return PD(5.0, 20.0, **kw), _tamu().model()


def _steering(kind: str):
    """The §8.3 pseudo-inverse law on Kurokawa's torque Tx = 0.2 sin 4πt (h/s), plain and with
    null motion toward the zero set, and the §8.5 null-motion reorientation (cases/cmg_pyramid)."""
    from flexsat.cases.cmg_pyramid import NullMotionSteering, PseudoInverseSteering
    from flexsat.dynamics.gimbal_cluster import GimbalCluster

    def kurokawa(t):
        return np.array([0.2 * np.sin(4 * np.pi * t), 0.0, 0.0])

    law = {
        "pseudo_inverse": lambda: PseudoInverseSteering(kurokawa),
        "pseudo_inverse_null": lambda: PseudoInverseSteering(
            kurokawa, alpha=1e-3, null_target=np.zeros(4), null_gain=0.5
        ),
        "null_motion": lambda: NullMotionSteering(np.radians([45.0, -45.0, 45.0, -45.0]), 1.0),
    }[kind]()
    return law, GimbalCluster()


def _station_feedback():
    """The station's attitude loop: one knot, u = −K x (cases/space_station_cmg)."""
    from flexsat.control.scheduled import ScheduledStateFeedback

    station = _station()
    return ScheduledStateFeedback([0.0], station.gain[None], "state", "torque"), station.plant


def _station_steering():
    """The station's attitude law with the pseudo-inverse steering of the momentum it demands,
    on the station with its gimbals (cases/space_station_cmg.cmg_simulation)."""
    from flexsat.cases.space_station_cmg import cmg_simulation

    station = _station()
    plant, law, _, _ = cmg_simulation(
        station, 100.0, "design", "1 deg", np.radians([45.0, -45.0, 45.0, -45.0])
    )
    return law, plant


def _bainum_feedback():
    """Bainum's Ch. II example on the beam in orbit: f = K x' (printed rate gains), one knot
    u = −[0, −K/ω_c] x in seconds, as BainumBeam.simulate builds it."""
    from flexsat.cases.bainum import PUBLISHED, bainum
    from flexsat.cases.bainum_control import CH2_LAYOUTS
    from flexsat.control.scheduled import ScheduledStateFeedback

    plant = bainum().plant(CH2_LAYOUTS[1][2], 2)
    K_rate = np.reshape(PUBLISHED["ch2_gains"], (1, 3))
    gain = -np.hstack([np.zeros((1, 3)), K_rate / plant.orbit_rate])
    law = ScheduledStateFeedback([0.0], gain[None], "state", tuple(plant.input_slices))
    return law, plant


def _playback():
    """A hammer-and-shaker table on the modal-survey plant, as simulate_test drives it."""
    from flexsat.control.playback import Playback

    t = np.arange(30) * DT
    table = np.column_stack([np.where(t < 2 * DT, 5.0, 0.0), 0.3 * np.sin(2 * np.pi * 0.9 * t)])
    return Playback(table, DT, "excitation"), _vibration_plant()


def _bang_off_bang():
    """The plug-in's law on its carts: pulses of 3 control periods, a 2-period coast."""
    from flexsat_example_plugin.law import BangOffBang

    return BangOffBang(0.5, 3 * DT, 2 * DT, DT), PLANTS["plugin_two_mass_spring"]()


def _synthesis(kind: str):
    """The robust-synthesis laws (issue 24) at the checks' period: H2 and H∞ on the TAMU LQG
    weights, LQG/LTR on the TAMU hub angle, HAC/LAC on the Draper/RPL hub and tip pairs."""
    from synthesis_plants import (
        DRAPER_PAIRS,
        TAMU_RN,
        draper_design,
        tamu_design,
        tamu_generalized,
    )

    if kind == "hac_lac":
        from flexsat.control.hac_lac import HacLacController

        _, plant, P, Q = draper_design(6, 0.002)
        law = HacLacController.design(
            P,
            DRAPER_PAIRS,
            0.5,
            ["u1_hub"],
            ["theta", "theta_dot"],
            Q,
            1.0,
            1.0,
            np.diag([1e-6, 1e-4]),
            DT,
            references={"theta": 0.1},
        )
        return law, plant
    _, plant, A, B, C, Q = tamu_design(3)
    if kind == "ltr":
        from flexsat.control.ltr import LTRController

        law = LTRController.design(A, B, C, Q, 1.0, TAMU_RN, 10.0, DT, ["theta"], ["torque"])
        return law, plant
    if kind == "h2":
        from flexsat.control.h2_synthesis import H2Controller, h2syn

        return H2Controller(h2syn(tamu_generalized(3)), DT, references={"theta": 0.2}), plant
    from flexsat.control.hinf_synthesis import HinfController, hinfsyn

    return HinfController(hinfsyn(tamu_generalized(3), rtol=1e-3), DT), plant


LAWS = {
    "pd_step": lambda: _pd(target=0.3),
    "pd_reference": lambda: _pd(reference=_tamu().reference()),
    "pd_per_case_gains": lambda: (
        __import__("flexsat.control", fromlist=["x"]).PD([4.0, 5.0, 6.0], 20.0, target=0.3),
        _tamu().model(),
    ),
    "lyapunov_i": lambda: _tamu_law("lyapunov_i"),
    "lyapunov_ii": lambda: _tamu_law("lyapunov_ii"),
    "lyapunov_ii_through_hardware": lambda: _tamu_hardware(),
    "lqg_step": lambda: _tamu_lqg(target=0.3),
    "lqg_reference": lambda: _tamu_lqg(reference=_tamu().reference()),
    "frequency_shaped": _nps_frequency_shaped,
    "scheduled": _scheduled,
    "state_space_compensator": _compensator,
    "ppf": _ppf,
    "gibbs_rigid": lambda: _attitude("gibbs", "rigid_spacecraft"),
    "mrp_rigid": lambda: _attitude("mrp", "rigid_spacecraft"),
    "quaternion_pd_rigid": lambda: _attitude("quaternion_pd", "rigid_spacecraft"),
    "quaternion_pd_flexible": lambda: _attitude("quaternion_pd", "flexible_spacecraft"),
    "mrp_cmg": lambda: _attitude("mrp", "cmg_spacecraft"),
    "attitude_lqg_rigid": lambda: _attitude_lqg("rigid_spacecraft", "mrp"),
    "attitude_lqg_flexible": lambda: _attitude_lqg("flexible_spacecraft", "quaternion"),
    "tether_decoupled": lambda: _tether("tension", "V10"),
    "tether_coupled": lambda: _tether("tension", "V11"),
    "tether_rate": lambda: _tether("rate", "V15"),
    "perturbation_feedback": lambda: _perturbation("feedback"),
    "nominal_torque": lambda: _perturbation("nominal"),
    "cmg_pseudo_inverse": lambda: _steering("pseudo_inverse"),
    "cmg_pseudo_inverse_null": lambda: _steering("pseudo_inverse_null"),
    "cmg_null_motion": lambda: _steering("null_motion"),
    "station_state_feedback": _station_feedback,
    "station_momentum_steering": _station_steering,
    "bainum_state_feedback": _bainum_feedback,
    "playback": _playback,
    "plugin_bang_off_bang": _bang_off_bang,
    "h2_synthesis": lambda: _synthesis("h2"),
    "hinf_synthesis": lambda: _synthesis("hinf"),
    "lqg_ltr": lambda: _synthesis("ltr"),
    "hac_lac": lambda: _synthesis("hac_lac"),
}


@functools.cache
def _law(key):
    """The (law, plant) of LAWS[key], built once."""
    return LAWS[key]()


def _all_law_checks():
    params = []
    for key in LAWS:
        law, plant = _law(key)
        rest = _tether_working_point(plant) if key.startswith("tether") else None
        params += [
            pytest.param(key, check, id=f"{key}-{check.name}", marks=_marks("law", key, check))
            for check in controller_checks(law, plant, rest_state=rest)
        ]
    return params


@pytest.mark.parametrize("key, check", _all_law_checks())
def test_law(key, check):
    check()


# -- coverage: every concrete plant and law of the package is in the dicts above ---------------
#: Plant / Controller subclasses of flexsat that are not subjects of their own, each with why
NOT_SUBJECTS = {
    # abstract bases: the shared machinery of the concrete classes below them
    "flexsat.dynamics.hybrid.HybridPlant": "base of HubAppendage and ModalHybrid",
    "flexsat.control.base.SlewLaw": "abstract base of PD, LQG, Lyapunov laws",
    "flexsat.control.lqg.EstimatorController": "abstract base of LQG, frequency-shaped",
    "flexsat.control.attitude_laws._AttitudeLaw": "base of the Gibbs, MRP, quaternion laws",
    "flexsat.control.tether_laws._TetherLaw": "base of the three tether laws",
    "flexsat.control.cmg_steering._GimbalLaw": "abstract base of the three steering laws",
    "flexsat.control.h2_synthesis.SynthesisCompensator": "base of the H2 and H∞ compensators",
    # the conformance checks' own test doubles
    "flexsat.testing.checks.HoldLaw": "the plant checks' open-loop drive",
    "flexsat.testing.law_checks._Without": "the law checks' plant missing a channel",
}


def _name(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def _subclasses(cls: type) -> set[type]:
    out = set()
    for sub in cls.__subclasses__():
        out |= {sub} | _subclasses(sub)
    return out


def _package_classes(base: type) -> set[str]:
    """Every subclass of ``base`` defined in flexsat, after importing every module of it (the
    command-line entry point ``__main__`` excepted: importing it runs the CLI)."""
    for mod in pkgutil.walk_packages(flexsat.__path__, "flexsat."):
        if not mod.name.endswith("__main__"):
            importlib.import_module(mod.name)
    return {_name(c) for c in _subclasses(base) if c.__module__.startswith("flexsat.")}


def test_every_plant_and_law_of_the_package_is_a_subject():
    """A concrete Plant or Controller subclass of src/flexsat missing from PLANTS / LAWS fails
    here, by name; so does a NOT_SUBJECTS entry that no longer exists or that is a subject."""
    plants, laws = _package_classes(Plant), _package_classes(Controller)
    stale = sorted(set(NOT_SUBJECTS) - plants - laws)
    assert not stale, f"NOT_SUBJECTS names classes that are gone: {stale}"
    covered = {_name(type(_plant(k))) for k in PLANTS}
    covered |= {_name(type(_law(k)[0])) for k in LAWS}
    both = sorted(covered & set(NOT_SUBJECTS))
    assert not both, f"in NOT_SUBJECTS but built by the suite: {both}"
    missing = sorted((plants | laws) - covered - set(NOT_SUBJECTS))
    assert not missing, f"plants/laws not in the conformance suite (PLANTS / LAWS): {missing}"
