r"""The pieces of the laboratories' hardware (:mod:`flexsat.sim.hardware` puts them in the
loop): analog anti-alias filters, power amplifiers and reaction wheels, their parameters in SI,
and two linear-algebra helpers — the exact zero-order hold of a state space and its companion
2×2 block form.

**Amplifier** (:class:`Amplifier`), current mode: the law's torque command c is converted with
the nominal torque constant to a current demand i_c = c / K_t, clipped at the current limit
(and at gain × D/A range), and the current follows a first-order lag of the amplifier's
bandwidth ω_b, :math:`\dot i = \omega_b (i_c - i)`; the applied torque is K_t i. Voltage mode
(a reaction wheel's drive only): the demand is the stall voltage V_c = c R / K_t, clipped at
the voltage limit, lagged by ω_b, and the motor current is :math:`i = (V - K_e \Omega)/R`
(armature inductance neglected: its time constant is below a millisecond), so the back-EMF
caps the wheel speed at V_max / K_e.

**Reaction wheel** (:class:`ReactionWheel`): with Ω_a the wheel's absolute spin rate and
Ω = Ω_a − θ̇ its speed relative to the body (θ̇ the plant's rate output about the wheel axis),

.. math::

    J_w \dot\Omega_a = \tau, \qquad \tau = K_t i - c_v \Omega - c_c\,\mathrm{sign}(\Omega),
    \qquad \text{hub torque} = -\tau,

(Hailey, Sortun & Agrawal, "Experimental verification of attitude control techniques for
slew maneuvers of flexible spacecraft", NPS, c. 1992, Eqs. 15 and 21, with the exact wheel
equation J_w(θ̈ + Ω̇) = −T_c).

**Anti-alias filter** (:class:`AntiAliasFilter`): an analog Butterworth or Bessel low-pass of
given order and −3 dB corner, as in the identification test rig
(:func:`flexsat.identify.excitation.with_anti_alias`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy import signal
from scipy.linalg import expm

from flexsat.input_checks import FieldError
from flexsat.units import to_si_array

if TYPE_CHECKING:
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = [
    "AMPLIFIER_MODES",
    "FILTER_KINDS",
    "Amplifier",
    "AntiAliasFilter",
    "ReactionWheel",
    "companion_blocks",
    "zoh",
]

FILTER_KINDS = ("butterworth", "bessel")
AMPLIFIER_MODES = ("current", "voltage")


def _scalar(value: QuantityArrayLike, unit: str, field: str, positive: bool, inf_ok: bool) -> float:
    v = to_si_array(value, unit, field)
    if v.ndim != 0:
        raise FieldError(field, f"must be one number, got shape {v.shape}")
    x = float(v)
    ok = (np.isfinite(x) or (inf_ok and x == np.inf)) and (x > 0 if positive else x >= 0)
    if not ok:
        rule = "> 0" if positive else ">= 0"
        raise FieldError(
            field, f"must be {rule}{' (inf for none)' if inf_ok else ''}, got {value!r}"
        )
    return x


def zoh(A: FloatArray, B: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    r"""Exact zero-order-hold discretisation (Φ, Γ) = (e^{AΔt}, ∫₀^Δt e^{As} ds B) of
    x' = A x + B u, from one exponential of the block matrix [[A, B], [0, 0]] Δt (Van Loan,
    "Computing integrals involving the matrix exponential", IEEE Trans. Automatic Control,
    1978)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = expm(M * dt)
    return E[:n, :n], E[:n, n:]


@lru_cache(maxsize=64)
def _filter_matrices(corner: float, order: int, kind: str) -> tuple[FloatArray, ...]:
    wc = 2 * np.pi * corner
    if kind == "butterworth":
        zpk = signal.butter(order, wc, analog=True, output="zpk")
    else:
        zpk = signal.bessel(order, wc, analog=True, output="zpk", norm="mag")
    A, B, C, D = signal.zpk2ss(*zpk)
    assert not np.any(D)  # an all-pole low-pass is strictly proper
    return np.asarray(A, float), np.asarray(B, float), np.asarray(C, float)


