r"""Liapunov retrieval laws of a tethered subsatellite (Vadali & Kim, AIAA 90-1197; Junkins,
Pollock & Rahman 1990, Att. 12, "In-plane Control Law" to "A Tether Rate Control Law"), on the plant
:class:`~flexsat.dynamics.tether.TetheredSubsatellite`.

All three are written in the nondimensional variables of Att. 12 Eq. 4 (x = [λ, θ, φ, λ', θ',
φ'], ' = d/dτ):

* :class:`DecoupledTetherLaw` (controller 1, Eqs. 13-15): z = λ cos φ, y = λ sin φ nearly
  uncouple the motion (Eq. 10); the in-plane law (7) on z and rate feedback on y give

  .. math::

      \hat T &= (3 + K_1)\lambda\cos^2\phi - K_1\lambda_f\cos\phi
               - 2K_2\theta'(1+\theta')/\lambda + K_3\lambda' \\
      \hat F &= (3 + K_1)\lambda\cos\phi\sin\phi - K_1\lambda_f\sin\phi
               - 2K_2\theta'(1+\theta')\tan\phi/\lambda - K_3\lambda\phi'

  The last sign is the repaired one: solving Eq. 13 exactly gives −K3λφ' (with Eqs. 11-12,
  K3 y' z − K3 z' y = K3 λ²φ' enters F̂/λ with the determinant −λ²). Att. 12 Eq. 15 prints "+", with
  which the retrieval diverges; ``printed_sign=True`` keeps it, to
  show that. At φ = 0 the tension is the in-plane law (7).
* :class:`CoupledTetherLaw` (controller 2, Eqs. 18 and 20), built on the integral of motion V1
  (Eq. 8) inside the Liapunov function (16), so that V' = −K3λ'² − (K2 + λ²)K4φ'² (Eq. 21):

  .. math::

      \hat T = 3\lambda + K_1(\lambda - \lambda_r)
               - 2K_2[\theta'(1+\theta')\cos^2\phi + \phi'^2]/\lambda + K_3\lambda', \qquad
      \hat F = -K_4\lambda\phi'

* :class:`TetherRateLaw` (Eqs. 24-25), the length rate as the control, from
  V = ½[K1(λ − λf)² + K2 V1] (Eq. 23), V' = −λ'² − ½K2K3φ'²:

  .. math::

      \lambda' = -K_1(\lambda - \lambda_f) + K_2[\theta'(1+\theta')\cos^2\phi + \phi'^2]/\lambda,
      \qquad \hat F = -K_3\lambda\phi'

Each law has a nondimensional kernel (:meth:`nondimensional`) inside the controller protocol
(a static feedback for the engine's sampled or continuous-law mode; reads the plant's SI
measurements, writes ``tension``/``reel_rate`` and ``thrust`` in SI through the plant's
:class:`~flexsat.dynamics.tether.TetherScales`). Gains and targets may be arrays over cases.

The measures of the paper: :func:`thrust_index` (∫|F̂|dτ over a grid), :func:`liapunov_coupled`
(V of Eq. 16) and, from the dynamics, the integral of motion V1.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics.tether import TetherScales, integral_of_motion, require_lengths
from flexsat.input_checks import FieldError, require_finite, require_nonneg, require_positive
from flexsat.units import holds_quantity

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = [
    "DecoupledTetherLaw",
    "CoupledTetherLaw",
    "TetherRateLaw",
    "thrust_index",
    "liapunov_coupled",
    "MEASUREMENTS",
]

#: what every tether law reads (the plant's outputs, SI)
MEASUREMENTS = ("length", "pitch", "roll", "length_rate", "pitch_rate", "roll_rate")


def thrust_index(tau: npt.ArrayLike, thrust: npt.ArrayLike) -> FloatArray:
    r"""∫|F̂| dτ over the grid ``tau`` (n_t,) of thrust samples (..., n_t), by the trapezoidal
    rule on |F̂| with each sign change split at its linear zero (so the kink of |F̂| costs no
    accuracy beyond the rule's O(Δτ²)). Multiply by mΩL (:attr:`TetherScales.impulse`) for
    N s."""
    grid = require_finite(tau, "tau")
    F = require_finite(thrust, "thrust")
    if grid.ndim != 1 or grid.size < 2:
        raise FieldError("tau", f"must be a grid of >= 2 times, got shape {grid.shape}")
    if F.ndim == 0 or F.shape[-1] != grid.size or np.any(np.diff(grid) <= 0):
        raise FieldError(
            "tau",
            "must be an increasing grid matching thrust's last axis, got "
            f"{grid.shape} and {F.shape}",
        )
    a, b, h = F[..., :-1], F[..., 1:], np.diff(grid)
    same = a * b >= 0
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing = (a * a + b * b) / (2 * (np.abs(a) + np.abs(b)))
    return np.sum(np.where(same, 0.5 * (np.abs(a) + np.abs(b)), crossing) * h, axis=-1)


def liapunov_coupled(
    x: npt.ArrayLike,
    K1: float | npt.ArrayLike,
    K2: float | npt.ArrayLike,
    lambda_r: float | npt.ArrayLike,
) -> FloatArray:
    r"""V of Eq. 16 (with θ'² for the printed θ², a misprint) at x = [λ, θ, φ, λ', θ', φ']:
    ½[λ'² + K1(λ − λr)² + (K2 + λ²)·2V1]."""
    s = require_finite(x, "x")
    if s.ndim == 0 or s.shape[-1] != 6:
        raise FieldError("x", f"must be states [λ, θ, φ, λ', θ', φ'] (..., 6), got {s.shape}")
    k1, k2, lr = (require_finite(v, n) for v, n in ((K1, "K1"), (K2, "K2"), (lambda_r, "lambda_r")))
    V1 = integral_of_motion(s[..., 1], s[..., 2], s[..., 4], s[..., 5])
    lam = s[..., 0]
    return 0.5 * (s[..., 3] ** 2 + k1 * (lam - lr) ** 2) + (k2 + lam**2) * V1


class _TetherLaw(Controller):
    """Shared plumbing: gains as arrays, SI ↔ nondimensional through the plant's scales."""

    reads: tuple[str, ...] = MEASUREMENTS
    writes: tuple[str, ...] = ("tension", "thrust")
    _gain_names: tuple[str, ...] = ()
    #: λ_f, nondimensional (set from the gains)
    final_length: FloatArray

    def __init__(self, scales: TetherScales | None, **gains: QuantityArrayLike) -> None:
        self.scales = TetherScales() if scales is None else scales
        if not isinstance(self.scales, TetherScales):
            raise FieldError("scales", f"must be a TetherScales, got {type(scales).__name__}")
        for name, given in gains.items():
            value = given
            if name == "final_length" and holds_quantity(given, strings=True):
                # a length with units ("200 m"): λf = l_f / L
                value = require_positive(given, name, "m") / self.scales.length
            check = require_positive if name in ("K1", "final_length") else require_nonneg
            checked = check(value, name)
            if checked.size == 0:
                raise FieldError(name, "must hold a value per case, got an empty array")
            setattr(self, name, checked)
        require_lengths(self.final_length, "final_length")
        self.target = self.final_length

    def _batched(self) -> list[tuple[int, ...]]:
        return [np.shape(getattr(self, n)) for n in self._gain_names]

    def _state(self, y: Mapping[str, FloatArray]) -> FloatArray:
        s = self.scales
        return np.stack(
            [
                np.asarray(y["length"], float) / s.length,
                y["pitch"],
                y["roll"],
                np.asarray(y["length_rate"], float) / s.speed,
                np.asarray(y["pitch_rate"], float) / s.orbit_rate,
                np.asarray(y["roll_rate"], float) / s.orbit_rate,
            ],
            -1,
        )

    @abstractmethod
    def nondimensional(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The law's two commands, nondimensional, at nondimensional states x (..., 6)."""

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
        u, F = self.nondimensional(self._state(y))
        s = self.scales
        first = u * (s.force if self.writes[0] == "tension" else s.speed)
        return {self.writes[0]: first, "thrust": F * s.force}, state


class DecoupledTetherLaw(_TetherLaw):
    """Controller 1: tension (14) and thrust (15, sign repaired) of the decoupled design
    (module docstring).

    Parameters
    ----------
    K1 : float or array
        Length stiffness (> 0).
    K2 : float or array
        Pitch weight (>= 0); K2 = 0 is the continuous Rupp law.
    K3 : float or array
        Length-rate damping, also the rate gain of y (>= 0).
    final_length : float, array, str or Quantity
        λ_f, the nondimensional final length (> 0), or a length with units (``"200 m"``),
        divided by the scales' L.
    scales : TetherScales, optional
    printed_sign : bool
        Use Att. 12 Eq. 15's "+K3λφ'" (an erratum: the retrieval diverges) instead of "−".
    """

    _gain_names = ("K1", "K2", "K3", "final_length")
    K1: FloatArray
    K2: FloatArray
    K3: FloatArray

    def __init__(
        self,
        K1: float | npt.ArrayLike,
        K2: float | npt.ArrayLike,
        K3: float | npt.ArrayLike,
        final_length: QuantityArrayLike,
        scales: TetherScales | None = None,
        printed_sign: bool = False,
    ) -> None:
        super().__init__(scales, K1=K1, K2=K2, K3=K3, final_length=final_length)
        self.printed_sign = bool(printed_sign)

    def nondimensional(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(T̂, F̂) of Eqs. 14-15 at nondimensional states x (..., 6)."""
        lam, ph, dl, dth, dph = x[..., 0], x[..., 2], x[..., 3], x[..., 4], x[..., 5]
        K1, K2, K3, lf = self.K1, self.K2, self.K3, self.final_length
        c, s = np.cos(ph), np.sin(ph)
        pitch = 2 * K2 * dth * (1 + dth) / lam
        T = (3 + K1) * lam * c * c - K1 * lf * c - pitch + K3 * dl
        roll_damping = K3 * lam * dph
        F = (
            (3 + K1) * lam * c * s
            - K1 * lf * s
            - pitch * s / c
            + (roll_damping if self.printed_sign else -roll_damping)
        )
        return T, F


class CoupledTetherLaw(_TetherLaw):
    """Controller 2: tension (18) and thrust (20) from the integral of motion (module
    docstring).

    Parameters
    ----------
    K1 : float or array
        Length stiffness (> 0).
    K2, K3, K4 : float or array
        Libration weight, length-rate damping and roll-rate thrust gain (>= 0).
    final_length : float, array, str or Quantity
        λ_r (> 0), nondimensional or a length with units (divided by L).
    scales : TetherScales, optional
    """

    _gain_names = ("K1", "K2", "K3", "K4", "final_length")
    K1: FloatArray
    K2: FloatArray
    K3: FloatArray
    K4: FloatArray

    def __init__(
        self,
        K1: float | npt.ArrayLike,
        K2: float | npt.ArrayLike,
        K3: float | npt.ArrayLike,
        K4: float | npt.ArrayLike,
        final_length: QuantityArrayLike,
        scales: TetherScales | None = None,
    ) -> None:
        super().__init__(scales, K1=K1, K2=K2, K3=K3, K4=K4, final_length=final_length)

    def nondimensional(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(T̂, F̂) of Eqs. 18 and 20 at nondimensional states x (..., 6)."""
        lam, ph, dl, dth, dph = x[..., 0], x[..., 2], x[..., 3], x[..., 4], x[..., 5]
        W = dth * (1 + dth) * np.cos(ph) ** 2 + dph * dph
        T = 3 * lam + self.K1 * (lam - self.final_length) - 2 * self.K2 * W / lam + self.K3 * dl
        return T, -self.K4 * lam * dph

    def liapunov(self, x: npt.ArrayLike) -> FloatArray:
        """V of Eq. 16 along nondimensional states x (..., 6)."""
        return liapunov_coupled(x, self.K1, self.K2, self.final_length)


class TetherRateLaw(_TetherLaw):
    """The tether-rate law: λ' of Eq. 24 and thrust of Eq. 25 (module docstring), for the plant
    under rate control (writes ``reel_rate`` and ``thrust``).

    Parameters
    ----------
    K1 : float or array
        Retrieval rate constant (> 0): λ'(0) = −K1(λ0 − λf) from rest.
    K2, K3 : float or array
        Weight of V1 and roll-rate thrust gain (>= 0).
    final_length : float, array, str or Quantity
        λ_f (> 0), nondimensional or a length with units (divided by L).
    scales : TetherScales, optional
    """

    reads = ("length", "pitch", "roll", "pitch_rate", "roll_rate")
    writes = ("reel_rate", "thrust")
    _gain_names = ("K1", "K2", "K3", "final_length")
    K1: FloatArray
    K2: FloatArray
    K3: FloatArray

    def __init__(
        self,
        K1: float | npt.ArrayLike,
        K2: float | npt.ArrayLike,
        K3: float | npt.ArrayLike,
        final_length: QuantityArrayLike,
        scales: TetherScales | None = None,
    ) -> None:
        super().__init__(scales, K1=K1, K2=K2, K3=K3, final_length=final_length)

    def _state(self, y: Mapping[str, FloatArray]) -> FloatArray:
        measured = dict(y)
        measured["length_rate"] = np.zeros(np.shape(y["length"]))  # the law sets it; not read
        return super()._state(measured)

    def nondimensional(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(λ', F̂) of Eqs. 24-25 at nondimensional states x (..., 6); x[..., 3] is unused."""
        lam, ph, dth, dph = x[..., 0], x[..., 2], x[..., 4], x[..., 5]
        W = dth * (1 + dth) * np.cos(ph) ** 2 + dph * dph
        rate = -self.K1 * (lam - self.final_length) + self.K2 * W / lam
        return rate, -self.K3 * lam * dph
