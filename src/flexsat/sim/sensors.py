"""Sensors sampled at the control rate: angle encoder, rate from a least-squares differentiating
filter or a gyro, strain-gauge root loads. Noise comes from per-case reproducible streams."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from flexsat.input_checks import FieldError, require_nonneg, set_si


def least_squares_derivative_weights(window: int, order: int, dt: float) -> np.ndarray:
    """Weights c_j with θ'(t_k) ≈ Σ_j c_j θ(t_{k−window+1+j}).

    Fits a polynomial of degree ``order`` to the last ``window`` samples by least squares and
    differentiates it at the newest sample (a causal Savitzky-Golay differentiator). Exact for
    polynomials of degree <= order.
    """
    if order < 1 or window < order + 1:
        raise FieldError(
            "rate_filter",
            f"need order >= 1 and window >= order + 1, got window={window}, order={order}",
        )
    tau = dt * (np.arange(window) - (window - 1))
    V = np.vander(tau, order + 1, increasing=True)
    return np.linalg.pinv(V)[1]


@dataclass(frozen=True)
class Sensors:
    """Sensor suite of the single-axis experiment.

    Parameters
    ----------
    encoder_resolution : float
        Angle quantum, rad (TAMU: 0.01 deg); 0 gives the exact angle.
    rate : {"ideal", "ls_filter", "gyro"}
        Source of the rate measurement.
    rate_window, rate_order : int
        Least-squares differentiating filter over the last ``rate_window`` encoder samples.
    gyro_noise : float
        Gyro white noise, 1σ rad/s per sample.
    strain_noise : float
        Noise on the measured l0 S0 − M0, 1σ N m per sample.

    Notes
    -----
    The physical fields take a number in SI, a pint Quantity or a unit string
    (``encoder_resolution="0.01 deg"``), and are stored in SI.
    """

    encoder_resolution: float = 0.0
    rate: Literal["ideal", "ls_filter", "gyro"] = "ideal"
    rate_window: int = 8
    rate_order: int = 1
    gyro_noise: float = 0.0
    strain_noise: float = 0.0

    def __post_init__(self) -> None:
        set_si(self, "encoder_resolution", require_nonneg, "rad")
        set_si(self, "gyro_noise", require_nonneg, "rad/s")
        set_si(self, "strain_noise", require_nonneg, "N*m")
        if self.rate not in ("ideal", "ls_filter", "gyro"):
            raise FieldError("rate", f"must be 'ideal', 'ls_filter' or 'gyro', got {self.rate!r}")
        least_squares_derivative_weights(self.rate_window, self.rate_order, 1.0)

    def quantize(self, theta: np.ndarray) -> np.ndarray:
        q = self.encoder_resolution
        return theta if q == 0 else q * np.round(theta / q)
