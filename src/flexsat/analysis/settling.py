r"""The settling time: the one definition every metric, check and report uses.

A response has settled at the first sample time :math:`t_s` after which every signal stays
inside its band:

.. math::

    t_s = t_{k+1}, \qquad k = \max\{\,j : |e_i(t_j)| > b_i \text{ for some signal } i\,\},

:math:`t_s = t_0` when no sample is outside, and *not settled* when the last sample is outside
(the run ended before the response settled; never reported as the run length). This is the
settling time of Ogata, *Modern Control Engineering*, 5th ed., Prentice Hall, 2010, §5-3
("the time required for the response curve to reach and stay within a range about the final
value"), read on the sampled response: a band crossed between two samples is not seen.

The band is absolute (rad, m, ...) by default; ``relative_to_peak`` makes it a fraction of the
signal's largest magnitude over the run (the 10 % settling of the tip error and the rotation in
the PPF study on the Agrawal-Bang structure,
:mod:`flexsat.scenarios.ppf`, Agrawal & Bang 1996, which
publishes no band). Several signals settle together when each is inside its own band (the
tether retrieval of Junkins, Pollock & Rahman 1990 Att. 12: "λ and θ reach their final values in
nearly two orbits", Figs. 2-3, read as pitch within 5° and length within 2 % of its
change; :mod:`flexsat.cases.tether`).

"Not settled" is NaN in arrays (a batch keeps its float dtype) and None at the JSON/report
boundary (:func:`reported`), one way each.
"""

from __future__ import annotations

import math
from typing import SupportsFloat

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray


def settling_time(
    t: npt.ArrayLike,
    error: npt.ArrayLike | tuple[npt.ArrayLike, ...],
    band: float | npt.ArrayLike | tuple[float | npt.ArrayLike, ...],
    *,
    relative_to_peak: bool = False,
) -> FloatArray:
    """First time after which every ``error`` signal stays within its ``band`` (module).

    Parameters
    ----------
    t : array_like (n_t,)
        Sample times, ascending (s, or any time-like axis such as the orbit angle τ).
    error : array_like (..., n_t), or a tuple of them
        Deviation from the final value (error to the target), time last; a tuple holds
        several signals that must all be inside their bands.
    band : float or array_like, or a tuple of them (one per signal)
        Half-width of each band, in the signal's unit (or, with ``relative_to_peak``, as a
        fraction of the signal's peak :math:`\\max_j |e(t_j)|`); broadcast against the leading
        axes of its signal (a per-case band has shape (..., 1)).
    relative_to_peak : bool
        Read ``band`` as a fraction of each signal's peak magnitude over the run.

    Returns
    -------
    ndarray (...)
        :math:`t_s`; NaN where the last sample is outside a band (not settled within the run).
    """
    t = np.asarray(t, dtype=float)
    signals = error if isinstance(error, tuple) else (error,)
    bands = band if isinstance(band, tuple) else (band,) * len(signals)
    if len(bands) != len(signals):
        raise FieldError("band", f"one per error signal ({len(signals)}), got {len(bands)}")
    outside: np.ndarray | bool = False
    for e, b in zip(signals, bands):
        magnitude = np.abs(np.asarray(e, dtype=float))
        if magnitude.shape[-1] != t.size:
            raise FieldError(
                "error", f"{magnitude.shape[-1]} samples along its last axis for {t.size} times"
            )
        limit = np.asarray(b, dtype=float)
        if relative_to_peak:
            limit = limit * magnitude.max(axis=-1, keepdims=True)
        outside = outside | (magnitude > limit)
    outside = np.asarray(outside)
    # index just after the last sample outside (0 when none is)
    after_last = np.where(outside.any(axis=-1), t.size - np.argmax(outside[..., ::-1], axis=-1), 0)
    return settled_at(t, after_last)


def settled_at(t: npt.ArrayLike, after_last_outside: float | npt.ArrayLike) -> FloatArray:
    """:math:`t_s` from the index just after the last sample outside the band (0 when none
    is; ``t.size`` when the last sample is outside: NaN, not settled). The step shared by
    :func:`settling_time` and the compiled loop, which accumulates that index sample by sample
    instead of keeping the history (:func:`flexsat.sim.compiled.run_reduced`)."""
    t = np.asarray(t, dtype=float)
    k = np.asarray(after_last_outside).astype(np.int64)  # the compiled loop keeps it as a float
    return np.where(k >= t.size, np.nan, t[np.minimum(k, t.size - 1)])


def reported(value: SupportsFloat) -> float | None:
    """A settling time as reported (JSON, tables): the float, or None for not settled (NaN)."""
    value = float(value)
    return None if math.isnan(value) else value


__all__ = ["reported", "settled_at", "settling_time"]
