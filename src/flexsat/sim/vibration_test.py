r"""Synthetic vibration tests of any :class:`~flexsat.structures.modal_model.ModalModel`, run on
the engine.

The structure with its sensors is the state space :math:`\dot x = A x + B u`,
:math:`y = C x + D u` of :func:`flexsat.identify.excitation.sensor_matrices` (modal
coordinates :math:`x = [\eta, \dot\eta]`; with ``anti_alias`` also one analog Butterworth
low-pass per recorded channel, :func:`flexsat.identify.excitation.with_anti_alias`), a
:class:`~flexsat.dynamics.state_space.StateSpacePlant`. The excitation, averaged over each fine
step :math:`h = \Delta t / \text{oversample}`
(:meth:`~flexsat.identify.excitation.Excitation.samples`: pulse areas kept), is played back
by :class:`~flexsat.control.playback.Playback` through
:func:`flexsat.sim.engine.simulate` at the rate 1/h: the engine's zero-order hold and its exact
linear step (:math:`e^{Ah}`, :math:`h\varphi_1(hA)B`) propagate the structure. The outputs are
read every ``oversample`` steps as :math:`y_k = C x_k + D u_k`, u_k the input held from t_k (an
accelerometer sees the force acting at its sample), and each channel then passes its sensor
(:class:`~flexsat.sim.channels.ChannelSensor`): white Gaussian noise of standard deviation
``noise`` × the RMS of the clean channel, and the ADC step ``quantization``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.playback import Playback
from flexsat.dynamics.plant import Channel
from flexsat.dynamics.state_space import StateSpacePlant
from flexsat.identify.excitation import Excitation, sensor_matrices, with_anti_alias
from flexsat.identify.measurements import Measurement
from flexsat.input_checks import FieldError, require_count, require_nonneg, require_positive
from flexsat.sim.channels import ChannelSensor
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

__all__ = ["simulate_test"]


def simulate_test(
    modal_model: ModalModel,
    excitation: Excitation | Sequence[Excitation],
    sensors: Sequence[Channel],
    duration: float,
    sample_rate: float,
    noise: float = 0.0,
    quantization: float | None = None,
    seed: int | None = None,
    oversample: int = 1,
    anti_alias: float | None = None,
) -> Measurement:
    """Simulate a vibration test and record it as a :class:`Measurement` (module docstring).

    Parameters
    ----------
    modal_model : ModalModel
    excitation : Excitation or sequence of Excitation
        See :func:`~flexsat.identify.excitation.impulse_hammer`,
        :func:`~flexsat.identify.excitation.harmonic_shaker`,
        :func:`~flexsat.identify.excitation.random_force`,
        :func:`~flexsat.identify.excitation.torque_history`.
    sensors : sequence of Channel
        Displacement, velocity, acceleration, rotation or strain channels.
    duration : float
        s; samples at 0, Δt, ... < duration.
    sample_rate : float
        Hz.
    noise : float
        Noise standard deviation as a fraction of each clean channel's RMS (0.01 = 1 %).
    quantization : float, optional
        ADC step in channel units (values rounded to multiples of it).
    seed : int, optional
        Random generator seed (random inputs first, then the noise).
    oversample : int
        Fine integration steps per sample (for pulses shorter than a sample or smooth inputs).
    anti_alias : float, optional
        Cut-off (Hz, below the Nyquist frequency) of the analog anti-aliasing filters on every
        recorded channel; the recorded inputs are then the filtered inputs.

    Returns
    -------
    Measurement
        ``outputs`` (sensors, N), ``inputs`` (excitations, N: the input sampled at the test rate,
        averaged over each sample), ``attrs`` with ``noise`` and ``seed``.
    """
    excitations = [excitation] if isinstance(excitation, Excitation) else list(excitation)
    if not excitations or not all(isinstance(e, Excitation) for e in excitations):
        raise FieldError("excitation", "must be an Excitation or a non-empty list of them")
    sensors = list(sensors)
    if not sensors or not all(isinstance(s, Channel) for s in sensors):
        raise FieldError("sensors", "must be a non-empty list of Channel")
    fs = float(require_positive(sample_rate, "sample_rate"))
    T = float(require_positive(duration, "duration"))
    noise = float(require_nonneg(noise, "noise"))
    over = require_count(oversample, "oversample")
    q = None if quantization is None else float(require_positive(quantization, "quantization"))
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    n = int(np.ceil(T * fs - 1e-9))
    if n < 2:
        raise FieldError("duration", f"gives {n} sample(s) at {fs} Hz; need at least 2")
    h = dt / over
    t_fine = np.arange(n * over, dtype=float) * h
    U = np.array([e.samples(t_fine, h, over, rng) for e in excitations])  # (r, n*over)

    chans = [e.channel for e in excitations]
    A, B, C, D = sensor_matrices(modal_model, sensors, chans)
    n_out = C.shape[0]
    if anti_alias is not None:
        cut = float(require_positive(anti_alias, "anti_alias"))
        if cut >= fs / 2:
            raise FieldError(
                "anti_alias",
                f"the cut-off must be below the Nyquist frequency {fs / 2:g} Hz, got {cut:g} Hz",
            )
        A, B, C, D = with_anti_alias(A, B, C, D, cut)
    plant = StateSpacePlant(A, B, C, D, "excitation", "sensors")
    # the engine's samples 0 ... n·over − 1 are the fine steps: the state at each before its
    # held input, the last one's input applied over no interval
    config = SimConfig(duration=(n * over - 1) * h, control_rate=1.0 / h)
    run = simulate(
        plant,
        Playback(U.T, h, "excitation"),
        config,
        initial_state=np.zeros(plant.nx),
        record_states=True,
    ).dataset
    X = run["state"].values[0, ::over]  # (n, n_x)
    u_held = run["excitation"].values[0].reshape(n * over, -1)[::over]  # (n, r)
    Y = X @ C.T + u_held @ D.T  # (n, q [+ r])
    u_samples = U[:, ::over] if over == 1 else U.reshape(len(chans), n, over).mean(axis=2)
    if anti_alias is not None:
        Y, u_samples = Y[:, :n_out], Y[:, n_out:].T
    Y = Y.T
    if noise > 0 or q is not None:
        rms = np.sqrt(np.mean(Y**2, axis=1))
        normals = rng.standard_normal(Y.shape) if noise > 0 else np.zeros(Y.shape)
        Y = np.array(
            [
                ChannelSensor(noise=noise * r, quantum=0.0 if q is None else q)
                # noise and quantum are in the output's own unit; the name only labels errors
                .bind(Channel("output", ""))
                .measure(y, z)
                for r, y, z in zip(rms, Y, normals)
            ]
        )
    return Measurement(
        np.arange(n, dtype=float) * dt,
        Y,
        tuple(sensors),
        u_samples,
        tuple(chans),
        "time",
        attrs={
            "noise": noise,
            "seed": -1 if seed is None else int(seed),
            "oversample": over,
            "anti_alias_hz": -1.0 if anti_alias is None else float(anti_alias),
        },
    )
