r"""Markov parameters (pulse response) from test data: impulse tests, FRFs and OKID.

A discrete system :math:`x_{k+1} = A x_k + B u_k`, :math:`y_k = C x_k + D u_k` has the pulse
response (Markov parameters) :math:`Y_0 = D`, :math:`Y_k = C A^{k-1} B`. They are read from an
impulse test (:func:`markov_parameters`) or, for arbitrary inputs, from the observer/Kalman
filter identification OKID (:func:`okid`; Juang, Phan, Horta & Longman, *J. Guid. Control Dyn.*
16(2), 1993): least squares on :math:`y_k = D u_k + \sum_{j=1}^{p} \bar Y_j v_{k-j}`,
:math:`v = [u; y]`, then :math:`Y_k = \bar Y^{(1)}_k + \sum_{i=1}^{k} \bar Y^{(2)}_i Y_{k-i}`.

From FRFs (:func:`markov_from_frf`), the Markov parameters are the inverse DFT of frequency
response samples on the uniform grid 0, Δf, …, Nyquist: :math:`Y_k = \frac1N \sum_l
H(f_l) e^{2\pi i k l / N}`, N = 2(N_f − 1), Δt = 1/(N Δf), the pulse response of the discrete
system whose transfer function :math:`\sum_k Y_k z^{-k}` takes the values H(f_l) at
:math:`z = e^{2\pi i f_l \Delta t}` (Juang, *Applied System Identification*, Prentice Hall, 1994).

The realization from them (ERA, ERA/DC) is :mod:`flexsat.identify.era`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from flexsat.identify.measurements import Measurement
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_positive_scalar,
)
from flexsat.units import FloatArray

__all__ = [
    "check_markov",
    "markov_from_frf",
    "markov_parameters",
    "okid",
]


# ------------------------------------------------------------------------------------------------
def check_markov(markov: npt.ArrayLike) -> FloatArray:
    """Markov parameters ``Y_0..Y_L`` as a finite ``(L+1, q, r)`` array (a vector: SISO), at
    least 4 of them; refused by name (``markov``) otherwise."""
    try:
        Y = np.array(markov, dtype=float)
    except (TypeError, ValueError):
        raise FieldError(
            "markov", f"must be a numeric array, got {type(markov).__name__}"
        ) from None
    if Y.ndim == 1:
        Y = Y[:, None, None]
    if Y.ndim != 3:
        raise FieldError("markov", f"must have shape (L+1, q, r) (Y_0 first), got {Y.shape}")
    if not np.all(np.isfinite(Y)):
        raise FieldError(
            "markov",
            f"must be finite (no NaN or inf), got "
            f"{int(np.sum(~np.isfinite(Y)))} non-finite entries",
        )
    if Y.shape[0] < 4:
        raise FieldError("markov", f"need at least 4 Markov parameters, got {Y.shape[0]}")
    return Y


def _time_data(u: npt.ArrayLike | None, y: npt.ArrayLike | None) -> tuple[FloatArray, FloatArray]:
    """Checked (r, N) inputs and (q, N) outputs (1-D taken as one channel)."""
    arrays = []
    for name, v in (("u", u), ("y", y)):
        try:
            a = np.array(v, dtype=float)
        except (TypeError, ValueError):
            raise FieldError(name, "must be a numeric array") from None
        a = a[None, :] if a.ndim == 1 else a
        if a.ndim != 2 or a.size == 0:
            raise FieldError(name, f"must have shape (channels, samples), non-empty, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise FieldError(
                name,
                f"must be finite (no NaN or inf), got "
                f"{int(np.sum(~np.isfinite(a)))} non-finite entries",
            )
        arrays.append(a)
    u, y = arrays
    if u.shape[1] != y.shape[1]:
        raise FieldError("y", f"must have as many samples as u ({u.shape[1]}), got {y.shape[1]}")
    return u, y


def markov_parameters(
    measurement: Measurement | Sequence[Measurement] | None = None,
    *,
    u: npt.ArrayLike | None = None,
    y: npt.ArrayLike | None = None,
    n_markov: int | None = None,
) -> FloatArray:
    """Markov parameters Y_0..Y_L from pulse-test data.

    Parameters
    ----------
    measurement : Measurement or list of Measurement, optional
        Time-domain tests with recorded ``inputs``, or FRFs (``domain="frequency"``, converted
        by :func:`markov_from_frf` with its defaults; the sample interval is then
        ``1 / (2 f_max)``, which :func:`markov_from_frf` returns). A list is stacked input by
        input (all with the same outputs and length).
    u, y : array_like (r, N), (q, N)
        Alternatively the raw input and output samples.
    n_markov : int, optional
        Number of parameters after Y_0 (default N − 1 for a single-sample pulse, N // 4 for a
        longer pulse).

    Returns
    -------
    ndarray (L+1, q, r)

    Notes
    -----
    A single-sample pulse u_0 (the default :func:`impulse_hammer`) gives Y_k = y_k / u_0
    exactly. A longer pulse is deconvolved by least squares on the Toeplitz system
    :math:`y_k = \\sum_j Y_j u_{k-j}`: exact with ``n_markov = N - 1`` in exact arithmetic,
    but when the sampled pulse has zeros outside the unit circle (a later sample larger than
    u_0, e.g. a half-sine over three or more samples) roundoff and noise grow exponentially
    along the sequence. Keep the pulse within two samples, or use :func:`okid`; with a smaller
    ``n_markov`` the response must have decayed within it.
    """
    if measurement is None and (u is None or y is None):
        raise FieldError("measurement", "give a Measurement (or a list of them), or u and y")
    if measurement is not None:
        tests = measurement if isinstance(measurement, (list, tuple)) else [measurement]
        blocks = []
        for i, m in enumerate(tests):
            if not isinstance(m, Measurement):
                raise FieldError(
                    f"measurement[{i}]", f"must be a Measurement, got {type(m).__name__}"
                )
            if m.domain == "frequency":
                blocks.append(markov_from_frf(m.abscissa, m.outputs, n_markov=n_markov)[0])
                continue
            if m.inputs is None:
                raise FieldError(
                    f"measurement[{i}]", "needs time histories with recorded inputs or FRFs"
                )
            blocks.append(markov_parameters(u=m.inputs, y=m.outputs, n_markov=n_markov))
        if len({b.shape for b in blocks}) != 1:
            raise FieldError("measurement", "tests must have the same outputs and length")
        return np.concatenate(blocks, axis=2)
    u, y = _time_data(u, y)
    r, N = u.shape
    q = y.shape[0]
    nz = np.flatnonzero(np.any(u != 0, axis=0))
    if nz.size == 0:
        raise FieldError("u", "the input is zero; no Markov parameters can be read")
    if r == 1 and nz.size == 1:
        k0 = nz[0]
        L = N - 1 - k0 if n_markov is None else require_count(n_markov, "n_markov")
        if L > N - 1 - k0:
            raise FieldError("n_markov", f"at most {N - 1 - k0} after the pulse, got {L}")
        return np.asarray((y[:, k0 : k0 + L + 1] / u[0, k0]).T[:, :, None], dtype=float)
    L = N // 4 if n_markov is None else require_count(n_markov, "n_markov")
    if (L + 1) * r > N:
        raise FieldError("n_markov", f"{(L + 1) * r} unknowns per output exceed the {N} samples")
    Phi = np.zeros(((L + 1) * r, N))
    for j in range(L + 1):
        Phi[j * r : (j + 1) * r, j:] = u[:, : N - j]
    sol, *_ = np.linalg.lstsq(Phi.T, y.T, rcond=None)  # ((L+1) r, q)
    return np.asarray(sol.reshape(L + 1, r, q).transpose(0, 2, 1), dtype=float)


def markov_from_frf(
    frequencies: npt.ArrayLike,
    frf: npt.ArrayLike,
    n_markov: int | None = None,
    tail_tolerance: float = 1e-3,
) -> tuple[FloatArray, float]:
    """Markov parameters from uniformly sampled FRFs by inverse FFT (module docstring).

    Parameters
    ----------
    frequencies : array_like (N_f,)
        Hz, exactly 0, Δf, 2Δf, …, (N_f − 1) Δf; the last line is taken as the Nyquist
        frequency, so N = 2 (N_f − 1) time samples and Δt = 1 / (2 f_max).
    frf : array_like (q, r, N_f) complex, or (N_f,) for one output and one input
        Output over input (as :class:`~flexsat.identify.measurements.Measurement` stores FRFs),
        with the :math:`e^{+i\\omega t}` convention :math:`H(\\omega) = \\int h(t)
        e^{-i\\omega t} dt`.
    n_markov : int, optional
        Number of parameters after Y_0 returned (default N // 2, at most N − 1).
    tail_tolerance : float
        Largest accepted ratio of the RMS of the last N // 20 samples (the end of the period,
        where a causal response that has died out leaves nothing) to the peak of
        :math:`\\|Y_k\\|_F`, k ≥ 1; above it a warning reports time aliasing.

    Returns
    -------
    markov : ndarray (L+1, q, r)
    dt : float
        Sample interval, s.

    Raises
    ------
    ValueError
        Naming the field: NaN/inf, a grid that does not start at 0 Hz or is not uniform, a
        shape that does not match the grid.

    Notes
    -----
    Time aliasing. The inverse DFT returns the periodic sum :math:`\\hat Y_k = \\sum_{m \\ge 0}
    Y_{k+mN}`, so the impulse response must have decayed within the period T = 1/Δf: with
    modal damping ζ at ω the envelope after T is :math:`e^{-\\zeta\\omega T}`. For an exact
    discrete system the sum is :math:`C A^{k-1} (I - A^N)^{-1} B` for k ≥ 1, a realization
    with the same A, so ERA's frequencies and damping survive aliasing and only B (modal
    participation, MSV) is scaled by :math:`1/(1-\\lambda^N)`; wrapped noise and leakage in
    measured FRFs are not of that form, hence the check.

    Band limit. For a continuous system :math:`Y_k \\approx \\Delta t\\, h(k \\Delta t)`, the
    response to an impulse of area Δt. Samples of a continuous-time FRF are not the FRF of a
    finite-order discrete system: the content above Nyquist is missing, which leaves a
    ringing decaying like :math:`1/k^2` in the first Markov parameters (and at the
    non-causal end of the period, which the tail ratio then also shows). On the TAMU grid
    (6 modes up to 13 Hz, ζ = 0.01, displacement per force, 100 Hz) ERA from all parameters
    is biased by 5e-5 in frequency and 0.16 % in damping; ERA on ``markov[20:]``
    (:math:`C A^{k+19} B`, the same A) reduces that to 2e-7 and 1.3e-5
    (``tests/identify/test_era.py``).
    """
    f = require_finite(frequencies, "frequencies", "Hz")
    if f.ndim != 1 or f.size < 3:
        raise FieldError(
            "frequencies", f"must be a 1-D grid of at least 3 values, got shape {f.shape}"
        )
    df = (f[-1] - f[0]) / (f.size - 1)
    if df <= 0:
        raise FieldError("frequencies", "must be ascending")
    # 1e-6 Δf: the same uniformity rule as a Measurement's time axis
    if abs(f[0]) > 1e-6 * df:
        raise FieldError(
            "frequencies",
            f"must start at 0 Hz (the inverse FFT needs every line "
            f"from DC to Nyquist), got {f[0]:.6g} Hz first",
        )
    dev = np.max(np.abs(f - df * np.arange(f.size)))
    if dev > 1e-6 * df:
        raise FieldError(
            "frequencies",
            f"must be uniformly spaced (0, Δf, 2Δf, …) for the "
            f"inverse FFT; deviation {dev:.3g} Hz from the grid of step {df:.6g} Hz",
        )
    try:
        H = np.array(frf, dtype=complex)
    except (TypeError, ValueError):
        raise FieldError("frf", f"must be a numeric array, got {type(frf).__name__}") from None
    if H.ndim == 1:
        H = H[None, None, :]
    if H.ndim != 3 or H.shape[2] != f.size:
        raise FieldError(
            "frf",
            f"must have shape (outputs, inputs, {f.size}) to match frequencies, got {H.shape}",
        )
    if not np.all(np.isfinite(H)):
        raise FieldError(
            "frf",
            f"must be finite (no NaN or inf), got "
            f"{int(np.sum(~np.isfinite(H)))} non-finite entries",
        )
    tol = require_positive_scalar(tail_tolerance, "tail_tolerance")
    N = 2 * (f.size - 1)
    L = N // 2 if n_markov is None else require_count(n_markov, "n_markov")
    if L > N - 1:
        raise FieldError("n_markov", f"the period holds {N} samples, so at most {N - 1}, got {L}")
    # irfft takes the Nyquist line as real (its imaginary part cannot belong to a real sequence)
    Y = np.fft.irfft(H, n=N, axis=2).transpose(2, 0, 1)
    size = np.sqrt(np.sum(Y**2, axis=(1, 2)))
    peak = np.max(size[1:])
    tail = np.sqrt(np.mean(size[N - max(1, N // 20) :] ** 2))
    if tail > tol * peak:
        warnings.warn(
            f"frf: the impulse response has not decayed within the period 1/Δf = "
            f"{1 / df:.4g} s (tail RMS / peak = {tail / peak:.3g} > tail_tolerance "
            f"{tol:g}); the Markov parameters are time-aliased: use a finer "
            f"frequency spacing",
            stacklevel=2,
        )
    return Y[: L + 1], 1.0 / (N * df)


def okid(
    u: npt.ArrayLike, y: npt.ArrayLike, n_markov: int, n_observer: int | None = None
) -> FloatArray:
    """Markov parameters from arbitrary input/output data by OKID (Juang et al. 1993).

    Parameters
    ----------
    u : array_like (r, N)
    y : array_like (q, N)
    n_markov : int
        Number of system Markov parameters after Y_0 wanted (L).
    n_observer : int, optional
        Observer order p (number of observer Markov parameters); p q must be ≥ the system
        order for the deadbeat observer to exist. Default ``min(n_markov, (N - 1) // (r + q + 1)
        // 2, 200)`` bounded below by 1.

    Returns
    -------
    ndarray (L+1, q, r)
        Y_0 = D, Y_k = C A^{k-1} B.

    Raises
    ------
    ValueError
        Mismatched sample counts, NaN, or too few samples for the regression.
    """
    u, y = _time_data(u, y)
    r, N = u.shape
    q = y.shape[0]
    L = require_count(n_markov, "n_markov")
    if L > N - 1:
        # the recursion would extrapolate past the record (and run for as long as asked)
        raise FieldError("n_markov", f"the record holds {N} samples, so at most {N - 1}, got {L}")
    p = (
        max(1, min(L, (N - 1) // (r + q + 1) // 2, 200))
        if n_observer is None
        else require_count(n_observer, "n_observer")
    )
    rows = r + p * (r + q)
    if N - p < rows:
        raise FieldError(
            "n_observer",
            f"{rows} regressors need more than the {N - p} equations; "
            "use a smaller observer order or a longer record",
        )
    v = np.vstack([u, y])
    V = np.zeros((rows, N - p))
    V[:r] = u[:, p:]
    for j in range(1, p + 1):
        V[r + (j - 1) * (r + q) : r + j * (r + q)] = v[:, p - j : N - j]
    sol, *_ = np.linalg.lstsq(V.T, y[:, p:].T, rcond=None)
    Ybar = sol.T  # (q, rows)
    D = Ybar[:, :r]
    P = [Ybar[:, r + (j - 1) * (r + q) : r + (j - 1) * (r + q) + r] for j in range(1, p + 1)]
    Q = [Ybar[:, r + (j - 1) * (r + q) + r : r + j * (r + q)] for j in range(1, p + 1)]
    Y = [D]
    for k in range(1, L + 1):
        Yk = P[k - 1].copy() if k <= p else np.zeros((q, r))
        for i in range(1, min(k, p) + 1):
            Yk += Q[i - 1] @ Y[k - i]
        Y.append(Yk)
    return np.array(Y)
