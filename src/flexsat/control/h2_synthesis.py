r"""H2-optimal output feedback for the standard generalized plant, with scipy Riccati solvers.

For the plant of :mod:`~flexsat.control.generalized_plant` with D11 = 0, D22 = 0, D12 of full
column rank and D21 of full row rank, and (A, B2) stabilizable, (C2, A) detectable, with no
uncontrollable/unobservable modes on the imaginary axis in the regulator and filter problems
(Doyle, Glover, Khargonekar & Francis, "State-space solutions to standard H2 and H∞ control
problems", IEEE Transactions on Automatic Control 34(8), 1989, 831–847; in the form with
cross terms of Zhou, Doyle & Glover, *Robust and Optimal Control*, Prentice Hall, 1996,
Chapter 14), the unique H2-optimal compensator is

.. math::

    \dot{\hat x} = (A + B_2F + LC_2)\hat x - L y, \qquad u = F\hat x,

    F = -R_1^{-1}(B_2^T X + D_{12}^T C_1), \qquad L = -(Y C_2^T + B_1 D_{21}^T) R_2^{-1},
    \qquad R_1 = D_{12}^T D_{12},\; R_2 = D_{21} D_{21}^T,

with X the stabilizing solution of the regulator Riccati equation of weights
(C1ᵀC1, R1, C1ᵀD12) (:func:`~flexsat.control.lqr.lqr`) and Y that of the filter equation of
intensities (B1B1ᵀ, R2, B1D21ᵀ) (:func:`~flexsat.control.estimation.kalman`), and the optimal
cost

.. math::

    \min \|T_{zw}\|_2^2 = \operatorname{tr}(B_1^T X B_1)
        + \operatorname{tr}(R_1 F Y F^T).

With the weights of :func:`~flexsat.control.generalized_plant.lqg_plant` this compensator is
the LQG compensator (separation principle). python-control's ``h2syn`` computes the same
through slycot (SB10HD); this module does not need it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from flexsat.control.estimation import kalman
from flexsat.control.generalized_plant import GeneralizedPlant
from flexsat.control.lqr import lqr
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.control.linear_form import ChannelItems
    from flexsat.control.lqr import RiccatiSolution
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = [
    "H2Controller",
    "H2Synthesis",
    "Synthesis",
    "SynthesisCompensator",
    "as_generalized_plant",
    "h2syn",
]


class Synthesis(Protocol):
    """What a synthesis on a generalized plant gives (:class:`H2Synthesis`,
    :class:`~flexsat.control.hinf_synthesis.HinfSynthesis`): the compensator and the plant it
    was designed on."""

    @property
    def controller(self) -> ct.StateSpace: ...

    @property
    def plant(self) -> GeneralizedPlant: ...


def as_generalized_plant(
    P: GeneralizedPlant | ct.StateSpace, nmeas: int | None, ncon: int | None
) -> GeneralizedPlant:
    """A GeneralizedPlant as it is, or a StateSpace partitioned by (nmeas, ncon)."""
    if isinstance(P, GeneralizedPlant):
        return P
    if nmeas is None or ncon is None:
        raise FieldError(
            "nmeas" if nmeas is None else "ncon",
            "give nmeas and ncon to partition a StateSpace into [w, u] → [z, y]",
        )
    return GeneralizedPlant.from_statespace(P, nmeas, ncon)


@dataclass(frozen=True)
class H2Synthesis:
    """Result of :func:`h2syn`.

    Attributes
    ----------
    controller : control.StateSpace
        K (y → u, u = K y), states ``x_hat[i]``.
    cost : float
        The optimal ‖T_zw‖₂ predicted by the Riccati solutions (module docstring).
    F, L : ndarray
        State-feedback gain (u = F x̂) and filter gain.
    regulator, filter : RiccatiSolution
        The two Riccati designs (X = regulator.solution, Y = filter.solution, with residuals).
    plant : GeneralizedPlant
    """

    controller: ct.StateSpace
    cost: float
    F: FloatArray
    L: FloatArray
    regulator: RiccatiSolution
    filter: RiccatiSolution
    plant: GeneralizedPlant


def h2syn(
    P: GeneralizedPlant | ct.StateSpace, nmeas: int | None = None, ncon: int | None = None
) -> H2Synthesis:
    r"""H2-optimal compensator of a generalized plant (module docstring).

    Parameters
    ----------
    P : GeneralizedPlant or control.StateSpace
        Continuous; a StateSpace is partitioned like python-control's ``h2syn(P, nmeas,
        ncon)``.
    nmeas, ncon : int, optional
        Number of measurements y (last outputs) and controls u (last inputs) of a StateSpace.

    Returns
    -------
    H2Synthesis

    Raises
    ------
    FieldError
        D11 or D22 nonzero, D12 / D21 rank deficient, or a Riccati problem without a
        stabilizing solution (the error of :func:`~flexsat.control.lqr.lqr` /
        :func:`~flexsat.control.estimation.kalman` names the rule).
    """
    import control as ct

    G = as_generalized_plant(P, nmeas, ncon)
    G.require_regular(need_d11_zero=True)
    A, B1, B2, C1, C2 = G.A, G.B1, G.B2, G.C1, G.C2
    D12, D21 = G.D12, G.D21
    R1, R2 = D12.T @ D12, D21 @ D21.T
    regulator = lqr(A, B2, C1.T @ C1, R1, C1.T @ D12)
    filt = kalman(A, B1, C2, np.eye(B1.shape[1]), R2, D21.T)
    F = -regulator.gain
    L = -filt.gain
    X, Y = regulator.solution, filt.solution
    cost2 = float(np.trace(B1.T @ X @ B1) + np.trace(R1 @ F @ Y @ F.T))
    n = A.shape[0]
    controller = ct.ss(
        A + B2 @ F + L @ C2,
        -L,
        F,
        np.zeros((B2.shape[1], C2.shape[0])),
        states=[f"x_hat[{i}]" for i in range(n)],
        inputs=list(G.measurement_names),
        outputs=list(G.control_names),
        name="h2",
    )
    return H2Synthesis(controller, math.sqrt(max(cost2, 0.0)), F, L, regulator, filt, G)


class SynthesisCompensator(StateSpaceCompensator):
    """The compensator of a synthesis on a generalized plant as a flexsat law (a continuous
    :class:`~flexsat.control.state_space_compensator.StateSpaceCompensator`, run through its
    exact zero-order-hold equivalent at the control period): the shared constructor of
    :class:`H2Controller` and :class:`~flexsat.control.hinf_synthesis.HinfController`, which
    name the synthesis they take (``synthesis_type``) and the function that makes it
    (``designer``)."""

    synthesis_type: ClassVar[type]
    designer: ClassVar[str]

    def __init__(
        self,
        synthesis: Synthesis,
        dt: QuantityArrayLike,
        measurements: ChannelItems | None = None,
        commands: ChannelItems | None = None,
        references: Mapping[str, QuantityArrayLike] | None = None,
    ) -> None:
        kind = self.synthesis_type.__name__
        if not isinstance(synthesis, self.synthesis_type):
            raise FieldError(
                "synthesis",
                f"must be an {kind} ({self.designer}), got {type(synthesis).__name__}",
            )
        self.synthesis = synthesis
        plant = synthesis.plant
        super().__init__(
            synthesis.controller,
            plant.measurement_names if measurements is None else measurements,
            plant.control_names if commands is None else commands,
            dt,
            references,
        )


class H2Controller(SynthesisCompensator):
    """An H2-optimal compensator as a flexsat law (a continuous
    :class:`~flexsat.control.state_space_compensator.StateSpaceCompensator`, run through its
    exact zero-order-hold equivalent at the control period).

    Parameters
    ----------
    synthesis : H2Synthesis
        The design (:func:`h2syn`), kept as ``.synthesis``.
    dt : float, str or Quantity
        Control period, s.
    measurements, commands : sequence of str or Channel, optional
        The plant channels y and u are (default the generalized plant's names of y and u).
    references : mapping {channel: value}, optional
        Set points subtracted from the measurements (e.g. the target angle).
    """

    synthesis_type = H2Synthesis
    designer = "h2syn"
