"""The Wie & Bernstein benchmark as a flexsat case: its published nominal parameters.

``flexsat cases`` reads ``source`` and ``description`` of every case builder, so this module is
imported by the lightest command: it imports nothing numerical (the plant comes in with the
``flexsat.plants`` entry point, when a scenario names it).
"""

from __future__ import annotations

import math


class WieBernstein:
    """Two carts and a spring (Wie & Bernstein 1992, problem 1), nominal m1 = m2 = 1 kg and
    k = 1 N/m; the keyword arguments override them (``flexsat modes wie_bernstein --set k=2``).

    Parameters
    ----------
    m1, m2 : float
        Cart masses, kg (> 0).
    k : float
        Spring stiffness, N/m (> 0).
    """

    source = (
        "Wie & Bernstein, Benchmark problems for robust control design, J. Guidance, Control, "
        "and Dynamics 15(5), 1057-1059 (1992), problem 1"
    )
    description = "Wie-Bernstein benchmark: two carts and a spring, force on cart 1 (plug-in)"

    def __init__(self, m1: float = 1.0, m2: float = 1.0, k: float = 1.0):
        for name, value in (("m1", m1), ("m2", m2), ("k", k)):
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: must be a finite number > 0, got {value!r}")
        self.m1, self.m2, self.k = float(m1), float(m2), float(k)

    def frequencies_hz(self, n_modes: int) -> list[float]:
        """The rigid mode (0 Hz) and the elastic one, sqrt(k (1/m1 + 1/m2)) / 2π; the system
        has no more than these two."""
        omega = math.sqrt(self.k * (1.0 / self.m1 + 1.0 / self.m2))
        return [0.0, omega / (2.0 * math.pi)][:n_modes]


__all__ = ["WieBernstein"]
