"""Sampled-data simulation of any plant under a digital control law.

The plant (:class:`~flexsat.dynamics.plant.Plant`) is continuous; the law
(:class:`~flexsat.control.base.Controller`) runs at a fixed rate and its commands are held
(zero-order hold) until the next sample. Per control sample the engine

1. applies the impulses due at this sample (Δx = B[:, j] J on input j),
2. evaluates the state-dependent input forces (bearing friction) from their driving outputs,
3. measures the channels the law reads through their sensors (:mod:`flexsat.sim.channels`),
4. calls the law, passes its commands through the actuators and adds the random disturbances,
5. propagates the plant over the period: the linear part exactly by matrix exponentials, the
   plant's nonlinear force and the input forces by an exponential Runge-Kutta scheme
   (:mod:`flexsat.sim.integrators`), or by the plant's own ``step`` (a quaternion integrator).

Everything carries a leading case axis, so a batch of maneuvers (a parameter sweep, a Monte
Carlo set, a dispersed plant) is one call with no per-case Python loop in the time loop. The
recorded outputs and energies are computed per chunk of samples after the fact
(:mod:`flexsat.sim.recording`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from flexsat.dynamics.plant import find_channel
from flexsat.input_checks import require_count, require_finite
from flexsat.sim import compiled as compiled_path
from flexsat.sim import compiled_attitude as attitude_path
from flexsat.sim import integrators
from flexsat.sim.channels import (
    input_impulses,
    noise_column,
    noise_columns,
    resolve_channels,
)
from flexsat.sim.compiled_arguments import CompiledRun
from flexsat.sim.config import FRICTION_STEP_LIMIT, SimConfig, check_resources, stable_substeps
from flexsat.sim.hardware import HardwareLaw, HardwarePlant
from flexsat.sim.instruments import InputForces, Instruments, unit_row
from flexsat.sim.recording import CHUNK, Recorder, SimResult

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.base import Controller
    from flexsat.dynamics.plant import Plant
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.sim.step import Values
    from flexsat.units import FloatArray

    #: a force term f(x, w) of the propagators: states (n_cases, n_x) and inputs (n_cases, m)
    Force = Callable[[FloatArray, FloatArray], FloatArray]

#: a state entry (rad, rad/s, modal coordinates) or a command (SI) beyond this is taken as
#: divergence: no slew or modal amplitude comes near it, and it leaves room for the products
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

    def __init__(self, message: str, cases: tuple[int, ...], time: float, cause: str) -> None:
        super().__init__(message)
        self.cases, self.time, self.cause = cases, time, cause


def divergence_error(
    x: FloatArray, u_cmd: FloatArray, time: float, k: int, state_prev: float, config: SimConfig
) -> SimulationDiverged:
    """The exception for a divergence found at sample ``k``: which cases, when, likely why."""
    bad_state = ~(np.abs(x) <= DIVERGENCE_BOUND).all(axis=1)
    bad_command = ~(np.abs(u_cmd) <= DIVERGENCE_BOUND).all(axis=1)
    cases = tuple(int(i) for i in np.flatnonzero(bad_state | bad_command))
    if k == 0:
        cause = (
            "the initial state or the first torque command is non-finite or beyond the "
            "bound (check the initial state, the gains and the reference)"
        )
    elif not np.isfinite(u_cmd).all() and np.isfinite(x).all():
        cause = (
            "the control law returned a non-finite torque command from a finite state "
            "(check its gains and reference)"
        )
    else:
        cause = (
            f"the closed loop is unstable: the feedback gains destabilise it at the "
            f"{config.control_rate:g} Hz control rate (a loop bandwidth near or above the "
            f"Nyquist frequency {config.control_rate / 2:g} Hz diverges in sampled time); "
            f"lower the gains or raise the control rate"
        )
    growth = (
        ""
        if k == 0
        else (
            f"; the largest state entry went from {state_prev:.3g} to "
            f"{np.abs(x).max():.3g} over the last control period"
        )
    )
    message = (
        f"simulation diverged at t = {time:.6g} s (sample {k}) in case(s) {_listed(cases)}: a "
        f"state entry or the torque command is non-finite or beyond "
        f"{DIVERGENCE_BOUND:g} (SI){growth}. Likely cause: {cause}."
    )
    return SimulationDiverged(message, cases, float(time), cause)


def _listed(cases: tuple[int, ...]) -> str:
    return ", ".join(map(str, cases[:10])) + (" ..." if len(cases) > 10 else "")


def offset_cases(exc: SimulationDiverged, offset: int) -> SimulationDiverged:
    """``exc`` with its cases counted from ``offset``: a divergence in a chunk of a larger batch
    (cases ``offset`` onwards) named by the batch's case numbers, in ``cases`` and the message."""
    cases = tuple(offset + c for c in exc.cases)
    message = str(exc).replace(
        f"in case(s) {_listed(exc.cases)}:", f"in case(s) {_listed(cases)}:", 1
    )
    return SimulationDiverged(message, cases, exc.time, exc.cause)


