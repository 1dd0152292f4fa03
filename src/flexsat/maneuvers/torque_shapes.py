"""Open-loop rest-to-rest rigid-body reference maneuvers ``I theta'' = u_ref(t)``.

Every shape slews from ``theta0`` to ``theta0 + angle`` over ``[0, T]`` and returns the torque and
the rigid-body angle, rate and acceleration in closed form (piecewise polynomials and sines; no
quadrature).  All shapes are odd about ``T/2`` (``u(T - t) = -u(t)``), so the motion is evaluated
on the first half and mirrored: ``theta(t) = theta0 + angle - [theta(T - t) - theta0]`` for
``t > T/2``, which also makes ``theta(T)`` land on the target up to one rounding.

Parameters are scalars or arrays that broadcast against each other and against ``t`` (a batch of
cases is a leading axis of shape ``(ncase,)``; a scalar ``t`` then gives ``(ncase,)`` outputs).
SI units throughout: rad, kg m^2, N m, s; a parameter may also be a pint Quantity or a unit string
(``angle="40 deg"``, ``inertia="2128 ozf*in*s**2"``), converted to SI.

Sources
-------
Junkins, Pollock & Rahman 1990, Att. 3 Eqs. 12-16: Junkins, Rahman & Bang, smoothed bang-bang.
Hailey, Sortun & Agrawal c. 1992, Eqs. 25-37 (NPS flexible spacecraft simulator), pseudo-square
and sinusoidal torque shaping. Full references: :func:`flexsat.references.references`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

from flexsat.input_checks import FieldError, require_finite, require_positive
from flexsat.units import FloatArray, QuantityArrayLike, to_si_array

__all__ = ["BangBang", "PseudoSquare", "Reference", "Sinusoidal", "SmoothBangBang", "TorqueShape"]

_C_SINE = 1.0 - 2.0 / np.pi  # plateau torque-impulse lost per unit rise time by a quarter sine

#: a profile and its first and second time integrals, ``(g, G1, G2)``
Integrals = tuple[FloatArray, FloatArray, FloatArray]
#: a rise or fall profile of :func:`_rounded_square`: ``x`` in [0, 1] to its :data:`Integrals`
Profile = Callable[[Any], Integrals]


@dataclass(frozen=True)
class Reference:
    """Reference torque [N m], angle [rad], rate [rad/s] and acceleration [rad/s^2] at ``t``.

    All four arrays have the broadcast shape of ``t`` and the shape parameters.
    """

    u: FloatArray
    theta: FloatArray
    theta_dot: FloatArray
    theta_ddot: FloatArray


def _exactly(n: int, **given: object) -> None:
    names = [k for k, v in given.items() if v is not None]
    if len(names) != n:
        raise ValueError(
            f"give exactly {n} of {{{', '.join(given)}}}; got {len(names)}: "
            f"{', '.join(names) or 'none'}"
        )


def _quarter_ratio(
    name: str, ratio: FloatArray, why: str, open_at_zero: bool = False, label: str | None = None
) -> FloatArray:
    """Check a dimensionless shape ratio lies in [0, 1/4] (or (0, 1/4]) and clip rounding.

    A solved ratio that misses a bound by <= 1e-12 (floating-point rounding of the closed-form
    inversion, e.g. bang-bang data giving alpha = -1e-17) is clipped onto the bound.
    """
    tol = 1e-12
    bad = (ratio <= 0) if open_at_zero else (ratio < -tol)
    bad = bad | (ratio > 0.25 + tol)
    if np.any(bad):
        worst = np.asarray(ratio)[bad].flat[0]
        raise FieldError(name, f"out of range ({why}); got {label or name} = {worst:.6g}")
    return np.clip(ratio, 0.0, 0.25)


def _rounded_square(
    tau: FloatArray, half: FloatArray, a: FloatArray, rise: Profile, fall: Profile
) -> Integrals:
    """Half of a rounded square wave and its first and second time integrals from 0.

    ``f`` rises over ``[0, a]`` as ``rise``, is 1 on ``[a, half - a]`` and falls over
    ``[half - a, half]`` as ``fall``.  ``rise`` and ``fall`` map ``x`` in [0, 1] to ``(g, G1, G2)``
    with ``G1 = int_0^x g``, ``G2 = int_0^x G1``.  ``a = 0`` gives the bang-bang plateau without
    dividing by zero (the ramp terms are multiplied by ``a``).

    Returns
    -------
    f, F1, F2 : ndarray
        ``f(tau)``, ``int_0^tau f`` [s] and ``int_0^tau int_0^s f`` [s^2].
    """
    scale = np.where(a > 0, a, 1.0)
    plateau = half - 2 * a
    gr, r1, r2 = rise(np.clip(tau / scale, 0.0, 1.0))
    gf, f1, f2 = fall(np.clip((tau - (half - a)) / scale, 0.0, 1.0))
    p = np.clip(tau - a, 0.0, plateau)
    f = np.where(tau < a, gr, np.where(tau <= half - a, 1.0, gf))
    F1 = a * r1 + p + a * f1
    F2 = (
        a * a * r2
        + a * rise(1.0)[1] * np.maximum(tau - a, 0.0)
        + 0.5 * p * p
        + plateau * np.maximum(tau - (half - a), 0.0)
        + a * a * f2
    )
    return f, F1, F2


def _smoothstep(x: Any) -> Integrals:
    """Junkins rise ``h = x^2 (3 - 2x)`` (Att. 3 Eq. 12, first piece) and its integrals."""
    x2 = x * x  # products, not **: numpy scalar and array power can differ by an ulp
    return x2 * (3 - 2 * x), x2 * x - x2 * x2 / 2, x2 * x2 / 4 - x2 * x2 * x / 10


def _smoothstep_fall(x: Any) -> Integrals:
    """Junkins reversal ``1 - 2 h(x/2)`` for its first half, ``x = (t - t1)/dt`` in [0, 1]."""
    h, h1, h2 = _smoothstep(x / 2)
    return 1 - 2 * h, x - 4 * h1, x * x / 2 - 8 * h2


def _sine_rise(x: Any) -> Integrals:
    """NPS quarter-sine rise ``sin(pi x / 2)`` (Eq. 26, first piece) and its integrals."""
    s, c = np.sin(np.pi * x / 2), np.cos(np.pi * x / 2)
    return s, (2 / np.pi) * (1 - c), (2 / np.pi) * (x - (2 / np.pi) * s)


def _sine_fall(x: Any) -> Integrals:
    """NPS reversal ``sin(pi (t - P/2 - 2 t_r) / (2 t_r)) = cos(pi x / 2)`` for its first half."""
    s, c = np.sin(np.pi * x / 2), np.cos(np.pi * x / 2)
    return c, (2 / np.pi) * s, (2 / np.pi) ** 2 * (1 - c)


class TorqueShape(ABC):
    """Rest-to-rest slew ``I theta'' = u_ref(t) = sign(angle) u_max f(t)`` on ``[0, T]``.

    Attributes
    ----------
    angle, inertia, u_max, duration, theta0 : ndarray
        Slew angle [rad] (nonzero, either sign), inertia [kg m^2], peak torque [N m],
        maneuver time ``T`` [s] and initial angle [rad], broadcast to a common shape.
        Subclasses add their shape parameter.
    """

    angle: FloatArray
    inertia: FloatArray
    u_max: FloatArray
    duration: FloatArray
    theta0: FloatArray

    def __init__(self, **fields: npt.ArrayLike) -> None:
        arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in fields.values()))
        for name, a in zip(fields, arrays):
            setattr(self, name, np.array(a))

    @property
    def end_time(self) -> FloatArray:
        """Maneuver end time ``T`` [s] (``= duration``)."""
        return self.duration

    @abstractmethod
    def _half(self, tau: FloatArray) -> Integrals:
        """``f``, ``int f`` and ``int int f`` from 0 to ``tau`` in ``[0, T/2]``."""

    def __call__(self, t: QuantityArrayLike) -> Reference:
        """Evaluate the reference at time(s) ``t`` [s].

        For ``t < 0`` the body rests at ``theta0``; for ``t >= T`` it rests at ``theta0 + angle``
        with ``u = 0`` exactly.  The second half is the mirror image of the first.  Outside
        ``[0, T)`` the clipped time gives ``tau = 0`` where both integrals vanish exactly, so only
        the torque needs masking (bang-bang has ``f(0) = 1``).  The second half is the closed
        interval ``[T/2, T)``: at ``t = T/2`` bang-bang already gives ``-u_max`` (the smooth
        shapes give 0 there either way), so a zero-order hold sampled with ``T/2`` on a sample
        applies each sign for the same number of samples and the net impulse is zero.

        Returns
        -------
        Reference
        """
        t = to_si_array(t, "s", "t")
        T = self.duration
        tc = np.clip(t, 0.0, T)
        late = tc >= 0.5 * T
        f, F1, F2 = self._half(np.where(late, T - tc, tc))
        sgn = np.sign(self.angle)
        k = sgn * self.u_max / self.inertia
        moving = (t >= 0) & (t < T)
        u = np.where(moving, sgn * self.u_max * np.where(late, -f, f), 0.0)
        theta = np.where(late, self.theta0 + self.angle - k * F2, self.theta0 + k * F2)
        return Reference(u=u, theta=theta, theta_dot=k * F1, theta_ddot=u / self.inertia)


def _slew(
    angle: QuantityArrayLike, inertia: QuantityArrayLike, theta0: QuantityArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    angle = require_finite(angle, "angle", "rad")
    if np.any(angle == 0):
        raise FieldError(
            "angle", "must be nonzero (a rest-to-rest slew of 0 rad has no torque shape)"
        )
    return (
        angle,
        require_positive(inertia, "inertia", "kg*m**2"),
        require_finite(theta0, "theta0", "rad"),
    )


class BangBang(TorqueShape):
    """Minimum-time bang-bang slew, ``T^2 = 4 I |angle| / u_max``.

    The ``alpha = 0`` case of Att. 3 Eq. 16 (Junkins, Pollock & Rahman 1990): ``u = +u_max`` on
    ``[0, T/2)``, ``-u_max`` on ``[T/2, T)`` (sign of ``angle``).

    Parameters
    ----------
    angle, inertia : array_like
        Slew angle [rad], nonzero; inertia [kg m^2] > 0.
    u_max, duration : array_like, optional
        Exactly one; the other is solved.
    theta0 : array_like
        Initial angle [rad].
    """

    def __init__(
        self,
        angle: QuantityArrayLike,
        inertia: QuantityArrayLike,
        u_max: QuantityArrayLike | None = None,
        duration: QuantityArrayLike | None = None,
        theta0: QuantityArrayLike = 0.0,
    ) -> None:
        angle, inertia, theta0 = _slew(angle, inertia, theta0)
        _exactly(1, u_max=u_max, duration=duration)
        m = inertia * np.abs(angle)
        if duration is None:
            assert u_max is not None  # given: checked by _exactly above
            u_max = require_positive(u_max, "u_max", "N*m")
            duration = np.sqrt(4 * m / u_max)
        else:
            duration = require_positive(duration, "duration", "s")
            u_max = 4 * m / duration**2
        super().__init__(
            angle=angle, inertia=inertia, u_max=u_max, duration=duration, theta0=theta0
        )

    def _half(self, tau: FloatArray) -> Integrals:
        return np.ones_like(tau), tau, 0.5 * tau * tau


class SmoothBangBang(TorqueShape):
    """Junkins smoothed bang-bang slew (Junkins, Pollock & Rahman 1990, Att. 3 Eqs. 12-16).

    ``u = sign(angle) u_max f(t)`` with ``dt = alpha T``, ``t1 = T/2 - dt``, ``t2 = T/2 + dt``,
    ``t3 = T - dt`` and the cubic smoothstep ``h(x) = x^2 (3 - 2x)``::

        f = h(t/dt)                      0  <= t <= dt
            1                            dt <= t <= t1
            1 - 2 h((t - t1)/(2 dt))     t1 <= t <= t2
            -1                           t2 <= t <= t3
            -1 + h((t - t3)/dt)          t3 <= t <= T

    Eq. 15: ``|angle| = (u_max/I) (1/4 - alpha/2 + alpha^2/10) T^2``, ``0 <= alpha <= 1/4``;
    ``alpha = 0`` is :class:`BangBang`.

    Parameters
    ----------
    angle, inertia : array_like
        Slew angle [rad], nonzero; inertia [kg m^2] > 0.
    u_max, duration, alpha : array_like, optional
        Exactly two; the third is solved (Eq. 16 for ``T``; given ``(u_max, T)``, ``alpha`` is
        the root of Eq. 15 in [0, 1/4]).
    theta0 : array_like
        Initial angle [rad].
    """

    alpha: FloatArray

    def __init__(
        self,
        angle: QuantityArrayLike,
        inertia: QuantityArrayLike,
        u_max: QuantityArrayLike | None = None,
        duration: QuantityArrayLike | None = None,
        alpha: QuantityArrayLike | None = None,
        theta0: QuantityArrayLike = 0.0,
    ) -> None:
        angle, inertia, theta0 = _slew(angle, inertia, theta0)
        _exactly(2, u_max=u_max, duration=duration, alpha=alpha)
        m = inertia * np.abs(angle)
        if alpha is None:
            assert u_max is not None  # given: checked by _exactly above
            u_max = require_positive(u_max, "u_max", "N*m")
            assert duration is not None  # given: checked by _exactly above
            duration = require_positive(duration, "duration", "s")
            # alpha^2/10 - alpha/2 + 1/4 = q; the other root exceeds 5/2
            alpha = (5 - np.sqrt(15 + 40 * m / (u_max * duration**2))) / 2
            why = (
                "alpha solved from (u_max, duration) must lie in [0, 1/4]: duration must be "
                "between the bang-bang time sqrt(4 I |angle| / u_max) and the alpha = 1/4 time "
                "sqrt(I |angle| / (0.13125 u_max))"
            )
        else:
            alpha = require_finite(alpha, "alpha", "")
            why = "alpha = rise time / duration must lie in [0, 1/4]; alpha = 1/4 leaves no plateau"
        alpha = _quarter_ratio("alpha", alpha, why)
        c = 0.25 - alpha / 2 + alpha**2 / 10
        if duration is None:
            assert u_max is not None  # given: checked by _exactly above
            u_max = require_positive(u_max, "u_max", "N*m")
            duration = np.sqrt(m / (u_max * c))
        elif u_max is None:
            duration = require_positive(duration, "duration", "s")
            u_max = m / (c * duration**2)
        super().__init__(
            angle=angle, inertia=inertia, u_max=u_max, duration=duration, theta0=theta0, alpha=alpha
        )

    def _half(self, tau: FloatArray) -> Integrals:
        return _rounded_square(
            tau, 0.5 * self.duration, self.alpha * self.duration, _smoothstep, _smoothstep_fall
        )

    def __call__(self, t: QuantityArrayLike) -> Reference:
        """:meth:`TorqueShape.__call__`; a table of samples × cases (``t`` of shape (n_t, 1),
        the parameters scalars or (n_cases,)) is evaluated by :func:`_smooth_table`, a
        compiled loop of the same operations (the same bits, without the ~20 temporary
        (n_t, n_cases) arrays of the array expression: 10× faster on a sweep's table)."""
        t = to_si_array(t, "s", "t")
        params = (self.duration, self.alpha, self.angle, self.u_max, self.inertia, self.theta0)
        if t.ndim != 2 or t.shape[1] != 1 or any(np.ndim(v) > 1 for v in params):
            return super().__call__(t)
        nc = max(np.size(v) for v in params)
        u, th, thd, thdd = _smooth_table(
            np.ascontiguousarray(t[:, 0]),
            *(np.ascontiguousarray(np.broadcast_to(v, (nc,)), dtype=float) for v in params),
        )
        return Reference(u=u, theta=th, theta_dot=thd, theta_ddot=thdd)


@njit(cache=True, error_model="numpy")
def _smooth_table(
    t: FloatArray,
    T: FloatArray,
    alpha: FloatArray,
    angle: FloatArray,
    u_max: FloatArray,
    inertia: FloatArray,
    theta0: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(u, θ, θ', θ'') of :class:`SmoothBangBang` at every t (n_t,) for every case (C,):
    :meth:`TorqueShape.__call__` with :func:`_rounded_square`, :func:`_smoothstep` and
    :func:`_smoothstep_fall`, element by element, each operation as the array expression
    performs it (no fused multiply-add: the same bits; tests/maneuvers)."""
    n_t, nc = t.shape[0], T.shape[0]
    u = np.empty((n_t, nc))
    th = np.empty((n_t, nc))
    thd = np.empty((n_t, nc))
    thdd = np.empty((n_t, nc))
    for i in range(n_t):  # row by row: the tables are written in memory order
        ti = t[i]
        for c in range(nc):
            Tc = T[c]
            half = 0.5 * Tc
            a = alpha[c] * Tc
            scale = a if a > 0 else 1.0
            plateau = half - 2 * a
            sgn = np.sign(angle[c])
            k = sgn * u_max[c] / inertia[c]
            tc = min(max(ti, 0.0), Tc)
            late = tc >= half
            tau = Tc - tc if late else tc
            # rise: h(x), x = clip(tau / scale, 0, 1)
            x = min(max(tau / scale, 0.0), 1.0)
            x2 = x * x
            gr = x2 * (3 - 2 * x)
            r1 = x2 * x - x2 * x2 / 2
            r2 = x2 * x2 / 4 - x2 * x2 * x / 10
            # fall: 1 − 2 h(x/2), x = clip((tau − (half − a)) / scale, 0, 1)
            x = min(max((tau - (half - a)) / scale, 0.0), 1.0)
            xh = x / 2
            x2 = xh * xh
            h = x2 * (3 - 2 * xh)
            h1 = x2 * xh - x2 * x2 / 2
            h2 = x2 * x2 / 4 - x2 * x2 * xh / 10
            gf, f1, f2 = 1 - 2 * h, x - 4 * h1, x * x / 2 - 8 * h2
            pl = min(max(tau - a, 0.0), plateau)
            f = gr if tau < a else (1.0 if tau <= half - a else gf)
            F1 = a * r1 + pl + a * f1
            F2 = (
                a * a * r2
                + a * 0.5 * max(tau - a, 0.0)
                + 0.5 * pl * pl
                + plateau * max(tau - (half - a), 0.0)
                + a * a * f2
            )
            moving = ti >= 0 and ti < Tc
            uc = sgn * u_max[c] * (-f if late else f) if moving else 0.0
            u[i, c] = uc
            th[i, c] = theta0[c] + angle[c] - k * F2 if late else theta0[c] + k * F2
            thd[i, c] = k * F1
            thdd[i, c] = uc / inertia[c]
    return u, th, thd, thdd


class PseudoSquare(TorqueShape):
    """NPS pseudo-square torque (Hailey, Sortun & Agrawal c. 1992, Eqs. 25-26).

    ``u = sign(angle) u_max f(t)`` with period ``P = duration`` and rise time ``t_r``::

        f = sin(pi t / (2 t_r))                      0         <= t <= t_r
            1                                        t_r       <= t <= P/2 - t_r
            sin(pi (t - P/2 - 2 t_r) / (2 t_r))      P/2 - t_r <= t <= P/2 + t_r
            -1                                       P/2 + t_r <= t <= P - t_r
            sin(pi (t - P + 4 t_r) / (2 t_r))        P - t_r   <= t <= P

    The third piece is printed as ``(t - P)/2 - 2 t_r`` in the OCR text; ``t - P/2 - 2 t_r`` is
    the reading that makes ``f`` continuous (``1, 0, -1`` at ``P/2 - t_r, P/2, P/2 + t_r``).
    Angle: ``|angle| = (u_max/I) S`` with ``S = int_0^P (P - t) f dt = P^2/4 - P t_r (1 - 2/pi)``,
    ``0 < t_r <= P/4``; ``t_r = P/4`` is the pure sine ``sin(2 pi t / P)`` (:class:`Sinusoidal`).

    Parameters
    ----------
    angle, inertia : array_like
        Slew angle [rad], nonzero; inertia [kg m^2] > 0.
    u_max, duration, rise_time : array_like, optional
        Exactly two; the third is solved (``P`` as the positive root of ``S(P) = I |angle|/u_max``).
    theta0 : array_like
        Initial angle [rad].
    """

    rise_time: FloatArray

    def __init__(
        self,
        angle: QuantityArrayLike,
        inertia: QuantityArrayLike,
        u_max: QuantityArrayLike | None = None,
        duration: QuantityArrayLike | None = None,
        rise_time: QuantityArrayLike | None = None,
        theta0: QuantityArrayLike = 0.0,
    ) -> None:
        angle, inertia, theta0 = _slew(angle, inertia, theta0)
        _exactly(2, u_max=u_max, duration=duration, rise_time=rise_time)
        m = inertia * np.abs(angle)
        why = (
            "rise_time must satisfy 0 < rise_time <= duration/4 so the quarter-sine rise and "
            "reversal do not overlap (rise_time = duration/4 is the pure sinusoid)"
        )
        if rise_time is None:
            assert u_max is not None  # given: checked by _exactly above
            u_max = require_positive(u_max, "u_max", "N*m")
            assert duration is not None  # given: checked by _exactly above
            duration = require_positive(duration, "duration", "s")
            rise_time = (duration**2 / 4 - m / u_max) / (duration * _C_SINE)
            why += (
                "; with u_max and duration given, I |angle| / u_max must lie in "
                "[duration^2 / (2 pi), duration^2 / 4)"
            )
        else:
            rise_time = require_finite(rise_time, "rise_time", "s")
            if duration is None:
                assert u_max is not None  # given: checked by _exactly above
                u_max = require_positive(u_max, "u_max", "N*m")
                duration = 2 * (
                    rise_time * _C_SINE + np.sqrt((rise_time * _C_SINE) ** 2 + m / u_max)
                )
        duration = require_positive(duration, "duration", "s")
        rise_time = duration * _quarter_ratio(
            "rise_time", rise_time / duration, why, True, "rise_time/duration"
        )
        if u_max is None:
            u_max = m / (duration**2 / 4 - duration * rise_time * _C_SINE)
        super().__init__(
            angle=angle,
            inertia=inertia,
            u_max=u_max,
            duration=duration,
            theta0=theta0,
            rise_time=rise_time,
        )

    def _half(self, tau: FloatArray) -> Integrals:
        return _rounded_square(tau, 0.5 * self.duration, self.rise_time, _sine_rise, _sine_fall)


class Sinusoidal(TorqueShape):
    """NPS sinusoidal torque (Hailey, Sortun & Agrawal c. 1992, Eqs. 27-37).

    ``I theta'' = sign(angle) A sin(2 pi t / P)`` over one period ``P = duration``, with
    ``A = u_max = 2 pi I |angle| / P^2`` (Eq. 36) and ``P = sqrt(2 pi I |angle| / A)`` (Eq. 37).
    The paper writes the reference as the error to go,
    ``theta_paper = dtheta [1 + ((P / 2 pi) sin(2 pi t / P) - t) / P]`` (Eq. 33) from ``dtheta``
    to 0; here ``theta = theta0 + angle - theta_paper`` with ``dtheta = angle``.

    Parameters
    ----------
    angle, inertia : array_like
        Slew angle [rad], nonzero; inertia [kg m^2] > 0.
    u_max, duration : array_like, optional
        Exactly one of amplitude ``A`` [N m] and period ``P`` [s]; the other is solved.
    theta0 : array_like
        Initial angle [rad].
    """

    def __init__(
        self,
        angle: QuantityArrayLike,
        inertia: QuantityArrayLike,
        u_max: QuantityArrayLike | None = None,
        duration: QuantityArrayLike | None = None,
        theta0: QuantityArrayLike = 0.0,
    ) -> None:
        angle, inertia, theta0 = _slew(angle, inertia, theta0)
        _exactly(1, u_max=u_max, duration=duration)
        m = 2 * np.pi * inertia * np.abs(angle)
        if duration is None:
            assert u_max is not None  # given: checked by _exactly above
            u_max = require_positive(u_max, "u_max", "N*m")
            duration = np.sqrt(m / u_max)
        else:
            duration = require_positive(duration, "duration", "s")
            u_max = m / duration**2
        super().__init__(
            angle=angle, inertia=inertia, u_max=u_max, duration=duration, theta0=theta0
        )

    def _half(self, tau: FloatArray) -> Integrals:
        w = 2 * np.pi / self.duration
        s = np.sin(w * tau)
        return s, (1 - np.cos(w * tau)) / w, (tau - s / w) / w
