r"""Frequency response functions: estimated from test data (H1) and computed from a model.

H1 estimator for several simultaneous, uncorrelated or correlated inputs (Bendat & Piersol,
*Random Data*, 4th ed., §7.2): with the cross-spectral densities :math:`G_{yu}(f)` (q × r) and
:math:`G_{uu}(f)` (r × r) averaged over Welch segments,

.. math::  H_1(f) = G_{yu}(f)\, G_{uu}(f)^{-1},

unbiased by output noise; the multiple coherence of output i is
:math:`\gamma_i^2 = G_{yu,i} G_{uu}^{-1} G_{uy,i} / G_{yy,ii}` (1 for noise-free linear data),
and the random error of each element (Bendat & Piersol §9.3.1, conditioned inputs) has the
standard deviation

.. math::  \sigma(H_{ia}) = \sqrt{\frac{(1 - \gamma_i^2)\, G_{yy,ii}\, [G_{uu}^{-1}]_{aa}}
           {2\,(n_d - r)}},

with :math:`n_d` Welch segments and r inputs: the output's unexplained power over input a's
power conditioned on the others, independent of :math:`|H_{ia}|` (an element that is zero by
symmetry still has the noise of its output).

The model FRF of the modal state space of
:func:`flexsat.identify.excitation.sensor_matrices` is
:math:`H(j\omega) = C (j\omega I - A)^{-1} B + D`; for an input held over each sample of
a test at rate :math:`1/\Delta t` (what :func:`~flexsat.sim.vibration_test.simulate_test`
records) the sampled data follow the zero-order-hold equivalent
:math:`H_d = C (e^{j\omega \Delta t} I - A_d)^{-1} B_d + D` with
:math:`[A_d, B_d] = e^{[A, B; 0, 0] \Delta t}` (Franklin, Powell & Workman, *Digital Control
of Dynamic Systems*, §4.3), which differs from :math:`H` by about :math:`\omega\Delta t/2` in
phase.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy import signal
from scipy.linalg import expm

from flexsat import limits
from flexsat.identify.excitation import sensor_matrices
from flexsat.identify.measurements import Channel, Measurement
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_numeric,
    require_positive_scalar,
    require_scalar,
)
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

__all__ = ["FRFEstimate", "estimate_frf", "frequency_response"]


@dataclass(frozen=True)
class FRFEstimate:
    """An H1 estimate (:func:`estimate_frf`).

    Attributes
    ----------
    frf : Measurement
        Frequency domain, outputs (q, r, F).
    coherence : ndarray (q, F)
        Multiple coherence of each output.
    std : ndarray (q, r, F)
        Random-error standard deviation of each element (module docstring), for the real and
        for the imaginary part alike.
    segments : int
        Welch segments averaged.
    """

    frf: Measurement
    coherence: FloatArray
    std: FloatArray
    segments: int


def _window(window: str | tuple[str, float] | npt.ArrayLike, n: int) -> FloatArray:
    """The Welch window of ``n`` samples: a scipy window name, a (name, parameter) tuple or
    ``n`` finite weights."""
    if isinstance(window, (str, tuple)):
        try:
            return np.asarray(signal.get_window(window, n, fftbins=True), dtype=float)
        except (TypeError, ValueError) as error:
            raise FieldError(
                "window",
                f"must be a scipy window name (e.g. 'hann'), a (name, parameter) tuple or "
                f"{n} weights, got {window!r} ({error})",
            ) from None
    weights = require_numeric(window, "window", "vector")
    if weights.shape != (n,) or not np.any(weights != 0):
        raise FieldError(
            "window", f"weights must be {n} numbers (one per segment sample), not all zero"
        )
    return weights


def estimate_frf(
    measurement: Measurement,
    segment: int,
    overlap: float = 0.5,
    window: str | tuple[str, float] | npt.ArrayLike = "hann",
) -> FRFEstimate:
    """H1 estimate of the FRFs of a time-domain test with recorded inputs.

    Parameters
    ----------
    measurement : Measurement
        Time domain, with ``inputs`` (r, N) and outputs (q, N).
    segment : int
        Welch segment length, samples (frequency resolution ``sample_rate / segment``).
    overlap : float
        Fraction of a segment shared with the next, in [0, 1).
    window : str, tuple or array_like
        scipy window name, (name, parameter) tuple (``("kaiser", 8.0)``) or ``segment``
        weights.

    Returns
    -------
    FRFEstimate
        The FRFs (a frequency-domain Measurement from the first non-zero frequency to Nyquist),
        the multiple coherence and the random error of every element.

    Raises
    ------
    ValueError
        ``measurement`` without inputs or in the frequency domain, ``segment`` longer than the
        record, ``overlap`` outside [0, 1), input spectra that are singular (inputs fully
        correlated or absent in a band).
    """
    if not isinstance(measurement, Measurement):
        raise FieldError("measurement", f"must be a Measurement, got {type(measurement).__name__}")
    if measurement.domain != "time" or measurement.inputs is None:
        raise FieldError(
            "measurement", "the H1 estimate needs a time-domain test with recorded inputs"
        )
    n = require_count(segment, "segment")
    N = measurement.abscissa.size
    if not 4 <= n <= N:
        raise FieldError("segment", f"must be between 4 and the record length {N} samples, got {n}")
    ov = require_scalar(overlap, "overlap")
    if not 0.0 <= ov < 1.0:
        raise FieldError("overlap", f"must be in [0, 1), got {overlap!r}")
    weights = _window(window, n)
    fs = measurement.sample_rate
    u, y = measurement.inputs, measurement.outputs
    step = n - int(ov * n)
    segments = (N - n) // step + 1
    if segments <= u.shape[0]:
        # n_d - r degrees of freedom of the random error (module docstring); with fewer
        # segments than inputs G_uu is singular at every frequency
        raise FieldError(
            "segment",
            f"{n} samples give {segments} Welch segments for {u.shape[0]} inputs; the H1 "
            "estimate needs more segments than inputs (a shorter segment or a longer record)",
        )
    kw = dict(fs=fs, nperseg=n, noverlap=int(ov * n), window=weights, detrend=False)
    f, _ = signal.csd(u[0], u[0], **kw)
    keep = f > 0
    f = f[keep]
    r, q = u.shape[0], y.shape[0]
    Guu = np.empty((f.size, r, r), complex)
    Gyu = np.empty((f.size, q, r), complex)
    Gyy = np.empty((f.size, q))
    for a in range(r):
        for b in range(r):
            Guu[:, a, b] = signal.csd(u[a], u[b], **kw)[1][keep]  # E[U_a* U_b]
        for i in range(q):
            Gyu[:, i, a] = signal.csd(u[a], y[i], **kw)[1][keep]  # E[U_a* Y_i]
    for i in range(q):
        Gyy[:, i] = signal.welch(y[i], **kw)[1][keep]
    # csd(x, y) = E[X* Y]: Guu[a, b] = E[U_a* U_b], Gyu[i, a] = E[U_a* Y_i]; Y = H U gives
    # E[U_a* Y_i] = sum_b H_ib Guu[a, b], i.e. Gyu^T = Guu H^T
    cond = np.linalg.cond(Guu)
    if np.any(~np.isfinite(cond)) or np.any(cond > 1e12):
        raise FieldError(
            "measurement",
            "the input cross-spectral matrix is singular at some "
            "frequencies (inputs fully correlated, or no input power there)",
        )
    H = np.transpose(np.linalg.solve(Guu, np.swapaxes(Gyu, 1, 2)), (2, 1, 0))  # (q, r, F)
    # E|Y_i|^2 explained by the inputs: sum_ab conj(H_ia) Guu[a, b] H_ib
    explained = np.einsum("iaf,fab,ibf->fi", H.conj(), Guu, H).real
    coherence = (explained / np.where(Gyy > 0, Gyy, np.inf)).T
    conditioned = np.real(np.diagonal(np.linalg.inv(Guu), axis1=1, axis2=2))  # (F, r)
    unexplained = np.clip(Gyy - explained, 0.0, None)  # (F, q)
    std = np.sqrt(unexplained.T[:, None, :] * conditioned.T[None, :, :] / (2.0 * (segments - r)))
    frf = Measurement(
        f,
        H,
        measurement.output_channels,
        None,
        measurement.input_channels,
        "frequency",
        attrs={
            "estimator": "H1",
            "segment": n,
            "overlap": ov,
            "window": window if isinstance(window, (str, tuple)) else "weights",
        },
    )
    return FRFEstimate(frf, coherence, std, segments)


def frequency_response(
    modal_model: ModalModel,
    sensors: Sequence[Channel],
    inputs: Sequence[Channel],
    frequencies_hz: npt.ArrayLike,
    sample_rate: float | None = None,
) -> npt.NDArray[np.complex128]:
    """Model FRFs (q, r, F) of a :class:`~flexsat.structures.modal_model.ModalModel`.

    ``sensors`` and ``inputs`` are :class:`~flexsat.identify.measurements.Channel` lists as in
    :func:`flexsat.sim.vibration_test.simulate_test`; ``frequencies_hz`` a finite vector.  With
    ``sample_rate`` (Hz): the zero-order-hold equivalent seen by a sampled test with held inputs
    (module docstring); without: the continuous FRF.
    """
    from flexsat.structures.modal_model import ModalModel  # the FE package: on first use

    if not isinstance(modal_model, ModalModel):
        raise FieldError("modal_model", f"must be a ModalModel, got {type(modal_model).__name__}")
    f = require_finite(frequencies_hz, "frequencies_hz")
    if f.ndim > 1 or f.size == 0 or np.any(f < 0):
        raise FieldError(
            "frequencies_hz", f"must be a non-empty vector of values >= 0 Hz, got shape {f.shape}"
        )
    f = f.ravel()
    channels = {}
    for name, given in (("sensors", sensors), ("inputs", inputs)):
        if not isinstance(given, Sequence) or isinstance(given, (str, bytes)) or not given:
            raise FieldError(name, f"must be a non-empty list of Channels, got {given!r}")
        for i, chan in enumerate(given):
            if not isinstance(chan, Channel) or chan.kind is None:
                raise FieldError(
                    f"{name}[{i}]", f"must be a Channel located on the structure, got {chan!r}"
                )
        channels[name] = list(given)
    try:
        A, B, C, D = sensor_matrices(modal_model, channels["sensors"], channels["inputs"])
    except FieldError as error:
        # the model refuses a node or direction: say which list holds it
        raise FieldError(f"sensors or inputs: {error.field}", error.rule) from None
    ns = A.shape[0]
    # the batched solve holds one complex ns x ns matrix per frequency
    limits.check_memory(16 * f.size * ns * (ns + B.shape[1]), "frequencies_hz", "the model FRFs")
    eye = np.eye(ns)
    if sample_rate is None:
        z, G, Bz = 2j * np.pi * f, A, B
    else:
        dt = 1.0 / require_positive_scalar(sample_rate, "sample_rate")
        r = B.shape[1]
        aug = np.zeros((ns + r, ns + r))
        aug[:ns, :ns], aug[:ns, ns:] = A * dt, B * dt
        E = expm(aug)
        if not np.all(np.isfinite(E)):
            raise FieldError(
                "sample_rate",
                f"{sample_rate!r} Hz is too low for the model: the zero-order-hold transition "
                "over one sample overflows",
            )
        z, G, Bz = np.exp(2j * np.pi * f * dt), E[:ns, :ns], E[:ns, ns:]
    try:
        X = np.linalg.solve(
            z[:, None, None] * eye - G[None], np.broadcast_to(Bz, (f.size,) + Bz.shape)
        )
    except np.linalg.LinAlgError:
        raise FieldError(
            "frequencies_hz", "a frequency is a pole of the model (an undamped resonance)"
        ) from None
    return np.transpose(C @ X + D, (1, 2, 0))
