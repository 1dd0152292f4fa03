r"""Continuous-law mode of the engine: the law evaluated inside the integrator, at every stage.

The sampled mode of :func:`flexsat.sim.engine.simulate` holds each command over a control
period (a digital controller). Here the law is a static state feedback u = k(t, y(x)), the
closed loop

.. math::

    \dot x = A x + B\,[k(t, C x) + d(t)] + B_f\, f(x, k(t, C x) + d(t))

(the plant's split of :class:`~flexsat.dynamics.plant.Plant`; d an optional exogenous input
history) is one ordinary differential equation, integrated by the explicit Runge-Kutta pair of
Dormand & Prince of order 8(5,3) with step-size control (E. Hairer, S. P. Nørsett and G.
Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993, §II.10; scipy's
``DOP853``). Its error per unit step is held below ``atol + rtol |x|`` component-wise, so the
accuracy of a run is the tolerance's, not a sampling period's: the setting of a paper whose
controller is continuous (the tether retrieval laws, the pseudo-inverse CMG steering).

:func:`run` is the integrator of the mode (output grid, terminal stop condition, dense output,
backward integration); :func:`simulate_continuous` is what :func:`~flexsat.sim.engine.simulate`
calls for ``SimConfig(law_mode="continuous")`` and returns the usual
:class:`~flexsat.sim.recording.SimResult`.

The law reads true outputs without feedthrough (D = 0: y(x) alone), since an output depending
on the command the law computes from it is an algebraic loop; it holds no internal state
(a dynamic compensator is a sampled-data law, or states of the plant). Sensors, actuators and
channel disturbances are sampled-data pieces (noise per sample, holds, rate limits) and have no
meaning here: a run with one is refused, naming it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from flexsat import limits
from flexsat.input_checks import FieldError, require_finite, require_positive
from flexsat.sim.integrators import apply
from flexsat.sim.recording import CHUNK, Recorder, SimResult

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.base import Controller
    from flexsat.dynamics.plant import Plant
    from flexsat.sim.channels import ChannelActuator, ChannelDisturbance, ChannelSensor
    from flexsat.sim.config import SimConfig, StopCondition
    from flexsat.units import FloatArray, QuantityArrayLike

#: the law's reading of one output from the states x (n_cases, n_x)
Reader = Callable[["FloatArray"], "FloatArray"]

#: default tolerances of the mode: with them the tether's libration angles are good to ~1e-9
#: rad over a few orbits, and the gimbal angles of a CMG steering run to ~1e-9 rad
RTOL, ATOL = 1e-10, 1e-12

__all__ = ["ATOL", "RTOL", "ContinuousRun", "first_touch", "run", "simulate_continuous"]


@dataclass(frozen=True)
class ContinuousRun:
    """A closed-loop run of :func:`run`.

    Attributes
    ----------
    t : (n_t,) array
        Output times reached, s: the grid, or after a terminal stop the grid points before it
        and the stop time itself (the last sample).
    states : (n_cases, n_t, n_x) array
    inputs : (n_cases, n_t, m) array
        The plant's input along the run: the law's commands plus the exogenous input.
    commands : (n_cases, n_t, m) array
        The law's commands alone.
    stopped : bool
        Whether the stop condition ended the run before the grid's end.
    stop_time : float or None
        The first time the stop condition's margin reached 0 (also when it is not terminal),
        None if it never did.
    t_end : float
        Time the run ended (the stop's exact root, or the grid's end), s.
    x_end : (n_cases, n_x) array
        State at ``t_end``.
    solution : callable
        Dense output: ``solution(t)`` with t scalar or (k,) in [t[0], t_end] gives the states,
        (n_cases, n_x) or (k, n_cases, n_x), from the integrator's own interpolant (order 7).
    steps : (n_steps + 1,) array
        The integrator's accepted step boundaries, s (where its interpolant changes piece).
    """

    t: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    commands: np.ndarray
    stopped: bool
    stop_time: float | None
    t_end: float
    x_end: np.ndarray
    solution: Callable[[float | FloatArray], FloatArray]
    steps: np.ndarray


class _Loop:
    """The closed-loop right-hand side of one run (module docstring)."""

    def __init__(
        self,
        plant: Plant,
        controller: Controller,
        nc: int,
        exogenous: Callable[[float], FloatArray] | None,
    ) -> None:
        self.plant, self.controller, self.nc = plant, controller, nc
        self.law = type(controller).__name__
        A, B = plant.linear_part()
        self.batched = np.ndim(A) == 3
        self.At, self.Bt = np.swapaxes(A, -1, -2), np.swapaxes(B, -1, -2)
        self.force = plant.nonlinear_force if plant.nonlinear else None
        # B_f: None only for a linear plant (Plant.force_matrix)
        Bf = plant.force_matrix if plant.nonlinear else None
        self.Bft = None if Bf is None else np.swapaxes(Bf, -1, -2)
        self.m, self.slices = plant.n_inputs, plant.input_slices
        self.reads, self.writes = tuple(controller.reads), tuple(controller.writes)
        self.exogenous = exogenous
        self.zero_u = np.zeros((nc, self.m))
        # right-hand-side evaluations so far, and the most a run may take (read at its start)
        self.evaluations, self.max_evaluations = 0, limits.MAX_ADAPTIVE_EVALUATIONS
        self.t0 = 0.0
        # how each read is taken from x: state columns, a product with C, or the plant's own
        # output (called several times per integrator step: the cheap forms matter)
        self.readers: list[tuple[str, Reader]] = []
        for name in self.reads:
            mats = plant.output_matrices(name)
            if mats is not None and mats[1] is not None and np.any(mats[1]):
                raise FieldError(
                    name,
                    f"{self.law} reads an output with feedthrough from the inputs, an "
                    "algebraic loop in continuous-law mode (read the states it is made of)",
                )
            self.readers.append((name, self._reader(name, mats)))

    def _reader(
        self, name: str, mats: tuple[FloatArray, FloatArray, FloatArray | None] | None
    ) -> Reader:
        plant = self.plant
        if mats is None:
            return lambda x: plant.output(name, x, self.zero_u, None)
        C = np.asarray(mats[0], float)
        one = C.shape[-2] == 1
        if C.ndim == 2 and np.all(np.sum(C != 0, axis=1) == 1) and np.all(C.max(axis=1) == 1):
            cols = np.argmax(C, axis=1)  # rows of the identity: y = x[:, cols]
            if one:
                col = int(cols[0])
                return lambda x: x[:, col]
            return lambda x: x[:, cols]
        CT = np.swapaxes(C, -1, -2)
        if one:
            return lambda x: apply(x, CT, self.batched)[:, 0]
        return lambda x: apply(x, CT, self.batched)

    def commands(self, t: float, x: np.ndarray) -> np.ndarray:
        """The law's commands (n_cases, m) at time t and states x (n_cases, n_x)."""
        y = {name: read(x) for name, read in self.readers}
        cmd, _ = self.controller(t, y, {})
        if not isinstance(cmd, Mapping):
            cmd = {self.writes[0]: cmd}
        if set(cmd) != set(self.writes):
            raise FieldError(
                f"{sorted(set(cmd) ^ set(self.writes))[0]}",
                f"{self.law} returned commands for "
                f"{sorted(cmd)!r} but writes {list(self.writes)!r}",
            )
        u = np.zeros((self.nc, self.m))
        for name in self.writes:
            sl = self.slices[name]
            width = sl.stop - sl.start
            shape = (self.nc,) if width == 1 else (self.nc, width)
            try:
                c = np.broadcast_to(np.asarray(cmd[name], float), shape)
            except ValueError:
                raise FieldError(
                    name,
                    f"{self.law} returned a command of shape {np.shape(cmd[name])}, "
                    f"expected {shape} (n_cases × channel size)",
                ) from None
            u[:, sl] = c.reshape(self.nc, width)
        return u

    def exogenous_at(self, t: float) -> np.ndarray | None:
        return None if self.exogenous is None else self.exogenous(t)

    def input(self, t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = self.commands(t, x)
        d = self.exogenous_at(t)
        return u, (u if d is None else u + d)

    def rhs(self, t: float, flat: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        if self.evaluations > self.max_evaluations:
            # an explicit pair on a stiff loop takes steps ~1/|fastest rate|: a run that would
            # take hours is ended here, bounded in time whatever the law
            raise FieldError(
                "law_mode",
                f"the continuous-law run of {self.law} took {self.max_evaluations:,} "
                "right-hand-side evaluations, the limit (flexsat.limits."
                f"MAX_ADAPTIVE_EVALUATIONS), and had integrated only to t = {t:.6g} s "
                f"(from {self.t0:.6g} s). Likely cause: a closed loop too stiff for the "
                "adaptive integrator (a gain far too large makes its steps tiny); use smaller "
                "gains, a shorter run, or law_mode='sampled'",
            )
        x = flat.reshape(self.nc, -1)
        _, w = self.input(t, x)
        dx = apply(x, self.At, self.batched) + apply(w, self.Bt, self.batched)
        if self.force is not None:
            assert self.Bft is not None  # both set for a nonlinear plant (__init__)
            dx = dx + apply(self.force(x, w), self.Bft, self.batched)
        return dx.ravel()


def _exogenous(
    plant: Plant,
    exogenous: Callable[[float], Mapping[str, npt.ArrayLike]] | None,
    nc: int,
    t0: float,
) -> Callable[[float], FloatArray] | None:
    """``exogenous`` as t -> (n_cases, m): a callable t -> {input channel: (n_cases,) or
    (n_cases, w) or broadcastable} checked once at the start t0."""
    if exogenous is None:
        return None
    if not callable(exogenous):
        raise FieldError(
            "exogenous", f"must be a callable t -> {{channel: values}}, got {exogenous!r}"
        )
    slices, m = plant.input_slices, plant.n_inputs

    def at(t: float) -> FloatArray:
        values = exogenous(t)
        if not isinstance(values, Mapping) or not set(values) <= set(slices):
            raise FieldError(
                "exogenous",
                f"must return {{input channel: values}} with channels of "
                f"{type(plant).__name__} ({', '.join(slices)}), got {values!r}",
            )
        d = np.zeros((nc, m))
        for name, v in values.items():
            sl = slices[name]
            width = sl.stop - sl.start
            shape = (nc,) if width == 1 else (nc, width)
            d[:, sl] = np.broadcast_to(np.asarray(v, float), shape).reshape(nc, width)
        return d

    if not np.isfinite(at(t0)).all():
        raise FieldError("exogenous", f"returned a non-finite input at t = {t0:g} s")
    return at


def _grid(times: QuantityArrayLike) -> FloatArray:
    t = require_finite(times, "times", "s")
    step = np.diff(t) if t.ndim == 1 else np.zeros(0)  # read only for a 1-D grid
    if t.ndim != 1 or t.size < 2 or not (np.all(step > 0) or np.all(step < 0)):
        raise FieldError(
            "times",
            "must be a strictly monotonic 1-D grid of >= 2 times (decreasing integrates "
            f"backward), got shape {t.shape}",
        )
    return t


def run(
    plant: Plant,
    controller: Controller,
    times: QuantityArrayLike,
    initial_state: QuantityArrayLike,
    rtol: float = RTOL,
    atol: float = ATOL,
    stop: StopCondition | None = None,
    exogenous: Callable[[float], Mapping[str, npt.ArrayLike]] | None = None,
    n_cases: int | None = None,
) -> ContinuousRun:
    """Integrate the closed loop of ``plant`` under the static law ``controller`` evaluated
    at every integrator stage (module docstring).

    Parameters
    ----------
    plant : Plant
        Any plant with the protocol's split (``linear_part``, ``force_matrix``,
        ``nonlinear_force``); not one with its own ``step`` (a quaternion integrator).
    controller : Controller
        A static law (``initial_state`` empty), reading outputs without feedthrough.
    times : (n_t,) array
        Output grid, s, strictly monotonic; a decreasing grid integrates backward in time.
    initial_state : (n_x,) or (n_cases, n_x) array
        State at ``times[0]``.
    rtol, atol : float
        Local error tolerances of the DOP853 step control (> 0).
    stop : StopCondition, optional
        Where the run ends (terminal) or what time it records: the first time the margin
        reaches zero, as a terminal event located to the integrator's root-finding precision,
        and with ``touches`` also where it only touches zero between steps
        (:func:`first_touch`).
    exogenous : callable, optional
        ``exogenous(t)`` -> {input channel: values}: a known input history added to the law's
        commands (a disturbance torque of time).
    n_cases : int, optional
        Batch size; default the controller's (or the dispersed plant's).

    Returns
    -------
    ContinuousRun

    Raises
    ------
    ValueError
        Naming the field: a bad grid, state or tolerance, a law with internal state, a plant
        with its own integrator, a start where a terminal stop condition already holds, an
        output with feedthrough read, the plant leaving its model's domain
        (``plant.domain_margin`` < 0, with its ``domain_rule``) or a failed integration
        (naming the time).
    SimulationDiverged
        When a state entry passes :data:`flexsat.sim.engine.DIVERGENCE_BOUND` (an unstable
        closed loop): no result with NaN or overflow is returned.
    flexsat.input_checks.FieldError
        Naming ``law_mode``, when the run takes more right-hand-side evaluations than
        :data:`flexsat.limits.MAX_ADAPTIVE_EVALUATIONS` (a stiff closed loop), in bounded
        time.
    """
    from flexsat.sim.engine import DIVERGENCE_BOUND, SimulationDiverged, check_law

    check_law(plant, controller)
    if getattr(plant, "step", None) is not None:
        raise FieldError(
            "law_mode",
            f"{type(plant).__name__} propagates itself (its own step on a manifold); "
            "continuous-law mode needs the protocol's split: use the sampled mode",
        )
    nc = n_cases or (controller.n_cases if plant.n_cases == 1 else plant.n_cases)
    if controller.initial_state(nc):
        raise FieldError(
            "law_mode",
            f"{type(controller).__name__} has an internal state; continuous-law mode "
            "takes a static state feedback (run a dynamic law in the sampled mode)",
        )
    t = _grid(times)
    rtol = float(require_positive(rtol, "rtol"))
    atol = float(require_positive(atol, "atol"))
    x0 = require_finite(initial_state, "initial_state")
    try:
        x0 = np.array(np.broadcast_to(x0, (nc, plant.nx)), float)
    except ValueError:
        raise FieldError(
            "initial_state", f"must have shape ({plant.nx},) or ({nc}, {plant.nx}), got {x0.shape}"
        ) from None
    loop = _Loop(plant, controller, nc, _exogenous(plant, exogenous, nc, float(t[0])))
    loop.t0 = float(t[0])

    # solve_ivp reads an event's ``terminal`` and ``direction`` from attributes of the function
    # (its documented interface), which a Callable type does not declare
    def diverging(_t: float, flat: FloatArray) -> float:
        return DIVERGENCE_BOUND - float(np.max(np.abs(flat)))

    diverging.terminal = True  # type: ignore[attr-defined]
    events: list[Callable[[float, FloatArray], float]] = [diverging]
    margin = getattr(plant, "domain_margin", None)
    if margin is not None:
        if np.min(margin(x0)) <= 0:
            # a plant with a domain_margin states its domain_rule (Plant's optional pair)
            raise FieldError("initial_state", f"{plant.domain_rule}")  # type: ignore[attr-defined]

        def left_domain(_t: float, flat: FloatArray) -> float:
            return float(np.min(margin(flat.reshape(nc, -1))))

        left_domain.terminal = True  # type: ignore[attr-defined]
        events.append(left_domain)
    if stop is not None:
        if stop.terminal and _margin(stop, t[:1], x0[None])[0] <= 0:
            raise FieldError("initial_state", f"the run would stop at its start: {stop.reason}")

        def stopped(t_: float, flat: FloatArray) -> float:
            return float(_margin(stop, np.array([t_]), flat.reshape(1, nc, -1))[0])

        stopped.terminal = stop.terminal  # type: ignore[attr-defined]
        stopped.direction = -1  # type: ignore[attr-defined]
        events.append(stopped)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        sol = solve_ivp(
            loop.rhs,
            (t[0], t[-1]),
            x0.ravel(),
            method="DOP853",
            t_eval=t,
            rtol=rtol,
            atol=atol,
            events=events,
            dense_output=True,
        )
    if sol.t_events[0].size:
        at = float(sol.t_events[0][0])
        x_at = sol.y_events[0][0].reshape(nc, -1)
        cases = tuple(int(i) for i in np.flatnonzero(np.abs(x_at).max(axis=1) >= DIVERGENCE_BOUND))
        raise SimulationDiverged(
            f"simulation diverged at t = {at:.6g} s in case(s) {cases}: a state entry passed "
            f"{DIVERGENCE_BOUND:g} (SI). Likely cause: the closed loop is unstable (check the "
            "law's gains and signs)",
            cases,
            at,
            "the closed loop is unstable",
        )
    if sol.status == -1:
        at = sol.t[-1] if len(sol.t) else t[0]  # a failed first step records no time
        raise FieldError("times", f"the integration failed at t = {at:.6g} s: {sol.message}")
    if margin is not None and sol.t_events[1].size:
        raise ValueError(
            f"{plant.domain_rule} at t = {sol.t_events[1][0]:.3g} s (the run ends there)"  # type: ignore[attr-defined]
        )
    dense = sol.sol

    def solution(tq: float | FloatArray) -> FloatArray:
        z = dense(tq)
        return z.reshape(nc, -1) if np.ndim(tq) == 0 else z.T.reshape(-1, nc, plant.nx)

    stop_time = None
    if stop is not None:
        if sol.t_events[-1].size:
            stop_time = float(sol.t_events[-1][0])
        if stop.touches:
            touch = first_touch(stop, solution, dense.ts)
            if touch is not None and (
                stop_time is None or abs(touch - t[0]) < abs(stop_time - t[0])
            ):
                stop_time = touch
    t_out, y = sol.t, sol.y.T.reshape(-1, nc, plant.nx)
    stopped_early = stop is not None and stop.terminal and stop_time is not None
    if stopped_early:
        assert stop_time is not None  # stopped_early says so
        t_end, x_end = stop_time, solution(stop_time)
        before = (t_out - t_end) * np.sign(t[-1] - t[0]) < 0
        t_out = np.append(t_out[before], t_end)
        y = np.concatenate([y[before], x_end[None]])
    else:
        t_end, x_end = float(t[-1]), y[-1]
    n_t = t_out.size
    states = np.ascontiguousarray(np.swapaxes(y, 0, 1))
    commands = np.empty((nc, n_t, loop.m))
    inputs = np.empty((nc, n_t, loop.m))
    for k, tk in enumerate(t_out):
        commands[:, k], inputs[:, k] = loop.input(float(tk), states[:, k])
    if not (np.isfinite(states).all() and np.isfinite(inputs).all()):
        raise FieldError("times", "the run left finite values (a diverging closed loop)")
    return ContinuousRun(
        t_out, states, inputs, commands, stopped_early, stop_time, t_end, x_end, solution, dense.ts
    )


def _margin(stop: StopCondition, t: FloatArray, x: FloatArray) -> FloatArray:
    """The stop condition's margin at times t (k,) and states x (k, n_cases, n_x), checked."""
    value = np.asarray(stop.margin(t, x), float)
    if value.shape != t.shape:
        raise FieldError(
            "stop.margin", f"must return one value per time, shape {t.shape}, got {value.shape}"
        )
    return value


def first_touch(
    stop: StopCondition,
    solution: Callable[[FloatArray], FloatArray],
    steps: FloatArray,
) -> float | None:
    """The first time the margin of ``stop`` touches zero between the integrator's steps
    ``steps`` on the dense output ``solution`` (t (k,) -> (k, n_cases, n_x)), or None.

    A terminal event sees only sign changes of the margin at the integrator's steps. A margin
    that is a product of squares (det(CCᵀ) of a CMG cluster, where the steering passes a
    singular set with finite rates) may only touch zero inside a step: so the dense output is
    sampled 8 points a step, a sampled value <= 0 bracketed by Brent's method (R. P. Brent,
    *Algorithms for Minimization without Derivatives*, Prentice-Hall 1973, ch. 4), and every
    sampled local minimum refined by bounded Brent minimisation (ibid., ch. 5) and bracketed
    when it reaches 0.
    """
    grid = np.concatenate(
        [np.linspace(t0, t1, 9)[:-1] for t0, t1 in zip(steps[:-1], steps[1:])] + [steps[-1:]]
    )

    def excess(tq: float) -> float:
        return float(_margin(stop, np.array([tq]), solution(np.array([tq])))[0])

    vals = _margin(stop, grid, solution(grid))
    if vals[0] <= 0:  # held at the start (a run that does not stop there)
        return float(grid[0])
    for j in range(1, grid.size):
        if vals[j] <= 0:
            lo, hi = sorted((grid[j - 1], grid[j]))
            return float(brentq(excess, lo, hi, xtol=1e-14))
        if j + 1 < grid.size and vals[j] <= vals[j - 1] and vals[j] <= vals[j + 1]:
            lo, hi = sorted((grid[j - 1], grid[j + 1]))
            res = minimize_scalar(
                excess,
                bounds=(lo, hi),
                method="bounded",
                options={"xatol": 1e-12 * max(1.0, abs(hi))},
            )
            if res.fun <= 0:
                a, b = sorted((grid[j - 1], float(res.x)))
                return float(brentq(excess, a, b, xtol=1e-14))
    return None


def simulate_continuous(
    plant: Plant,
    controller: Controller,
    config: SimConfig,
    nc: int,
    x0: FloatArray,
    theta0: FloatArray | None,
    record_states: bool,
    pieces: tuple[
        Mapping[str, ChannelSensor], Mapping[str, ChannelActuator], Mapping[str, ChannelDisturbance]
    ],
) -> SimResult:
    """The continuous-law run of :func:`~flexsat.sim.engine.simulate` on the grid of
    ``config`` (0, 1/control_rate, ..., duration; the output samples), as a
    :class:`~flexsat.sim.recording.SimResult`.

    With ``config.stop`` the dataset's attributes say ``stop_reason``, ``stopped`` (1 when the
    terminal condition ended the run: its time axis then ends with the grid points before the
    stop and the stop time itself) and ``stop_time`` (the first time the condition held, NaN
    if it never did); ``config.exogenous`` is added to the commands and recorded as the
    ``disturbance_<channel>`` of each channel it drives.

    ``pieces`` are the run's bound (sensors, actuators, disturbances): any is refused (module
    docstring).
    """
    for role, bound in zip(("sensor", "actuator", "disturbance"), pieces):
        if bound:
            name = next(iter(bound))
            raise FieldError(
                name,
                f"a {role} is a sampled-data piece; continuous-law mode evaluates the "
                "law on the true outputs (use law_mode='sampled')",
            )
    t = config.dt * np.arange(config.n_steps + 1, dtype=np.float64)
    if getattr(controller, "reference", None) is not None:
        # a law with a reference is a slew law (flexsat.control.base.SlewLaw)
        controller.tabulate_reference(t)  # type: ignore[attr-defined]
    out = run(
        plant,
        controller,
        t,
        x0,
        config.rtol,
        config.atol,
        stop=config.stop,
        exogenous=config.exogenous,
        n_cases=nc,
    )
    n = out.t.size
    # the exogenous input is recorded as the disturbance of the channels it drives
    driven = () if config.exogenous is None else tuple(config.exogenous(0.0))
    rec = Recorder(plant, n, nc, (), {}, record_states, plant.n_cases != 1, driven, input_lag=0)
    rec.commands[:] = np.swapaxes(out.commands, 0, 1)
    rec.applied[:] = rec.commands
    rec.disturbed[:] = np.swapaxes(out.inputs, 0, 1)
    X = np.swapaxes(out.states, 0, 1)
    for k0 in range(0, n, CHUNK):
        end = min(n, k0 + CHUNK)
        if rec.states is not None:
            rec.states[k0:end] = X[k0:end]
        else:
            rec.buffer[: end - k0] = X[k0:end]
        rec.flush(end)
    result = rec.dataset(out.t, controller, theta0, config, 1, engine="continuous")
    if config.stop is not None:
        result.dataset.attrs.update(
            stop_reason=config.stop.reason,
            stopped=int(out.stopped),
            stop_time=np.nan if out.stop_time is None else out.stop_time,
        )
    return result