class _NoiseStreams:
    """Standard normals per case, drawn chunk by chunk from each case's own generator (the
    same numbers as one draw of the whole run: the generator fills its output in order)."""

    def __init__(self, seeds: Iterable[int | np.integer[Any]], width: int) -> None:
        self.rngs = [np.random.default_rng(int(s)) for s in seeds]
        self.width = width

    def next(self, rows: int) -> np.ndarray:
        out = np.empty((rows, len(self.rngs), self.width))
        for i, rng in enumerate(self.rngs):
            out[:, i, :] = rng.standard_normal((rows, self.width))
        return out


def build_stepper(
    kind: str,
    A: FloatArray,
    B: FloatArray,
    Bf: FloatArray | None,
    dt: float,
    substeps: int,
) -> integrators.ExponentialStepper | integrators.ExpRK4Stepper:
    """The propagator of a run: Krogstad's ``exp_rk4`` for a plant asking for it with a force,
    else the exact linear step with ETD2RK for the force columns ``Bf`` (None: linear)."""
    if kind not in integrators.INTEGRATORS:
        raise ValueError(
            f"integrator: must be one of {', '.join(integrators.INTEGRATORS)}, got {kind!r}"
        )
    if kind == "exp_rk4" and Bf is not None:
        return integrators.ExpRK4Stepper.build(A, B, Bf, dt, substeps)
    return ExponentialStepper.build(A, B, Bf, dt, substeps)


#: the linear propagator class (a module name, so a test can swap its construction)
ExponentialStepper = integrators.ExponentialStepper


def _noise_streams(
    seeds: Iterable[int | np.integer[Any]], n_samples: int, width: int = 3
) -> np.ndarray:
    """Standard normals (n_samples, n_cases, width) of the whole run at once, case i from its
    seed: the numbers the loop draws chunk by chunk (benchmarks replay them)."""
    return _NoiseStreams(seeds, width).next(n_samples)


def check_law(plant: Plant, controller: Controller) -> None:
    """Check the law's ``reads`` and ``writes`` against the plant's channels.

    Raises
    ------
    ValueError
        Naming the channel: a measurement the plant does not have, an unknown input channel, a
        channel written twice.
    """
    law = type(controller).__name__
    for field, role in (("reads", "measurement"), ("writes", "input")):
        declared = getattr(controller, field, None)
        if not isinstance(declared, (tuple, list)) or not all(
            isinstance(name, str) for name in declared
        ):
            raise ValueError(
                f"{field}: {law} declares no {role} channels (set {field} = a tuple of the "
                f"plant's channel names on the law; got {declared!r})"
            )
    reads, writes = tuple(controller.reads), tuple(controller.writes)
    for name in reads:
        try:
            find_channel(plant.outputs, name, "output", type(plant).__name__)
        except ValueError as exc:
            raise ValueError(
                f"{name}: {law} reads a measurement the plant does not have ({exc})"
            ) from None
    for name in writes:
        try:
            find_channel(plant.inputs, name, "input", type(plant).__name__)
        except ValueError as exc:
            raise ValueError(f"{name}: {law} writes an unknown input channel ({exc})") from None
    if len(set(writes)) != len(writes) or not writes:
        raise ValueError(f"writes: {law} must write each input channel once, got {writes!r}")


