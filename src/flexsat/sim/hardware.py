r"""Laboratory hardware in the loop: reaction wheels, amplifiers, analog anti-alias filters and
the control computer's delay, on any linear plant, run by the one engine.

Each piece is continuous linear dynamics (plus the wheel bearing's Coulomb friction and the
drive's speed limit), so the engine takes them as states appended to the plant's
(:class:`HardwarePlant`): the plant, the hardware and the filters are then propagated together
by the engine's exact matrix exponential over each control period — the analog filter's
response to the continuous plant output is exact, and on a piecewise-constant input it is the
filter's exact zero-order-hold discretisation (:func:`zoh`) — batched and compiled like an
ideal plant. The law is wrapped (:class:`HardwareLaw`) to read the filtered channels, to write
the hardware's command channels and to hold its commands for the computer's delay.

The pieces and their equations are in :mod:`flexsat.sim.hardware_models`. A wheel's hub
feels −τ, the reaction of the motor and bearing torque τ on the wheel, so the plant's hub
inertia is the body's without the wheel's spin inertia, and the body's and the wheel's momenta
sum to a constant without external torque (:meth:`HardwarePlant.momentum`). The Coulomb term
of the wheel bearing is the engine's bearing-friction force (regularised sign, ETD2RK) on an
internal input channel. A finite ``max_speed`` is the drive's speed limiter: at each sample
the command is zeroed while |Ω| >= max_speed and the command would raise |Ω|. It is a
state-dependent switch, so the Python loop runs it.

**Anti-alias filter** (:class:`AntiAliasFilter`): an analog Butterworth or Bessel low-pass of
given order and −3 dB corner on a measured channel, as in the identification test rig
(:func:`flexsat.identify.excitation.with_anti_alias`); the law reads ``<channel>_filtered``
and the truth stays recorded under the channel's own name.

**Computation delay** (:attr:`Hardware.delay`, samples): whole samples hold the law's command
in a FIFO (the linear form gains a shift register, so the compiled loop keeps it); a fraction
f of a sample applies the previous command over the first f·Δt of each period (the Python
loop, with two exact steps).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Channel, ManeuverChannels, Plant, find_channel
from flexsat.input_checks import FieldError
from flexsat.sim.channels import ChannelActuator, ChannelDisturbance, ChannelSensor
from flexsat.sim.disturbances import BearingFriction
from flexsat.sim.hardware_models import (
    Amplifier,
    AntiAliasFilter,
    ReactionWheel,
    companion_blocks,
    zoh,
)
from flexsat.sim.wheel_array import ReactionWheelArray, WheelArrayPlant
from flexsat.units import to_si_array

if TYPE_CHECKING:
    from flexsat.control.linear_form import LinearLaw
    from flexsat.units import FloatArray

__all__ = [
    "Amplifier",
    "AntiAliasFilter",
    "Hardware",
    "HardwareLaw",
    "HardwarePlant",
    "ReactionWheel",
    "companion_blocks",
    "delayed_linear_law",
    "zoh",
]


@dataclass(frozen=True)
class Hardware:
    """The laboratory hardware of a run (:class:`~flexsat.sim.config.SimConfig` ``hardware``).

    Parameters
    ----------
    actuators : dict
        Input channel (size 1) -> :class:`ReactionWheel` or :class:`Amplifier`; a three-axis
        torque channel -> :class:`~flexsat.sim.wheel_array.ReactionWheelArray`.
    filters : dict
        Measured output channel -> :class:`AntiAliasFilter`.
    delay : float
        Computation delay, control samples (1 = the one-step-ahead command).
    """

    actuators: Mapping[str, ReactionWheel | Amplifier | ReactionWheelArray] = field(
        default_factory=dict
    )
    filters: Mapping[str, AntiAliasFilter] = field(default_factory=dict)
    delay: float = 0.0
    # the augmented plant of each plant run with this hardware (built once: a batch of runs
    # of one plant, a sweep's chunks); not an __init__ argument
    _built: dict[int, tuple[Any, HardwarePlant]] = field(
        init=False, repr=False, compare=False, default_factory=dict
    )

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the built plants (weak references: a batch sent to workers)."""
        state = dict(self.__dict__)
        state["_built"] = {}
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)

    def plant_for(self, plant: Plant) -> HardwarePlant:
        """The augmented plant of ``plant`` (built on first use, kept while ``plant`` lives)."""
        got = self._built.get(id(plant))
        if got is not None and got[0]() is plant:
            return got[1]
        inner = plant
        for k, a in self.actuators.items():
            if isinstance(a, ReactionWheelArray):
                inner = WheelArrayPlant(inner, k, a)
        hp = HardwarePlant(inner, self.driven, self.filters)
        try:
            self._built[id(plant)] = (weakref.ref(plant), hp)
        except TypeError:  # a plant without weak references: built per run
            pass
        return hp

    def __post_init__(self) -> None:
        for name, kinds, pieces in (
            ("actuators", (ReactionWheel, Amplifier, ReactionWheelArray), self.actuators),
            ("filters", (AntiAliasFilter,), self.filters),
        ):
            if not isinstance(pieces, Mapping) or not all(
                isinstance(k, str) and isinstance(v, kinds) for k, v in pieces.items()
            ):
                names = " or ".join(k.__name__ for k in kinds)
                raise FieldError(name, f"must map channel names to {names}, got {pieces!r}")
        for k, a in self.actuators.items():
            if isinstance(a, Amplifier) and a.mode == "voltage":
                raise FieldError(
                    f"actuators[{k}].mode",
                    "voltage mode needs a motor speed for the back-EMF: give the amplifier "
                    "to a ReactionWheel",
                )
        d = to_si_array(self.delay, "", "delay")
        if d.ndim != 0 or not (np.isfinite(d) and d >= 0):
            raise FieldError("delay", f"must be one number of samples >= 0, got {self.delay!r}")
        object.__setattr__(self, "delay", float(d))

    @property
    def driven(self) -> dict[str, ReactionWheel | Amplifier]:
        """The actuators with dynamics (a wheel, an amplifier with a finite bandwidth): each
        gets a drive channel and states; an instantaneous amplifier is its limit alone, on
        the channel itself."""
        return {
            k: a
            for k, a in self.actuators.items()
            if isinstance(a, ReactionWheel)
            or (isinstance(a, Amplifier) and np.isfinite(a.si("bandwidth")))
        }

    @property
    def whole_delay(self) -> int:
        return int(np.floor(float(self.delay) + 1e-12))

    @property
    def fractional_delay(self) -> float:
        f = float(self.delay) - self.whole_delay
        return 0.0 if f < 1e-12 else f

    def apply(
        self,
        plant: Plant,
        controller: Controller,
        sensors: dict[str, ChannelSensor],
        actuators: dict[str, ChannelActuator],
        disturbances: dict[str, ChannelDisturbance],
    ) -> tuple[
        HardwarePlant,
        HardwareLaw,
        dict[str, ChannelSensor],
        dict[str, ChannelActuator],
        dict[str, ChannelDisturbance],
    ]:
        """The run with this hardware: the augmented plant, the wrapped law and the bound
        sensors, actuators and disturbances moved to the channels the law now reads and
        writes (an actuator's limits on its command channel, tightened by the drive's)."""
        hp = self.plant_for(plant)
        reads = {k: f"{k}_filtered" for k in self.filters}
        writes = {k: f"{k}_drive" for k in self.driven}
        arrays = {k: a for k, a in self.actuators.items() if isinstance(a, ReactionWheelArray)}
        writes.update({k: f"{k}_wheels" for k in arrays})
        for k in arrays:
            if k in actuators:
                raise FieldError(
                    f"actuators[{k}]",
                    "a wheel array's channel takes no channel actuator (its limits are the "
                    "wheels' speed limits)",
                )
        for k in self.filters:
            if k not in controller.reads:
                raise FieldError(f"filters[{k}]", f"the law does not read {k!r}")
        for k in self.actuators:
            if k not in controller.writes:
                raise FieldError(f"actuators[{k}]", f"the law does not write {k!r}")
        s_out: dict[str, ChannelSensor] = {}
        for k, s in sensors.items():
            if s.derivative_of in reads:
                s = replace(s, derivative_of=reads[s.derivative_of])
            s_out[reads.get(k, k)] = _rebind(s, hp, reads.get(k, k), "output")
        a_out: dict[str, ChannelActuator] = {}
        for k, a in actuators.items():
            a_out[writes.get(k, k)] = a
        for k, piece in self.actuators.items():
            name = writes.get(k, k)
            a = a_out.get(name, ChannelActuator())
            if isinstance(piece, ReactionWheelArray):
                continue
            if isinstance(piece, ReactionWheel):
                amp = piece.amplifier
                limit = amp.torque_limit(piece.si("resistance"), piece.si("torque_constant"))
            else:
                limit = piece.torque_limit()
            sat = np.minimum(np.asarray(a.saturation, float), limit)
            a_out[name] = ChannelActuator(
                saturation=sat if sat.ndim else float(sat),
                rate_limit=a.rate_limit,
                scale=a.scale,
                bias=a.bias,
            ).bind(find_channel(hp.inputs, name, "input", type(hp).__name__))
        d_out = dict(disturbances)
        for k, piece in self.actuators.items():
            if isinstance(piece, ReactionWheel) and piece.si("coulomb") > 0:
                ch = find_channel(hp.inputs, f"{k}_wheel_friction", "input", "HardwarePlant")
                d_out[ch.name] = ChannelDisturbance(
                    force=BearingFriction(piece.si("coulomb"), 0.0, piece.si("smoothing")),
                    force_output=f"{k}_wheel_speed",
                    force_name="coulomb",
                ).bind(ch)
        gates: dict[str, tuple[str, Any]] = {
            writes[k]: (f"{k}_wheel_speed", p.si("max_speed"))
            for k, p in self.actuators.items()
            if isinstance(p, ReactionWheel) and np.isfinite(p.si("max_speed"))
        }
        gates.update(
            {
                writes[k]: (f"{k}_wheel_speed", np.asarray(a.max_speed, float))
                for k, a in arrays.items()
                if np.any(np.isfinite(np.asarray(a.max_speed, float)))
            }
        )
        law = HardwareLaw(
            controller,
            reads,
            writes,
            self.whole_delay,
            self.fractional_delay,
            gates,
            {writes[k]: a.distribution for k, a in arrays.items()},
        )
        return hp, law, s_out, a_out, d_out


