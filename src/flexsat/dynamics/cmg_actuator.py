r"""A rigid spacecraft actuated by a cluster of single-gimbal CMGs, as a
:class:`~flexsat.dynamics.plant.Plant` (Vadali, Oh & Walker, Eqs. 3–7;
in Junkins, Pollock & Rahman 1990).

State :math:`x = [\beta, \omega, \sigma]` (Euler parameters inertial to body, scalar first; body
rate, rad/s; the n gimbal angles, rad), input the commanded torque on the body τ_c (N m, body
axes). The cluster momentum is :math:`h = h_r\,\hat h(\sigma)` with :math:`\hat h` the unit-rotor
momentum of :func:`flexsat.dynamics.cmg.momentum` and h_r one rotor's momentum (N m s);
:math:`\dot h = h_r C(\sigma)\dot\sigma` in body axes. The equations are Eq. (3)–(4)

.. math::

    I\dot\omega + \omega\times I\omega = -\dot h - \omega\times h, \qquad
    \dot\beta = \Omega(\omega)\beta,

so the torque the cluster puts on the body is :math:`-\dot h - \omega\times h` (gyroscopic
coupling included). The steering law (Eq. 5–7) asks that torque to equal τ_c:

.. math::

    C\dot\sigma = T,\quad T = -(\tau_c + \omega\times h)/h_r,\qquad
    \dot\sigma = C^T(CC^T + \alpha I)^{-1}T

(α = 0: the pseudo-inverse "pi", which raises at a singular set; α > 0: the
singularity-robust inverse "sr", Eq. 17). A gimbal-rate limit scales the whole rate vector by
:math:`\min(1, \dot\sigma_{max}/\max_i|\dot\sigma_i|)`: the torque keeps its direction and
loses magnitude (clipping each gimbal separately would turn it). The body then feels the torque
of the rates actually run, :math:`-h_r C\dot\sigma - \omega\times h`.

No external torque acts, so the total angular momentum :math:`C(\beta)^T(I\omega + h)` is
constant whatever is commanded (:meth:`CmgSpacecraft.momentum`): the cluster only exchanges
momentum with the body. Only the axial rotor momentum is modelled; gimbal and transverse rotor
inertia are neglected, as in the paper (Att. 13 "CMG Steering").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics import cmg
from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.rigid_body import cross3, dexpinv, matvec, require_inertia, rkmk4_step
from flexsat.dynamics.rigid_spacecraft import (
    ATTITUDE_OUTPUTS,
    attitude_output,
    attitude_state_from,
    dcm,
    normalize_quaternion,
    quaternion_kinematics,
)
from flexsat.input_checks import FieldError, require_finite
from flexsat.units import to_si_array

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

__all__ = ["CmgSpacecraft", "SingularityEvent", "STEERING_LAWS"]

#: steering laws: the pseudo-inverse (Eq. 7) and the singularity-robust inverse (Eq. 17)
STEERING_LAWS = ("pi", "sr")


@dataclass(frozen=True)
class SingularityEvent:
    """A passage of the gain det(CCᵀ) below the threshold (:meth:`CmgSpacecraft.
    singularity_events`): start time, least gain in the passage and its time, and whether the
    set there is an internal singularity (:func:`flexsat.dynamics.cmg.classify_singularity`)."""

    time: float
    min_gain: float
    time_of_min: float
    internal: bool


class CmgSpacecraft(Plant):
    """Rigid spacecraft with a single-gimbal CMG pyramid (module docstring).

    Parameters
    ----------
    inertia : array_like (3, 3), str or pint.Quantity
        Spacecraft inertia about the centre of mass, body axes, kg m² (rotors included).
    rotor_momentum : float, str or pint.Quantity
        Momentum h_r of one rotor, N m s (> 0); the station's 3500 ft-lb-s is
        ``"3500 lbf*ft*s"``.
    skew : float or str
        Pyramid skew angle δ (default the paper's 54.74°).
    n_units : int
        Number of CMGs (>= 3).
    steering : {"pi", "sr"}
        Pseudo-inverse (raises ValueError at a singular set) or singularity-robust inverse.
    alpha : float
        SR weight α on CCᵀ (dimensionless, unit rotors; the paper's ≈ 0.001); must be > 0 for
        "sr" and is ignored by "pi".
    gimbal_rate_limit : float, str or pint.Quantity
        Largest gimbal rate, rad/s (> 0; inf for none).
    """

    inputs = (Channel("torque", "N*m", 3, "commanded torque on the body, body axes"),)
    recorded = ("attitude", "euler123", "rate", "gimbal_angles", "cmg_momentum", "gain")
    nonlinear = True

    def __init__(
        self,
        inertia: QuantityArrayLike,
        rotor_momentum: QuantityLike,
        skew: QuantityLike = cmg.SKEW,
        n_units: int = 4,
        steering: str = "pi",
        alpha: float = 1e-3,
        gimbal_rate_limit: QuantityLike = np.inf,
    ) -> None:
        J = require_inertia(inertia)
        if J.shape != (3, 3):
            raise FieldError("inertia", f"must have shape (3, 3), got {J.shape}")
        # numpy types inv() as floating[Any]; it is float64 here, so the astype copies nothing
        self.inertia, self.inertia_inverse = J, np.linalg.inv(J).astype(np.float64, copy=False)
        hr = to_si_array(rotor_momentum, "N*m*s", "rotor_momentum")
        if hr.ndim != 0 or not np.isfinite(hr) or hr <= 0:
            raise FieldError(
                "rotor_momentum", f"must be one finite value > 0 N m s, got {rotor_momentum!r}"
            )
        self.rotor_momentum = float(hr)
        self.n_units = cmg._require_units(n_units)
        self.skew = cmg._require_skew(skew)
        if steering not in STEERING_LAWS:
            raise FieldError(
                "steering",
                f"must be one of {STEERING_LAWS} (pseudo-inverse or "
                f"singularity-robust inverse), got {steering!r}",
            )
        self.steering = steering
        al = float(require_finite(alpha, "alpha"))
        if steering == "sr" and al <= 0:
            raise FieldError(
                "alpha", f"the singularity-robust inverse needs alpha > 0, got {alpha!r}"
            )
        self.alpha = al if steering == "sr" else 0.0
        limit = to_si_array(gimbal_rate_limit, "rad/s", "gimbal_rate_limit")
        if limit.ndim != 0 or np.isnan(limit) or limit <= 0:
            raise FieldError(
                "gimbal_rate_limit", f"must be > 0 rad/s (inf for none), got {gimbal_rate_limit!r}"
            )
        self.gimbal_rate_limit = float(limit)
        n = self.n_units
        _, self._a, self._b = cmg.pyramid_axes(n, self.skew)
        self.outputs = ATTITUDE_OUTPUTS + (
            Channel("gimbal_angles", "rad", n, "gimbal angles σ"),
            Channel("gimbal_rates", "rad/s", n, "gimbal rates σ̇ after the rate limit"),
            Channel("cmg_momentum", "N*m*s", 3, "cluster momentum h, body axes"),
            Channel("gain", "", 1, "cluster gain det(CCᵀ), unit rotors"),
        )

    @property
    def nx(self) -> int:
        return 7 + self.n_units

    def initial_state(self, n_cases: int) -> FloatArray:
        """At rest, inertial attitude, gimbals at zero."""
        x = np.zeros((n_cases, self.nx))
        x[:, 0] = 1.0
        return x

    def state_from(self, **values: QuantityArrayLike) -> FloatArray:
        """Initial state from ``attitude`` or ``euler123``, ``rate`` and ``gimbal_angles``
        (rad or unit strings, e.g. a preferred set), or ``state``."""
        values = dict(values)
        sig = values.pop("gimbal_angles", None)
        x = attitude_state_from(self, values)
        if sig is not None:
            s = to_si_array(sig, "rad", "gimbal_angles")
            if s.shape != (self.n_units,) or not np.all(np.isfinite(s)):
                raise FieldError("gimbal_angles", f"{self.n_units} finite angles, got {sig!r}")
            x[7:] = s
        return x

    @property
    def initial_values(self) -> tuple[str, ...]:
        return ("attitude", "euler123", "rate", "gimbal_angles", "state")

    def cmg_momentum(self, x: FloatArray) -> FloatArray:
        """Cluster momentum h = h_r ĥ(σ), body axes, N m s, (..., 3)."""
        return self._momentum(x[..., 7:])

    # unchecked kernels on the cached axes: they run at every RK stage
    def _momentum(self, sig: FloatArray) -> FloatArray:
        return self.rotor_momentum * (np.cos(sig) @ self._a + np.sin(sig) @ self._b)

    def _hdot(self, sig: FloatArray, sdot: FloatArray) -> FloatArray:
        """h_r C(σ) σ̇ = h_r Σ_i σ̇_i (−sinσ_i a_i + cosσ_i b_i)."""
        return self.rotor_momentum * (
            (-np.sin(sig) * sdot) @ self._a + (np.cos(sig) * sdot) @ self._b
        )

    def gimbal_rates(self, x: FloatArray, u: npt.ArrayLike) -> FloatArray:
        """σ̇ of the steering law for the commanded torque u, after the rate limit (module
        docstring), (..., n).

        Raises
        ------
        ValueError
            With steering "pi" at a singular gimbal set (CCᵀ singular to working precision).
        """
        return self._gimbal_rates(x[..., 4:7], x[..., 7:], np.asarray(u, float))

    def _gimbal_rates(self, w: FloatArray, sig: FloatArray, u: FloatArray) -> FloatArray:
        demand = (u + cross3(w, self._momentum(sig))) / self.rotor_momentum
        try:
            rates = cmg.steer(sig, demand, self._a, self._b, self.alpha)
        except ValueError as err:
            raise FieldError(
                "torque",
                "the pseudo-inverse steering (steering='pi') cannot "
                f"deliver it: {err}; configure steering='sr'",
            ) from None
        if np.isfinite(self.gimbal_rate_limit):
            peak = np.abs(rates).max(axis=-1, keepdims=True)
            rates = rates * np.minimum(1.0, self.gimbal_rate_limit / np.maximum(peak, 1e-300))
        return rates

    def _rates(
        self, w: FloatArray, sig: FloatArray, u: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """(ω̇, σ̇) at body rate w, gimbals sig and command u."""
        sdot = self._gimbal_rates(w, sig, np.asarray(u, float))
        wdot = matvec(
            self.inertia_inverse,
            -cross3(w, matvec(self.inertia, w) + self._momentum(sig)) - self._hdot(sig, sdot),
        )
        return wdot, sdot

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A = 0, B = 0: the command reaches the body only through the steering law, which is
        nonlinear in σ; the whole motion is the force f (``force_matrix`` = I)."""
        return np.zeros((self.nx, self.nx)), np.zeros((self.nx, 3))

    @property
    def force_matrix(self) -> FloatArray:
        return np.eye(self.nx)

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """f = ẋ = [Ω(ω)β, ω̇, σ̇] (module docstring)."""
        wdot, sdot = self._rates(x[..., 4:7], x[..., 7:], u)
        return np.concatenate([quaternion_kinematics(x[..., :4], x[..., 4:7]), wdot, sdot], -1)

    def rhs(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """ẋ (for reference integrators)."""
        return self.nonlinear_force(x, u)

    def step(self, x: FloatArray, u: FloatArray, h: float) -> FloatArray:
        """One RKMK4 step h (s) with the command u held (:func:`flexsat.dynamics.rigid_body.
        rkmk4_step` on the attitude, classical RK4 on (ω, σ)): fourth order, β unit to
        round-off."""
        u = np.asarray(u, float)
        n_w = 3

        def rates(tau: float, theta: FloatArray, ws: FloatArray) -> tuple[FloatArray, FloatArray]:
            wdot, sdot = self._rates(ws[..., :n_w], ws[..., n_w:], u)
            return dexpinv(theta, ws[..., :n_w]), np.concatenate([wdot, sdot], -1)

        beta, ws = rkmk4_step(x[..., :4], x[..., 4:], h, rates, np.zeros(x.shape[:-1] + (3,)))
        return np.concatenate([beta, ws], -1)

    def normalize(self, x: FloatArray) -> FloatArray:
        return normalize_quaternion(x)

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)  # unknown names: a ValueError naming the channel
        if name == "gimbal_angles":
            return x[..., 7:]
        if name == "cmg_momentum":
            return self.cmg_momentum(x)
        if name == "gain":
            return cmg.gain(x[..., 7:], self.skew, self.n_units)
        if name == "gimbal_rates":
            if u is None:
                raise FieldError("gimbal_rates", "needs the commanded torque u")
            return self.gimbal_rates(x, u)
        return attitude_output(name, x[..., :4], x[..., 4:7])

    def energy(self, x: FloatArray) -> FloatArray:
        """Body kinetic energy ½ωᵀIω, J (constant-speed rotors: their energy does not change;
        the CMG exchanges momentum, and work with the gimbal motors)."""
        w = x[..., 4:7]
        return 0.5 * np.sum(w * matvec(self.inertia, w), axis=-1)

    def momentum(self, x: FloatArray) -> FloatArray:
        """Total angular momentum C(β)ᵀ(Iω + h) in inertial axes, N m s: constant (no external
        torque)."""
        total = matvec(self.inertia, x[..., 4:7]) + self.cmg_momentum(x)
        return np.einsum("...ji,...j->...i", dcm(x[..., :4]), total)

    def singularity_events(
        self, t: npt.ArrayLike, x: npt.ArrayLike, threshold: float = 1e-3
    ) -> list[SingularityEvent]:
        """Passages of the gain below ``threshold`` along a recorded run (times ``t`` (n_t,),
        states ``x`` (n_t, nx)), each classified internal or external at its least gain."""
        thr = float(require_finite(threshold, "threshold"))
        if thr <= 0:
            raise FieldError("threshold", f"must be > 0, got {threshold!r}")
        t = np.asarray(t, float)
        g = cmg.gain(np.asarray(x)[..., 7:], self.skew, self.n_units)
        below = g < thr
        events = []
        edges = np.flatnonzero(np.diff(np.concatenate([[0], below.astype(int), [0]])))
        for start, stop in zip(edges[::2], edges[1::2]):
            k = start + int(np.argmin(g[start:stop]))
            sing = cmg.classify_singularity(
                np.asarray(x)[k, 7:],
                self.skew,
                self.n_units,
                threshold=max(thr, g[k] * (1 + 1e-12)),
            )
            events.append(
                SingularityEvent(float(t[start]), float(g[k]), float(t[k]), bool(sing.internal))
            )
        return events
