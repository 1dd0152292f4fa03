"""A published-number check for ``flexsat validate``: the benchmark's elastic mode.

With the published nominal parameters m1 = m2 = 1 kg, k = 1 N/m (Wie & Bernstein 1992) the
open-loop poles are 0, 0 and ±j sqrt(2) rad/s. The check recomputes the elastic frequency from
the eigenvalues of the plug-in plant's state matrix, an independent route to the closed form
ω = sqrt(k (1/m1 + 1/m2)).
"""

from __future__ import annotations

from flexsat.checks import Check


def _elastic_frequency() -> float:
    import numpy as np

    from flexsat_example_plugin.case import WieBernstein
    from flexsat_example_plugin.plant import TwoMassSpring

    case = WieBernstein()
    A, _ = TwoMassSpring(case.m1, case.m2, case.k).linear_part()
    return float(np.abs(np.linalg.eigvals(A).imag).max())


ELASTIC_FREQUENCY = Check(
    "wie_bernstein",
    "elastic mode ω, nominal plant",
    "Wie & Bernstein, J. Guidance, Control, and Dynamics 15(5), 1057-1059 (1992), "
    "problem 1: m1 = m2 = 1, k = 1",
    1.414214,  # sqrt(2 k / m) of the published nominal values, to seven digits
    "rad/s",
    _elastic_frequency,
    atol=5e-7,  # half a unit in the seventh digit; eig of this 4x4 is good to ~1e-15
    note="ω = sqrt(k (1/m1 + 1/m2)) of the published parameters (the paper gives the model)",
)

__all__ = ["ELASTIC_FREQUENCY"]
