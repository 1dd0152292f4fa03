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

Chapters reproduced: Ch. II controllability Cases 1-4 (:func:`chapter2_case`) and its numerical
example (:func:`chapter2_example`); Ch. III decoupling (:func:`decoupling_gains`) and per-mode
linear regulator in closed form (:func:`modal_riccati`, :func:`modal_lqr_gains`); Ch. IV
three-mass model, independent modal control against coupled rate feedback
(:class:`ThreeMassBeam`, :func:`three_mass`). The errata (repaired printed numbers) are in
:data:`ERRATA` and applied by :func:`published_matrix` (docs/bainum.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq

from flexsat.analysis.controllability import (
    RepeatedFrequencyResult,
    controllability_rank,
    pbh_test,
    repeated_frequency_test,
)
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
def _stiffness(stiffness, name: str = "stiffness") -> np.ndarray:
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


def _modal_input(G, n: int, name: str = "G") -> np.ndarray:
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
    k = _stiffness(stiffness)
    n = k.size
    G = _modal_input(G, n)
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


# -- Ch. II: controllability cases 1-4 and the numerical example --------------------------------
#: (pitch in the model, bending modes, actuator positions ξ/l), Bainum & Reddy 1979 Ch. II §3
CH2_LAYOUTS = {
    1: (True, 2, (-0.5,)),
    2: (False, 2, (-0.5, 0.5, 0.0)),
    3: (True, 1, (-0.5, 0.5)),
    4: (True, 2, (-0.5, 0.5, 0.0)),
}


@dataclass(frozen=True)
class ControllabilityCase:
    """A Ch. II case: the reduced pair of eq 17, ``stiffness`` = diag(A), ``B``, and the tests."""

    case: int
    stiffness: np.ndarray
    B: np.ndarray
    positions: tuple[float, ...]
    kalman_rank: int
    blocks: RepeatedFrequencyResult
    uncontrollable: np.ndarray  # PBH on the first-order 2n-state model

    @property
    def n(self) -> int:
        return self.stiffness.size

    @property
    def controllable(self) -> bool:
        return self.kalman_rank == self.n


def chapter2_case(
    case: int,
    c: float | None = None,
    d: float | None = None,
    beam: BainumBeam | None = None,
    midspan: str = "exact",
) -> ControllabilityCase:
    """Ch. II Case 1-4: reduced pair (A, B) of eq 17 and its controllability.

    Parameters
    ----------
    case : {1, 2, 3, 4}
        Layout of :data:`CH2_LAYOUTS`.
    c, d : float, optional
        (ω_1/ω_c)² and (ω_2/ω_c)² (default the beam's, 3200 and 28800); pitch is κ = 3, so
        Case 4 loses controllability exactly when d = 3 (ω_2 = √3 ω_c).
    beam : BainumBeam, optional
        Influence coefficients a = ``pitch_influence`` and b = 2·``modal_influence``.
    midspan : {"exact", "published"}
        Mode-1 value at the midspan actuator: the Appendix A shape (-1.21564, erratum) or the
        report's -√2 (e = √2/(M_1 l ω_c²), Ch. II §3, Cases 2 and 4).

    Returns
    -------
    ControllabilityCase
        Kalman rank of the reduced pair (n x np, Balas' reduction), the repeated-
        frequency block test, and PBH uncontrollable eigenvalues of the full 2n-state model.
    """
    if case not in CH2_LAYOUTS:
        raise FieldError("case", f"must be one of {sorted(CH2_LAYOUTS)}, got {case!r}")
    if midspan not in ("exact", "published"):
        raise FieldError("midspan", f"must be 'exact' or 'published', got {midspan!r}")
    beam = bainum() if beam is None else beam
    pitch, k, positions = CH2_LAYOUTS[case]
    F = beam.ratios(k)
    for i, (name, value) in enumerate((("c", c), ("d", d))[:k]):
        if value is not None:
            F[i] = float(require_finite(value, name))
    B = beam.actuator_matrix(positions, k, pitch=pitch)
    if midspan == "published":
        B[int(pitch), np.asarray(positions) == 0.0] = -np.sqrt(2.0) * beam.modal_influence
    kappa = np.concatenate([[3.0], F]) if pitch else F
    A_full, B_full = first_order(kappa, B)
    return ControllabilityCase(
        case,
        kappa,
        B,
        positions,
        controllability_rank(np.diag(kappa), B),
        repeated_frequency_test(kappa, B),
        pbh_test(A_full, B_full),
    )


@dataclass(frozen=True)
class ClosedLoop:
    """A closed loop x'' + F x = G (K_pos x + K_rate x') and its poles."""

    stiffness: np.ndarray
    G: np.ndarray
    K_pos: np.ndarray
    K_rate: np.ndarray
    matrix: np.ndarray = field(repr=False)
    poles: np.ndarray


def _closed_loop(stiffness, G, K_pos, K_rate) -> ClosedLoop:
    M = closed_loop_matrix(stiffness, G, K_pos, K_rate)
    G = np.asarray(G, dtype=float)
    G = G.reshape(-1, 1) if G.ndim == 1 else G
    return ClosedLoop(
        np.asarray(stiffness, float),
        G,
        np.asarray(K_pos, float),
        np.asarray(K_rate, float),
        M,
        sorted_poles(M),
    )


def chapter2_example(
    gains: npt.ArrayLike = PUBLISHED["ch2_gains"], beam: BainumBeam | None = None
) -> ClosedLoop:
    """Ch. II §4: Case 1 (one actuator at ξ = -l/2, pitch + 2 modes) with the
    printed rate feedback f = K1 x1' + K2 x2' + K3 x3' (the Ch. II §4 errata applied: the equations
    are built from eq 16).

    Poles with the printed gains: -0.171737 ± 1.723625j, -0.565594 ± 56.562701j,
    -0.169485 ± 169.703929j. The gains are not a decoupling design (one actuator
    cannot decouple three coordinates); they match uncoupled ζ = 0.1, 0.01, 0.001.
    """
    beam = bainum() if beam is None else beam
    K = require_finite(gains, "gains").reshape(1, -1)
    if K.shape != (1, 3):
        raise FieldError("gains", f"must be the three rate gains K1, K2, K3, got {gains!r}")
    G = beam.actuator_matrix(CH2_LAYOUTS[1][2], 2)
    return _closed_loop(beam.stiffness(2), G, np.zeros((1, 3)), K)


# -- Ch. III: decoupling and per-mode linear regulator ------------------------------------------
def _svd_rank(M: np.ndarray, rtol: float) -> int:
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0


def decoupling_gains(
    G: npt.ArrayLike,
    stiffness: npt.ArrayLike,
    damping_ratio: npt.ArrayLike = 1.0,
    target_stiffness: npt.ArrayLike | None = None,
    damping: npt.ArrayLike | None = None,
    rtol: float = 1e-8,
) -> tuple[np.ndarray, np.ndarray]:
    """Decoupling state feedback of Ch. III §2 (eqs 1-13).

    For ``x'' + E x' + F x = G f`` (E = ``damping``, default 0; F = diag(``stiffness``)) and
    f = L x + K x' (eq 3), the closed loop x'' + (E - GK) x' + (F - GL) x = 0 is decoupled with
    E - GK = Z = diag(2 ζ_i √W_i) and F - GL = W = diag(``target_stiffness``, default F):
    column by column G K_i = (E - Z)_i and G L_i = (F - W)_i (eq 12).

    Each column is solvable iff rank G = rank [G | column] (Rouché-Capelli; the report's rule
    "rank must be n when n > m", Ch. III §2, is impossible); the solution is unique iff
    rank G = m (columns of G), otherwise the minimum-norm one is returned. Ranks count singular
    values above ``rtol`` · σ_max.

    Parameters
    ----------
    G : (n, m) array_like
        Modal input matrix (eq 9: A⁻¹D; the beam's B_act).
    stiffness : (n,) array_like
        F = diag(A⁻¹C), e.g. (3, 3200, 28800).
    damping_ratio : float or (n,) array_like
        ζ of each decoupled coordinate; 1 = critical (the report's choice, Ch. III §4).
    target_stiffness, damping : optional
        W (default F: rate feedback only, L = 0) and E (default 0).

    Returns
    -------
    K_pos, K_rate : (m, n) ndarray
        L and K of eq 3.

    Raises
    ------
    ValueError
        Bad shapes or values; ``G``: a column has no solution (decoupling impossible with these
        actuators), with the rank numbers.
    """
    F = _stiffness(stiffness)
    n = F.size
    G = _modal_input(G, n)
    W = F if target_stiffness is None else _stiffness(target_stiffness, "target_stiffness")
    if W.size != n:
        raise FieldError("target_stiffness", f"must have {n} entries, got {W.size}")
    if np.any(W < 0):
        raise FieldError("target_stiffness", f"must be >= 0, got {W.tolist()}")
    zeta = np.broadcast_to(require_finite(damping_ratio, "damping_ratio"), (n,))
    if np.any(zeta < 0):
        raise FieldError("damping_ratio", f"must be >= 0, got {damping_ratio!r}")
    E = np.zeros((n, n)) if damping is None else require_finite(damping, "damping")
    if E.shape != (n, n):
        raise FieldError("damping", f"must be {n}x{n}, got shape {E.shape}")
    rhs_rate = E - np.diag(2 * zeta * np.sqrt(W))
    rhs_pos = np.diag(F) - np.diag(W)
    rank_G = _svd_rank(G, rtol)
    for name, rhs in (("rate", rhs_rate), ("position", rhs_pos)):
        for i in range(n):
            r = _svd_rank(np.column_stack([G, rhs[:, i]]), rtol)
            if r > rank_G:
                raise FieldError(
                    "G",
                    f"decoupling impossible: {name} column {i + 1} is not in the range of G "
                    f"(rank G = {rank_G}, rank [G | column] = {r}); move or add actuators",
                )
    G_pinv = np.linalg.pinv(G, rcond=rtol)
    return G_pinv @ rhs_pos, G_pinv @ rhs_rate


def modal_riccati(
    stiffness: npt.ArrayLike,
    Q1: npt.ArrayLike = 1.0,
    Q2: npt.ArrayLike | None = None,
    R: npt.ArrayLike = 1.0,
    D: npt.ArrayLike = 0.0,
) -> tuple[np.ndarray, ...]:
    """Closed-form 2x2 Riccati solution of one modal coordinate (Ch. III eqs 19-27).

    For x'' + D x' + F x = u', cost ∫ (Q1 x² + Q2 x'² + R u'²) dτ, the stabilizing S of
    ``-SA - AᵀS + S b R⁻¹ bᵀ S - Q = 0`` (eq 24) is

    - S12 = R [-F + √(F² + Q1/R)]                 (eq 25)
    - S22 = R [-D + √(D² + (Q2 + 2 S12)/R)]       (eq 26)
    - S11 = F S22 + D S12 + S12 S22 / R          (eq 27)

    with the + roots. Eq 25 (and 26) cancel catastrophically when F² ≫ Q1/R; they are
    evaluated as Q1/(F + √(F² + Q1/R)) for F > 0. The control is
    u' = -(S12 x + S22 x')/R (eq 28 has R = 1).

    Parameters
    ----------
    stiffness : float or array_like
        F_i (any real; vectorized).
    Q1, Q2 : float or array_like
        Position and rate weights, >= 0. ``Q2=None`` is F: rates "penalized by a factor of
        frequency squared" (Ch. III §4), the report's choice with Q1 = R = 1.
    R : float or array_like
        Control weight, > 0.
    D : float or array_like
        Modal damping D_i (0 for the beam).

    Returns
    -------
    S11, S12, S22 : ndarray
        Pitch (F = 3, Q = diag(1, 3), R = 1): 5.7658957, 0.16227766, 1.8233363.

    Raises
    ------
    ValueError
        ``R`` not > 0 (not positive definite), ``Q1``/``Q2`` negative, or no stabilizing
        solution (a coordinate the weights do not see, e.g. F = 0 with Q1 = 0).
    """
    F = np.asarray(require_finite(stiffness, "stiffness"), dtype=float)
    Q1 = require_finite(Q1, "Q1")
    Q2 = F if Q2 is None else require_finite(Q2, "Q2")
    R = require_finite(R, "R")
    D = require_finite(D, "D")
    if np.any(R <= 0):
        raise FieldError("R", f"must be > 0 (positive definite control weight), got {R.tolist()}")
    for name, Q in (("Q1", Q1), ("Q2", Q2)):
        if np.any(Q < 0):
            raise FieldError(name, f"must be >= 0 (positive semidefinite weight), got {Q.tolist()}")
    F, Q1, Q2, R, D = np.broadcast_arrays(F, Q1, Q2, R, D)
    q = Q1 / R
    root = np.sqrt(F * F + q)
    with np.errstate(divide="ignore", invalid="ignore"):
        S12 = R * np.where(F > 0, q / (F + root), root - F)
        p = (Q2 + 2 * S12) / R
        rootd = np.sqrt(D * D + p)
        S22 = R * np.where(D > 0, p / (D + rootd), rootd - D)
    S11 = F * S22 + D * S12 + S12 * S22 / R
    # closed loop s² + (D + S22/R) s + (F + S12/R): Hurwitz iff both coefficients > 0
    bad = ~((D + S22 / R > 0) & (F + S12 / R > 0))
    if np.any(bad):
        raise ValueError(
            f"Q1, Q2: no stabilizing solution for coordinate(s) "
            f"{np.flatnonzero(np.atleast_1d(bad)).tolist()} (the weights do not "
            f"see an undamped or unstable coordinate, e.g. F = 0 with Q1 = 0)"
        )
    return S11, S12, S22


def modal_lqr_gains(
    G: npt.ArrayLike,
    stiffness: npt.ArrayLike,
    Q1: npt.ArrayLike = 1.0,
    Q2: npt.ArrayLike | None = None,
    R: npt.ArrayLike = 1.0,
    D: npt.ArrayLike = 0.0,
    rcond: float = 1e-8,
) -> tuple[np.ndarray, np.ndarray]:
    """Per-mode linear regulator mapped to the actuators (Ch. III eqs 16-28).

    x'' + D x' + F x = G f = u' (eq 16-17 with E = G); each coordinate gets
    u'_i = -(S_i12 x_i + S_i22 x_i')/R_i (:func:`modal_riccati`) and f = G⁻¹ u' (eq 18), i.e.
    K_pos = -G⁻¹ diag(S12/R), K_rate = -G⁻¹ diag(S22/R) in the report's f = K_pos x + K_rate x'.

    Raises
    ------
    ValueError
        ``G`` not square (#actuators ≠ #coordinates: use the full 2n x 2n regulator,
        :func:`flexsat.control.lqr`, Ch. V) or singular (σ_min ≤ ``rcond`` σ_max, e.g. the
        exact-shape symmetric five-actuator layout of Ch. III Case 2); and the
        errors of :func:`modal_riccati`.
    """
    F = _stiffness(stiffness)
    n = F.size
    G = _modal_input(G, n)
    if G.shape != (n, n):
        raise FieldError(
            "G",
            "per-mode regulator needs as many actuators as coordinates "
            f"(u = E⁻¹u', eq 18), got shape {G.shape}; use the full regulator",
        )
    s = np.linalg.svd(G, compute_uv=False)
    if s[-1] <= rcond * s[0]:
        raise FieldError(
            "G",
            f"singular (σ_min/σ_max = {s[-1] / s[0]:.3g} <= {rcond:g}): these "
            f"actuators cannot drive every coordinate independently",
        )
    _, S12, S22 = modal_riccati(F, Q1, Q2, R, D)
    R = np.broadcast_to(np.asarray(R, dtype=float), (n,))
    return (np.linalg.solve(G, -np.diag(S12 / R)), np.linalg.solve(G, -np.diag(S22 / R)))


def chapter3_case(
    case: int, beam: BainumBeam | None = None, shapes: str = "published"
) -> tuple[np.ndarray, np.ndarray]:
    """(stiffness, G) of Ch. III Case 1 (pitch + 2 modes, actuators -l/2, +l/2, +l/4; Ch. III §4)
    or Case 2 (pitch + 4 modes, -l/2, -l/4, 0, +l/4, +l/2; Ch. III §4).

    ``shapes="published"``: the printed G with the errata (G13 = -29.76); ``"exact"``: built
    from the Appendix A shapes (Case 2 is then singular: symmetric forces drive only modes 1
    and 3).
    """
    if case not in (1, 2):
        raise FieldError("case", f"must be 1 or 2, got {case!r}")
    if shapes not in ("published", "exact"):
        raise FieldError("shapes", f"must be 'published' or 'exact', got {shapes!r}")
    beam = bainum() if beam is None else beam
    k = 2 if case == 1 else 4
    if shapes == "published":
        G = published_matrix(f"ch3_case{case}_G")
    else:
        G = beam.actuator_matrix(PUBLISHED[f"ch3_case{case}_positions"], k)
    return beam.stiffness(k), G


# -- Ch. IV: three-mass model ------------------------------------------------------------------
_THREE_MASS_INPUTS = {
    "total_mass": Param(PUBLISHED["ch4_total_mass"], "kg"),
    "interior_mass_ratio": Param(PUBLISHED["ch4_interior_mass_ratio"], rule="nonneg"),
    "spring": Param(PUBLISHED["ch4_spring"], "N/m", "nonneg"),
    "orbit_rate": Param(PUBLISHED["ch4_orbit_rate"], "rad/s", "nonneg"),
    # None: c = 3ω0²M*(2 + m̄0) + k = 0.1862132; the report prints 0.1862522 (Ch. IV example)
    "c": Param(PUBLISHED["ch4_c"], "N/m", optional=True),
}


@dataclass(frozen=True)
class ThreeMassBeam:
    """Ch. IV three-mass model: end masses m, centre mass m0 = m̄0 m, total M̄,
    two hinged cantilever springs k = 3EI/ℓ³; end deflections v1, v2 (SI, time in s)."""

    total_mass: float
    interior_mass_ratio: float
    spring: float
    orbit_rate: float
    c: float | None

    @property
    def end_mass(self) -> float:
        return self.total_mass / (2 + self.interior_mass_ratio)

    @property
    def m_star(self) -> float:
        """M* = m²/M̄ (111.11 kg)."""
        return self.end_mass**2 / self.total_mass

    @property
    def a(self) -> float:
        return self.m_star * (1 + self.interior_mass_ratio)

    @property
    def b(self) -> float:
        return self.m_star

    @property
    def c_formula(self) -> float:
        """3 ω0² M* (2 + m̄0) + k (eq 1)."""
        return 3 * self.orbit_rate**2 * self.m_star * (2 + self.interior_mass_ratio) + self.spring

    @property
    def c_value(self) -> float:
        return self.c_formula if self.c is None else self.c

    @property
    def lambdas(self) -> tuple[float, float]:
        """λ1 = c/(a + b), λ2 = c/(a - b) (eqs 7-8)."""
        return self.c_value / (self.a + self.b), self.c_value / (self.a - self.b)

    @property
    def g(self) -> float:
        return (self.a + self.b) / (self.a - self.b)

    def reduced_pair(self, n_actuators: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """(A_r, B_r) of eq 4: v'' = -A_r v + B_r F (one actuator: F_v2 = 0, eq 6)."""
        if n_actuators not in (1, 2):
            raise FieldError("n_actuators", f"must be 1 or 2, got {n_actuators!r}")
        a, b, c = self.a, self.b, self.c_value
        P = np.array([[a, -b], [-b, a]]) / (a * a - b * b)
        return c * P, P[:, :n_actuators]

    def controllability_det(self) -> float:
        """det [B, -A_r B] with one actuator = b c/(a² - b²)² (Ch. IV)."""
        A_r, B_r = self.reduced_pair(1)
        return float(np.linalg.det(np.hstack([B_r, -A_r @ B_r])))

    def plant(self, n_actuators: int = 1) -> StructuralPlant:
        """The model as a :class:`~flexsat.dynamics.structural.StructuralPlant`:
        M = [[a, b], [b, a]], K = c I (so that v'' = -A_r v + B_r F, eq 4, with A_r = c M⁻¹),
        force inputs ``F_v1`` (and ``F_v2``), N, on the end deflections, outputs ``v1``, ``v2``
        (m) and their rates ``v1_dot``, ``v2_dot`` (m/s)."""
        from flexsat.dynamics.second_order import SecondOrderModel
        from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant

        if n_actuators not in (1, 2):
            raise FieldError("n_actuators", f"must be 1 or 2, got {n_actuators!r}")
        a, b = self.a, self.b
        model = SecondOrderModel(
            np.array([[a, b], [b, a]]),
            np.zeros((2, 2)),
            self.c_value * np.eye(2),
            np.zeros((2, 1)),
            np.zeros((1, 2)),
        )
        acts = [Actuator(f"F_v{j}", "force", j - 1) for j in range(1, n_actuators + 1)]
        sensors = [Sensor(f"v{j}", "displacement", j - 1) for j in (1, 2)]
        sensors += [Sensor(f"v{j}_dot", "displacement", j - 1, rate=True) for j in (1, 2)]
        return StructuralPlant.from_second_order(model, acts, sensors)

    def plant_lambdas(self) -> np.ndarray:
        """λ1, λ2 as the squared natural frequencies of :meth:`plant` (eig(K, M); eqs 7-8 give
        them in closed form, :attr:`lambdas`)."""
        return self.plant().model.frequencies() ** 2

    def _physical_closed_loop(self, gain_q: np.ndarray) -> np.ndarray:
        """v-coordinates closed loop with F_v1 = 2(a + b) u1 and u1 = -gain_q·[q, q'],
        q = T⁻¹ v, T = [[1, 1], [1, -1]] (v1 = q1 + q2, v2 = q1 - q2), on :meth:`plant`'s
        linear part."""
        A, B = self.plant(1).linear_part()
        Tinv = np.array([[0.5, 0.5], [0.5, -0.5]])
        to_q = np.block([[Tinv, np.zeros((2, 2))], [np.zeros((2, 2)), Tinv]])
        return A - 2 * (self.a + self.b) * B @ (gain_q.reshape(1, 4) @ to_q)

    def imc_closed_loop(self, f1: float, f2: float) -> np.ndarray:
        """Independent modal control u1 = -f1 q1 - f2 q1' (eq 9), one actuator at v1."""
        return self._physical_closed_loop(np.array([f1, 0.0, f2, 0.0]))

    def coupled_rate_closed_loop(self, K1: float, K2: float) -> np.ndarray:
        """Coupled rate feedback u1 = -K1 q1' - K2 q2' (eq 13)."""
        return self._physical_closed_loop(np.array([0.0, 0.0, K1, K2]))

    def imc_poles(self, f1: float, f2: float) -> np.ndarray:
        """Roots of (s² + λ2)(s² + f2 s + f1 + λ1) (eq 12): ±j√λ2 stays undamped."""
        l1, l2 = self.lambdas
        return np.sort_complex(np.roots(np.polymul([1, 0, l2], [1, f2, f1 + l1])))

    def characteristic_polynomial(self, K1: float, K2: float) -> np.ndarray:
        """Coefficients of eq 16: s⁴ + (K1 + gK2)s³ + (λ1 + λ2)s² + (λ2K1 + λ1gK2)s + λ1λ2."""
        l1, l2 = self.lambdas
        g = self.g
        return np.array([1.0, K1 + g * K2, l1 + l2, l2 * K1 + l1 * g * K2, l1 * l2])

    def coupled_rate_poles(self, K1: float, K2: float) -> np.ndarray:
        """Roots of eq 16 (sorted by real part); with K1 = 0.4728, K2 = 0.4: -1.6719864,
        -6.405150e-4, -8.654170e-5 ± 2.957334e-2j."""
        return np.sort_complex(np.roots(self.characteristic_polynomial(K1, K2)))


def three_mass(**overrides: Any) -> ThreeMassBeam:
    """Build the Ch. IV three-mass model; inputs ``total_mass`` ("1000 kg"),
    ``interior_mass_ratio`` (1), ``spring`` ("0.18497 N/m"), ``orbit_rate`` ("1.115e-3 rad/s"),
    ``c`` (printed "0.1862522 N/m"; None for the formula, 0.1862132)."""
    return ThreeMassBeam(**read_inputs("three_mass", _THREE_MASS_INPUTS, overrides))


__all__ = [
    "CH2_LAYOUTS",
    "ERRATA",
    "PUBLISHED",
    "SOURCE",
    "BainumBeam",
    "ClosedLoop",
    "ControllabilityCase",
    "Erratum",
    "Response",
    "ThreeMassBeam",
    "bainum",
    "chapter2_case",
    "chapter2_example",
    "chapter3_case",
    "closed_loop_matrix",
    "decoupling_gains",
    "first_order",
    "free_free_lambda_l",
    "modal_lqr_gains",
    "modal_riccati",
    "mode_shape",
    "published_matrix",
    "sorted_poles",
    "theory_ratios",
    "three_mass",
]
