"""Bainum & Reddy's Ch. IV three-mass model of the free-free beam in orbit (Bainum & Reddy
1979, NASA CR-158684, Howard University): independent modal control against coupled rate
feedback (:class:`ThreeMassBeam`, :func:`three_mass`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.cases.inputs import Param, read_inputs
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from flexsat.dynamics.structural import StructuralPlant
from flexsat.cases.bainum import (
    PUBLISHED,
)

__all__ = [
    "ThreeMassBeam",
    "three_mass",
]


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