def _rebind(s: ChannelSensor, plant: Plant, name: str, role: str) -> ChannelSensor:
    """A bound sensor re-bound on ``plant``'s channel ``name`` (same unit and width: its SI
    fields stay what they are)."""
    ch = find_channel(plant.outputs, name, role, type(plant).__name__)
    fresh = ChannelSensor(
        noise=s.noise,
        bias=s.bias,
        quantum=s.quantum,
        range=s.range,
        derivative_of=s.derivative_of,
        window=s.window,
        order=s.order,
    )
    return fresh.bind(ch)


class HardwarePlant(Plant):
    """A linear (or plant-nonlinear) plant with hardware states appended (module docstring):
    x_H = [x, hardware states, filter states]; inputs: the plant's own (disturbances act there
    directly), ``<channel>_drive`` (the law's command to the drive) per actuated channel,
    ``<channel>_wheel_friction`` per wheel with Coulomb friction; outputs: the plant's own,
    ``<channel>_filtered``, ``<channel>_wheel_speed`` (Ω, rad/s) and
    ``<channel>_motor_current`` (A)."""

    def __init__(
        self,
        plant: Plant,
        actuators: Mapping[str, ReactionWheel | Amplifier],
        filters: Mapping[str, AntiAliasFilter],
    ) -> None:
        if getattr(plant, "step", None) is not None or plant.n_cases != 1:
            raise FieldError(
                "hardware",
                f"{type(plant).__name__}: hardware needs a shared plant propagated by the "
                "engine's exponential integrators (no own step, not dispersed)",
            )
        self.inner = plant
        A, B = plant.linear_part()
        n, m = plant.nx, plant.n_inputs
        sl = plant.input_slices
        owner = type(plant).__name__
        inputs = list(plant.inputs)
        for k in actuators:
            ch = find_channel(plant.inputs, k, "input", owner)
            if ch.size != 1:
                raise FieldError(f"actuators[{k}]", f"needs a channel 1 wide, {k!r} is {ch.size}")
            inputs.append(Channel(f"{k}_drive", ch.unit, 1, f"command to the drive of {k}"))
        for k, piece in actuators.items():
            if isinstance(piece, ReactionWheel) and piece.si("coulomb") > 0:
                inputs.append(Channel(f"{k}_wheel_friction", "N*m", 1, "wheel bearing friction"))
        self.inputs = tuple(inputs)
        M = sum(c.size for c in inputs)
        col = {c.name: i for i, c in enumerate(inputs)}  # the added channels are 1 wide
        # state layout: plant, then per actuated channel its drive state and wheel speed
        idx = n
        layout: dict[str, dict[str, int]] = {}
        for k, piece in actuators.items():
            amp = piece.amplifier if isinstance(piece, ReactionWheel) else piece
            d: dict[str, int] = {}
            if np.isfinite(amp.si("bandwidth")):
                d["drive"], idx = idx, idx + 1
            if isinstance(piece, ReactionWheel):
                d["wheel"], idx = idx, idx + 1
            layout[k] = d
        filt: dict[str, tuple[int, int, AntiAliasFilter]] = {}
        for k, f in filters.items():
            ch = find_channel(plant.outputs, k, "output", owner)
            if plant.output_matrices(k) is None:
                raise FieldError(f"filters[{k}]", f"{k!r} is a nonlinear output of {owner}")
            order = f.order * ch.size
            filt[k] = (idx, order, f)
            idx += order
        N = idx
        G = np.zeros((m, N))  # the plant's input u = G x_H + H w_H (w_H without forces)
        H = np.zeros((m, M))
        H[:, :m] = np.eye(m)
        Ah = np.zeros((N, N))
        Bh = np.zeros((N, M))
        extra: dict[str, tuple[FloatArray, FloatArray]] = {}  # output rows over (x_H, w_H)
        for k, piece in actuators.items():
            j, c, d = sl[k].start, col[f"{k}_drive"], layout[k]
            amp = piece.amplifier if isinstance(piece, ReactionWheel) else piece
            wb = 2 * np.pi * amp.si("bandwidth")
            kt = (piece if isinstance(piece, ReactionWheel) else amp).si("torque_constant")
            res = piece.si("resistance") if isinstance(piece, ReactionWheel) else 1.0
            # the drive's output (current, or voltage in voltage mode) over (x_H, w_H)
            to_demand = 1.0 / kt if amp.mode == "current" else res / kt
            if isinstance(piece, ReactionWheel):  # the hub feels −τ: the motor is asked for −c
                to_demand = -to_demand
            gx, gw = np.zeros(N), np.zeros(M)
            if "drive" in d:
                s = d["drive"]
                Ah[s, s] = -wb
                Bh[s, c] = wb * to_demand
                gx[s] = 1.0
            else:
                gw[c] = to_demand
            if not isinstance(piece, ReactionWheel):
                G[j] += kt * gx
                H[j] += kt * gw
                extra[f"{k}_motor_current"] = (gx, gw)
                continue
            C_r, D_r, _ = _linear_rows(plant, piece.rate_output)
            if C_r.shape[0] != 1 or np.any(D_r):
                raise FieldError(
                    f"actuators[{k}].rate_output",
                    f"{piece.rate_output!r} must be a scalar rate read from the state alone",
                )
            w = d["wheel"]
            om_x = np.zeros(N)  # Ω = Ω_a − C_r x
            om_x[w], om_x[:n] = 1.0, -C_r[0]
            if amp.mode == "voltage":  # i = (V − K_e Ω) / R
                ix, iw = (gx - piece.si("back_emf") * om_x) / res, gw / res
            else:
                ix, iw = gx, gw
            tx = kt * ix - piece.si("viscous") * om_x  # τ over x_H
            tw = kt * iw
            if f"{k}_wheel_friction" in col:
                tw = tw.copy()
                tw[col[f"{k}_wheel_friction"]] = 1.0
            Ah[w] += tx / piece.si("inertia")
            Bh[w] += tw / piece.si("inertia")
            G[j] -= tx
            H[j] -= tw
            extra[f"{k}_wheel_speed"] = (om_x, np.zeros(M))
            extra[f"{k}_motor_current"] = (ix, iw)
        Ah[:n, :n] = A
        Ah[:n] += B @ G
        Bh[:n] += B @ H
        for k, (s, order, f) in filt.items():
            C, D, _ = _linear_rows(plant, k)
            af, bf, cf = f.matrices()
            w_ = C.shape[0]
            Af, Bf, Cf = (np.kron(np.eye(w_), a) for a in (af, bf, cf))
            Cx = np.zeros((w_, N))
            Cx[:, :n] = C
            Cx += D @ G
            Ah[s : s + order, s : s + order] = Af
            Ah[s : s + order] += Bf @ Cx
            Bh[s : s + order] += Bf @ (D @ H)
            cx = np.zeros((w_, N))
            cx[:, s : s + order] = Cf
            extra[f"{k}_filtered"] = (cx, np.zeros((w_, M)))
        self._A, self._B, self._G, self._H = Ah, Bh, G, H
        self._rows: dict[str, tuple[FloatArray, FloatArray, FloatArray | None] | None] = {}
        self._modal: list[Any] = []
        self._nx, self._n, self._m = N, n, m
        self._extra = extra
        self._filters = filt
        self._layout = layout
        self._wheels = {k: p for k, p in actuators.items() if isinstance(p, ReactionWheel)}
        outputs = list(plant.outputs)
        for name in extra:
            if name.endswith("_filtered"):
                src = find_channel(plant.outputs, name[: -len("_filtered")], "output", owner)
                outputs.append(Channel(name, src.unit, src.size, f"{src.name} after its filter"))
            elif name.endswith("_wheel_speed"):
                outputs.append(Channel(name, "rad/s", 1, "wheel speed relative to the body"))
            else:
                outputs.append(Channel(name, "A", 1, "motor current"))
        self.outputs = tuple(outputs)
        self.recorded = tuple(plant.recorded) + tuple(
            n_ for n_ in extra if n_.endswith(("_wheel_speed", "_motor_current"))
        )
        self.nonlinear = plant.nonlinear
        mv = plant.maneuver
        if mv is not None and mv.torque in actuators:
            mv = replace(mv, torque=f"{mv.torque}_drive")
        self.maneuver: ManeuverChannels | None = mv
        renamed = {k: f"{k}_filtered" for k in filters}
        self.noise_channels = tuple(renamed.get(c, c) for c in plant.noise_channels)
        self.recorded_measurements = tuple(
            renamed.get(c, c) for c in getattr(plant, "recorded_measurements", ())
        )
        self.integrator = getattr(plant, "integrator", "etd2rk")
        # without wheels the energy is the plant's: its quadratic form and momentum row,
        # padded, let the compiled loop record it in modal coordinates
        self.energy_matrix: FloatArray | None = None
        if not self._wheels:
            Q = getattr(plant, "energy_matrix", None)
            if Q is not None:
                self.energy_matrix = np.zeros((N, N))
                self.energy_matrix[:n, :n] = Q
            row, inertia = (getattr(plant, k, None) for k in ("momentum_row", "total_inertia"))
            if row is not None and inertia is not None:
                self.momentum_row = np.concatenate([np.asarray(row, float), np.zeros(N - n)])
                self.total_inertia = inertia

    # -- the Plant protocol ------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return self._nx

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        return self._A, self._B

    @property
    def force_matrix(self) -> FloatArray | None:
        Bf = self.inner.force_matrix
        if Bf is None:
            return None
        out = np.zeros((self._nx, Bf.shape[1]))
        out[: self._n] = Bf
        return out

    def plant_input(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """The wrapped plant's input u = G x_H + H w_H."""
        return x @ self._G.T + u @ self._H.T

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        return self.inner.nonlinear_force(x[..., : self._n], self.plant_input(x, u))

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        if name not in self._rows:
            self._rows[name] = self._output_matrices(name)
        return self._rows[name]

    def _output_matrices(
        self, name: str
    ) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        if name in self._extra:
            cx, cw = self._extra[name]
            cx, cw = np.atleast_2d(cx), np.atleast_2d(cw)
            return cx, cw, cw
        mats = self.inner.output_matrices(name)
        if mats is None:
            return None
        C, D, Df = mats
        Cx = np.zeros((C.shape[0], self._nx))
        Cx[:, : self._n] = C
        Cx += D @ self._G
        Dw = D @ self._H
        Dfw = np.zeros_like(Dw)
        if Df is not None:
            Dfw[:, : self._m] = Df
        Dfw[:, self._m :] = Dw[:, self._m :]
        return Cx, Dw, Dfw

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        if self.output_matrices(name) is not None:
            return super().output(name, x, u, f_in)
        fi = None if f_in is None else f_in[..., : self._m]
        return self.inner.output(name, x[..., : self._n], self.plant_input(x, u), fi)

    def settled(self, x: FloatArray) -> FloatArray:
        """``x`` (..., n_x of the plant or of this one) with the hardware at rest on it: each
        wheel spinning with the body (Ω = 0), each drive at zero, each filter at its steady
        state for the plant's output at zero input."""
        x = np.asarray(x, float)
        lift = getattr(self.inner, "settled", None)
        if x.shape[-1] < self._n and lift is not None:  # the state of the plant a wheel
            x = lift(x)  # array wraps: its wheels settled first
        out = np.zeros(x.shape[:-1] + (self._nx,))
        out[..., : self._n] = x[..., : self._n]
        for k, p in self._wheels.items():
            C_r, _, _ = _linear_rows(self.inner, p.rate_output)
            out[..., self._layout[k]["wheel"]] = out[..., : self._n] @ C_r[0]
        for k, (s, order, f) in self._filters.items():
            C, _, _ = _linear_rows(self.inner, k)
            af, bf, _ = f.matrices()
            gain = -np.linalg.solve(af, bf)[:, 0]  # z_ss per unit input
            y = out[..., : self._n] @ C.T  # (..., w)
            out[..., s : s + order] = (y[..., :, None] * gain).reshape(y.shape[:-1] + (order,))
        return out

    def initial_state(self, n_cases: int) -> FloatArray:
        return self.settled(self.inner.initial_state(n_cases))

    def momentum(self, x: FloatArray) -> FloatArray | None:
        """The plant's momentum plus each wheel's J_w Ω_a (planar plants)."""
        h = self.inner.momentum(x[..., : self._n])
        if h is None:
            return None
        for k, p in self._wheels.items():
            h = h + p.si("inertia") * x[..., self._layout[k]["wheel"]]
        return h

    def energy(self, x: FloatArray) -> FloatArray | None:
        """The plant's energy plus each wheel's ½ J_w Ω_a²."""
        e = self.inner.energy(x[..., : self._n])
        if e is None:
            return None
        for k, p in self._wheels.items():
            e = e + 0.5 * p.si("inertia") * x[..., self._layout[k]["wheel"]] ** 2
        return e

    @property
    def vibration_energy(self) -> Callable[..., FloatArray]:
        """The plant's vibration energy of x_H (the energy, which holds the wheels', is not
        used); no such attribute when the plant has none (a structure without a rigid mode:
        the engine then records none)."""
        vib = getattr(self.inner, "vibration_energy", None)
        if vib is None:
            raise AttributeError("vibration_energy")
        n = self._n

        def energy(x: FloatArray, energy: FloatArray | None = None) -> FloatArray:
            return np.asarray(vib(x[..., :n]), float)

        return energy

    def modal_form(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
        """(T, T⁻¹, ω, ζ) with x_H = T z, z in companion 2×2 blocks, for the compiled loop's
        O(n) propagation (:func:`flexsat.sim.compiled_arguments.modal_form`), or None.

        Exists when the plant has a modal form (T_p, Λ_p) and the only hardware states are
        filters whose poles come in complex pairs (even orders): with the filters' drive
        F = ∂z'/∂x and their own blocks A_F T_F = T_F Λ_F, T = [[T_p, 0], [X, T_F]] where X
        solves the Sylvester equation A_F X − X Λ_p = −F T_p (disjoint spectra: a filter pole
        is never a plant pole)."""
        from scipy.linalg import solve_sylvester

        from flexsat.sim.compiled_arguments import modal_form

        if self._modal:
            return self._modal[0]
        self._modal.append(self._modal_form(modal_form, solve_sylvester))
        return self._modal[0]

    def _modal_form(
        self, modal_form: Any, solve_sylvester: Any
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
        if any(self._layout.values()) or self.nonlinear:
            return None
        inner = modal_form(self.inner, np.inf)
        if inner is None or np.ndim(inner[0]) != 2:
            return None
        Tp, Tpi, wp, zp = (np.asarray(a, float) for a in inner)
        n = self._n
        if self._nx == n:
            return Tp, Tpi, wp, zp
        AF, F = self._A[n:, n:], self._A[n:, :n]
        blocks = companion_blocks(AF)
        if blocks is None:
            return None
        TF, TFi, wF, zF = blocks
        Lp = np.zeros((wp.size * 2, wp.size * 2))
        for i, (w, z) in enumerate(zip(wp, zp)):
            Lp[2 * i, 2 * i + 1] = 1.0
            Lp[2 * i + 1, 2 * i], Lp[2 * i + 1, 2 * i + 1] = -(w**2), -2 * z * w
        X = solve_sylvester(AF, -Lp, -F @ Tp)
        nf = self._nx - n
        T = np.zeros((self._nx, self._nx))
        Ti = np.zeros((self._nx, self._nx))
        T[:n, :n], T[n:, :n], T[n:, n:] = Tp, X, TF
        Ti[:n, :n], Ti[n:, :n], Ti[n:, n:] = Tpi, -TFi @ X @ Tpi, TFi
        assert Ti.shape == (n + nf, n + nf)
        return T, Ti, np.concatenate([wp, wF]), np.concatenate([zp, zF])

    def hardware_states(self) -> dict[str, int]:
        """Index of each hardware state: ``<channel>_drive``, ``<channel>_wheel`` (Ω_a),
        ``<channel>_filter`` (the first of its filter's)."""
        out = {f"{k}_{s}": i for k, d in self._layout.items() for s, i in d.items()}
        out.update({f"{k}_filter": s for k, (s, _, _) in self._filters.items()})
        return out


def _linear_rows(plant: Plant, name: str) -> tuple[FloatArray, FloatArray, Any]:
    mats = plant.output_matrices(name)
    if mats is None:
        raise FieldError(name, f"{type(plant).__name__}: {name!r} must be a linear output")
    C, D, Df = mats
    return np.atleast_2d(C), np.atleast_2d(D), Df


def delayed_linear_law(law: LinearLaw, samples: int) -> LinearLaw:
    r"""``law`` with its commands held ``samples`` control periods: a shift register of the
    commands appended to ξ, ξ' = [ξ, r_1 .. r_d], r_1 ← C ξ + D e, r_i ← r_{i−1}, applied
    u_k = u_ff,k−d + r_d (0 over the first d samples): the law's commands computed at k
    applied at k + d."""
    if samples == 0:
        return law
    Ak, Bk, Ck, Dk = law.Ak, law.Bk, law.Ck, law.Dk
    T = max(a.shape[0] for a in (Ak, Bk, Ck, Dk))
    C_ = max(a.shape[1] for a in (Ak, Bk, Ck, Dk))
    nk, p, m = Ak.shape[-1], Bk.shape[-1], Ck.shape[-2]
    N = nk + samples * m
    A2 = np.zeros((T, C_, N, N))
    B2 = np.zeros((T, C_, N, p))
    A2[:, :, :nk, :nk] = Ak
    B2[:, :, :nk] = Bk
    A2[:, :, nk : nk + m, :nk] = Ck
    B2[:, :, nk : nk + m] = Dk
    for i in range(1, samples):
        r0, r1 = nk + (i - 1) * m, nk + i * m
        A2[:, :, r1 : r1 + m, r0 : r0 + m] = np.eye(m)
    C2 = np.zeros((1, 1, m, N))
    C2[0, 0, :, N - m :] = np.eye(m)
    u_ff = np.zeros_like(law.u_ff)
    u_ff[samples:] = law.u_ff[:-samples]
    K0 = None
    if law.K0 is not None:
        K0 = np.zeros((law.K0.shape[0], N, p))
        K0[:, :nk] = law.K0
    return replace(
        law,
        Ak=A2,
        Bk=B2,
        Ck=C2,
        Dk=np.zeros((1, 1, m, p)),
        u_ff=u_ff,
        K0=K0,
    )


class HardwareLaw(Controller):
    """A law run through the hardware (module docstring): it reads ``reads[k]`` for each
    filtered channel k, writes ``writes[k]`` for each driven channel, its commands delayed by
    ``whole`` samples (and ``fraction`` of one, applied by the engine), gated by the wheels'
    speed limits. Everything else (target, reference, ...) is the law's."""

    def __init__(
        self,
        law: Controller,
        reads: Mapping[str, str],
        writes: Mapping[str, str],
        whole: int = 0,
        fraction: float = 0.0,
        gates: Mapping[str, tuple[str, Any]] | None = None,
        distribute: Mapping[str, FloatArray] | None = None,
    ) -> None:
        self.law = law
        # a wheel array's channel: the body torque c sent as r = G⁺ c (before the delay)
        self.distribute = dict(distribute or {})
        self._rmap, self._wmap = dict(reads), dict(writes)
        self.whole, self.fraction = int(whole), float(fraction)
        self.gates = dict(gates or {})
        own = tuple(self._rmap.get(k, k) for k in law.reads)
        self.reads = own + tuple(g for g, _ in self.gates.values() if g not in own)
        self.writes = tuple(self._wmap.get(k, k) for k in law.writes)

    def __getattr__(self, name: str) -> Any:
        if name in ("law", "__setstate__") or name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.law, name)

    @property
    def n_cases(self) -> int:
        return self.law.n_cases

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        state = dict(self.law.initial_state(n_cases))
        for i in range(self.whole):
            for k in self.writes:
                state[f"_held_{i}_{k}"] = np.zeros(0)  # filled with the command's shape
        return state

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[Mapping[str, FloatArray], dict[str, FloatArray]]:
        inner_y = {k: y[self._rmap.get(k, k)] for k in self.law.reads}
        own = {k: v for k, v in state.items() if not k.startswith("_held_")}
        cmd, own = self.law(t, inner_y, own)
        if not isinstance(cmd, Mapping):
            cmd = {self.law.writes[0]: cmd}
        out = {self._wmap.get(k, k): np.asarray(v, float) for k, v in cmd.items()}
        for k, M in self.distribute.items():
            out[k] = out[k] @ M.T
        new = dict(own)
        for k in self.writes:  # the FIFO: slot 0 newest
            c = out[k]
            for i in range(self.whole):
                held = state[f"_held_{i}_{k}"]
                new[f"_held_{i}_{k}"] = c
                c = np.zeros_like(c) if held.size == 0 else held
            out[k] = c
        for k, (speed, limit) in self.gates.items():
            om = np.asarray(y[speed], float)
            c = out[k]
            # the motor is asked for −c: it would speed the wheel up when c Ω < 0
            out[k] = np.where((np.abs(om) >= limit) & (c * om < 0), 0.0, c)
        return out, new

    @property
    def compiled_reason(self) -> str | None:
        """Why the compiled loop cannot run this law's hardware, or None
        (:func:`flexsat.sim.compiled.unsupported`)."""
        if self.gates:
            return f"{', '.join(self.gates)}: a wheel's speed limit (a switch on the state)"
        if self.distribute:
            return f"{', '.join(self.distribute)}: a wheel array on a three-axis spacecraft"
        if self.fraction:
            return f"a fractional computation delay ({self.fraction:g} of a sample)"
        return None

    def linear_form(self, dt: float, times: FloatArray, n_cases: int) -> LinearLaw | None:
        if self.compiled_reason is not None:
            return None
        law = self.law.linear_form(dt, times, n_cases)
        if law is None:
            return None
        law = replace(
            law,
            reads=tuple(self._rmap.get(k, k) for k in law.reads),
            writes=tuple(self._wmap.get(k, k) for k in law.writes),
        )
        return delayed_linear_law(law, self.whole)