@dataclass(frozen=True)
class AntiAliasFilter:
    """Analog low-pass on a measured channel (module docstring).

    Parameters
    ----------
    corner : float, str or Quantity
        −3 dB frequency, Hz (TAMU: 10 Hz).
    order : int
        Filter order (number of poles).
    kind : {"butterworth", "bessel"}
        Maximally flat magnitude, or maximally flat group delay (``norm="mag"``: the corner is
        the −3 dB point for both).
    """

    corner: QuantityArrayLike
    order: int = 2
    kind: str = "butterworth"

    def __post_init__(self) -> None:
        object.__setattr__(self, "corner", _scalar(self.corner, "Hz", "corner", True, False))
        if isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer)):
            raise FieldError("order", f"must be an integer 1 .. 10, got {self.order!r}")
        if not 1 <= int(self.order) <= 10:
            raise FieldError("order", f"must be an integer 1 .. 10, got {self.order!r}")
        if self.kind not in FILTER_KINDS:
            raise FieldError("kind", f"must be one of {FILTER_KINDS}, got {self.kind!r}")

    def matrices(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(A_f, B_f, C_f) of a unit-DC-gain realisation, strictly proper."""
        A, B, C = _filter_matrices(float(self.corner), int(self.order), self.kind)  # type: ignore[arg-type]
        return A.copy(), B.copy(), C.copy()

    def frequency_response(self, f: FloatArray) -> FloatArray:
        """H(j 2π f), complex."""
        A, B, C = self.matrices()
        s = 2j * np.pi * np.asarray(f, float)
        eye = np.eye(A.shape[0])
        return np.array([(C @ np.linalg.solve(si * eye - A, B))[0, 0] for si in s.ravel()])


@dataclass(frozen=True)
class Amplifier:
    """Power amplifier driving a motor (module docstring).

    Parameters
    ----------
    mode : {"current", "voltage"}
    gain : float
        Current mode, A/V; voltage mode, V/V (TAMU KEPCO BOP: 1.2 A/V).
    current_limit : float
        Largest current, A (TAMU: 12 A); current mode.
    bandwidth : float
        −3 dB bandwidth of the first-order loop, Hz; inf for an instantaneous amplifier.
    torque_constant : float
        Motor K_t, N m/A (TAMU: 52.77 oz-in/A); on a plain torque channel it only scales the
        current limit to a torque.
    dac_range : float
        Largest commanded voltage at the amplifier's input, V (gain × it is a limit too).
    voltage_limit : float
        Largest output voltage, V; voltage mode.
    """

    mode: str = "current"
    gain: QuantityArrayLike = 1.0
    current_limit: QuantityArrayLike = np.inf
    bandwidth: QuantityArrayLike = np.inf
    torque_constant: QuantityArrayLike = 1.0
    dac_range: QuantityArrayLike = np.inf
    voltage_limit: QuantityArrayLike = np.inf

    def __post_init__(self) -> None:
        if self.mode not in AMPLIFIER_MODES:
            raise FieldError("mode", f"must be one of {AMPLIFIER_MODES}, got {self.mode!r}")
        for name, unit, inf_ok in (
            ("gain", "", False),
            ("current_limit", "A", True),
            ("bandwidth", "Hz", True),
            ("torque_constant", "N*m/A", False),
            ("dac_range", "V", True),
            ("voltage_limit", "V", True),
        ):
            object.__setattr__(
                self, name, _scalar(getattr(self, name), unit, f"amplifier.{name}", True, inf_ok)
            )

    def si(self, name: str) -> float:
        """The field ``name`` in SI, a float."""
        return float(getattr(self, name))

    def torque_limit(
        self, resistance: float = np.nan, torque_constant: float | None = None
    ) -> float:
        """Largest torque command it passes, N m: K_t min(I_max, gain · V_dac) in current
        mode, K_t min(V_max, gain · V_dac) / R in voltage mode (K_t the motor's: a wheel's
        ``torque_constant`` when given, else the amplifier's)."""
        kt = self.si("torque_constant") if torque_constant is None else torque_constant
        g, dac = self.si("gain"), self.si("dac_range")
        if self.mode == "current":
            return kt * min(self.si("current_limit"), g * dac)
        return kt * min(self.si("voltage_limit"), g * dac) / resistance


@dataclass(frozen=True)
class ReactionWheel:
    """Reaction wheel on a body-axis torque channel (module docstring).

    Parameters
    ----------
    inertia : float
        Spin inertia J_w, kg m².
    torque_constant : float
        K_t, N m/A.
    back_emf : float
        K_e, V s/rad (equal to K_t in SI for an ideal motor).
    resistance : float
        Armature resistance R, Ω (voltage mode).
    viscous, coulomb : float
        Bearing friction c_v (N m s/rad) and c_c (N m) on the relative speed.
    max_speed : float
        Drive speed limit on |Ω|, rad/s; inf for none.
    amplifier : Amplifier
        Its drive (current mode, ideal, by default).
    rate_output : str
        The plant's output channel of the body rate about the wheel axis.
    smoothing : float
        ε of the regularised Coulomb sign, rad/s.
    """

    inertia: QuantityArrayLike
    torque_constant: QuantityArrayLike = 1.0
    back_emf: QuantityArrayLike = 0.0
    resistance: QuantityArrayLike = 1.0
    viscous: QuantityArrayLike = 0.0
    coulomb: QuantityArrayLike = 0.0
    max_speed: QuantityArrayLike = np.inf
    amplifier: Amplifier = field(default_factory=Amplifier)
    rate_output: str = "theta_dot"
    smoothing: QuantityArrayLike = 1e-3

    def __post_init__(self) -> None:
        for name, unit, positive, inf_ok in (
            ("inertia", "kg*m^2", True, False),
            ("torque_constant", "N*m/A", True, False),
            ("back_emf", "V*s/rad", False, False),
            ("resistance", "ohm", True, False),
            ("viscous", "N*m*s/rad", False, False),
            ("coulomb", "N*m", False, False),
            ("max_speed", "rad/s", True, True),
            ("smoothing", "rad/s", True, False),
        ):
            object.__setattr__(
                self, name, _scalar(getattr(self, name), unit, f"wheel.{name}", positive, inf_ok)
            )
        if not isinstance(self.amplifier, Amplifier):
            raise FieldError("wheel.amplifier", f"must be an Amplifier, got {self.amplifier!r}")

    def si(self, name: str) -> float:
        """The field ``name`` in SI, a float."""
        return float(getattr(self, name))

    @property
    def no_load_speed(self) -> float:
        """Voltage mode: the speed the back-EMF caps the wheel at, V_max / K_e, rad/s."""
        a = self.amplifier
        v = min(a.si("voltage_limit"), a.si("gain") * a.si("dac_range"))
        k = self.si("back_emf")
        return np.inf if k == 0 else v / k


def companion_blocks(
    A: FloatArray, tol: float = 1e-9
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """(T, T⁻¹, ω, ζ) with T⁻¹ A T = diag([[0, 1], [−ω², −2ζω]]) for a matrix whose
    eigenvalues are all complex pairs λ (a = |λ|² = ω², b = −2 Re λ = 2ζω); None when one is
    real. Per pair: t2 = Re v (v its eigenvector), t1 = (A + b) t2, since A t1 = −a t2 on the
    pair's invariant plane (Cayley–Hamilton)."""
    mu, V = np.linalg.eig(A)
    if np.any(np.abs(mu.imag) <= tol * np.abs(mu)):
        return None
    up = np.flatnonzero(mu.imag > 0)
    cols, w, z = [], [], []
    for i in up:
        a, b = abs(mu[i]) ** 2, -2 * mu[i].real
        t2 = V[:, i].real / np.linalg.norm(V[:, i].real)
        cols += [(A + b * np.eye(A.shape[0])) @ t2, t2]
        w.append(np.sqrt(a))
        z.append(b / (2 * np.sqrt(a)))
    T = np.column_stack(cols)
    return T, np.linalg.inv(T), np.array(w), np.array(z)
