r"""A linear time-invariant plant given by its matrices: x' = A x + B u, y = C x + D u.

For systems whose model is a state space already (a modal structure with its sensors, plus
analog filters: the synthetic vibration tests of :mod:`flexsat.sim.vibration_test`), so they run
on the engine like any plant. One input channel carries the whole input vector and one output
channel the whole output vector, unless named channels are given.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.plant import Channel, Plant
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = ["StateSpacePlant"]


class StateSpacePlant(Plant):
    """x' = A x + B u, y = C x + D u (module docstring).

    Parameters
    ----------
    A, B, C, D : array_like
        (n, n), (n, m), (p, n), (p, m).
    input_name, output_name : str
        Names of the input channel (width m) and the output channel (width p).
    input_unit, output_unit : str
        Their SI units (a pint expression, "" for mixed or dimensionless).
    """

    def __init__(
        self,
        A: npt.ArrayLike,
        B: npt.ArrayLike,
        C: npt.ArrayLike,
        D: npt.ArrayLike,
        input_name: str = "u",
        output_name: str = "y",
        input_unit: str = "",
        output_unit: str = "",
    ) -> None:
        self.A, self.B = require_finite(A, "A"), require_finite(B, "B")
        self.C, self.D = require_finite(C, "C"), require_finite(D, "D")
        n = self.A.shape[0] if self.A.ndim == 2 else -1
        m, p = self.B.shape[-1], self.C.shape[0]
        for name, M, shape in (
            ("A", self.A, (n, n)),
            ("B", self.B, (n, m)),
            ("C", self.C, (p, n)),
            ("D", self.D, (p, m)),
        ):
            if M.shape != shape or n < 1:
                raise FieldError(name, f"must have shape {shape} (A square), got {M.shape}")
        self.inputs = (Channel(input_name, input_unit, m, "the input vector"),)
        self.outputs = (
            Channel(output_name, output_unit, p, "the output vector"),
            Channel("state", "", n, "the state vector"),
        )
        self.recorded = (output_name,)
        self.noise_channels = (output_name, input_name)

    @property
    def nx(self) -> int:
        return self.A.shape[0]

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        return self.A, self.B

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        if name == self.outputs[0].name:
            return self.C, self.D, None
        if name == "state":
            return np.eye(self.nx), np.zeros((self.nx, self.B.shape[1])), None
        return None
