r"""Closed-loop poles with damping, natural frequency and the mode each belongs to.

Each eigenvalue λ_k of the closed-loop state matrix (z-plane for a sampled loop, mapped to the
s-plane by :math:`s = \ln z / dt`) gets :math:`\omega_n = |s|`, :math:`\zeta = -\operatorname{Re}
s/|s|` (ζ = 1 for a real pole at the origin's left, −1 at its right), and a *mode*: the group of
the plant's states with the largest participation, the participation factor of state i in
eigenvalue k being :math:`p_{ik} = |w_{ki} v_{ik}|` with V the right eigenvectors and
:math:`W = V^{-1}` the left ones (Pérez-Arriaga, Verghese & Schweppe, "Selective modal analysis
with applications to electric power systems, Part I", IEEE Trans. PAS-101(9), 1982,
3117–3125); the factors of one eigenvalue sum to 1 over all states, and the plant states' share
is reported beside the mode (near 0 for an estimator's or a filter's own pole).

States are grouped into modes by their labels: a coordinate and its rate (``eta[2]`` and
``eta_dot[2]``, ``theta`` and ``theta_dot``) form one mode, named after the coordinate; the
law's states (labels with its ``name.`` prefix) never name a mode. An explicit ``modes``
mapping overrides the grouping of the plant's states.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from flexsat.analysis.frequency_domain import Loop

__all__ = ["ClosedLoopPole", "closed_loop_poles", "damping_table", "mode_of_state"]


@dataclass(frozen=True)
class ClosedLoopPole:
    """One closed-loop pole (module docstring).

    Attributes
    ----------
    pole : complex
        In the s-plane (for a sampled loop, ln z / dt).
    natural_frequency_rad_s : float
    damping_ratio : float
    mode : str
        The plant's state group with the largest participation.
    participation : float
        That group's share of the plant states' participation, in [0, 1].
    plant_share : float
        The plant states' share of the whole participation (near 0: a pole of the law's own
        dynamics, an estimator or a filter, that the plant barely sees).
    """

    pole: complex
    natural_frequency_rad_s: float
    damping_ratio: float
    mode: str
    participation: float
    plant_share: float


def mode_of_state(label: str) -> str:
    """The mode a plant state label belongs to: its coordinate (``eta_dot[2]`` -> ``eta[2]``)."""
    return re.sub(r"_dot(?=\[|$)", "", label)


def closed_loop_poles(
    loop: Loop, modes: Mapping[str, Sequence[str]] | None = None
) -> tuple[ClosedLoopPole, ...]:
    """Poles of a loop's closed loop, sorted by natural frequency (module docstring).

    Parameters
    ----------
    loop : Loop
        From :func:`~flexsat.analysis.frequency_domain.build_loop`.
    modes : mapping {mode: state labels}, optional
        Explicit grouping; states not listed keep the label rule.

    Raises
    ------
    FieldError
        When ``modes`` names a state the loop does not have.
    """
    labels = list(loop.states)
    group = {s: mode_of_state(s) for s in labels}
    for name, states in (modes or {}).items():
        for s in states:
            if s not in group:
                raise FieldError("modes", f"{name!r} lists {s!r}, not a state of the loop")
            group[s] = name
    # the plant's states are those without the law's "name." prefix
    plant = np.array(["." not in s for s in labels])
    if not plant.any():
        raise FieldError("loop", "has no plant states to assign the poles to")
    names = sorted({group[s] for s, p in zip(labels, plant) if p})
    index = np.array([names.index(group[s]) if p else -1 for s, p in zip(labels, plant)])
    lam, V = np.linalg.eig(loop.closed_loop_A)
    W = np.linalg.inv(V)
    P = np.abs(W.T * V)  # P[i, k] = |w_ki v_ik|
    P /= P.sum(axis=0, keepdims=True)
    shares = np.zeros((len(names), lam.size))
    np.add.at(shares, index[plant], P[plant])
    plant_share = P[plant].sum(axis=0)
    out = []
    for k, z in enumerate(lam):
        pole = complex(np.log(z) / loop.dt) if loop.dt else complex(z)
        wn = abs(pole)
        zeta = -pole.real / wn if wn > 0 else 1.0
        g = int(np.argmax(shares[:, k]))
        share = float(shares[g, k] / plant_share[k]) if plant_share[k] > 0 else 0.0
        out.append(ClosedLoopPole(pole, wn, zeta, names[g], share, float(plant_share[k])))
    return tuple(sorted(out, key=lambda p: (p.natural_frequency_rad_s, p.pole.imag)))


def damping_table(poles: Sequence[ClosedLoopPole]) -> str:
    """A plain-text table of the poles with Im >= 0 (one line per mode pair)."""
    rows = [f"{'mode':>24} {'ω_n (rad/s)':>12} {'f_n (Hz)':>10} {'ζ':>9} {'share':>6} {'plant':>6}"]
    for p in poles:
        if p.pole.imag < 0:
            continue
        rows.append(
            f"{p.mode:>24} {p.natural_frequency_rad_s:12.5g} "
            f"{p.natural_frequency_rad_s / (2 * math.pi):10.5g} {p.damping_ratio:9.4g} "
            f"{p.participation:6.2f} {p.plant_share:6.2f}"
        )
    return "\n".join(rows)
