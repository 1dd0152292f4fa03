r"""LQG/LTR: loop transfer recovery at the plant input.

An LQ state feedback :math:`u = -Kx` has, at the plant input, the loop
:math:`L_{LQ}(s) = K(sI - A)^{-1}B` with guaranteed margins (Kalman's inequality
:math:`|1 + L_{LQ}(j\omega)| \ge 1` for a diagonal R: gain margin [1/2, ∞), phase margin
>= 60°). An LQG compensator, which feeds back the Kalman estimate instead, loses them: the
loop :math:`L_q(s) = K(sI - A + BK + LC)^{-1}L\;C(sI - A)^{-1}B` has no guaranteed margin
(Doyle, "Guaranteed margins for LQG regulators", IEEE Transactions on Automatic Control 23(4),
1978, 756–757).

Doyle & Stein ("Robustness with observers", IEEE Transactions on Automatic Control 24(4),
1979, 607–611; "Multivariable feedback design: concepts for a classical/modern synthesis",
IEEE Transactions on Automatic Control 26(1), 1981, 4–16) design the filter with a
fictitious process noise on the plant input,

.. math::

    Q_n(q) = Q_{n,0} + q^2 B B^T, \qquad L_q = P_q C^T R_n^{-1},

and show that, if :math:`C(sI - A)^{-1}B` is minimum phase with at least as many outputs as
inputs, :math:`L_q(j\omega) \to L_{LQ}(j\omega)` pointwise as q → ∞: the compensated loop
recovers the LQ loop and its margins. The price is a filter whose bandwidth grows with q
(its gain grows like q), so the recovery is taken only as far as noise and the sample rate
allow; a flexible structure's collocated torque-to-angle transfer is minimum phase, so it
recovers.

The law (:class:`LTRController`) is the compensator :math:`\dot{\hat x} = (A - BK - L_qC)\hat x
+ L_q y`, :math:`u = -K\hat x` as a continuous
:class:`~flexsat.control.state_space_compensator.StateSpaceCompensator`; :meth:`LTRController.
target_loop` is :math:`L_{LQ}` for comparison.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.estimation import kalman
from flexsat.control.lqr import check_matrix, check_square, lqr
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    import control as ct
    from flexsat.control.linear_form import ChannelItems
    from flexsat.control.lqr import RiccatiSolution
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["LTRController"]


class LTRController(StateSpaceCompensator):
    r"""LQG compensator with input loop transfer recovery (module docstring).

    Build it with :meth:`design`.

    Attributes
    ----------
    q : float
        Recovery parameter.
    regulator, filter : RiccatiSolution
        The LQ design (K) and the recovery filter (L_q), with residuals.
    plant_matrices : tuple of ndarray
        (A, B, C) of the design plant.
    """

    q: float
    regulator: RiccatiSolution
    filter: RiccatiSolution
    plant_matrices: tuple[FloatArray, FloatArray, FloatArray]

    @classmethod
    def design(
        cls,
        A: npt.ArrayLike,
        B: npt.ArrayLike,
        C: npt.ArrayLike,
        Q: npt.ArrayLike,
        R: npt.ArrayLike,
        Rn: npt.ArrayLike,
        q: float,
        dt: QuantityArrayLike,
        measurements: ChannelItems,
        commands: ChannelItems,
        Qn0: npt.ArrayLike | None = None,
        references: Mapping[str, QuantityArrayLike] | None = None,
    ) -> LTRController:
        r"""Design K = lqr(A, B, Q, R) and the recovery filter, and build the law.

        Parameters
        ----------
        A, B, C : array_like
            Continuous design plant (n, n), (n, m), (p, n), p >= m.
        Q, R : array_like
            LQ weights.
        Rn : array_like (p, p)
            Measurement-noise intensity.
        q : float
            Recovery parameter, >= 0 (0: the plain LQG of Qn0).
        dt : float, str or Quantity
            Control period, s.
        measurements, commands : sequence of str or Channel
            Plant channels of y (rows of C) and u (columns of B).
        Qn0 : array_like (n, n), optional
            Nominal process-noise intensity on the state (default B Bᵀ: unit torque noise).
        references : mapping, optional
            Set points of the measurements.
        """
        a = check_square(A, "A")
        n = a.shape[0]
        b = check_matrix(B, "B", n, None, f"(n, m) with n = {n}")
        c = check_matrix(C, "C", None, n, f"(p, n) with n = {n}")
        if c.shape[0] < b.shape[1]:
            raise FieldError(
                "C",
                f"recovery at the plant input needs at least as many measurements as inputs "
                f"({c.shape[0]} < {b.shape[1]})",
            )
        qv = float(require_finite(q, "q"))
        if qv < 0:
            raise FieldError("q", f"must be >= 0, got {qv:g}")
        W0 = b @ b.T if Qn0 is None else check_matrix(Qn0, "Qn0", n, n, f"({n}, {n})")
        reg = lqr(a, b, Q, R)
        filt = kalman(a, None, c, W0 + qv**2 * (b @ b.T), Rn)
        K, L = reg.gain, filt.gain
        import control as ct

        system = ct.ss(a - b @ K - L @ c, L, -K, np.zeros((b.shape[1], c.shape[0])))
        law = cls(system, measurements, commands, dt, references)
        law.q, law.regulator, law.filter = qv, reg, filt
        law.plant_matrices = (a, b, c)
        return law

    def target_loop(self) -> ct.StateSpace:
        r""":math:`L_{LQ}(s) = K(sI - A)^{-1}B`, the LQ loop broken at the plant input
        (negative-feedback convention of :mod:`~flexsat.analysis.frequency_domain`), inputs and
        outputs named after the commands."""
        import control as ct
        from flexsat.control.state_space_export import channel_labels

        a, b, _ = self.plant_matrices
        names = channel_labels(self.writes, self.write_sizes)
        return ct.ss(
            a,
            b,
            self.regulator.gain,
            np.zeros((b.shape[1], b.shape[1])),
            inputs=names,
            outputs=names,
            name="L_LQ",
        )
