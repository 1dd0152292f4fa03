r"""Two carts joined by a spring: the plant of the Wie & Bernstein benchmark.

.. math::

    m_1 \ddot x_1 = -k (x_1 - x_2) - c (\dot x_1 - \dot x_2) + u, \qquad
    m_2 \ddot x_2 = k (x_1 - x_2) + c (\dot x_1 - \dot x_2) + w,

with the control force u on cart 1 and the disturbance force w on cart 2 (Wie, B. and
Bernstein, D. S., "Benchmark problems for robust control design", Journal of Guidance,
Control, and Dynamics 15(5), 1057-1059, 1992; nominal m1 = m2 = 1 kg, k = 1 N/m, c = 0).
State x = [x1, x2, ẋ1, ẋ2] (m, m/s). The eigenvalues of the undamped system are 0 (twice, the
rigid mode) and ±j ω with ω = sqrt(k (1/m1 + 1/m2)) (the elastic mode).
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, ConfigDict

from flexsat.dynamics.plant import Channel, Plant
from flexsat.scenarios import quantity


class TwoMassSpring(Plant):
    """Two carts and a spring (module docstring): a linear plant with named SI channels.

    Parameters
    ----------
    m1, m2 : float
        Cart masses, kg (> 0).
    k : float
        Spring stiffness, N/m (> 0).
    c : float
        Damper across the spring, N s/m (>= 0).
    """

    inputs = (
        Channel("force", "N", 1, "control force on cart 1"),
        Channel("disturbance", "N", 1, "disturbance force on cart 2"),
    )
    outputs = (
        Channel("x1", "m", 1, "position of cart 1"),
        Channel("x2", "m", 1, "position of cart 2 (the benchmark's measurement)"),
        Channel("v1", "m/s", 1, "velocity of cart 1"),
        Channel("v2", "m/s", 1, "velocity of cart 2"),
        Channel("state", "", 4, "[x1, x2, v1, v2] (SI per coordinate)"),
    )
    recorded = ("x1", "x2", "v1", "v2")

    class Parameters(BaseModel):
        """The ``plant:`` section of a scenario (quantities with units, SI when bare)."""

        model_config = ConfigDict(extra="forbid")

        m1: quantity("kg", positive=True) = 1.0
        m2: quantity("kg", positive=True) = 1.0
        k: quantity("N/m", positive=True) = 1.0
        c: quantity("N*s/m") = 0.0

    def __init__(self, m1: float = 1.0, m2: float = 1.0, k: float = 1.0, c: float = 0.0):
        for name, value in (("m1", m1), ("m2", m2), ("k", k)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: must be a finite number > 0, got {value!r}")
        if not (math.isfinite(c) and c >= 0):
            raise ValueError(f"c: must be a finite number >= 0, got {c!r}")
        self.m1, self.m2, self.k, self.c = float(m1), float(m2), float(k), float(c)
        self.M = np.diag([self.m1, self.m2])
        self.K = self.k * np.array([[1.0, -1.0], [-1.0, 1.0]])
        self.D = self.c * np.array([[1.0, -1.0], [-1.0, 1.0]])
        # E = 1/2 x^T Q x: the spring's potential and the carts' kinetic energy
        self.energy_matrix = np.block([[self.K, np.zeros((2, 2))], [np.zeros((2, 2)), self.M]])

    @classmethod
    def from_scenario(cls, parameters: Parameters, context) -> TwoMassSpring:
        """The plant of a scenario's ``plant:`` section (``context`` is not needed)."""
        return cls(**parameters.model_dump())

    @property
    def nx(self) -> int:
        return 4

    @property
    def elastic_frequency(self) -> float:
        """ω = sqrt(k (1/m1 + 1/m2)), rad/s: the undamped elastic mode."""
        return math.sqrt(self.k * (1.0 / self.m1 + 1.0 / self.m2))

    def linear_part(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) of x' = A x + B [u, w]."""
        Minv = np.diag([1.0 / self.m1, 1.0 / self.m2])
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ self.K, -Minv @ self.D]])
        B = np.zeros((4, 2))
        B[2, 0] = 1.0 / self.m1
        B[3, 1] = 1.0 / self.m2
        return A, B

    def output_matrices(self, name: str):
        """(C, D, D_f) of every output: each reads state coordinates, no feedthrough."""
        rows = {"x1": [0], "x2": [1], "v1": [2], "v2": [3], "state": [0, 1, 2, 3]}
        if name not in rows:
            raise ValueError(f"{name}: TwoMassSpring has no output {name!r}")
        C = np.eye(4)[rows[name]]
        return C, np.zeros((len(rows[name]), 2)), None

    def energy(self, x: np.ndarray) -> np.ndarray:
        """Spring plus kinetic energy, J, shape (...,)."""
        x = np.asarray(x, float)
        return 0.5 * np.einsum("...i,ij,...j->...", x, self.energy_matrix, x)


__all__ = ["TwoMassSpring"]
