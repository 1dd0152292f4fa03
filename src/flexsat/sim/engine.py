"""Sampled-data simulation of a hub + appendage plant under a digital control law.

The plant is continuous; the controller runs at a fixed rate and its command is held (zero-order
hold) until the next sample. Between samples the linear dynamics are propagated exactly by matrix
exponentials; friction and rotational stiffening go through the ETD2RK exponential integrator
(:mod:`flexsat.sim.integrators`). Everything carries a leading case axis, so a batch of maneuvers
(a parameter sweep, a Monte Carlo set) is one call with no per-case Python loop in the time loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from flexsat import limits
from flexsat.sim.actuators import TorqueActuator
from flexsat.sim.disturbances import BearingFriction, Impulses, RandomTorque
from flexsat.sim.integrators import ExponentialStepper
from flexsat.sim.metrics import METRIC_UNITS, maneuver_metrics
from flexsat.sim.sensors import Sensors, SensorState
from flexsat.validation import require_count, require_finite, require_positive, set_si

N_NOISE_CHANNELS = 3  # gyro, strain gauge, random torque — fixed so streams never shift


@dataclass(frozen=True)
class SimConfig:
    """Run settings shared by every case of a batch.

    Parameters
    ----------
    duration : float             run length, s
    control_rate : float         controller sample rate, Hz (TAMU: 75 Hz)
    substeps : int               integrator substeps per control period when the plant has
                                 nonlinear terms (friction, stiffening); ignored otherwise and
                                 raised where friction needs it (:func:`stable_substeps`)
    settling_band : float        |θ − θ_f| band for the settling time, rad
    seed : int                   base seed; case i uses seed + i unless seeds are given

    ``duration``, ``control_rate`` and ``settling_band`` take a number in SI, a pint Quantity or
    a unit string (``"15 s"``, ``"75 Hz"``, ``"0.5 deg"``) and are stored in SI.
    """

    duration: float
    control_rate: float = 75.0
    substeps: int = 4
    actuator: TorqueActuator = field(default_factory=TorqueActuator)
    sensors: Sensors = field(default_factory=Sensors)
    friction: BearingFriction = field(default_factory=BearingFriction)
    random_torque: RandomTorque = field(default_factory=RandomTorque)
    impulses: Impulses = field(default_factory=Impulses)
    settling_band: float = np.radians(0.5)
    seed: int = 0

    def __post_init__(self):
        set_si(self, "duration", require_positive, "s")
        set_si(self, "control_rate", require_positive, "Hz")
        set_si(self, "settling_band", require_positive, "rad")
        require_count(self.substeps, "substeps")
        if not limits.is_integral(self.seed) or not 0 <= self.seed <= limits.MAX_SEED:
            raise ValueError(f"seed: must be an integer in [0, {limits.MAX_SEED}], got "
                             f"{self.seed!r}")
        limits.check_count(self.duration * self.control_rate, limits.MAX_SAMPLES, "duration",
                           "control samples (duration × control_rate)",
                           "shorten the run or lower the control rate")
        limits.check_count(self.substeps, limits.MAX_SUBSTEPS, "substeps",
                           "integrator substeps per control period")

    @property
    def dt(self) -> float:
        return 1.0 / self.control_rate

    @property
    def n_steps(self) -> int:
        return int(round(self.duration * self.control_rate))


@dataclass
class SimResult:
    """Time histories (``dataset``, dims case × time) and per-case ``metrics``."""

    dataset: xr.Dataset
    metrics: dict[str, np.ndarray]

    def metrics_records(self, labels=None) -> list[dict]:
        """One JSON-ready dict per case (NaN → None)."""
        n = len(next(iter(self.metrics.values())))
        rows = []
        for i in range(n):
            row = {} if labels is None else {"run": labels[i]}
            for key, val in self.metrics.items():
                v = float(val[i])
                row[key] = None if not np.isfinite(v) else v
            rows.append(row)
        return rows


#: largest h λ_friction allowed; ETD2RK treats friction explicitly and is stable for h λ <= 2
FRICTION_STEP_LIMIT = 1.5


def stable_substeps(plant, friction: BearingFriction, dt: float, requested: int) -> int:
    """Substeps per control period: the requested number, raised where needed so that the
    explicitly integrated friction stays stable.

    Inside |θ'| < ε the regularised friction is a damper of rate λ = (c1/ε + c2) (M⁻¹)_θθ on the
    hub; the substep h must keep h λ <= FRICTION_STEP_LIMIT.
    """
    if not friction.active:
        return requested
    rate = (friction.coulomb / friction.smoothing + friction.viscous) * plant.mass_inverse[0, 0]
    needed = dt * rate / FRICTION_STEP_LIMIT
    # compared as a float first: a near-zero smoothing makes it too large for an int
    limits.check_count(needed, limits.MAX_SUBSTEPS, "friction",
                       f"a stable integration of the friction (damping rate {rate:.3g} 1/s below "
                       f"the smoothing speed) needs substeps per control period",
                       "lower coulomb or viscous, raise smoothing or the control rate")
    return max(requested, math.ceil(needed))


#: recorded histories of :func:`simulate`; the memory estimate counts them twice (the loop's
#: arrays and the dataset's copies) plus the noise streams
_N_RECORDED = 13


def check_resources(plant, config: SimConfig, n_cases: int = 1, record_states: bool = False
                    ) -> int:
    """Check that a run fits the limits of :mod:`flexsat.limits` before it starts.

    Parameters
    ----------
    plant, config
        As for :func:`simulate`.
    n_cases : int
        Batch size.
    record_states : bool
        Whether the full state history is kept.

    Returns
    -------
    int
        The integrator substeps per control period (:func:`stable_substeps`).

    Raises
    ------
    ValueError
        ``"field: ... above the limit ..."`` for too many cases, substeps, integrator steps or
        too much memory.
    """
    limits.check_count(n_cases, limits.MAX_CASES, "n_cases", "cases in one batch",
                       "split the batch")
    nonlinear = config.friction.active or plant.stiffening
    substeps = stable_substeps(plant, config.friction, config.dt, config.substeps) \
        if nonlinear else 1
    n = config.n_steps + 1
    limits.check_count(n * substeps, limits.MAX_INTEGRATOR_STEPS, "duration",
                       f"integrator steps ({n} control samples × {substeps} substeps)",
                       "shorten the run or lower the control rate or the substeps")
    values = 2 * _N_RECORDED + N_NOISE_CHANNELS + (2 * plant.nx if record_states else 0)
    limits.check_memory(limits.memory_estimate(n, n_cases, values), "duration",
                        f"a run of {n} samples × {n_cases} cases × {values} values")
    return substeps


#: a state entry (rad, rad/s, modal coordinates) or a torque command (N m) beyond this is taken
#: as divergence: no slew or modal amplitude comes near it, and it leaves room for the products
#: (energies, x²) to stay finite
DIVERGENCE_BOUND = 1e12


class SimulationDiverged(ValueError):
    """A simulation stopped because its state or command became non-finite or unbounded.

    Attributes
    ----------
    cases : tuple of int
        Batch indices of the diverged cases.
    time : float
        Time of the sample where it was detected, s.
    cause : str
        The likely cause.
    """

    def __init__(self, message: str, cases: tuple[int, ...], time: float, cause: str):
        super().__init__(message)
        self.cases, self.time, self.cause = cases, time, cause


def _diverged(x, u_cmd, time: float, k: int, state_prev: float, config: SimConfig
              ) -> SimulationDiverged:
    """The exception for a divergence found at sample ``k``: which cases, when, likely why."""
    bad_state = ~(np.abs(x) <= DIVERGENCE_BOUND).all(axis=1)
    bad_command = ~(np.abs(u_cmd) <= DIVERGENCE_BOUND)
    cases = tuple(int(i) for i in np.flatnonzero(bad_state | bad_command))
    if k == 0:
        cause = ("the initial state or the first torque command is non-finite or beyond the "
                 "bound (check the initial state, the gains and the reference)")
    elif not np.isfinite(u_cmd).all() and np.isfinite(x).all():
        cause = ("the control law returned a non-finite torque command from a finite state "
                 "(check its gains and reference)")
    else:
        cause = (f"the closed loop is unstable: the feedback gains destabilise it at the "
                 f"{config.control_rate:g} Hz control rate (a loop bandwidth near or above the "
                 f"Nyquist frequency {config.control_rate / 2:g} Hz diverges in sampled time); "
                 f"lower the gains or raise the control rate")
    growth = "" if k == 0 else (f"; the largest state entry went from {state_prev:.3g} to "
                                f"{np.abs(x).max():.3g} over the last control period")
    which = ", ".join(map(str, cases[:10])) + (" ..." if len(cases) > 10 else "")
    message = (f"simulation diverged at t = {time:.6g} s (sample {k}) in case(s) {which}: a "
               f"state entry or the torque command is non-finite or beyond "
               f"{DIVERGENCE_BOUND:g} (SI){growth}. Likely cause: {cause}.")
    return SimulationDiverged(message, cases, float(time), cause)


def _noise_streams(seeds: np.ndarray, n_samples: int) -> np.ndarray:
    """Standard normals (n_samples, n_cases, channels), case i drawn from its own seed."""
    out = np.empty((n_samples, len(seeds), N_NOISE_CHANNELS))
    for i, s in enumerate(seeds):
        out[:, i, :] = np.random.default_rng(int(s)).standard_normal((n_samples, N_NOISE_CHANNELS))
    return out


def simulate(
    plant,
    controller,
    config: SimConfig,
    n_cases: int | None = None,
    seeds=None,
    theta0=None,
    initial_state=None,
    record_states: bool = False,
) -> SimResult:
    """Run a batch of closed-loop maneuvers.

    Parameters
    ----------
    plant : HubAppendage
        Plant model (state x = [θ, q, θ', q']).
    controller : Controller
        Law evaluated at each sample on arrays of shape (n_cases,).
    config : SimConfig
    n_cases : int, optional
        Batch size; by default the size implied by the controller's parameters.
    seeds : array of int, optional
        Per-case noise seeds (default ``config.seed + arange(n_cases)``); a case run alone with
        its seed reproduces its batch result.
    theta0 : float or array, optional
        Initial hub angle (at rest, undeformed); default the reference start or 0.
    initial_state : array (n_x,) or (n_cases, n_x), optional
        Full initial state [θ, q, θ', q'] instead of rest at ``theta0``.
    record_states : bool
        Also store the full state history (n_cases × n_t × n_x).

    Raises
    ------
    ValueError
        Before the run, for a non-finite ``theta0`` or ``initial_state``, or a run beyond the
        limits of :mod:`flexsat.limits` (:func:`check_resources`).
    SimulationDiverged
        When a state entry or the torque command becomes non-finite or exceeds
        :data:`DIVERGENCE_BOUND`: no result with NaN is returned.
    """
    nc = controller.n_cases if n_cases is None else require_count(n_cases, "n_cases")
    dt, n = config.dt, config.n_steps
    substeps = check_resources(plant, config, nc, record_states)
    seeds = config.seed + np.arange(nc) if seeds is None else np.asarray(seeds, int).reshape(nc)
    ref = controller.reference
    if theta0 is None:
        theta0 = ref.theta0 if ref is not None else 0.0
    theta0 = np.broadcast_to(require_finite(theta0, "theta0", "rad"), (nc,)).copy()

    A, Bu, Bf = plant.state_space
    friction = config.friction
    nonlinear = friction.active or plant.stiffening
    # friction alone acts on the hub dof only: a rank-1 force keeps the substeps cheap; a
    # linear run needs no force columns (the smallest exponential)
    Bf_used = None if not nonlinear else Bf if plant.stiffening else Bf[:, :1]
    stepper = ExponentialStepper.build(A, Bu, Bf_used, dt, substeps)
    ndof = plant.ndof
    impulse_velocity = plant.mass_inverse[:, 0]

    def friction_torque(x):
        return friction(x[:, ndof]) if friction.active else np.zeros(x.shape[0])

    def force(x, w):
        tau = friction_torque(x)
        if not plant.stiffening:
            return tau[:, None]
        f = plant.nonlinear_force(x, w + tau)
        f[:, 0] += tau
        return f

    x = np.zeros((nc, plant.nx))
    x[:, 0] = theta0
    if initial_state is not None:
        x[:] = require_finite(initial_state, "initial_state")
        theta0 = x[:, 0].copy()
    noise = _noise_streams(seeds, n + 1)
    sensor_state = SensorState(config.sensors, theta0, dt)
    cstate = controller.initial_state(nc)
    impulses = config.impulses.at_samples(n + 1, dt)
    t = dt * np.arange(n + 1)
    controller.tabulate_reference(t)

    names = ("theta", "theta_dot", "theta_ref", "theta_dot_ref", "torque_command", "torque",
             "disturbance_torque", "friction_torque", "root_torque", "root_torque_measured",
             "tip_deflection", "energy", "vibration_energy")
    rec = {k: np.empty((n + 1, nc)) for k in names}
    states = np.empty((n + 1, nc, plant.nx)) if record_states else None
    w_prev = np.zeros(nc)
    state_prev = 0.0
    for k in range(n + 1):
        if k in impulses:
            x[:, ndof:] += impulses[k] * impulse_velocity
        tau_fric = friction_torque(x)
        truth = plant.outputs(x, w_prev, np.multiply.outer(tau_fric, plant.torque_input))
        y = sensor_state.measure(truth, noise[k, :, :2])
        u_cmd, cstate = controller(t[k], y, cstate)
        u_cmd = np.broadcast_to(u_cmd, (nc,))
        # one reduction per sample (NaN fails the comparison too): a diverging run stops here
        state_size = np.abs(x).max()
        if not (state_size <= DIVERGENCE_BOUND and np.abs(u_cmd).max() <= DIVERGENCE_BOUND):
            raise _diverged(x, u_cmd, t[k], k, state_prev, config)
        state_prev = state_size
        u = config.actuator(u_cmd)
        w = u + config.random_torque.std * noise[k, :, 2]
        th_r, thd_r, _, _ = controller.reference_at(t[k])
        for key, val in (("theta", truth["theta"]), ("theta_dot", truth["theta_dot"]),
                         ("theta_ref", th_r), ("theta_dot_ref", thd_r), ("torque_command", u_cmd),
                         ("torque", u), ("disturbance_torque", w - u),
                         ("friction_torque", tau_fric), ("root_torque", truth["root_torque"]),
                         ("root_torque_measured", y["root_torque"]),
                         ("tip_deflection", truth["tip_deflection"])):
            rec[key][k] = val
        rec["energy"][k] = plant.energy(x)
        rec["vibration_energy"][k] = plant.vibration_energy(x, rec["energy"][k])
        if record_states:
            states[k] = x
        if k < n:
            x = stepper.step(x, w, force if nonlinear else None)
        w_prev = w

    result = _package(rec, states, t, controller, theta0, config, nc)
    result.dataset.attrs["substeps"] = substeps
    return result


_UNITS = {"theta": "rad", "theta_dot": "rad/s", "theta_ref": "rad", "theta_dot_ref": "rad/s",
          "torque_command": "N m", "torque": "N m", "disturbance_torque": "N m",
          "friction_torque": "N m", "root_torque": "N m", "root_torque_measured": "N m",
          "tip_deflection": "m", "energy": "J", "vibration_energy": "J"}


def _package(rec, states, t, controller, theta0, config, nc) -> SimResult:
    data = {k: (("case", "time"), v.T.copy(), {"units": _UNITS[k]}) for k, v in rec.items()}
    if states is not None:
        data["state"] = (("case", "time", "state_index"), states.transpose(1, 0, 2).copy(), {})
    ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s"}), "case": np.arange(nc)})
    target = np.broadcast_to(np.asarray(controller.target, float), (nc,))
    ref = controller.reference
    ref_end = None if ref is None else np.broadcast_to(np.asarray(ref.end_time, float), (nc,))
    metrics = maneuver_metrics(
        t, rec["theta"].T, rec["theta_dot"].T, rec["theta_dot_ref"].T, rec["torque"].T,
        rec["tip_deflection"].T, rec["vibration_energy"].T, theta0, target, ref_end,
        config.settling_band,
    )
    for key, val in metrics.items():
        ds[key] = (("case",), val, {"units": METRIC_UNITS[key]})
    ds.attrs.update(control_rate_Hz=config.control_rate, settling_band_rad=config.settling_band)
    return SimResult(ds, metrics)
