"""Sensors, actuators and disturbances per plant channel, and the planar presets mapped onto them.

A :class:`ChannelSensor` turns the true value of one output channel into its measurement, a
:class:`ChannelActuator` turns a law's command on one input channel into the applied input, and a
:class:`ChannelDisturbance` adds to one input channel: a Gaussian input held over the control
period, impulses (Δx = B[:, j] J), and a state-dependent force driven by an output (the bearing
friction τ(θ')), which the integrator treats as an extra force on that input's column of B.

The planar classes (:class:`~flexsat.sim.sensors.Sensors`, ``TorqueActuator``,
``BearingFriction``, ``RandomTorque``, ``Impulses``) stay the presets of the single-axis plants:
:func:`resolve_channels` maps them onto channels ``theta``, ``theta_dot``, ``root_torque`` and
``torque``. Values are in the channel's unit (a number in SI, a pint Quantity or a unit string),
converted when the piece is bound to its channel.

A piece is given by channel name only; its width comes from the plant's channel when it is bound
(:meth:`ChannelSensor.bind` takes the :class:`~flexsat.dynamics.plant.Channel`). On a channel one
value wide a field is a number or one per case (n_cases,); on a channel ``size`` values wide (a
three-axis torque) it is a number for every element, one per element (size,), or one per case
and element (n_cases, size), and each impulse is ``size`` values. Anything else is refused,
naming the field and the width, rather than read as one value per case.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from flexsat.dynamics.plant import Channel, Plant, find_channel
from flexsat.input_checks import FieldError, require_count
from flexsat.sim.disturbances import impulses_at_samples
from flexsat.sim.sensors import least_squares_derivative_weights
from flexsat.sim.step import quantised, rate_limited, saturated
from flexsat.units import to_si_array

if TYPE_CHECKING:
    from flexsat.sim.config import SimConfig
    from flexsat.sim.step import Values
    from flexsat.units import FloatArray, QuantityArrayLike


def _si(
    value: QuantityArrayLike,
    unit: str,
    field: str,
    nonneg: bool = True,
    inf_ok: bool = False,
    size: int = 1,
) -> FloatArray | float:
    """``value`` in SI of ``unit``: finite (+inf too where it means "no limit"), >= 0 if
    ``nonneg``; shaped for a channel ``size`` values wide (see the module)."""
    v = to_si_array(value, unit, field)
    finite = np.isfinite(v) | (inf_ok & (v == np.inf))
    if not np.all(finite) or (nonneg and np.any(v < 0)):
        rule = "finite" if not nonneg else ">= 0 (inf for none)" if inf_ok else "finite and >= 0"
        raise FieldError(field, f"must be {rule}, got {value!r}")
    if v.ndim == 0:
        return float(v)
    if size == 1 and v.ndim != 1:
        raise FieldError(
            field,
            f"the channel is one value wide: give a number or one per case, got shape {v.shape}",
        )
    if size > 1 and not (v.ndim in (1, 2) and v.shape[-1] == size):
        raise FieldError(
            field,
            f"the channel is {size} values wide: give a number, {size} values (one "
            f"per element) or (n_cases, {size}), got shape {v.shape}",
        )
    return v


def _rate_unit(unit: str) -> str:
    return f"({unit})/s" if unit else "1/s"


def _impulse_unit(unit: str) -> str:
    return f"({unit})*s" if unit else "s"


@dataclass(frozen=True)
class ChannelSensor:
    """Measurement of one output channel: y = sat(Q(v + bias + noise·n)), n standard normal.

    Parameters
    ----------
    noise : float
        1σ white noise per sample, in the channel's unit (gyro, strain gauge).
    bias : float
        Constant offset, channel unit.
    quantum : float
        Quantization step (an encoder's resolution), channel unit; 0 for none.
    range : float
        Saturation |y| <= range, channel unit; inf for none.
    derivative_of : str, optional
        Measure this channel as the least-squares derivative (:func:`~flexsat.sim.sensors.
        least_squares_derivative_weights`) of the *measured* channel named here over its last
        ``window`` samples with a polynomial of degree ``order`` (a rate from an encoder).
    """

    noise: QuantityArrayLike = 0.0
    bias: QuantityArrayLike = 0.0
    quantum: QuantityArrayLike = 0.0
    range: QuantityArrayLike = np.inf
    derivative_of: str | None = None
    window: int = 8
    order: int = 1
    # which operations act, set by bind; not an __init__ argument, so a copy made by replace
    # is unbound again
    _acts: tuple[bool, bool, int, bool] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        require_count(self.window, "window")
        require_count(self.order, "order")
        least_squares_derivative_weights(self.window, self.order, 1.0)

    def bind(self, channel: Channel) -> ChannelSensor:
        """A copy with every field in SI of ``channel``'s unit, shaped for its width."""
        f, unit, w = f"sensors[{channel.name}]", channel.unit, channel.size
        noise = _si(self.noise, unit, f"{f}.noise", size=w)
        bias = _si(self.bias, unit, f"{f}.bias", nonneg=False, size=w)
        quantum = _si(self.quantum, unit, f"{f}.quantum", size=w)
        range_ = _si(self.range, unit, f"{f}.range", inf_ok=True, size=w)
        out = replace(self, noise=noise, bias=bias, quantum=quantum, range=range_)
        if np.any(np.asarray(range_) <= 0):
            raise FieldError(f"{f}.range", f"must be > 0 (inf for none), got {self.range!r}")
        # which operations act, decided once: the sample loop skips the others
        object.__setattr__(
            out,
            "_acts",
            (
                bool(np.any(bias)),
                bool(np.any(noise)),
                # 2: some elements (cases) without a quantiser, 1: all with one
                0 if not np.any(quantum) else 1 if np.all(np.asarray(quantum) > 0) else 2,
                bool(np.any(np.isfinite(range_))),
            ),
        )
        return out

    def measure(self, v: FloatArray, noise: FloatArray | float) -> FloatArray:
        """Measured value from v (the truth, or the derivative filter's output); a bound
        sensor (:meth:`bind`) only."""
        bias, noisy, quantized, ranged = self._acts
        # bound (the precondition above): bind left every field in SI, a float or an array
        if bias:
            v = v + cast("Values", self.bias)
        if noisy:
            v = v + cast("Values", self.noise) * noise
        if quantized == 1:
            v = quantised(v, cast("Values", self.quantum))
        elif quantized:  # a zero quantum reads the value itself (as the compiled loop does)
            q = cast("Values", self.quantum)
            v = np.where(q > 0, quantised(v, np.where(q > 0, q, 1.0)), v)
        if ranged:
            v = saturated(v, cast("Values", self.range))
        return v


@dataclass(frozen=True)
class ChannelActuator:
    """Applied input u = scale · sat(rate_limit(command)) + bias on one input channel.

    Parameters
    ----------
    saturation : float or array
        Largest magnitude, channel unit (per case when an array); inf for none.
    rate_limit : float
        Largest change per second of the (saturated) command, channel unit / s; inf for none.
    scale : float
        Scale factor (actual over nominal gain, e.g. of a motor's torque constant).
    bias : float
        Constant offset, channel unit.
    """

    saturation: QuantityArrayLike = np.inf
    rate_limit: QuantityArrayLike = np.inf
    scale: QuantityArrayLike = 1.0
    bias: QuantityArrayLike = 0.0
    # which operations act, set by bind; not an __init__ argument, so a copy made by replace
    # is unbound again
    _acts: tuple[bool, bool, bool] = field(init=False, repr=False, compare=False)

    def bind(self, channel: Channel) -> ChannelActuator:
        """A copy with every field in SI of ``channel``'s unit, shaped for its width."""
        f, unit, w = f"actuators[{channel.name}]", channel.unit, channel.size
        saturation = _si(self.saturation, unit, f"{f}.saturation", inf_ok=True, size=w)
        rate_limit = _si(self.rate_limit, _rate_unit(unit), f"{f}.rate_limit", inf_ok=True, size=w)
        scale = _si(self.scale, "", f"{f}.scale", size=w)
        bias = _si(self.bias, unit, f"{f}.bias", nonneg=False, size=w)
        out = replace(self, saturation=saturation, rate_limit=rate_limit, scale=scale, bias=bias)
        for name, value in (
            ("saturation", saturation),
            ("rate_limit", rate_limit),
            ("scale", scale),
        ):
            if np.any(np.asarray(value) <= 0):
                raise FieldError(f"{f}.{name}", f"must be > 0, got {getattr(self, name)!r}")
        object.__setattr__(
            out,
            "_acts",
            (
                bool(np.any(np.isfinite(rate_limit))),
                bool(np.any(np.isfinite(saturation))),
                bool(np.any(bias)),
            ),
        )
        return out

    def apply(
        self, command: FloatArray, previous: FloatArray | None, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        """(applied input, limited command) of a bound actuator (:meth:`bind`); ``previous``
        is the last limited command (None at the first sample: the rate limit starts there)."""
        limited, clipped, biased = self._acts
        # bound (the precondition above): bind left every field in SI, a float or an array
        c = command
        if limited and previous is not None:
            c = rate_limited(c, previous, cast("Values", self.rate_limit) * dt)
        if clipped:
            c = saturated(c, cast("Values", self.saturation))
        u = cast("Values", self.scale) * c
        return (u + cast("Values", self.bias) if biased else u), c


@dataclass(frozen=True)
class ChannelDisturbance:
    """Disturbances on one input channel.

    Parameters
    ----------
    random : float
        1σ of a zero-mean Gaussian input held over each control period, channel unit.
    impulse_times, impulses : sequences
        Impulses (channel unit × s) at these times (s), each applied as Δx = B[:, j] J at the
        first control sample at or after its time; on a channel ``size`` values wide each
        impulse is ``size`` values (one per element).
    force : callable, optional
        State-dependent input force f(y) of the output ``force_output`` (e.g.
        :class:`~flexsat.sim.disturbances.BearingFriction` of θ'), integrated with the plant as
        an extra force on this input's column; a ``max_slope`` attribute (|∂f/∂y|) lets the
        engine keep the explicit treatment stable (:func:`flexsat.sim.config.stable_substeps`).
    force_output : str, optional
        Output channel driving ``force``.
    force_name : str
        Prefix of its recorded history (``friction`` → ``friction_torque``).
    """

    random: QuantityArrayLike = 0.0
    # each a number, a unit string or a Quantity (to_si_array reads the list); SI once bound
    impulse_times: Sequence[Any] = ()
    impulses: Sequence[Any] = ()
    force: Callable[[FloatArray], FloatArray] | None = None
    force_output: str | None = None
    force_name: str = "friction"

    def __post_init__(self) -> None:
        if (self.force is None) != (self.force_output is None):
            raise FieldError(
                "force_output", "give the output channel driving the force, and only with a force"
            )
        if self.force is not None and not callable(self.force):
            raise FieldError("force", f"must be callable f(y), got {self.force!r}")

    def bind(self, channel: Channel) -> ChannelDisturbance:
        """A copy with every field in SI of ``channel``'s unit, shaped for its width."""
        f, unit, w = f"disturbances[{channel.name}]", channel.unit, channel.size
        times = np.atleast_1d(
            _si(self.impulse_times, "s", f"{f}.impulse_times")
            if len(self.impulse_times)
            else np.zeros(0)
        )
        values = (
            to_si_array(self.impulses, _impulse_unit(unit), f"{f}.impulses")
            if len(self.impulses)
            else np.zeros((0,) if w == 1 else (0, w))
        )
        each = () if w == 1 else (w,)
        if times.ndim != 1 or values.shape != (times.size, *each):
            per = "one number" if w == 1 else f"{w} values (the channel is {w} values wide)"
            raise FieldError(
                f"{f}.impulses",
                f"give {per} for each of the {times.size} impulse times, got shape {values.shape}",
            )
        if not np.all(np.isfinite(values)):
            raise FieldError(f"{f}.impulses", f"must be finite, got {self.impulses!r}")
        return replace(
            self,
            random=_si(self.random, unit, f"{f}.random", size=w),
            impulse_times=tuple(times.tolist()),
            impulses=tuple(values if w > 1 else values.tolist()),
        )

    def impulses_at_samples(self, n_steps: int, dt: float) -> dict[int, float]:
        """Impulse per control-sample index (rounded up to the next sample;
        :func:`flexsat.sim.disturbances.impulses_at_samples`)."""
        return impulses_at_samples(self.impulse_times, self.impulses, n_steps, dt)

    @property
    def active(self) -> bool:
        return bool(np.any(self.random) or self.impulses or self.force is not None)


def _planar_presets(
    config: SimConfig,
) -> tuple[dict[str, ChannelSensor], dict[str, ChannelActuator], dict[str, ChannelDisturbance]]:
    """The single-axis presets of ``config`` as per-channel pieces (only those not ideal)."""
    s = config.sensors
    sensors: dict[str, ChannelSensor] = {}
    if s.encoder_resolution > 0:
        sensors["theta"] = ChannelSensor(quantum=s.encoder_resolution)
    if s.rate == "ls_filter":
        sensors["theta_dot"] = ChannelSensor(
            derivative_of="theta", window=s.rate_window, order=s.rate_order
        )
    elif s.rate == "gyro" and s.gyro_noise > 0:
        sensors["theta_dot"] = ChannelSensor(noise=s.gyro_noise)
    if s.strain_noise > 0:
        sensors["root_torque"] = ChannelSensor(noise=s.strain_noise)
    a = config.actuator
    actuators: dict[str, ChannelActuator] = {}
    if np.any(np.isfinite(a.saturation)) or a.torque_constant_ratio != 1.0:
        actuators["torque"] = ChannelActuator(
            saturation=a.saturation, scale=a.torque_constant_ratio
        )
    fr, imp = config.friction, config.impulses
    disturbances: dict[str, ChannelDisturbance] = {}
    d = ChannelDisturbance(
        random=config.random_torque.std,
        impulse_times=imp.times,
        impulses=imp.impulses,
        force=fr if fr.active else None,
        force_output="theta_dot" if fr.active else None,
    )
    if d.active:
        disturbances["torque"] = d
    return sensors, actuators, disturbances


def resolve_channels(
    plant: Plant, config: SimConfig
) -> tuple[dict[str, ChannelSensor], dict[str, ChannelActuator], dict[str, ChannelDisturbance]]:
    """Bound sensors, actuators and disturbances by channel name: the planar presets of
    ``config`` overridden by its ``channel_sensors``, ``channel_actuators`` and
    ``channel_disturbances``; each checked against the plant's channels.

    Raises
    ------
    ValueError
        Naming the channel, for a piece on a channel the plant does not have.
    """
    owner = type(plant).__name__
    sensors, actuators, disturbances = _planar_presets(config)
    preset = {
        **{k: "sensors" for k in sensors},
        **{k: "actuator" for k in actuators},
        **{k: "friction, random_torque, impulses" for k in disturbances},
    }
    explicit = {*config.channel_sensors, *config.channel_actuators, *config.channel_disturbances}
    sensors.update(config.channel_sensors)
    actuators.update(config.channel_actuators)
    disturbances.update(config.channel_disturbances)
    out: list[dict[str, Any]] = []  # the bound sensors, actuators and disturbances
    for pieces, role, kind in (
        (sensors, "output", ChannelSensor),
        (actuators, "input", ChannelActuator),
        (disturbances, "input", ChannelDisturbance),
    ):
        bound: dict[str, Any] = {}
        for name, piece in pieces.items():
            if not isinstance(piece, kind):
                raise FieldError(name, f"expected a {kind.__name__}, got {piece!r}")
            channels = plant.outputs if role == "output" else plant.inputs
            try:
                ch = find_channel(channels, name, role, owner)
            except FieldError as exc:
                where = preset.get(name)
                if where is None or name in explicit:
                    raise
                raise FieldError(
                    exc.field, f"{exc.rule} — set by the planar preset config.{where}"
                ) from None
            bound[name] = piece.bind(ch)
        out.append(bound)
    sensors, actuators, disturbances = out
    for name, s in sensors.items():
        if s.derivative_of is not None:
            src = find_channel(plant.outputs, s.derivative_of, "output", owner)
            if sensors.get(src.name, ChannelSensor()).derivative_of is not None:
                raise FieldError(name, f"derivative_of {src.name!r} is itself a derivative")
    columns = noise_columns(plant)
    for name, d in disturbances.items():
        if d.force is not None:
            assert d.force_output is not None  # __post_init__: a force comes with its output
            find_channel(plant.outputs, d.force_output, "output", owner)
        if np.any(d.random):
            noise_column(columns, name, "its random disturbance", plant)
    for name, s in sensors.items():
        if np.any(s.noise):
            noise_column(columns, name, "its sensor noise", plant)
    return sensors, actuators, disturbances


def input_impulses(
    disturbances: Mapping[str, ChannelDisturbance],
    slices: Mapping[str, slice],
    m: int,
    n_t: int,
    dt: float,
) -> dict[int, FloatArray]:
    """The impulses of the channels' disturbances on the sample grid: {sample: J (m,)}, the
    impulses of every input channel at that sample (SI), summed where two fall on
    one sample; both loops apply Δx = B J there."""
    impulses: dict[int, FloatArray] = {}
    for k, d in disturbances.items():
        for i, J in d.impulses_at_samples(n_t, dt).items():
            impulses.setdefault(i, np.zeros(m))[slices[k]] += J
    return impulses


def noise_columns(plant: Plant) -> dict[str, slice]:
    """Columns of each noise channel in a case's stream (the plant's ``noise_channels``)."""
    out: dict[str, slice] = {}
    start = 0
    for name in plant.noise_channels:
        for channels in (plant.outputs, plant.inputs):
            ch = next((c for c in channels if c.name == name), None)
            if ch is not None:
                break
        else:
            raise FieldError(name, f"noise_channels names no channel of {type(plant).__name__}")
        out[name] = slice(start, start + ch.size)
        start += ch.size
    return out


def noise_column(columns: Mapping[str, slice], name: str, what: str, plant: Plant) -> int | slice:
    """The stream column(s) of channel ``name``, or a ValueError when it has no stream."""
    if name not in columns:
        raise FieldError(
            name,
            f"{what} needs a noise stream, but {type(plant).__name__}."
            f"noise_channels ({', '.join(columns) or 'none'}) has none for it",
        )
    sl = columns[name]
    return sl.start if sl.stop - sl.start == 1 else sl


__all__ = [
    "ChannelActuator",
    "ChannelDisturbance",
    "ChannelSensor",
    "input_impulses",
    "noise_column",
    "noise_columns",
    "resolve_channels",
]
