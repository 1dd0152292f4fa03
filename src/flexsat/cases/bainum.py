"""Bainum & Reddy's long free-free beam in orbit with point actuators (Bainum & Reddy 1979).

P. M. Bainum and A. S. S. R. Reddy, *The Dynamics and Control of Large Flexible Space
Structures - II, Part A*, NASA CR-158684, Howard University (1979).

Model (Ch. II eqs 1-6; Ch. III eqs 29-34). A uniform free-free beam of
length l, centre of mass on a circular orbit of rate ω_c, planar pitch θ (from the local
vertical) and transverse bending amplitudes A_n = l z_n. In the nondimensional time τ = ω_c t,
with ' = d/dτ:

- nonlinear (eqs 1-2)::

      θ'' + 1.5 sin 2θ                               = u_θ
      z_n'' + [F_n - (3 sin²θ - 1) - (θ' - 1)²] z_n = u_n,    F_n = (ω_n/ω_c)²

- linear (eqs 5-6): θ'' + 3θ = u_θ, z_n'' + F_n z_n = u_n (the orbital terms -(3sin²θ - 1) and
  -(θ' - 1)² cancel at θ = θ' = 0);
- point forces f_j at ξ_j (eqs 10-15): u = B_act f with pitch row -ξ_j/(J ω_c²) and mode rows
  φ_n(ξ_j)/(M_n l ω_c²). The report's numbers are l/(2 J ω_c²) = 59.52 and 2/(M_n l ω_c²) = 20.0
  (Ch. II §4; M_n = ρl for every mode, Ch. II §2), so here ``pitch_influence`` = 59.52 and
  ``modal_influence`` = 1/(M l ω_c²) = 10.0, with the mode shapes of Appendix A normalized to
  φ = +2 at the left end ξ = -l/2 and ∫φ² dχ = l (Appendix A).

Sign convention of the gains (the report's, Ch. III eq 3): f = K_pos x + K_rate x', so the
closed loop is x'' + F x = G (K_pos x + K_rate x').

This module is the beam model (:class:`BainumBeam`, :func:`bainum`). The chapters reproduced
are in :mod:`flexsat.cases.bainum_control` (Ch. II controllability Cases 1-4 and the numerical
example; Ch. III decoupling and the per-mode linear regulator) and
:mod:`flexsat.cases.bainum_three_mass` (Ch. IV three-mass model). The errata (repaired printed
numbers) are in :data:`ERRATA` and applied by :func:`published_matrix` (docs/bainum.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.control.scheduled import ScheduledStateFeedback
from flexsat.input_checks import FieldError, require_count, require_finite
from flexsat.sim import continuous

if TYPE_CHECKING:
    from flexsat.dynamics.orbit import BeamInOrbit
    from flexsat.dynamics.structural import StructuralPlant

SOURCE = CASES["bainum"].source

#: Earth's gravitational parameter (m³/s²) and equatorial radius (m), for the orbit rate
EARTH_MU = 3.986004418e14
EARTH_RADIUS = 6378137.0

#: numbers of Bainum & Reddy 1979 exactly as printed (matrices row by row); see :data:`ERRATA`
PUBLISHED: dict[str, Any] = {
    # Ch. II §4 and Ch. III §4
    "orbit_altitude": "250 nmi",  # Ch. II §4
    "fundamental_frequency": "0.01 Hz",  # Ch. II §4 "1/100 cps"
    "frequency_ratios": (3200.0, 28800.0, 93079.50, 255331.40),  # (ω_n/ω_c)², Ch. II §4, Ch. III §4
    "pitch_influence": 59.52,  # l/(2 J ω_c²), Ch. II §4
    "modal_influence_end": 20.0,  # 2/(M_1 l ω_c²) (the end value φ = 2), Ch. II §4
    "ch2_gains": (-0.00577, -0.05656, -0.01695),  # K1, K2, K3 (rate), Ch. II §4
    "initial_position": 0.01,  # every position coordinate, rates zero (Ch. II §4, Ch. III §4)
    # Ch. III Case 1, actuators at (-l/2, +l/2, +l/4)
    "ch3_case1_positions": (-0.5, 0.5, 0.25),
    "ch3_case1_G": ((59.52, -59.52, 29.76), (20.0, 20.0, -2.0), (20.0, -20.0, 9.3)),
    "ch3_case1_K": ((-0.011, -2.835, -5.2757), (0.017, -2.835, 3.5171), (0.0602, 0.0, -17.5855)),
    # Ch. III Case 2, actuators at (-l/2, -l/4, 0, +l/4, +l/2)
    "ch3_case2_positions": (-0.5, -0.25, 0.0, 0.25, 0.5),
    "ch3_case2_G": (
        (59.52, 29.76, 0.0, -29.76, -59.52),
        (20.0, -1.98, -14.0, -1.99, 20.0),
        (20.0, -11.698, 0.0, 11.685, -20.0),
        (20.0, -12.437, 14.18, -12.37, 20.0),
        (20.0, -5.1266, 0.0, 5.01, -20.0),
    ),
    "ch3_case2_K": (
        (-1.199, -1.423, -789.03, -7.578, 3365.27),
        (-3.329, 0.0, -2183.39, 0.0, 9392.17),
        (-2.443, 4.015, -1620.70, -21.649, 6946.89),
        (-3.278, 0.0, -2200.36, 0.0, 9397.81),
        (-1.669, -1.423, -780.55, -7.578, 3362.45),
    ),
    # 5 x 10: columns 1-5 position gains on (θ, z1..z4), 6-10 rate gains (Ch. III §4)
    "ch3_case2_lqr": (
        (-0.056, 1.258e-6, 0.0, 0.0, 0.0, -0.6312, -0.712, -394.52, -4.348, 1582.6),
        (-0.1559, 0.0, 0.0, 0.0, 0.0, -1.7527, 0.0, -109.17, 0.0, 4696.0),
        (-0.1144, 3.548e-6, 0.0, 0.0, 0.0, -1.2859, 2.007, -310.35, -6.021, 3473.4),
        (-0.1535, 0.0, 0.0, 0.0, 0.0, -1.7255, 0.0, -1100.18, 0.0, 4698.9),
        (-0.0545, 0.0, 0.0, 0.0, 0.0, -0.6142, -0.712, 390.27, -4.348, 1531.2),
    ),
    # Ch. IV numerical example
    "ch4_total_mass": "1000 kg",
    "ch4_interior_mass_ratio": 1.0,  # m0/m, m = m0 = M/3
    "ch4_spring": "0.18497 N/m",  # k = 3EI/ℓ³
    "ch4_orbit_rate": "1.115e-3 rad/s",
    "ch4_c": "0.1862522 N/m",
    "ch4_lambda": (5.5876e-4, 1.67627e-3),
    "ch4_g": 3.0,
    "ch4_gains": (0.4728, 0.4000),  # K1, K2 of eq (13)
    "ch4_roots": (
        -6.4019e-4,
        complex(-8.58139e-4, 2.952816e-2),
        complex(-8.58139e-4, -2.952816e-2),
        -1.670404,
    ),
}


@dataclass(frozen=True)
class Erratum:
    """One repair of a printed number."""

    where: str
    item: str
    printed: object
    corrected: object
    evidence: str
    index: tuple | None = None  # entry of the PUBLISHED matrix ``item`` replaced, if any


#: the errata applied; ``index`` marks those applied by :func:`published_matrix`
ERRATA = (
    Erratum(
        "Ch. III §4, Case 1 G",
        "ch3_case1_G",
        29.76,
        -29.76,
        "-ξ/(Jω_c²) at ξ = +l/4 is -29.76; only then does -G⁻¹diag(2√F) give the printed K; "
        "with +29.76 the printed K gives an unstable loop (+0.0625 ± 1.7309j)",
        (0, 2),
    ),
    Erratum(
        "Ch. III §4, Case 2 K",
        "ch3_case2_K",
        -1.669,
        -1.167,
        "-G⁻¹diag(2√F) gives -1.16685; the LQR column ratio -0.6142/0.52635 = -1.1669; with "
        "-1.669 the loop is unstable (+0.114, +26.34)",
        (4, 0),
    ),
    Erratum(
        "Ch. III §4, Case 2 LQR", "ch3_case2_lqr", -109.17, -1091.7, "recomputed column 8", (1, 7)
    ),
    Erratum(
        "Ch. III §4, Case 2 LQR", "ch3_case2_lqr", -310.35, -810.35, "recomputed column 8", (2, 7)
    ),
    Erratum(
        "Ch. III §4, Case 2 LQR", "ch3_case2_lqr", 390.27, -390.27, "recomputed column 8", (4, 7)
    ),
    Erratum(
        "Ch. III §4, Case 2 LQR", "ch3_case2_lqr", 1582.6, 1682.6, "recomputed column 10", (0, 9)
    ),
    Erratum(
        "Ch. III §4, Case 2 LQR", "ch3_case2_lqr", 1531.2, 1681.2, "recomputed column 10", (4, 9)
    ),
    Erratum(
        "Ch. II §3, Cases 2 and 4",
        "mode-1 mid-span value",
        -np.sqrt(2.0),
        -1.2156445,
        "Appendix A shape: φ_1(0) = cosh(0)/cosh(h) + 1/cos(h), h = 2.365020; used by "
        "chapter2_case (midspan='exact'); Ch. III Case 2 prints -14.0 = 10 × (-1.40), kept "
        "as printed there because the printed gains were computed with it",
    ),
    Erratum(
        "Ch. IV numerical example",
        "ch4_roots",
        PUBLISHED["ch4_roots"],
        (
            -6.405150e-4,
            complex(-8.654170e-5, 2.957334e-2),
            complex(-8.654170e-5, -2.957334e-2),
            -1.6719864,
        ),
        "roots of eq (16) with the printed c, K1, K2 (np.roots and eig agree); the printed "
        "ones are accurate to about 3 figures (single-precision Bairstow)",
    ),
    Erratum(
        "Ch. II §4",
        "Ch. II example equations",
        "ẍ1 + 3ẋ1; -20K2ẋ1",
        "ẍ1 + 3x1; -20K1ẋ1",
        "structure of eqs (16)-(17); chapter2_example builds the equations from them",
    ),
)


def published_matrix(item: str, errata: bool = True) -> np.ndarray:
    """A printed matrix of :data:`PUBLISHED` as an array, with the :data:`ERRATA` applied.

    Column 9 of ``"ch3_case2_lqr"`` (printed -4.348, -6.021; recomputed -3.789, -10.826) is
    unresolved and left as printed.
    """
    if item not in PUBLISHED:
        raise FieldError("item", f"unknown published item {item!r}")
    M = np.array(PUBLISHED[item], dtype=float)
    if errata:
        for e in ERRATA:
            if e.item == item and e.index is not None:
                M[e.index] = e.corrected
    return M


# -- free-free beam modes (Appendix A) ---------------------------------------------------------
@cache
def _half_root(r: int) -> float:
    """h_r = λ_r l / 2 of bending mode r (r = 1, 2, ...): symmetric modes (odd r) solve
    tan h + tanh h = 0, antisymmetric ones (even r) tan h - tanh h = 0; together they are the
    roots of cos λl cosh λl = 1 (eq A-4)."""
    h0 = (2 * r + 1) * np.pi / 4
    sign = 1.0 if r % 2 else -1.0
    return brentq(
        lambda h: np.sin(h) + sign * np.cos(h) * np.tanh(h),
        h0 - np.pi / 8,
        h0 + np.pi / 8,
        xtol=1e-15,
        rtol=4 * np.finfo(float).eps,
    )


def free_free_lambda_l(n: int) -> np.ndarray:
    """λ_r l, r = 1..n, of the free-free beam (eq A-4): 4.730041, 7.853205, 10.995608, ..."""
    n = require_count(n, "n")
    return np.array([2 * _half_root(r) for r in range(1, n + 1)])


def mode_shape(r: int, x: npt.ArrayLike) -> np.ndarray:
    """Free-free bending mode r at x = ξ/l ∈ [-1/2, 1/2] (eqs A-3, A-5), normalized as the
    report: φ = +2 at the left end x = -1/2 and ∫φ² dχ = l (so M_r = ρl, eq A-13).

    Written about the midpoint, which is stable for large λ and exact in symmetry (an
    antisymmetric mode is exactly 0 at x = 0): with h = λ_r l/2,
    symmetric (odd r) φ = cosh(2hx)/cosh h + cos(2hx)/cos h;
    antisymmetric (even r) φ = -[sinh(2hx)/sinh h + sin(2hx)/sin h].
    """
    r = require_count(r, "r")
    x = require_finite(x, "x")
    if np.any(np.abs(x) > 0.5 + 1e-12):
        raise FieldError("x", f"positions are ξ/l in [-0.5, 0.5], got {x!r}")
    h = _half_root(r)
    if r % 2:
        return np.cosh(2 * h * x) / np.cosh(h) + np.cos(2 * h * x) / np.cos(h)
    return -(np.sinh(2 * h * x) / np.sinh(h) + np.sin(2 * h * x) / np.sin(h))


def theory_ratios(n: int, first: float = 3200.0) -> np.ndarray:
    """(ω_r/ω_c)² of free-free theory scaled to ``first`` for mode 1: first·(λ_r/λ_1)⁴
    (3200, 24315.2, 93447.4, 255352.3, ...; the report's 28,800 for mode 2 is 18 % high)."""
    lam = free_free_lambda_l(n)
    return first * (lam / lam[0]) ** 4


# -- the beam case -----------------------------------------------------------------------------
def _ratios(raw, name: str) -> tuple[float, ...]:
    """A list of (ω_n/ω_c)² > 0; a string "3200, 24315.2" (or "[3200, 24315.2]", as
    ``flexsat modes --set`` passes it) is split at the commas."""
    if isinstance(raw, str):
        try:
            raw = [float(v) for v in raw.strip().strip("[]()").split(",") if v.strip()]
        except ValueError:
            raise FieldError(
                name, f"must be a comma-separated list of numbers, got {raw!r}"
            ) from None
    arr = np.atleast_1d(require_finite(raw, name))
    if arr.ndim != 1 or arr.size == 0 or np.any(arr <= 0):
        raise FieldError(name, f"must be a non-empty list of (ω_n/ω_c)² > 0, got {raw!r}")
    return tuple(float(v) for v in arr)


_INPUTS = {
    "frequency_ratios": Param(PUBLISHED["frequency_ratios"], rule=_ratios),
    "pitch_influence": Param(PUBLISHED["pitch_influence"]),
    "modal_influence": Param(PUBLISHED["modal_influence_end"] / 2),
    "orbit_altitude": Param(PUBLISHED["orbit_altitude"], "m"),
    "orbit_rate": Param(None, "rad/s", optional=True),  # None: circular orbit at the altitude
}


def _positions(positions, name: str = "positions") -> np.ndarray:
    x = require_finite(positions, name)
    x = np.atleast_1d(x)
    if x.ndim != 1 or x.size == 0:
        raise FieldError(name, f"must be a non-empty list of ξ/l, got {positions!r}")
    if np.any(np.abs(x) > 0.5):
        raise FieldError(name, f"actuator positions are ξ/l in [-0.5, 0.5], got {positions!r}")
    return x


#: default stations of :meth:`BainumBeam.plant` (ξ/l): the ends and the midpoint
DEFAULT_STATIONS = {"left": -0.5, "middle": 0.0, "right": 0.5}


@dataclass(frozen=True)
class Response:
    """Closed-loop time history: τ, states [θ, z..., θ', z'...] (columns), forces f_j."""

    tau: np.ndarray
    states: np.ndarray  # (len(tau), 2n)
    forces: np.ndarray  # (len(tau), p)


@dataclass(frozen=True)
class BainumBeam:
    """The beam in orbit, nondimensional (τ = ω_c t, z = A/l); build it with :func:`bainum`.

    Coordinates are ``[θ, z_1, ..., z_k]`` (k = ``n_bending`` bending modes) and states
    ``[θ, z, θ', z']`` (eq 16 / eq 31).
    """

    frequency_ratios: tuple[float, ...]
    pitch_influence: float
    modal_influence: float
    orbit_altitude: float
    orbit_rate: float | None

    # -- parameters --------------------------------------------------------------------------
    @property
    def orbit_rate_value(self) -> float:
        """ω_c, rad/s: ``orbit_rate`` or the circular-orbit rate √(μ/r³) at ``orbit_altitude``
        (250 n.mi. → 1.11577e-3 rad/s; the report's ratio 3200 at 0.01 Hz implies 1.11072e-3)."""
        if self.orbit_rate is not None:
            return self.orbit_rate
        return float(np.sqrt(EARTH_MU / (EARTH_RADIUS + self.orbit_altitude) ** 3))

    def ratios(self, n_bending: int) -> np.ndarray:
        """(ω_n/ω_c)² of the first ``n_bending`` modes: the given ones, then free-free theory
        scaled to mode 1 (:func:`theory_ratios`) beyond them."""
        k = require_count(n_bending, "n_bending")
        given = np.array(self.frequency_ratios)
        if k <= given.size:
            return given[:k].copy()
        return np.concatenate([given, theory_ratios(k, given[0])[given.size :]])

    def stiffness(self, n_bending: int) -> np.ndarray:
        """diag(3, F_1, ..., F_k): the reduced A of eq 17 (pitch libration κ = 3)."""
        return np.concatenate([[3.0], self.ratios(n_bending)])

    def seconds(self, tau: npt.ArrayLike) -> np.ndarray:
        """t = τ/ω_c, s."""
        return np.asarray(tau, dtype=float) / self.orbit_rate_value

    # -- actuators and linear model (eqs 15-17) ----------------------------------------------
    def actuator_matrix(
        self, positions: npt.ArrayLike, n_bending: int, pitch: bool = True
    ) -> np.ndarray:
        """B_act of eq 15 for point forces at ``positions`` (ξ/l): rows θ (if ``pitch``),
        z_1..z_k; pitch row -2(ξ/l)·``pitch_influence``, mode rows φ_r(ξ)·``modal_influence``
        (exact Appendix A shapes)."""
        x = _positions(positions)
        k = require_count(n_bending, "n_bending")
        rows = [-2 * x * self.pitch_influence] if pitch else []
        rows += [mode_shape(r, x) * self.modal_influence for r in range(1, k + 1)]
        return np.array(rows)

    def linear_model(
        self, positions: npt.ArrayLike, n_bending: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """First-order (A, B) of eq 16, states [θ, z, θ', z'], inputs the forces f."""
        kappa = self.stiffness(n_bending)
        return first_order(kappa, self.actuator_matrix(positions, n_bending))

    # -- the plants (flexsat.dynamics.orbit, flexsat.dynamics.structural) ---------------------
    def plant(
        self,
        positions: npt.ArrayLike,
        n_bending: int,
        stations: Mapping[str, float] = DEFAULT_STATIONS,
        length: float | None = None,
    ) -> BeamInOrbit:
        """The nonlinear beam in orbit (eqs 1-2) as a :class:`~flexsat.dynamics.orbit.BeamInOrbit`
        in seconds: point forces ``f1``, ``f2``, ... (N) at ``positions`` (ξ/l, columns of
        :meth:`actuator_matrix`), outputs pitch, pitch rate, z_n, their rates and the elastic
        deflection ``w_<station>`` at each named station (ξ/l; w/l, or metres given ``length``)."""
        from flexsat.dynamics.orbit import BeamInOrbit

        G = self.actuator_matrix(positions, n_bending)
        k = G.shape[0] - 1
        shapes = {
            name: [
                mode_shape(r, float(_positions(xi, f"stations[{name!r}]")[0]))
                for r in range(1, k + 1)
            ]
            for name, xi in dict(stations).items()
        }
        return BeamInOrbit(
            self.orbit_rate_value,
            self.ratios(k),
            {f"f{j + 1}": G[:, j] for j in range(G.shape[1])},
            shapes,
            length,
        )

    def linear_plant(
        self,
        positions: npt.ArrayLike,
        n_bending: int,
        stations: Mapping[str, float] = DEFAULT_STATIONS,
    ) -> StructuralPlant:
        """The linear beam (eqs 5-6) as a :class:`~flexsat.dynamics.structural.StructuralPlant`
        in seconds: M = I, K = ω_c² diag(3, F), inputs ``f1``, ... (N) with influence ω_c² G,
        outputs ``pitch``, ``z1`` ... and the station deflections w/l, with their ``_rate``
        s; it is the linear part of :meth:`plant`."""
        from flexsat.dynamics.second_order import SecondOrderModel
        from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant

        G = self.actuator_matrix(positions, n_bending)
        n = G.shape[0]
        w2 = self.orbit_rate_value**2
        acts = [Actuator(f"f{j + 1}", "force", w2 * G[:, j]) for j in range(G.shape[1])]
        rows = {"pitch": ("rotation", np.eye(n)[0])}
        rows.update({f"z{r}": ("displacement", np.eye(n)[r]) for r in range(1, n)})
        for name, xi in dict(stations).items():
            x = float(_positions(xi, f"stations[{name!r}]")[0])
            rows[f"w_{name}"] = (
                "displacement",
                np.concatenate([[0.0], [mode_shape(r, x) for r in range(1, n)]]),
            )
        units = {"rotation": ("rad", "rad/s"), "displacement": ("", "1/s")}  # z = A/l
        sensors = [
            Sensor(name, kind, row, unit=units[kind][0]) for name, (kind, row) in rows.items()
        ]
        sensors += [
            Sensor(f"{name}_rate", kind, row, rate=True, unit=units[kind][1])
            for name, (kind, row) in rows.items()
        ]
        model = SecondOrderModel(
            np.eye(n),
            np.zeros((n, n)),
            w2 * np.diag(self.stiffness(n - 1)),
            np.zeros((n, 1)),
            np.zeros((1, n)),
        )
        return StructuralPlant.from_second_order(model, acts, sensors)

    # -- equations of motion (eqs 1-2 and 5-6, nondimensional) --------------------------------
    def accelerations(
        self, state: npt.ArrayLike, u: npt.ArrayLike, nonlinear: bool = True
    ) -> np.ndarray:
        """[θ'', z''] for ``state`` = [θ, z, θ', z'] and control accelerations ``u`` = [u_θ, u_z]
        (= B_act f): eqs 1-2 in τ (``nonlinear``) or eqs 5-6; the right-hand side of
        :meth:`plant` (:class:`~flexsat.dynamics.orbit.BeamInOrbit`, in seconds) converted to τ."""
        state = np.asarray(state, dtype=float)
        n = state.size // 2
        u = np.asarray(u, dtype=float)
        return _tau_rhs(self._orbit_plant(np.eye(n)), state, u, nonlinear)[n:]

    def _orbit_plant(self, G: np.ndarray, linearised: bool = False):
        """The :class:`~flexsat.dynamics.orbit.BeamInOrbit` of these ratios with influence
        matrix ``G`` ((1 + k) x p: pitch, then k modes) for inputs ``f1`` … ``fp``."""
        from flexsat.dynamics.orbit import BeamInOrbit

        k = G.shape[0] - 1
        return BeamInOrbit(
            self.orbit_rate_value,
            self.ratios(k) if k else np.zeros(0),
            {f"f{j + 1}": G[:, j] for j in range(G.shape[1])},
            linearised=linearised,
        )

    def simulate(
        self,
        G: npt.ArrayLike,
        K_pos: npt.ArrayLike,
        K_rate: npt.ArrayLike,
        x0: npt.ArrayLike,
        tau_end: float,
        nonlinear: bool = True,
        n_points: int = 401,
        rtol: float = 1e-10,
        atol: float = 1e-13,
    ) -> Response:
        """Closed loop f = K_pos x + K_rate x', u = G f, from ``x0`` ([θ, z] positions, rates
        zero, or a full state) over τ ∈ [0, ``tau_end``]: the beam-in-orbit plant (:meth:`plant`,
        in seconds; ``nonlinear=False`` its linearisation) under the state feedback (a constant
        :class:`~flexsat.control.scheduled.ScheduledStateFeedback`) in the engine's
        continuous-law mode (:func:`flexsat.sim.continuous.run`, DOP853), its states [x, ẋ]
        brought to [x, x' = ẋ/ω_c]. This is what the report's NON-LINEAR program (App. C,
        Appendix C) does, with the full feedback in every equation (its FCT kept only the
        pitch-rate term in the pitch equation)."""
        G = require_finite(G, "G")
        G = G.reshape(-1, 1) if G.ndim == 1 else G
        if G.ndim != 2:
            raise FieldError(
                "G", f"must be a 2-D (coordinates x actuators) array, got shape {G.shape}"
            )
        n = G.shape[0]
        K_pos = np.zeros((G.shape[1], n)) if K_pos is None else require_finite(K_pos, "K_pos")
        K_rate = require_finite(K_rate, "K_rate")
        for name, K in (("K_pos", K_pos), ("K_rate", K_rate)):
            if K.shape != (G.shape[1], n):
                raise FieldError(
                    name, f"must be {G.shape[1]}x{n} (G is {n}x{G.shape[1]}), got shape {K.shape}"
                )
        x0 = require_finite(x0, "x0").ravel()
        if x0.size == n:
            x0 = np.concatenate([x0, np.zeros(n)])
        if x0.size != 2 * n:
            raise FieldError("x0", f"must have {n} positions or {2 * n} states, got {x0.size}")
        if not tau_end > 0:
            raise FieldError("tau_end", f"must be > 0, got {tau_end!r}")
        gain = np.hstack([K_pos, K_rate])
        plant = self._orbit_plant(G, linearised=not nonlinear)
        wc = plant.orbit_rate
        # seconds: ẋ = ω_c x', so f = K_pos x + K_rate x' = K_pos x + (K_rate/ω_c) ẋ
        law = ScheduledStateFeedback(
            [0.0], -np.hstack([K_pos, K_rate / wc])[None], "state", tuple(plant.input_slices)
        )
        tau = np.linspace(0.0, float(tau_end), int(n_points))
        to_seconds = np.concatenate([np.ones(n), np.full(n, wc)])
        # the tolerances hold for the τ-state [x, x']: the rates in seconds are ω_c x'
        run = continuous.run(
            plant, law, tau / wc, x0 * to_seconds, rtol=rtol, atol=atol * min(1.0, wc)
        )
        states = run.states[0] / to_seconds
        return Response(tau, states, states @ gain.T)

    # -- the case protocol (flexsat modes) ---------------------------------------------------
    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        """Pitch libration √3 ω_c, then the bending modes √F_n ω_c, Hz (first ``n_modes``)."""
        n = require_count(n_modes, "n_modes")
        kappa = self.stiffness(max(n - 1, 1))[:n]
        return np.sqrt(kappa) * self.orbit_rate_value / (2 * np.pi)

    def mode_descriptions(self, n_modes: int) -> list[str]:
        n = require_count(n_modes, "n_modes")
        out = ["rigid pitch libration (gravity gradient, ω = √3 ω_c)"]
        for r in range(1, n):
            kind = "symmetric" if r % 2 else "antisymmetric"
            src = "" if r <= len(self.frequency_ratios) else " (free-free theory, not published)"
            out.append(f"free-free bending {r}, {kind}{src}")
        return out[:n]

    def mode_details(self, n_modes: int) -> dict:
        """(ω/ω_c)² used, free-free theory scaled to mode 1, λl, and the mode-shape values at
        ξ/l = -1/2, -1/4, 0, 1/4, 1/2 (JSON-ready)."""
        n = require_count(n_modes, "n_modes")
        k = max(n - 1, 1)
        x = np.array([-0.5, -0.25, 0.0, 0.25, 0.5])
        return {
            "orbit_rate_rad_s": self.orbit_rate_value,
            "ratio_sq_used": self.stiffness(k)[:n].tolist(),
            "ratio_sq_theory": [3.0, *theory_ratios(k, self.frequency_ratios[0]).tolist()][:n],
            "lambda_l": free_free_lambda_l(k).tolist(),
            "shape_at_xi_over_l": {
                "xi_over_l": x.tolist(),
                **{f"mode_{r}": mode_shape(r, x).tolist() for r in range(1, k + 1)},
            },
        }


def bainum(**overrides: Any) -> BainumBeam:
    """Build the beam-in-orbit case; override any input by name (numbers SI or unit strings).

    Inputs: ``frequency_ratios`` ((ω_n/ω_c)², default the report's 3200, 28800, 93079.5,
    255331.4), ``pitch_influence`` (l/(2Jω_c²) = 59.52), ``modal_influence`` (1/(M l ω_c²) =
    10.0), ``orbit_altitude`` ("250 nmi"), ``orbit_rate`` (None: from the altitude).

    >>> beam = bainum(frequency_ratios=(3200, 24315.2))
    """
    return BainumBeam(**read_inputs("bainum", _INPUTS, overrides))


def _tau_rhs(plant, y, f, nonlinear: bool) -> np.ndarray:
    """dy/dτ of y = [x, x'] (τ = ω_c t) from a BeamInOrbit's ẋ in seconds at inputs f: the
    state in seconds is [x, ω_c x'] and d/dτ = (1/ω_c) d/dt, so x'' = ẍ/ω_c²."""
    n = y.size // 2
    wc = plant.orbit_rate
    dx = plant.derivative(np.concatenate([y[:n], wc * y[n:]]), f, nonlinear)
    return np.concatenate([y[n:], dx[n:] / wc**2])


# -- generic second-order helpers --------------------------------------------------------------
def check_stiffness(stiffness: npt.ArrayLike, name: str = "stiffness") -> np.ndarray:
    """The diagonal stiffness (ω/ω_c)² as a 1-D array (a diagonal matrix is reduced to its
    diagonal); refused by ``name`` otherwise."""
    k = require_finite(stiffness, name)
    if k.ndim == 2 and k.shape[0] == k.shape[1] and not np.any(k - np.diag(np.diag(k))):
        k = np.diag(k).copy()
    if k.ndim != 1 or k.size == 0:
        raise FieldError(
            name,
            "must be the diagonal (ω/ω_c)² as a 1-D array or a diagonal "
            f"matrix, got shape {k.shape}",
        )
    return k


def check_modal_input(G: npt.ArrayLike, n: int, name: str = "G") -> np.ndarray:
    """The input matrix ``G`` with ``n`` rows (a vector is one column); refused by ``name``
    otherwise."""
    G = require_finite(G, name)
    if G.ndim == 1:
        G = G.reshape(-1, 1)
    if G.ndim != 2 or G.shape[0] != n:
        raise FieldError(name, f"must have {n} rows (one per coordinate), got shape {G.shape}")
    return G


def first_order(
    stiffness: npt.ArrayLike, G: npt.ArrayLike, damping: npt.ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of ``x'' + E x' + diag(κ) x = G f`` with states [x, x'] (eq 16; Ch. III eq 2 with
    A = I)."""
    k = check_stiffness(stiffness)
    n = k.size
    G = check_modal_input(G, n)
    E = np.zeros((n, n)) if damping is None else require_finite(damping, "damping")
    if E.shape != (n, n):
        raise FieldError("damping", f"must be {n}x{n}, got shape {E.shape}")
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(k), -E]])
    return A, np.vstack([np.zeros_like(G), G])


def closed_loop_matrix(
    stiffness: npt.ArrayLike,
    G: npt.ArrayLike,
    K_pos: npt.ArrayLike | None,
    K_rate: npt.ArrayLike | None,
    damping: npt.ArrayLike | None = None,
) -> np.ndarray:
    """First-order matrix of ``x'' + E x' + diag(κ) x = G (K_pos x + K_rate x')``."""
    A, B = first_order(stiffness, G, damping)
    n, p = A.shape[0] // 2, B.shape[1]
    K_pos = np.zeros((p, n)) if K_pos is None else require_finite(K_pos, "K_pos")
    K_rate = np.zeros((p, n)) if K_rate is None else require_finite(K_rate, "K_rate")
    for name, K in (("K_pos", K_pos), ("K_rate", K_rate)):
        if K.shape != (p, n):
            raise FieldError(name, f"must be {p}x{n} (G is {n}x{p}), got shape {K.shape}")
    return A + B @ np.hstack([K_pos, K_rate])


def sorted_poles(M: npt.ArrayLike) -> np.ndarray:
    """Eigenvalues sorted by |Im|, then Im, then Re (conjugate pairs adjacent, -j first)."""
    lam = np.linalg.eigvals(np.asarray(M, dtype=float))
    return lam[np.lexsort((lam.real, lam.imag, np.round(np.abs(lam.imag), 9)))]


__all__ = [
    "ERRATA",
    "PUBLISHED",
    "SOURCE",
    "BainumBeam",
    "Erratum",
    "Response",
    "bainum",
    "check_modal_input",
    "check_stiffness",
    "closed_loop_matrix",
    "first_order",
    "free_free_lambda_l",
    "mode_shape",
    "published_matrix",
    "sorted_poles",
    "theory_ratios",
]
