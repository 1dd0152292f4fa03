"""The frontal-assault identification on the TAMU grid: its motors, strain gauges and FRF grid.

Sources: Junkins, Pollock & Rahman 1990 (the Texas A&M final report), Att. 6 (G. H. James and
J. L. Junkins, "Novel Sensing and Structural Identification Methods: Preliminary Analytical and
Experimental Results", AAS paper 89-425, 1989: three reaction-wheel motors, node 3 about y and
nodes 7 and 9 about x; six strain-gauge packets; FRFs of all 3 inputs × 6 outputs from 0.4 to
10.0 Hz in 0.2 Hz steps; Table 1 damping ratios) and the slides "Structural identification: a
frontal assault" (Eqs. 8–12) of the same report (:mod:`flexsat.identify.frontal_assault`).

The model is the case's 60-dof finite-element grid (:func:`flexsat.cases.tamu_grid`, default
0.5 kg motors) with its three stiffness substructures as the parameters (K(p) = K_g +
Σ p_k K_k: EI and GJ of the clamp verticals, the other verticals and the horizontals scale,
the gravity stiffness K_g does not), Rayleigh damping C = α M + β K(p) matched to Att. 6
Table 1's ζ₁ = 0.00603 and ζ₅ = 0.01293 at p = 1, the motors' torques as inputs and six
strain gauges as outputs. A gauge on the member from node a to node b reads the member's mean
surface strain, ε = (t/2)(θ_b − θ_a)/L (Att. 6 Eqs. 16–21 averaged over the element: the mean
curvature of a cubic element is the rotation difference over its length; t = 1/8 in), θ the
rotation about the gauge's axis. The gauge layout is the one of ``examples/
tamu_grid_identification.yaml`` (three on the clamp verticals, two mid-height, one low), since
Att. 6 does not give the gauge positions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.identify.frontal_assault import FRFData, FrontalAssaultModel
from flexsat.input_checks import FieldError, require_nonneg
from flexsat.units import FloatArray, to_si

__all__ = [
    "FRF_HZ",
    "GAUGES",
    "WHEELS",
    "grid_frf_model",
    "simulate_grid_frf",
]

#: (node a, node b, rotation axis) of the six strain-gauge packets
GAUGES = ((16, 21, "x"), (18, 23, "x"), (20, 25, "x"), (11, 16, "x"), (13, 18, "x"), (9, 14, "x"))
#: (node, torque axis) of the three reaction-wheel motors (Att. 6)
WHEELS = ((3, "y"), (7, "x"), (9, "x"))
#: Att. 6: 0.4 to 10.0 Hz in 0.2 Hz steps, 49 frequencies
FRF_HZ = np.round(np.arange(0.4, 10.0 + 1e-9, 0.2), 10)
#: Att. 6 Table 1: damping ratios of modes 1 and 5, which set α and β
ZETA_1, ZETA_5 = 0.00603, 0.01293
THICKNESS = to_si("0.125 in", "m")


def _dof_vector(asm: Any, terms: dict[tuple[int, str], float]) -> FloatArray:
    v = np.zeros(asm.n_dofs)
    for (node, dof), weight in terms.items():
        try:
            v[asm.index(int(node), dof)] += weight
        except ValueError:
            continue  # a clamped node does not rotate
    return v


def grid_frf_model(
    case: Any = None,
    gauges: Sequence[tuple[int, int, str]] = GAUGES,
    wheels: Sequence[tuple[int, str]] = WHEELS,
) -> FrontalAssaultModel:
    """The :class:`~flexsat.identify.frontal_assault.FrontalAssaultModel` of the grid (module
    docstring); ``case`` a :class:`~flexsat.cases.tamu_grid.TamuGridCase` (default
    ``tamu_grid(motor_mass="0.5 kg")``)."""
    from flexsat.cases.tamu_grid import tamu_grid

    grid = case if case is not None else tamu_grid(motor_mass="0.5 kg")
    base = grid.structure().assemble()
    m, k = base.M.toarray(), base.K.toarray()
    parts = []
    for name in grid.substructures:
        doubled = grid.structure(stiffness_scale={name: 2.0}).assemble().K.toarray()
        parts.append(doubled - k)
    k0 = k - sum(parts, np.zeros_like(k))  # the gravity stiffness, not scaled
    h = np.array(
        [
            _dof_vector(base, {(b, "r" + ax): 1.0, (a, "r" + ax): -1.0})
            * THICKNESS
            / (2 * grid.spacing)
            for a, b, ax in gauges
        ]
    )
    if h.ndim != 2 or not np.all(np.abs(h).sum(axis=1) > 0):
        raise FieldError("gauges", "every gauge must span a member with a free node")
    b = np.column_stack([_dof_vector(base, {(n, "r" + ax): 1.0}) for n, ax in wheels])
    if not np.all(np.abs(b).sum(axis=0) > 0):
        raise FieldError("wheels", "every wheel must sit on a free node")
    w = np.sqrt(sla.eigh(k, m, eigvals_only=True, subset_by_index=(0, 4)))
    w1, w5 = w[0], w[4]
    # ζ_i = α/(2ω_i) + β ω_i/2 at modes 1 and 5
    alpha, beta = np.linalg.solve(
        [[1 / (2 * w1), w1 / 2], [1 / (2 * w5), w5 / 2]], [ZETA_1, ZETA_5]
    )
    return FrontalAssaultModel(
        m, k0, tuple(parts), b, h, float(alpha), float(beta), tuple(grid.substructures)
    )


def simulate_grid_frf(
    model: FrontalAssaultModel,
    p_true: npt.ArrayLike,
    noise: float = 0.0,
    n_frequencies: int = 5,
    frequency_noise: float = 0.0,
    seed: int | np.random.Generator | None = None,
    frequencies_hz: npt.ArrayLike = FRF_HZ,
) -> FRFData:
    """Measured FRFs (Att. 6 grid, default) and the lowest ``n_frequencies`` free-vibration
    frequencies of the model at ``p_true``, with complex Gaussian noise of RMS ``noise`` × each
    gauge's RMS over the inputs and the band (σ = that / √2 on each real and imaginary part) and
    ``frequency_noise`` × Ω on each frequency. The returned standard deviations are the true
    ones (without noise: the same fractions at 1e-3 and 1e-4, which only weight the fit)."""
    rng = np.random.default_rng(seed)
    wgrid = 2 * np.pi * np.asarray(frequencies_hz, float)
    g = model.frf(p_true, wgrid)
    nz = float(require_nonneg(noise, "noise").reshape(-1)[0])
    fz = float(require_nonneg(frequency_noise, "frequency_noise").reshape(-1)[0])
    # per gauge: its RMS over inputs and band (an element zero by symmetry has its gauge's noise)
    rms = np.sqrt(np.mean(np.abs(g) ** 2, axis=(0, 2)))[:, None]  # (s, 1)
    sigma = np.broadcast_to((nz if nz > 0 else 1e-3) * rms / np.sqrt(2), g.shape)
    if nz > 0:
        g = g + sigma * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape))
    om = model.modes(p_true, n_frequencies)[0] if n_frequencies else np.zeros(0)
    osig = (fz if fz > 0 else 1e-4) * om
    if fz > 0:
        om = om + osig * rng.standard_normal(om.shape)
    return FRFData(wgrid, g, sigma, om, osig)
