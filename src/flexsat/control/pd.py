"""Proportional-derivative attitude control with rigid-body pole placement.

Hailey, Sortun & Agrawal c. 1992 (NPS), Eqs. 20-24 and 29:

    T_c = −k (θ_e + τ θ'_e),   θ_e = θ − θ_ref
    s² + 2 ζ ω_n s + ω_n² = 0  for the rigid plant I θ'' = T_c  ⇒  k = I ω_n²,  k τ = 2 ζ ω_n I
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.control.base import SlewLaw
from flexsat.control.linear_form import per_case, reference_tables, sample_times, static_law
from flexsat.input_checks import require_finite, require_nonneg, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.linear_form import LinearLaw
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.units import FloatArray, QuantityArrayLike


class PD(SlewLaw):
    """u = u_ref − kp (θ − θ_ref) − kd (θ' − θ'_ref).

    Parameters
    ----------
    kp, kd : float, array, str or pint.Quantity
        Position gain (N m/rad) and rate gain (N m s/rad), >= 0; a number is in these SI
        units, a Quantity or a string such as ``"3000 ozf*in/rad"`` is converted.
    target : float, array, str or pint.Quantity
        Final angle, rad, when no reference is given (a step command, Hailey,
        Sortun & Agrawal c. 1992 Eq. 20).
    reference : TorqueShape, optional
        Shaped reference to track (Hailey, Sortun & Agrawal c. 1992 Eq. 29);
        its torque is fed forward when
        ``feedforward`` is true.
    """

    reads = ("theta", "theta_dot")
    writes = ("torque",)

    def __init__(
        self,
        kp: QuantityArrayLike,
        kd: QuantityArrayLike,
        target: QuantityArrayLike = 0.0,
        reference: TorqueShape | None = None,
        feedforward: bool = True,
    ) -> None:
        self.kp = require_nonneg(kp, "kp", "N*m/rad")
        self.kd = require_nonneg(kd, "kd", "N*m*s/rad")
        self.reference = reference
        self.feedforward = bool(feedforward)
        final = target if reference is None else reference.theta0 + reference.angle
        self.target = require_finite(final, "target", "rad")

    @classmethod
    def from_rigid_poles(
        cls,
        inertia: QuantityArrayLike,
        natural_frequency: QuantityArrayLike,
        damping_ratio: QuantityArrayLike,
        **kwargs: Any,
    ) -> PD:
        """Gains placing the rigid closed-loop poles at ω_n, ζ (Hailey, Sortun & Agrawal
        c. 1992 Eqs. 20-24).

        ``inertia`` in kg m², ``natural_frequency`` in rad/s (``"0.06 Hz"`` converts with its
        2π), ``damping_ratio`` dimensionless; each a number in SI, a Quantity or a unit string.
        """
        J = require_positive(inertia, "inertia", "kg*m**2")
        wn = require_positive(natural_frequency, "natural_frequency", "rad/s")
        zeta = require_nonneg(damping_ratio, "damping_ratio", "")
        return cls(J * wn**2, 2 * zeta * wn * J, **kwargs)

    def _batched(self) -> list[tuple[int, ...]]:
        return [np.shape(self.kp), np.shape(self.kd), np.shape(self.target)]

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        th_r, thd_r, _, u_r = self.reference_at(t)
        u = -self.kp * (y["theta"] - th_r) - self.kd * (y["theta_dot"] - thd_r)
        if self.feedforward:
            u = u + u_r
        return u, state

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        """No internal state: D = [−kp, −kd] on y = (θ, θ'), y_ref = (θ_ref, θ'_ref) and
        u_ff = u_ref (zero without ``feedforward``), Hailey, Sortun &
        Agrawal c. 1992 Eqs. 20 and 29."""
        _, grid = sample_times(dt, times)
        th, thd, _, u_r = reference_tables(self, grid, n_cases)
        kp, kd = per_case(self.kp, n_cases, "kp"), per_case(self.kd, n_cases, "kd")
        D = np.stack(np.broadcast_arrays(-kp, -kd), axis=-1)
        y_ref = np.stack(np.broadcast_arrays(th, thd), axis=-1)
        u_ff = (u_r if self.feedforward else np.zeros((len(grid), 1)))[..., None]
        return static_law(D[None, :, None, :], y_ref, u_ff, self.reads, self.writes)
