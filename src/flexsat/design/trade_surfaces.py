r"""Trade surfaces of the smoothed bang-bang maneuver over (α, u_max): T, E(T) and μ_max.

Att. 3 of Junkins, Pollock & Rahman 1990 (Junkins, Rahman & Bang), Eqs. 12-16 and 22, the
designer's three surfaces for a rest-to-rest slew of a hub with flexible appendages:

- **T(α, u_max)** (Fig. 5), Eq. 16:
  :math:`T = \sqrt{I\,|\theta_f - \theta_o| / (u_{max}(1/4 - \alpha/2 + \alpha^2/10))}`;
- **E(T)(α, u_max)** (Fig. 6): the vibration energy of the open-loop flexible response to
  u_ref = u_max f(αT, T, t) (Eq. 12) at t = T. The torque's net impulse is zero, so the angular
  momentum at T is zero and this is also the total energy the paper plots;
- **μ_max(α, u_max)** (Fig. 7): the largest value over the maneuver of the tracking bound of
  Control Law II, Eq. 22 (Att. 1/2 Eq. 18)

  .. math::

      \mu(t) = \frac{1}{g_2}\left|g_1\Delta\theta + g_2\Delta\dot\theta
               + g_3\Delta(l_oS_o - M_o)\right|,\qquad \Delta(\,) = (\,)_r - (\,)_{ref},

  ()_r the open-loop flexible response to u_ref, ()_ref the rigid reference
  (θ_ref, θ'_ref, I_b θ''_ref). Wherever |θ' − θ'_r| > μ(t), U' <= 0 (Eq. 21).

The flexible responses are exact (:func:`flexsat.sim.open_loop.open_loop_response`: the
Duhamel integral of the piecewise-cubic torque in modal coordinates), so a grid point costs a
few complex exponentials, with no time step. Every surface is an array of shape
(n_alpha, n_u_max): axis 0 is α, axis 1 is u_max.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.control.lyapunov import check_lyapunov_gains
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)
from flexsat.maneuvers.torque_shapes import SmoothBangBang
from flexsat.sim.instruments import unit_row
from flexsat.sim.open_loop import open_loop_response
from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

if TYPE_CHECKING:
    from flexsat.dynamics.hub_appendage import HubAppendage
    from flexsat.dynamics.hybrid import HybridPlant


def _grid_shape(
    angle: QuantityLike, inertia: QuantityLike, alpha: QuantityArrayLike, u_max: QuantityArrayLike
) -> tuple[SmoothBangBang, tuple[int, ...]]:
    """The smoothed bang-bang family on the (α, u_max) grid, flattened to C = n_alpha · n_u_max
    cases (α-major), and the grid's shape."""
    alpha = require_finite(alpha, "alpha", "")
    u_max = require_positive(u_max, "u_max", "N*m")
    if alpha.ndim != 1 or u_max.ndim != 1:
        raise ValueError(
            f"alpha, u_max: give 1-D grids, got shapes {alpha.shape} and {u_max.shape}"
        )
    a, u = np.meshgrid(alpha, u_max, indexing="ij")
    return SmoothBangBang(angle, inertia, u_max=u.ravel(), alpha=a.ravel()), a.shape


def maneuver_time_surface(
    angle: QuantityLike, inertia: QuantityLike, alpha: QuantityArrayLike, u_max: QuantityArrayLike
) -> FloatArray:
    """Rigid maneuver time T [s] over the grid, Att. 3 Eq. 16 (module docstring).

    Parameters
    ----------
    angle : float
        Slew angle θ_f − θ_o, rad (or a unit string, ``"40 deg"``).
    inertia : float
        Rigid inertia I of the reference design, kg m².
    alpha : (n_alpha,) array
        Rise-time fractions Δt/T in [0, 1/4].
    u_max : (n_u_max,) array
        Peak torques, N m (or quantities, ``["100 ozf*in", ...]``).

    Returns
    -------
    (n_alpha, n_u_max) array
    """
    shape, grid = _grid_shape(angle, inertia, alpha, u_max)
    return shape.duration.reshape(grid)


def residual_energy_surface(
    plant: HybridPlant,
    angle: QuantityLike,
    inertia: QuantityLike,
    alpha: QuantityArrayLike,
    u_max: QuantityArrayLike,
) -> FloatArray:
    """Vibration energy E(T) [J] of the open-loop flexible response at the maneuver's end.

    Parameters
    ----------
    plant : HybridPlant
        A linear hub + flexible-body plant (e.g. the 10-mode TAMU model), at rest at t = 0.
    angle, inertia, alpha, u_max
        As for :func:`maneuver_time_surface`; ``inertia`` designs the reference torque (the
        plant keeps its own inertia).

    Returns
    -------
    (n_alpha, n_u_max) array
        ``plant.vibration_energy`` of the exact state at t = T (Att. 3 Fig. 6).
    """
    shape, grid = _grid_shape(angle, inertia, alpha, u_max)
    x = open_loop_response(plant, shape, shape.duration[None, :])[0]
    return plant.vibration_energy(x).reshape(grid)


