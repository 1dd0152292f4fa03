r"""The pieces of a synthetic vibration test of any
:class:`~flexsat.structures.modal_model.ModalModel`: the excitations and the test's state space.
The test itself runs on the engine (:func:`flexsat.sim.vibration_test.simulate_test`).

Each excitation is described by its average over every fine step h of the run
(:meth:`Excitation.samples`, so pulse areas are kept). :func:`sensor_matrices` gives the modal
state space :math:`x = [\eta, \dot\eta]`, :math:`\dot x = A x + B u`, y = C x + D u, with the
sensors

* displacement / rotation / strain: :math:`y = c^T \eta`;
* velocity: :math:`y = c^T \dot\eta`;
* acceleration: :math:`y = c^T \ddot\eta = c^T(-K\eta - D\dot\eta + B u)`.

Anti-aliasing (:func:`with_anti_alias`, a cut-off in Hz): every recorded channel, outputs and
inputs alike, passes an analog Butterworth low-pass of order :data:`ANTI_ALIAS_ORDER` before it
is sampled, as a data-acquisition front end does. The filters are continuous states of the
simulated system, so the exact propagation covers them. Identical filters on the inputs and
outputs cancel in an FRF estimate, which then approximates the continuous FRF of the structure
(no zero-order-hold distortion and no aliased modes), and modes above the cut-off no longer fold
into the band.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeAlias

import numpy as np
import numpy.typing as npt
from scipy import signal
from scipy.linalg import block_diag

from flexsat.identify.measurements import Channel
from flexsat.input_checks import (
    FieldError,
    require_numeric,
    require_positive_scalar,
    require_scalar,
)
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

__all__ = [
    "Excitation",
    "harmonic_shaker",
    "impulse_hammer",
    "random_force",
    "sensor_matrices",
    "torque_history",
    "with_anti_alias",
]

_KINDS = ("impulse", "harmonic", "random", "history")
#: order of the analog Butterworth anti-aliasing filter (:func:`with_anti_alias`)
ANTI_ALIAS_ORDER = 6

#: a continuous state-space system (A, B, C, D)
StateSpaceMatrices: TypeAlias = tuple[FloatArray, FloatArray, FloatArray, FloatArray]


@dataclass(frozen=True)
class Excitation:
    """One input of a test (build it with the helper functions below).

    Parameters
    ----------
    kind : {"impulse", "harmonic", "random", "history"}
    channel : Channel
        Where and what (force at node/direction or torque about an axis).
    amplitude : float
        Peak force/torque (impulse, harmonic) or RMS (random), N or N m.
    width : float, optional
        Half-sine pulse duration, s (impulse; default one sample).
    frequency : float, optional
        Hz (harmonic).
    values : array_like, optional
        Samples at the test sample rate (history), held between samples.
    """

    kind: str
    channel: Channel
    amplitude: float = 1.0
    width: float | None = None
    frequency: float | None = None
    values: FloatArray | None = None

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise FieldError("kind", f"must be one of {_KINDS}, got {self.kind!r}")
        if not isinstance(self.channel, Channel) or self.channel.kind not in ("force", "torque"):
            raise FieldError(
                "channel", f"an excitation is a force or torque Channel, got {self.channel!r}"
            )
        amplitude = require_scalar(self.amplitude, "rms" if self.kind == "random" else "amplitude")
        if self.kind == "random" and amplitude < 0:
            raise FieldError("rms", f"must be >= 0, got {self.amplitude!r}")
        object.__setattr__(self, "amplitude", amplitude)
        if self.width is not None:
            object.__setattr__(self, "width", require_positive_scalar(self.width, "width", "s"))
        if self.kind == "harmonic" and self.frequency is None:
            raise FieldError("frequency", "a harmonic excitation needs its frequency, Hz")
        if self.frequency is not None:
            # Hz, a plain number: a pint Quantity would not say whether it is cycles or radians
            object.__setattr__(
                self, "frequency", require_positive_scalar(self.frequency, "frequency")
            )
        if self.kind == "history" and self.values is None:
            raise FieldError("values", "a history excitation needs its samples")
        if self.values is not None:
            vals = require_numeric(self.values, "values", "vector")
            if vals.ndim != 1 or vals.size == 0:
                raise FieldError(
                    "values", f"must be a finite, non-empty 1-D array of samples, got {vals.shape}"
                )
            object.__setattr__(self, "values", vals)

    def samples(
        self, t_fine: FloatArray, h: float, oversample: int, rng: np.random.Generator
    ) -> FloatArray:
        """Average of the input over each fine step starting at ``t_fine``."""
        a = float(self.amplitude)
        if self.kind == "impulse":
            w = h * oversample if self.width is None else float(self.width)
            lo, hi = np.clip(t_fine, 0, w), np.clip(t_fine + h, 0, w)
            return a * w / np.pi * (np.cos(np.pi * lo / w) - np.cos(np.pi * hi / w)) / h
        if self.kind == "harmonic":
            assert self.frequency is not None  # a harmonic excitation has one (__post_init__)
            om = 2 * np.pi * float(self.frequency)
            return a * (np.cos(om * t_fine) - np.cos(om * (t_fine + h))) / (om * h)
        if self.kind == "random":
            n = -(-t_fine.size // oversample)
            return np.repeat(a * rng.standard_normal(n), oversample)[: t_fine.size]
        vals = np.asarray(self.values, dtype=float)
        n = -(-t_fine.size // oversample)
        full = np.zeros(n)
        full[: min(n, vals.size)] = vals[:n]
        return np.repeat(full, oversample)[: t_fine.size]


def _load(load: str, node: int, direction: str, name: str = "") -> Channel:
    if load not in ("force", "torque"):
        raise FieldError("load", f"must be 'force' or 'torque', got {load!r}")
    return Channel.at(load, node, direction, name=name)


def impulse_hammer(
    node: int,
    direction: str,
    amplitude: float = 1.0,
    width: float | None = None,
    load: str = "force",
) -> Excitation:
    """Half-sine hammer pulse of peak ``amplitude`` (N) and duration ``width`` (s).

    The impulse is :math:`2 F w / \\pi`; the default width is one sample, which makes the
    sampled input a single discrete pulse (ERA Markov parameters come out exactly).
    """
    return Excitation("impulse", _load(load, node, direction), amplitude, width=width)


def harmonic_shaker(
    node: int, direction: str, amplitude: float, frequency: float, load: str = "force"
) -> Excitation:
    """Sine force (or torque) of ``amplitude`` and ``frequency`` (Hz) from t = 0."""
    return Excitation("harmonic", _load(load, node, direction), amplitude, frequency=frequency)


def random_force(node: int, direction: str, rms: float = 1.0, load: str = "force") -> Excitation:
    """White Gaussian force (or torque) of standard deviation ``rms``, held over each sample."""
    return Excitation("random", _load(load, node, direction), rms)


def torque_history(node: int, axis: str, values: npt.ArrayLike) -> Excitation:
    """User torque history (e.g. a reaction wheel), N m, one value per sample (zero after)."""
    samples = require_numeric(values, "values", "vector")  # the field's type; shape checked there
    return Excitation("history", _load("torque", node, axis), 1.0, values=samples)


def _located(chan: Channel) -> tuple[int, str]:
    """The node and direction of a test channel (one with a structural kind)."""
    # a Channel with a structural kind has both (Channel.__post_init__)
    assert chan.node is not None and chan.direction is not None
    return chan.node, chan.direction


def _input_vector(model: ModalModel, chan: Channel) -> FloatArray:
    node, direction = _located(chan)
    if chan.kind == "force":
        return model.force_input(node, direction)
    return model.torque_input(node, direction)


def _output_rows(model: ModalModel, chan: Channel) -> FloatArray:
    if chan.kind not in ("displacement", "velocity", "acceleration", "rotation", "strain"):
        raise FieldError("sensors", f"{chan.kind!r} is not a sensor kind")
    node, direction = _located(chan)
    if chan.kind == "rotation":
        return model.rotation_output(node, direction)
    if chan.kind == "strain":
        assert chan.node_a is not None  # a strain channel has both ends (Channel.__post_init__)
        return model.strain_output(chan.node_a, node, direction)
    return model.displacement_output(node, direction)


def sensor_matrices(
    model: ModalModel, sensors: Sequence[Channel], inputs: Sequence[Channel]
) -> StateSpaceMatrices:
    """Continuous (A, B, C, D) of the modal model for the given sensors and input channels."""
    m = model.n_modes
    w, z = model.frequencies, model.damping
    K, Dm = np.diag(w**2), np.diag(2 * z * w)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -Dm]])
    B2 = np.column_stack([_input_vector(model, c) for c in inputs]) if inputs else np.zeros((m, 0))
    B = np.vstack([np.zeros_like(B2), B2])
    C = np.zeros((len(sensors), 2 * m))
    D = np.zeros((len(sensors), B2.shape[1]))
    for i, s in enumerate(sensors):
        c = _output_rows(model, s)
        if s.kind == "velocity":
            C[i, m:] = c
        elif s.kind == "acceleration":
            C[i] = np.concatenate([-c @ K, -c @ Dm])
            D[i] = c @ B2
        else:
            C[i, :m] = c
    return A, B, C, D


def with_anti_alias(
    A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray, cutoff_hz: float
) -> StateSpaceMatrices:
    """System + one analog low-pass of order :data:`ANTI_ALIAS_ORDER` (Butterworth, cut-off
    ``cutoff_hz``) per output and per input channel (module docstring).

    Returns (A, B, C, D) whose outputs are the filtered outputs followed by the filtered
    inputs."""
    ns, r = B.shape
    q = C.shape[0]
    af, bf, cf, _ = signal.zpk2ss(
        *signal.butter(ANTI_ALIAS_ORDER, 2 * np.pi * cutoff_hz, analog=True, output="zpk")
    )
    k = af.shape[0]
    Af = block_diag(*([af] * (q + r)))
    Bf = block_diag(*([bf] * (q + r)))  # (k (q + r), q + r): one input per channel
    Cf = block_diag(*([cf] * (q + r)))
    drive_x = np.vstack([C, np.zeros((r, ns))])  # filter inputs: C x + D u, then u
    drive_u = np.vstack([D, np.eye(r)])
    A_aug = np.block([[A, np.zeros((ns, k * (q + r)))], [Bf @ drive_x, Af]])
    B_aug = np.vstack([B, Bf @ drive_u])
    C_aug = np.hstack([np.zeros((q + r, ns)), Cf])
    return A_aug, B_aug, C_aug, np.zeros((q + r, r))
