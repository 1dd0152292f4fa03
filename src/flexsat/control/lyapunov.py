"""Lyapunov maneuver laws of Junkins, Rahman & Bang for a hub with flexible appendages.

Att. 3 of Junkins, Pollock & Rahman 1990 (Junkins, Rahman & Bang, AIAA Aerospace Sciences 1990).
With the error-energy function (Att. 3 Eq. 8, a1 = 1)

    2U = I_hub θ'² + g1 (θ − θ_f)² + (1 + g3/n) · 2 E_beams

the rate is U' = θ' [u + g1 (θ − θ_f) + g3 (l0 S0 − M0)] (Eq. 9), and Control Law I (Eq. 11)

    u = −[g1 (θ − θ_f) + g2 θ' + g3 (l0 S0 − M0)]     ⇒  U' = −g2 θ'²

is globally stabilising for g1 >= 0, g2 >= 0, g3 > −n (n = 4 appendages in the paper; the
papers print g3 = 4 (a3 − a1)/a1, so a3 > 0 ⇔ g3 > −n). Control Law II (Eq. 17) tracks a
torque-shaped rigid reference and equals Law I once the reference has ended:

    u = u_ref − [g1 (θ − θ_ref) + g2 (θ' − θ'_ref) + g3 ((l0 S0 − M0) − I_b θ''_ref)]
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import SlewLaw
from flexsat.control.linear_form import per_case, reference_tables, sample_times, static_law
from flexsat.input_checks import FieldError, require_finite, require_nonneg

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.linear_form import LinearLaw
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.units import FloatArray, QuantityArrayLike


def check_lyapunov_gains(
    g1: QuantityArrayLike, g2: QuantityArrayLike, g3: QuantityArrayLike, n_appendages: int = 4
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Validate the global-stability conditions g1 >= 0, g2 >= 0, g3 > −n (Att. 3 Eq. 11)."""
    k1 = require_nonneg(g1, "g1", "N*m/rad")
    k2 = require_nonneg(g2, "g2", "N*m*s/rad")
    k3 = require_finite(g3, "g3", "")
    if np.any(k3 <= -n_appendages):
        raise FieldError(
            "g3",
            f"must be > -{n_appendages} (= -n_appendages) for the Lyapunov function to be "
            f"positive definite (a3 > 0), got {k3.tolist()}",
        )
    return k1, k2, k3


class LyapunovRegulator(SlewLaw):
    """Control Law I: constant-gain Lyapunov output feedback (Att. 3 Eq. 11).

    Parameters
    ----------
    g1 : N m/rad;  g2 : N m s/rad;  g3 : dimensionless gain on l0 S0 − M0.
    target : final angle θ_f, rad.

    Notes
    -----
    Each a number in these SI units, a pint Quantity or a unit string (converted).
    """

    reads = ("theta", "theta_dot", "root_torque")
    writes = ("torque",)

    def __init__(
        self,
        g1: QuantityArrayLike,
        g2: QuantityArrayLike,
        g3: QuantityArrayLike = 0.0,
        target: QuantityArrayLike = 0.0,
        n_appendages: int = 4,
    ) -> None:
        self.g1, self.g2, self.g3 = check_lyapunov_gains(g1, g2, g3, n_appendages)
        self.target = require_finite(target, "target", "rad")

    def _batched(self) -> list[tuple[int, ...]]:
        return [np.shape(a) for a in (self.g1, self.g2, self.g3, self.target)]

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        u = -(
            self.g1 * (y["theta"] - self.target)
            + self.g2 * y["theta_dot"]
            + self.g3 * y["root_torque"]
        )
        return u, state

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        """No internal state: D = −[g1, g2, g3] on y = (θ, θ', l0 S0 − M0),
        y_ref = (θ_f, 0, 0), u_ff = 0 (Eq. 11)."""
        _, grid = sample_times(dt, times)
        th, _, _, _ = reference_tables(self, grid, n_cases)
        z = np.zeros((len(grid), 1))
        y_ref = np.stack(np.broadcast_arrays(th, z, z), axis=-1)
        return static_law(_gain_row(self, n_cases), y_ref, z[..., None], self.reads, self.writes)


class LyapunovTracker(SlewLaw):
    """Control Law II: Lyapunov tracking of a torque-shaped rigid reference (Att. 3 Eq. 17).

    Parameters
    ----------
    reference : TorqueShape
        Open-loop rigid reference (e.g. ``SmoothBangBang``); its ``theta_ddot`` is u_ref / I.
    g1, g2, g3 : gains as for Law I.
    appendage_inertia : float
        I_b = ρ (l³ − l0³)/3 + m l² (+ J), kg m², scaling the reference root load
        (l0 S0 − M0)_ref = I_b θ''_ref (Eq. 17).
    """

    reads = ("theta", "theta_dot", "root_torque")
    writes = ("torque",)

    reference: TorqueShape

    def __init__(
        self,
        reference: TorqueShape,
        g1: QuantityArrayLike,
        g2: QuantityArrayLike,
        g3: QuantityArrayLike = 0.0,
        appendage_inertia: QuantityArrayLike = 0.0,
        n_appendages: int = 4,
    ) -> None:
        self.reference = reference
        self.g1, self.g2, self.g3 = check_lyapunov_gains(g1, g2, g3, n_appendages)
        self.appendage_inertia = require_nonneg(appendage_inertia, "appendage_inertia", "kg*m**2")
        self.target = np.asarray(reference.theta0 + reference.angle, float)

    def _batched(self) -> list[tuple[int, ...]]:
        shapes = [np.shape(a) for a in (self.g1, self.g2, self.g3, self.target)]
        return shapes + [np.shape(self.reference.duration)]

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        th_r, thd_r, thdd_r, u_r = self.reference_at(t)
        u = u_r - (
            self.g1 * (y["theta"] - th_r)
            + self.g2 * (y["theta_dot"] - thd_r)
            + self.g3 * (y["root_torque"] - self.appendage_inertia * thdd_r)
        )
        return u, state

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        """No internal state: D = −[g1, g2, g3] on y = (θ, θ', l0 S0 − M0),
        y_ref = (θ_ref, θ'_ref, I_b θ''_ref), u_ff = u_ref (Eq. 17)."""
        _, grid = sample_times(dt, times)
        th, thd, thdd, u_r = reference_tables(self, grid, n_cases)
        Ib = per_case(self.appendage_inertia, n_cases, "appendage_inertia")
        y_ref = np.stack(np.broadcast_arrays(th, thd, Ib * thdd), axis=-1)
        y_ref.flags.writeable = False  # ours alone: the LinearLaw keeps it without a copy
        return static_law(_gain_row(self, n_cases), y_ref, u_r[..., None], self.reads, self.writes)


def _gain_row(law: LyapunovRegulator | LyapunovTracker, n_cases: int) -> FloatArray:
    """D = −[g1, g2, g3], shape (1, C, 1, 3)."""
    g = [per_case(getattr(law, k), n_cases, k) for k in ("g1", "g2", "g3")]
    return -np.stack(np.broadcast_arrays(*g), axis=-1)[None, :, None, :]