def tracking_bound(
    plant: HubAppendage,
    shape: SmoothBangBang,
    times: QuantityArrayLike,
    g1: npt.ArrayLike,
    g2: npt.ArrayLike,
    g3: npt.ArrayLike = 0.0,
    appendage_inertia: QuantityLike = 0.0,
) -> FloatArray:
    """μ(t) of Control Law II (Att. 3 Eq. 22) at ``times`` for the reference torque ``shape``.

    Parameters
    ----------
    plant : HybridPlant
        Linear plant with the ``root_torque`` output (l_o S_o − M_o for beam appendages).
    shape : SmoothBangBang
        The rigid reference; its parameters scalars or (C,) arrays (C cases).
    times : (n_t,) or (n_t, C) array
        Times, s (>= 0).
    g1, g2, g3 : float or (C,) array
        Law II gains: N m/rad, N m s/rad (> 0: μ divides by it), dimensionless.
    appendage_inertia : float
        I_b of the reference root load (l_o S_o − M_o)_ref = I_b θ''_ref (Att. 3 Eq. 17), kg m²,
        as the law uses it.

    Returns
    -------
    (n_t, C) array
        μ(t), rad/s.
    """
    k1, k2, k3 = check_lyapunov_gains(g1, g2, g3, plant.n_appendages)
    if np.any(k2 <= 0):
        raise FieldError("g2", "must be > 0 (μ of Eq. 22 is divided by g2)")
    I_b = require_nonneg(appendage_inertia, "appendage_inertia", "kg*m**2")
    if np.ndim(shape.duration) > 1:
        raise FieldError(
            "shape",
            f"parameters must be scalars or (C,) arrays, got shape {np.shape(shape.duration)}",
        )
    times = require_finite(times, "times", "s")
    C = int(np.size(shape.duration))
    t = np.broadcast_to(times.reshape(times.shape[0], -1), (times.shape[0], C))
    x = open_loop_response(plant, shape, t)
    ref = shape(t)
    R_r = plant.output("root_torque", x, ref.u[..., None])
    th, thd = unit_row(plant, "theta"), unit_row(plant, "theta_dot")
    if th is None or thd is None:
        raise FieldError("plant", "μ needs θ and θ' as state coordinates (a hub plant)")
    d = (
        k1 * (x[..., th] - ref.theta)
        + k2 * (x[..., thd] - ref.theta_dot)
        + k3 * (R_r - I_b * ref.theta_ddot)
    )
    return np.abs(d) / k2


def tracking_bound_surface(
    plant: HubAppendage,
    angle: QuantityLike,
    inertia: QuantityLike,
    alpha: QuantityArrayLike,
    u_max: QuantityArrayLike,
    g1: npt.ArrayLike,
    g2: npt.ArrayLike,
    g3: npt.ArrayLike = 0.0,
    appendage_inertia: QuantityLike = 0.0,
    n_samples: int = 2001,
    horizon: float = 1.0,
) -> FloatArray:
    """μ_max(α, u_max) = max_t μ(t) over the grid (Att. 3 Fig. 7), rad/s.

    μ is sampled at ``n_samples`` equally spaced times over [0, horizon · T] of each maneuver
    (horizon 1: the maneuver itself; after T the law is Law I and μ holds the residual
    vibration and any inertia mismatch). The sampled maximum falls short of the true one by
    about (π/n_per_period)²/2 of it, n_per_period the samples per period of the fastest
    significant content.

    Parameters
    ----------
    plant, angle, inertia, alpha, u_max
        As for :func:`residual_energy_surface`.
    g1, g2, g3, appendage_inertia
        As for :func:`tracking_bound` (scalars: one set of gains for the whole grid).
    n_samples : int
        Samples per maneuver.
    horizon : float
        Window length as a multiple of T (>= 1 keeps the whole maneuver).

    Returns
    -------
    (n_alpha, n_u_max) array
    """
    n = require_count(n_samples, "n_samples")
    window = require_positive(horizon, "horizon", "")
    shape, grid = _grid_shape(angle, inertia, alpha, u_max)
    t = np.linspace(0.0, 1.0, n)[:, None] * (window * shape.duration)[None, :]
    mu = tracking_bound(plant, shape, t, g1, g2, g3, appendage_inertia)
    return mu.max(axis=0).reshape(grid)


__all__ = [
    "maneuver_time_surface",
    "residual_energy_surface",
    "tracking_bound",
    "tracking_bound_surface",
]
