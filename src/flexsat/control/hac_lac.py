r"""HAC/LAC: a high-authority attitude loop over a low-authority collocated damping loop.

Aubrun ("Theory of the control of structures by low-authority controllers", Journal of
Guidance and Control 3(5), 1980, 444–451) damps a structure with a low-authority controller
(LAC): direct velocity feedback on collocated actuator/sensor pairs,

.. math::

    u_{LAC} = -G\,\dot y_{c}, \qquad \dot y_c = B_{LAC}^T\dot q, \qquad G = G^T \succeq 0,

which only removes energy (:math:`\dot E = -\dot y_c^T G \dot y_c \le 0`) and so is stable for
any gain and any model error that keeps the pairs collocated; for small gains each mode i
gains the damping :math:`\Delta\zeta_i \approx \phi_i^T B G B^T \phi_i / (2\omega_i)`
(first-order perturbation of the undamped modes, Aubrun 1980). The high-authority controller
(HAC) is then designed on the LAC-damped plant :math:`A_{LAC} = A - B_{LAC}\,G\,C_{\dot y}`:
the modes it does not control (spillover) and the modal frequencies it gets wrong now carry
damping, which is what makes the HAC robust (Aubrun & Margulies, "Low-authority control
synthesis for large space structures", NASA CR-3495, 1982; Wie, *Space Vehicle Dynamics and
Control*, 2nd ed., AIAA, 2008, on collocated rate feedback and flexible-structure control).

Here the HAC is an LQG compensator (:func:`~flexsat.control.lqr.lqr`,
:func:`~flexsat.control.estimation.kalman`) on the LAC-damped plant from the HAC measurements to
the HAC commands; :class:`HacLacController` is both loops in one continuous compensator

.. math::

    \begin{bmatrix} u_{HAC} \\ u_{LAC} \end{bmatrix} =
    \left[\begin{array}{c|cc} A_{LAC} - B_hK - LC_h & L & 0 \\ \hline
      -K & 0 & 0 \\ 0 & 0 & -G \end{array}\right]
    \begin{bmatrix} y_{HAC} \\ \dot y_c \end{bmatrix},

a :class:`~flexsat.control.state_space_compensator.StateSpaceCompensator` (zero-order hold at
the control period).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.analysis.norms import system_matrices
from flexsat.control.estimation import kalman
from flexsat.control.lqr import lqr
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.input_checks import FieldError, require_numeric

if TYPE_CHECKING:
    import numpy.typing as npt

    import control as ct
    from flexsat.control.lqr import RiccatiSolution
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["HacLacController", "ModalDamping", "lac_plant", "modal_damping"]


@dataclass(frozen=True)
class ModalDamping:
    """Natural frequencies (rad/s) and damping ratios of the oscillatory poles of a system,
    one per conjugate pair, sorted by frequency."""

    frequency_rad_s: FloatArray
    damping: FloatArray


def modal_damping(A: npt.ArrayLike, min_frequency: float = 1e-6) -> ModalDamping:
    """Frequencies ω = |λ| and damping ζ = −Re λ / |λ| of the eigenvalues of A with
    Im λ > 0 and |λ| > ``min_frequency`` (rigid and real poles left out)."""
    lam = np.linalg.eigvals(np.asarray(A, float))
    osc = lam[(lam.imag > 0) & (np.abs(lam) > min_frequency)]
    order = np.argsort(np.abs(osc))
    osc = osc[order]
    return ModalDamping(np.abs(osc), -osc.real / np.abs(osc))


def _indices(labels: Sequence[str], names: Sequence[str], field: str, role: str) -> list[int]:
    labels = [str(s) for s in labels]
    missing = [n for n in names if n not in labels]
    if missing:
        raise FieldError(field, f"{missing} are not {role} of the plant (it has {labels})")
    return [labels.index(n) for n in names]


def _lac_gain(gain: npt.ArrayLike, k: int) -> FloatArray:
    G = require_numeric(gain, "lac_gain")
    if G.ndim == 0:
        G = float(G) * np.eye(k)
    elif G.ndim == 1 and G.shape == (k,):
        G = np.diag(G)
    if G.shape != (k, k):
        raise FieldError(
            "lac_gain", f"must be a scalar, ({k},) or ({k}, {k}) for {k} pairs, got {G.shape}"
        )
    G = 0.5 * (G + G.T)
    if np.linalg.eigvalsh(G).min() < 0:
        raise FieldError(
            "lac_gain", "must be positive semi-definite (rate feedback that only dissipates)"
        )
    return np.asarray(G, float)


def lac_plant(
    plant: ct.StateSpace, pairs: Sequence[tuple[str, str]], gain: npt.ArrayLike
) -> ct.StateSpace:
    r"""The plant with the LAC loop closed, :math:`A - B_{LAC} G C_{\dot y}`, same signals.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous, labelled (e.g. :func:`~flexsat.dynamics.linear_model.plant_state_space`).
    pairs : sequence of (actuator, rate sensor)
        Collocated pairs: an input and the output measuring the rate of its work conjugate.
    gain : float, (k,) or (k, k)
        G, positive semi-definite.
    """
    import control as ct

    A, B, C, D, dt = system_matrices(plant, "plant")
    if dt:
        raise FieldError("plant", "must be continuous")
    acts = _indices(plant.input_labels, [a for a, _ in pairs], "pairs", "inputs")
    rates = _indices(plant.output_labels, [s for _, s in pairs], "pairs", "outputs")
    if np.any(D[np.ix_(rates, acts)] != 0):
        raise FieldError("pairs", "the rate sensors must not feed the actuators through (D = 0)")
    G = _lac_gain(gain, len(acts))
    Bl, Cl = B[:, acts], C[rates]
    return ct.ss(
        A - Bl @ G @ Cl,
        B,
        C - D[:, acts] @ G @ Cl,
        D,
        inputs=plant.input_labels,
        outputs=plant.output_labels,
        states=plant.state_labels,
        name="lac_damped",
    )


class HacLacController(StateSpaceCompensator):
    """HAC (LQG on the LAC-damped plant) and LAC (collocated rate feedback) in one law
    (module docstring). Build it with :meth:`design`.

    Attributes
    ----------
    lac_gain : ndarray (k, k)
    pairs : tuple of (str, str)
    regulator, filter : RiccatiSolution
        The HAC's LQ and Kalman designs on the damped plant.
    damped_plant : control.StateSpace
        The plant with the LAC loop closed (:func:`lac_plant`).
    """

    lac_gain: FloatArray
    pairs: tuple[tuple[str, str], ...]
    regulator: RiccatiSolution
    filter: RiccatiSolution
    damped_plant: ct.StateSpace

    @classmethod
    def design(
        cls,
        plant: ct.StateSpace,
        pairs: Sequence[tuple[str, str]],
        lac_gain: npt.ArrayLike,
        hac_commands: Sequence[str],
        hac_measurements: Sequence[str],
        Q: npt.ArrayLike,
        R: npt.ArrayLike,
        Qn: npt.ArrayLike,
        Rn: npt.ArrayLike,
        dt: QuantityArrayLike,
        references: Mapping[str, QuantityArrayLike] | None = None,
    ) -> HacLacController:
        """Close the LAC, design the HAC LQG on the damped plant, build the law.

        Parameters
        ----------
        plant : control.StateSpace
            Continuous design plant with labelled signals; its state is the LQG's.
        pairs : sequence of (actuator, rate sensor)
            The LAC's collocated pairs.
        lac_gain : float, (k,) or (k, k)
            Rate-feedback gain G (positive semi-definite; 0 gives the HAC alone).
        hac_commands, hac_measurements : sequence of str
            Inputs the HAC drives and outputs it reads (not LAC actuators).
        Q, R : array_like
            LQ weights on the plant state and the HAC commands.
        Qn, Rn : array_like
            Process-noise intensity on the HAC inputs (torque noise) and measurement-noise
            intensity of the HAC measurements.
        dt : float, str or Quantity
            Control period, s.
        references : mapping, optional
            Set points of HAC measurements (e.g. the target angle).
        """
        import control as ct

        pairs_t = tuple((str(a), str(s)) for a, s in pairs)
        if not pairs_t:
            raise FieldError("pairs", "give at least one (actuator, rate sensor) pair")
        lac_acts = [a for a, _ in pairs_t]
        if set(lac_acts) & set(hac_commands):
            raise FieldError(
                "hac_commands", f"{sorted(set(lac_acts) & set(hac_commands))} are LAC actuators"
            )
        damped = lac_plant(plant, pairs_t, lac_gain)
        G = _lac_gain(lac_gain, len(pairs_t))
        A, B, C, _, _ = system_matrices(damped, "plant")
        Bh = B[:, _indices(damped.input_labels, hac_commands, "hac_commands", "inputs")]
        Ch = C[_indices(damped.output_labels, hac_measurements, "hac_measurements", "outputs")]
        reg = lqr(A, Bh, Q, R)
        filt = kalman(A, Bh, Ch, Qn, Rn)
        K, L = reg.gain, filt.gain
        mh, ph, k = Bh.shape[1], Ch.shape[0], len(pairs_t)
        system = ct.ss(
            A - Bh @ K - L @ Ch,
            np.hstack([L, np.zeros((A.shape[0], k))]),
            np.vstack([-K, np.zeros((k, A.shape[0]))]),
            np.block([[np.zeros((mh, ph)), np.zeros((mh, k))], [np.zeros((k, ph)), -G]]),
        )
        law = cls(
            system,
            list(hac_measurements) + [s for _, s in pairs_t],
            list(hac_commands) + lac_acts,
            dt,
            references,
        )
        law.lac_gain, law.pairs = G, pairs_t
        law.regulator, law.filter, law.damped_plant = reg, filt, damped
        return law