def _commands(
    cmd: FloatArray | Mapping[str, FloatArray],
    writes: tuple[str, ...],
    shapes: list[tuple[int, ...]],
    nc: int,
    law: str,
    check: bool,
) -> list[np.ndarray]:
    """The law's commands as one array per written channel, shape (n_cases,) or (n_cases, w);
    on the first sample (``check``) a wrong shape, key or type is a ValueError naming it."""
    if not isinstance(cmd, Mapping):
        if len(writes) != 1 and check:
            raise ValueError(
                f"{writes[0]}: {law} returned a bare array but writes "
                f"{len(writes)} channels {writes!r}; return a dict"
            )
        cmd = {writes[0]: cmd}
    elif check and set(cmd) != set(writes):
        odd = sorted(set(cmd) ^ set(writes))[0]
        raise ValueError(
            f"{odd}: {law} returned commands for {sorted(cmd)!r} but writes {list(writes)!r}"
        )
    out = []
    for name, shape in zip(writes, shapes):
        c = np.asarray(cmd[name], float)
        if c.shape != shape:
            try:
                c = np.broadcast_to(c, shape)
            except ValueError:
                raise ValueError(
                    f"{name}: {law} returned a command of shape {c.shape}, "
                    f"expected {shape} (n_cases × channel size)"
                ) from None
        out.append(c)
    return out


def _initial_state(
    plant: Plant, nc: int, initial_state: npt.ArrayLike | None, ref: TorqueShape | None
) -> tuple[FloatArray, FloatArray | None]:
    """(x0, start angle per case or None): the given state, else the plant's rest state, a
    maneuver plant's angle (:attr:`~flexsat.dynamics.plant.Plant.maneuver`) at the start of
    the law's reference; the start angle is that of a maneuver plant's angle coordinate."""
    x = np.array(np.broadcast_to(plant.initial_state(nc), (nc, plant.nx)))
    axis = plant.maneuver
    row = None if axis is None else unit_row(plant, axis.angle)
    if initial_state is not None:
        x0 = require_finite(initial_state, "initial_state")
        try:
            x[:] = x0
        except ValueError:
            raise ValueError(
                f"initial_state: must have shape ({plant.nx},) or ({nc}, "
                f"{plant.nx}), got {x0.shape}"
            ) from None
    elif row is not None and ref is not None:
        x[:, row] = np.broadcast_to(require_finite(ref.theta0, "reference.theta0", "rad"), (nc,))
    return x, (x[:, row].copy() if row is not None else None)


def _propagator(
    plant: Plant,
    A: FloatArray,
    B: FloatArray,
    forces: InputForces,
    nc: int,
    batched: bool,
    dt: float,
    substeps: int,
) -> tuple[integrators.ExponentialStepper | integrators.ExpRK4Stepper, Force | None]:
    """(stepper, force) of a plant propagated by the exponential integrators: the force
    columns are the plant's B_f and the columns of B of the inputs with a force (friction),
    rank-1 for the bearing; ``force`` is None for a linear run (the exact step alone)."""
    Bf = plant.force_matrix if plant.nonlinear else None
    cols = [Bf] if Bf is not None else []
    if forces.cols:
        cols.append(B[..., :, forces.cols])
    if batched:  # a dispersed plant: every column block per case
        cols = [c if c.ndim == 3 else np.broadcast_to(c, (nc,) + c.shape) for c in cols]
    Bf_all = np.concatenate(cols, axis=-1) if cols else None
    kind = getattr(plant, "integrator", "etd2rk")
    stepper = build_stepper(kind, A, B, Bf_all, dt, substeps if Bf_all is not None else 1)
    if Bf_all is None:
        return stepper, None
    if Bf is None:  # input forces only (the friction of a linear plant)
        return stepper, forces.compact
    if not forces.cols:
        return stepper, plant.nonlinear_force

    def force(xs: FloatArray, w: FloatArray) -> FloatArray:
        fc = forces.compact(xs, w)
        return np.concatenate([plant.nonlinear_force(xs, w + forces.full(fc)), fc], axis=1)

    return stepper, force


