"""The Junkins, Pollock & Rahman 1990 trade surfaces of the TAMU 40° maneuver: T, E(T) and
μ_max over (α, u_max).

Junkins, Rahman & Bang, Att. 3 Figs. 5–7 and Eqs. 12–16, 22 (Junkins, Pollock & Rahman 1990),
on :func:`flexsat.cases.tamu`: the published
slew angle (40°), the reference designed with the case's ``reference_inertia`` (the published
I = 2128 oz-in-s² by default), the open-loop flexible response of the case's model (10 modes,
hub 50 oz-in-s², damping 0.005) and, for μ, Control Law II with the default scenario's gains
(g1 = 3000 oz-in/rad, g2 = 800 oz-in-s/rad, g3 = 0; the paper does not state Fig. 7's
gains). The physics is :mod:`flexsat.design.trade_surfaces`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from flexsat.cases.tamu import TamuCase, tamu
from flexsat.design.trade_surfaces import (
    maneuver_time_surface,
    residual_energy_surface,
    tracking_bound_surface,
)
from flexsat.units import QuantityArrayLike, QuantityLike, to_si_array

#: the grid of the developers' T table (Eq. 16 evaluated), as published: α and u_max [oz-in]
ALPHA_GRID = (0.0, 0.05, 0.10, 0.15, 0.20, 0.25)
U_MAX_GRID = tuple(f"{v} ozf*in" for v in (100, 200, 300, 400, 500, 600))
#: Law II gains of the default scenario (tamu_default.yaml), used for μ
LAW_II_GAINS: dict[str, QuantityLike] = {
    "g1": "3000 ozf*in/rad",
    "g2": "800 ozf*in*s/rad",
    "g3": 0.0,
}


def tamu_trade_surfaces(
    case: TamuCase | None = None,
    alpha: QuantityArrayLike = ALPHA_GRID,
    u_max: QuantityArrayLike = U_MAX_GRID,
    g1: QuantityArrayLike = LAW_II_GAINS["g1"],
    g2: QuantityArrayLike = LAW_II_GAINS["g2"],
    g3: QuantityArrayLike = LAW_II_GAINS["g3"],
    reference_inertia: QuantityLike | None = None,
    n_samples: int = 2001,
    horizon: float = 1.0,
) -> xr.Dataset:
    """T, E(T) and μ_max of the TAMU 40° slew over the (α, u_max) grid.

    Parameters
    ----------
    case : TamuCase, optional
        Default ``tamu()``; the model must be linear (``stiffening=False``).
    alpha : (n_alpha,) array
        Rise-time fractions in [0, 1/4].
    u_max : (n_u_max,) array
        Peak torques: numbers in N m, or quantities (default 100 … 600 oz-in, as published).
    g1, g2, g3 : gains of Law II for μ (N m/rad, N m s/rad, dimensionless; unit strings taken).
    reference_inertia : float, optional
        Rigid inertia of the reference design, kg m² (default the case's); the model's own
        total inertia (``case.model().total_inertia``) removes the 4 % design mismatch, so μ
        then measures the flexibility alone.
    n_samples, horizon
        μ sampling: :func:`~flexsat.design.trade_surfaces.tracking_bound_surface`.

    Returns
    -------
    xarray.Dataset
        ``maneuver_time`` [s], ``residual_energy`` [J], ``mu_max`` [rad/s] on dims
        (alpha, u_max); coordinate u_max in N m.
    """
    case = tamu() if case is None else case
    model = case.model()
    inertia = case.reference_inertia if reference_inertia is None else reference_inertia
    u = to_si_array(u_max, "N*m", "u_max")
    a = np.asarray(alpha, float)
    g = {
        k: to_si_array(v, unit, k)
        for k, v, unit in (("g1", g1, "N*m/rad"), ("g2", g2, "N*m*s/rad"), ("g3", g3, ""))
    }
    T = maneuver_time_surface(case.angle, inertia, a, u)
    E = residual_energy_surface(model, case.angle, inertia, a, u)
    mu = tracking_bound_surface(
        model,
        case.angle,
        inertia,
        a,
        u,
        g["g1"],
        g["g2"],
        g["g3"],
        case.params.appendage_inertia,
        n_samples,
        horizon,
    )
    dims = ("alpha", "u_max")
    return xr.Dataset(
        {
            "maneuver_time": (dims, T, {"units": "s", "source": "Att. 3 Eq. 16 (Fig. 5)"}),
            "residual_energy": (
                dims,
                E,
                {
                    "units": "J",
                    "source": "Att. 3 Fig. 6: vibration "
                    "energy of the open-loop flexible response at T",
                },
            ),
            "mu_max": (
                dims,
                mu,
                {
                    "units": "rad/s",
                    "source": f"Att. 3 Eq. 22 (Fig. 7), max over [0, {horizon:g} T]",
                },
            ),
        },
        coords={"alpha": ("alpha", a), "u_max": ("u_max", u, {"units": "N m"})},
        attrs={
            "angle_rad": case.angle,
            "reference_inertia_kg_m2": float(inertia),
            "model_inertia_kg_m2": model.total_inertia,
            "n_modes": model.n_modes,
            **{f"{k}_si": float(v) for k, v in g.items()},
        },
    )


__all__ = ["ALPHA_GRID", "LAW_II_GAINS", "U_MAX_GRID", "tamu_trade_surfaces"]