def simulate(
    plant: Plant,
    controller: Controller,
    config: SimConfig,
    n_cases: int | None = None,
    seeds: npt.ArrayLike | None = None,
    initial_state: npt.ArrayLike | None = None,
    record_states: bool = False,
    compiled: bool | None = None,
    metrics_only: bool = False,
    batch_independent: bool = False,
) -> SimResult:
    """Run a batch of closed-loop maneuvers.

    Parameters
    ----------
    plant : Plant
        Any :class:`~flexsat.dynamics.plant.Plant` (a hub + appendage model, a three-axis
        spacecraft, a dispersed batch of plants from
        :func:`~flexsat.dynamics.dispersion.stack_plants`).
    controller : Controller
        Law evaluated at each sample on arrays with a leading case axis; it reads the
        measurement channels ``controller.reads`` and writes the input channels
        ``controller.writes``.
    config : SimConfig
    n_cases : int, optional
        Batch size; by default the size implied by the controller's parameters (or the
        dispersed plant's cases).
    seeds : array of int, optional
        Per-case noise seeds (default ``config.seed + arange(n_cases)``); a case run alone with
        its seed reproduces its batch result.
    initial_state : array (n_x,) or (n_cases, n_x), optional
        Initial state (named values: ``plant.state_from(theta=0.1)``); by default the plant's
        rest state, with a maneuver plant's angle (:attr:`~flexsat.dynamics.plant.Plant.
        maneuver`) at the start of the law's reference.
    record_states : bool
        Also store the full state history (n_cases × n_t × n_x).
    compiled : bool, optional
        Which loop runs: by default (None) the compiled loop of :mod:`flexsat.sim.compiled`
        whenever the plant, the law and every sensor, actuator and disturbance have its array
        form (:func:`flexsat.sim.compiled.unsupported`; for a rigid or flexible three-axis
        spacecraft the loop of :mod:`flexsat.sim.compiled_attitude`, under a linear-form or
        attitude law: :func:`flexsat.sim.compiled_attitude.unsupported`), else this module's
        Python loop (also where a three-axis case stops in the compiled loop: the Python loop
        then raises its own error);
        False forces the Python loop, True the compiled one (a ValueError saying why when it
        cannot). Both give the same result to round-off; ``dataset.attrs["engine"]`` says
        which ran.
    metrics_only : bool
        Only the metrics are wanted (a sweep's cases): where the compiled loop can accumulate
        them in the loop (the single-axis maneuver metrics,
        :func:`flexsat.sim.compiled.run_reduced`; a three-axis spacecraft's channel and
        pointing metrics, :func:`flexsat.sim.compiled_attitude.run_metrics`) the result holds
        them without any time history (``dataset.attrs["histories"] == "none"``), a hybrid
        plant is propagated in its modal coordinates whatever the batch size (a case's
        metrics do not depend on its batch) and no history is allocated; elsewhere (or with
        ``record_states``) the full result.
    batch_independent : bool
        Propagate on a path that does not depend on the batch size: the compiled loop uses a
        plant's modal coordinates whenever it has them (by default only above a number of
        integrator steps, :func:`flexsat.sim.compiled.modal_form`), so every case's result is
        bit for bit that of the same case run alone (a sweep's chunks). ``metrics_only``
        implies it.

    Raises
    ------
    ValueError
        Before the run, naming the channel or field: a law reading a measurement the plant does
        not have or writing an unknown channel, a command of the wrong shape (first sample), a
        sensor, actuator or disturbance on a missing channel, a non-finite or misshapen
        ``initial_state``, a run beyond the limits of :mod:`flexsat.limits`.
    SimulationDiverged
        When a state entry or a command becomes non-finite or exceeds
        :data:`DIVERGENCE_BOUND`: no result with NaN is returned.
    """
    check_law(plant, controller)
    plant_cases = plant.n_cases
    if n_cases is None:
        nc = controller.n_cases if plant_cases == 1 else plant_cases
    else:
        nc = require_count(n_cases, "n_cases")
    if plant_cases != 1 and nc != plant_cases:
        raise ValueError(
            f"n_cases: the dispersed plant carries {plant_cases} cases, the batch has {nc}"
        )
    dt, n = config.dt, config.n_steps
    sensors, actuators, disturbances = resolve_channels(plant, config)
    if config.hardware is not None:  # the hardware's states appended, the law wrapped
        plant, controller, sensors, actuators, disturbances = config.hardware.apply(
            plant, controller, sensors, actuators, disturbances
        )
        check_law(plant, controller)
        if initial_state is not None:
            initial_state = plant.settled(require_finite(initial_state, "initial_state"))
    substeps = check_resources(plant, config, nc, record_states, disturbances)
    seeds = config.seed + np.arange(nc) if seeds is None else np.asarray(seeds, int).reshape(nc)
    x, theta0 = _initial_state(plant, nc, initial_state, getattr(controller, "reference", None))
    if isinstance(plant, HardwarePlant) and initial_state is None:
        x = plant.settled(x)  # the filters settled on the start angle set above
    if config.law_mode == "continuous":
        from flexsat.sim.continuous import simulate_continuous

        return simulate_continuous(
            plant,
            controller,
            config,
            nc,
            x,
            theta0,
            record_states,
            (sensors, actuators, disturbances),
        )

    A, B = plant.linear_part()
    # per-case matrices (a dispersed plant, even of one case) are applied case by case
    batched = np.ndim(A) == 3
    Bt = np.swapaxes(B, -1, -2)
    m, slices = plant.n_inputs, plant.input_slices
    columns = noise_columns(plant)
    forced = {k: d for k, d in disturbances.items() if d.force is not None}
    writes = tuple(controller.writes)
    shapes: list[tuple[int, ...]] = [
        (nc,) if slices[k].stop - slices[k].start == 1 else (nc, slices[k].stop - slices[k].start)
        for k in writes
    ]
    measured = tuple(controller.reads) + tuple(
        k
        for k in getattr(plant, "recorded_measurements", ())
        if k not in controller.reads and any(c.name == k for c in plant.outputs)
    )
    inst = Instruments(plant, measured, sensors, columns, dt, nc, batched, bool(forced))
    forces = InputForces(plant, forced, batched)
    t = dt * np.arange(n + 1, dtype=np.float64)
    if getattr(controller, "reference", None) is not None:  # laws without one may be frozen
        # a law with a reference is a slew law (flexsat.control.base.SlewLaw)
        controller.tabulate_reference(t)  # type: ignore[attr-defined]
    kept = tuple(k for k in measured if k in getattr(plant, "recorded_measurements", ()))
    job = CompiledRun(
        plant,
        controller,
        config,
        nc,
        seeds,
        x,
        theta0,
        sensors,
        actuators,
        disturbances,
        substeps,
        measured,
        kept,
    )
    if compiled is not False and attitude_path.spacecraft_kind(plant) is not None:
        reason = attitude_path.unsupported(
            plant, controller, sensors, actuators, disturbances, measured
        )
        law = None
        if reason is None and not attitude_path.attitude_law_of(controller):
            law = controller.linear_form(dt, t, nc)
            if law is None:
                reason = f"{type(controller).__name__} has no linear form"
        if reason is None and metrics_only and not record_states:
            result = attitude_path.run_metrics(job, law)
            if result is not None:
                return result
        if reason is None:
            result = attitude_path.run(job, record_states, law)
            if result is not None:
                return result
            # a case stopped (diverged, a singular law) or a mode the kernel does not take:
            # the Python loop runs, and raises its own error
        elif compiled:
            raise ValueError(f"compiled: this run cannot take the compiled loop: {reason}")
    elif compiled is not False:
        reason = compiled_path.unsupported(
            plant, controller, sensors, actuators, disturbances, measured
        )
        law = None if reason is not None else controller.linear_form(dt, t, nc)
        if reason is None and law is None:
            reason = f"{type(controller).__name__} has no linear form"
        if reason is None and metrics_only and not record_states:
            result = compiled_path.run_reduced(job, law)
            if result is not None:
                return result
        if reason is None:
            return compiled_path.run(
                job, record_states, law, always_modal=batch_independent or metrics_only
            )
        if compiled:
            raise ValueError(f"compiled: this run cannot take the compiled loop: {reason}")

    def input_force(xs: FloatArray, w: FloatArray) -> FloatArray:
        """Input-channel forces f_in (n_cases, m) at states xs."""
        return forces.full(forces.compact(xs, w))

    own_step = getattr(plant, "step", None)
    stepper, force = (
        (None, None)
        if own_step is not None
        else _propagator(plant, A, B, forces, nc, batched, dt, substeps)
    )
    # a fractional computation delay f: the previous command over f Δt, then the new one
    frac = controller.fraction if isinstance(controller, HardwareLaw) else 0.0
    split = (
        (
            _propagator(plant, A, B, forces, nc, batched, frac * dt, substeps)[0],
            _propagator(plant, A, B, forces, nc, batched, (1 - frac) * dt, substeps)[0],
        )
        if frac
        else None
    )

    impulses = input_impulses(disturbances, slices, m, n + 1, dt)
    random = [
        # d is bound (resolve_channels): its random is SI, a float or an array
        (
            slices[k],
            cast("Values", d.random),
            noise_column(columns, k, "its random disturbance", plant),
        )
        for k, d in disturbances.items()
        if np.any(d.random)
    ]
    acts = [(slices[k], actuators.get(k)) for k in writes]
    noisy = (
        bool(random)
        or any(c is not None for _, _, c in inst.plan)
        or any(d[5] is not None for d in inst.derived)
    )
    width = sum(s.stop - s.start for s in columns.values())
    streams = _NoiseStreams(seeds, width) if noisy else None

    cstate = controller.initial_state(nc)
    rec = Recorder(
        plant,
        n + 1,
        nc,
        kept,
        {k: d.force_name for k, d in forced.items()},
        record_states,
        batched,
        [k for k, d in disturbances.items() if np.any(d.random)],
    )
    law_name = type(controller).__name__
    # views the loop writes into: one history per written channel, the state slot ring
    cmd_hist = [
        rec.commands[:, :, sl.start] if sl.stop - sl.start == 1 else rec.commands[:, :, sl]
        for sl, _ in acts
    ]
    meas_hist = [(rec.measured[k], k) for k in rec.measured]
    ring = rec.states is None
    buffer, nbuf = rec.buffer, len(rec.buffer)
    single = m == 1  # one written input of size 1: u is the command column itself
    w_prev: FloatArray = np.zeros((nc, m))
    f_in: FloatArray | None = None
    prev_cmd: list[FloatArray | None] = [None] * len(acts)  # the last rate-limited commands
    state_prev = 0.0
    noise: FloatArray = np.empty((0, nc, width))  # drawn at sample 0 of a noisy run, read after
    noise_k: FloatArray | None = None
    for k in range(n + 1):
        if noisy:
            if k % CHUNK == 0:
                assert streams is not None  # made for a noisy run
                noise = streams.next(min(CHUNK, n + 1 - k))
            noise_k = noise[k % CHUNK]
        if k in impulses:
            x = x + impulses[k] @ Bt
        if forced:
            f_in = input_force(x, w_prev)
        y = inst.measure(x, w_prev, f_in, noise_k, k == 0)
        cmd, cstate = controller(t[k], y, cstate)
        cmds = _commands(cmd, writes, shapes, nc, law_name, k == 0)
        # one reduction per sample (NaN fails the comparison too): a diverging run stops here
        state_size = np.abs(x).max()
        size = np.abs(cmds[0]).max() if len(cmds) == 1 else max(np.abs(c).max() for c in cmds)
        if not (state_size <= DIVERGENCE_BOUND and size <= DIVERGENCE_BOUND):
            raise divergence_error(x, np.column_stack(cmds), t[k], k, state_prev, config)
        state_prev = state_size
        u = None if single else np.zeros((nc, m))
        for i, ((sl, act), c) in enumerate(zip(acts, cmds)):
            cmd_hist[i][k] = c
            if act is not None:
                c, prev_cmd[i] = act.apply(c, prev_cmd[i], dt)
            if single:
                u = c[:, None]
            else:
                assert u is not None  # allocated above when not single
                u[:, sl] = c if c.ndim == 2 else c[:, None]
        assert u is not None  # set by the one written channel when single (check_law: >= 1)
        w = u
        for sl, std, col in random:
            assert noise_k is not None  # a random disturbance makes the run noisy
            w = w.copy() if w is u else w
            w[:, sl] += (
                (std * noise_k[:, col])[:, None] if isinstance(col, int) else std * noise_k[:, col]
            )
        rec.applied[k] = u
        rec.disturbed[k] = w
        if forced:
            assert rec.forces is not None  # kept for the forced channels
            rec.forces[k] = f_in
        for hist, name in meas_hist:
            hist[k] = y[name]
        if ring:
            buffer[k % nbuf] = x
            if (k + 1) % nbuf == 0:
                rec.flush(k + 1)
        else:
            buffer[k] = x
        if k < n:
            if own_step is not None:
                h = dt / substeps
                for _ in range(substeps):
                    x = plant.normalize(
                        own_step(x, w if f_in is None else w + input_force(x, w), h)
                    )
            elif split is not None:
                x = split[1].step(split[0].step(x, w_prev, force), w, force)
            else:
                assert stepper is not None  # built by _propagator for a plant without own step
                x = stepper.step(x, w, force)
        w_prev = w
    rec.flush(n + 1)
    return rec.dataset(t, controller, theta0, config, substeps, engine="python")


__all__ = [
    "DIVERGENCE_BOUND",
    "FRICTION_STEP_LIMIT",
    "SimConfig",
    "SimResult",
    "SimulationDiverged",
    "check_law",
    "check_resources",
    "simulate",
    "stable_substeps",
]
