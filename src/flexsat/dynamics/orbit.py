r"""A free-free beam in a circular orbit: nonlinear pitch and bending with gravity gradient.

Bainum & Reddy (1979), NASA CR-158684, Ch. II eqs 1–2, for a
uniform beam whose centre of mass is on a circular orbit of rate :math:`\omega_c`, pitch θ
from the local vertical and bending amplitudes :math:`A_n = l z_n`. The report writes them in
the nondimensional time :math:`\tau = \omega_c t` (' = d/dτ):

.. math::

    \theta'' + \tfrac32 \sin 2\theta = u_\theta, \qquad
    z_n'' + [F_n - (3\sin^2\theta - 1) - (\theta' - 1)^2]\, z_n = u_n,
    \qquad u = G f,

with :math:`F_n = (\omega_n/\omega_c)^2` and point forces f (N) through the modal influence
matrix G (eq 15: pitch row :math:`-\xi_j/(J\omega_c^2)`, mode rows
:math:`\phi_n(\xi_j)/(M_n l\omega_c^2)`, in 1/N).

**Time is in seconds here** (SI, as every plant): the state is
:math:`x = [\theta, z_1 \dots z_k, \dot\theta, \dot z_1 \dots \dot z_k]` with
:math:`\dot{} = d/dt = \omega_c\, d/d\tau`, so each acceleration above is multiplied by
:math:`\omega_c^2` and :math:`\theta' = \dot\theta/\omega_c`. Callers working in τ convert at
the boundary (``cases/bainum.py`` does).

Split for the exponential integrator (:mod:`flexsat.dynamics.plant`): the linear part is the
linearisation at rest, eqs 5–6 (the orbital terms :math:`-(3\sin^2\theta - 1) - (\theta' - 1)^2`
cancel at θ = θ' = 0),

.. math::

    A = \begin{bmatrix} 0 & I \\ -\omega_c^2\,\mathrm{diag}(3, F) & 0 \end{bmatrix},\quad
    B = \begin{bmatrix} 0 \\ \omega_c^2 G \end{bmatrix},

and the remainder is a generalized acceleration on every coordinate (:math:`B_f = [0; I]`)

.. math::

    f_\theta = \omega_c^2 (3\theta - \tfrac32\sin 2\theta), \qquad
    f_{z_n} = \omega_c^2 [(3\sin^2\theta - 1) + (\dot\theta/\omega_c - 1)^2]\, z_n .
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.plant import Channel, Plant, find_channel
from flexsat.input_checks import FieldError, require_finite, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.dynamics.structural import ModalBlocks
    from flexsat.units import FloatArray, QuantityLike

__all__ = ["BeamInOrbit"]


class BeamInOrbit(Plant):
    r"""Bainum's beam in orbit (module docstring), time in seconds.

    Parameters
    ----------
    orbit_rate : float
        :math:`\omega_c`, rad/s.
    frequency_ratios : array_like (k,)
        :math:`F_n = (\omega_n/\omega_c)^2` of the k bending modes kept.
    actuators : dict {name: array_like (1 + k,)}
        Point forces: each name's column of G (the pitch row, then the k mode rows), 1/N.
    stations : dict {name: array_like (k,)}, optional
        Mode-shape values :math:`\phi_n(\xi)` at named stations; output ``w_<name>`` is the
        elastic deflection there, :math:`\sum_n z_n \phi_n(\xi)` (= w/l, dimensionless), or in
        metres when ``length`` is given.
    length : float, optional
        Beam length l, m (Bainum & Reddy 1979 does not publish one).
    linearised : bool
        Drop the nonlinear remainder f (eqs 5–6 only, the linearisation at rest).

    Notes
    -----
    Outputs: ``pitch`` (rad), ``pitch_rate`` (rad/s), ``z1`` … ``zk`` (modal amplitudes
    A_n/l), their rates ``z1_rate`` … (1/s), and the station deflections.
    """

    nonlinear = True

    def __init__(
        self,
        orbit_rate: QuantityLike,
        frequency_ratios: npt.ArrayLike,
        actuators: dict[str, npt.ArrayLike],
        stations: Mapping[str, npt.ArrayLike] | None = None,
        length: QuantityLike | None = None,
        linearised: bool = False,
    ) -> None:
        self.nonlinear = not linearised
        self.orbit_rate = float(require_positive(orbit_rate, "orbit_rate", "rad/s"))
        F = np.atleast_1d(require_finite(frequency_ratios, "frequency_ratios"))
        if F.ndim != 1 or np.any(F <= 0):
            raise FieldError(
                "frequency_ratios",
                f"must be a 1-D list of (ω_n/ω_c)² > 0, got {frequency_ratios!r}",
            )
        self.frequency_ratios = F
        k = F.size
        n = k + 1
        if not isinstance(actuators, dict) or not actuators:
            raise FieldError("actuators", "must be a non-empty {name: column of G} mapping")
        cols = []
        for name, given in actuators.items():
            Channel(name, "N")
            col = require_finite(given, name)
            if col.shape != (n,):
                raise FieldError(
                    name,
                    f"its column of G must have 1 + {k} = {n} entries "
                    f"(pitch, then each mode), got shape {col.shape}",
                )
            cols.append(col.astype(float))
        self.G = np.column_stack(cols)
        self.G.flags.writeable = False
        self.inputs = tuple(Channel(name, "N", description="point force") for name in actuators)
        self.length = None if length is None else float(require_positive(length, "length", "m"))
        unit = "" if self.length is None else "m"
        rows = {}
        for name, given in ({} if stations is None else stations).items():
            values = np.atleast_1d(require_finite(given, f"w_{name}"))
            if values.shape != (k,):
                raise FieldError(
                    f"w_{name}",
                    f"station shape values must have {k} entries (one "
                    f"per mode), got shape {values.shape}",
                )
            rows[f"w_{name}"] = values * (1.0 if self.length is None else self.length)
        outs = [
            Channel("pitch", "rad", description="pitch from the local vertical"),
            Channel("pitch_rate", "rad/s"),
        ]
        outs += [
            Channel(f"z{i}", "", description=f"bending amplitude A_{i}/l") for i in range(1, n)
        ]
        outs += [Channel(f"z{i}_rate", "1/s") for i in range(1, n)]
        outs += [Channel(name, unit, description="elastic deflection") for name in rows]
        outs += [Channel("state", "", 2 * n, "[θ, z, θ̇, ż] (what a state-feedback law reads)")]
        names = [c.name for c in outs]
        for name in names:
            if names.count(name) > 1:
                raise FieldError(name, "duplicate output channel name")
        self.outputs = tuple(outs)
        self.recorded = ("pitch", "pitch_rate")
        self._rows = rows
        self._state_index = {"pitch": 0, "pitch_rate": n}
        for i in range(1, n):
            self._state_index.update({f"z{i}": i, f"z{i}_rate": n + i})

    @property
    def n_coordinates(self) -> int:
        """1 + k: pitch and the bending modes."""
        return self.frequency_ratios.size + 1

    @property
    def nx(self) -> int:
        return 2 * self.n_coordinates

    @cached_property
    def stiffness(self) -> FloatArray:
        """diag(3, F_1, …, F_k): pitch libration κ = 3 and the modes (eqs 5–6, τ units)."""
        return np.concatenate([[3.0], self.frequency_ratios])

    @cached_property
    def _linear(self) -> tuple[FloatArray, FloatArray]:
        n, w2 = self.n_coordinates, self.orbit_rate**2
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -w2 * np.diag(self.stiffness)
        B = np.vstack([np.zeros_like(self.G), w2 * self.G])
        for arr in (A, B):
            arr.flags.writeable = False
        return A, B

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B) of the linearisation at rest, eqs 5–6 in seconds (module docstring)."""
        return self._linear

    @cached_property
    def modal_blocks(self) -> ModalBlocks:
        """The linear part is decoupled: pitch libration ω_c√3 and the bending modes ω_c√F_n,
        undamped, none rigid (a :class:`~flexsat.dynamics.structural.ModalBlocks`)."""
        from flexsat.dynamics.structural import ModalBlocks

        n = self.n_coordinates
        return ModalBlocks(self.orbit_rate * np.sqrt(self.stiffness), np.zeros(n), 0)

    @cached_property
    def force_matrix(self) -> FloatArray:
        """B_f = [0; I]: the remainder is an acceleration on every coordinate."""
        n = self.n_coordinates
        Bf = np.vstack([np.zeros((n, n)), np.eye(n)])
        Bf.flags.writeable = False
        return Bf

    def _split(self, x: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        x = np.asarray(x, dtype=float)
        n = self.n_coordinates
        return x[..., 0], x[..., 1:n], x[..., n], x

    def nonlinear_force(self, x: npt.ArrayLike, u: npt.ArrayLike | None = None) -> FloatArray:
        """f(x), (..., 1 + k): eqs 1–2 less eqs 5–6, times ω_c² (module docstring)."""
        theta, z, dtheta, _ = self._split(x)
        wc = self.orbit_rate
        f_theta = wc**2 * (3.0 * theta - 1.5 * np.sin(2.0 * theta))
        g = (3.0 * np.sin(theta) ** 2 - 1.0) + (dtheta / wc - 1.0) ** 2
        return np.concatenate([f_theta[..., None], wc**2 * g[..., None] * z], axis=-1)

    def force_jacobian(
        self, x: npt.ArrayLike, u: npt.ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """(∂f/∂x (..., 1 + k, 2(1 + k)), ∂f/∂u = 0 (..., 1 + k, m)), analytic."""
        theta, z, dtheta, states = self._split(x)
        n, wc = self.n_coordinates, self.orbit_rate
        lead = states.shape[:-1]
        J = np.zeros(lead + (n, 2 * n))
        J[..., 0, 0] = wc**2 * (3.0 - 3.0 * np.cos(2.0 * theta))
        g = (3.0 * np.sin(theta) ** 2 - 1.0) + (dtheta / wc - 1.0) ** 2
        J[..., 1:, 0] = wc**2 * 3.0 * np.sin(2.0 * theta)[..., None] * z
        J[..., 1:, n] = 2.0 * wc * (dtheta / wc - 1.0)[..., None] * z
        idx = np.arange(1, n)
        J[..., idx, idx] = wc**2 * g[..., None]
        return J, np.zeros(lead + (n, self.n_inputs))

    def derivative(self, x: npt.ArrayLike, u: npt.ArrayLike, nonlinear: bool = True) -> FloatArray:
        """ẋ = A x + B u + B_f f(x) (eqs 1–2; ``nonlinear=False``: eqs 5–6 only), (..., 2n)."""
        A, B = self.linear_part()
        states = np.asarray(x, dtype=float)
        dx = states @ A.T + np.asarray(u, dtype=float) @ B.T
        if nonlinear:
            dx = dx + self.nonlinear_force(states) @ self.force_matrix.T
        return dx

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """(C (1, 2n), 0, None): every output is linear in the state."""
        find_channel(self.outputs, name, "output", type(self).__name__)
        n = self.n_coordinates
        if name == "state":
            return np.eye(2 * n), np.zeros((2 * n, self.n_inputs)), None
        C = np.zeros((1, 2 * n))
        if name in self._rows:
            C[0, 1:n] = self._rows[name]
        else:
            C[0, self._state_index[name]] = 1.0
        return C, np.zeros((1, self.n_inputs)), None

    def __repr__(self) -> str:
        return (
            f"BeamInOrbit(orbit_rate={self.orbit_rate:.6g} rad/s, "
            f"modes={self.n_coordinates - 1}, inputs={[c.name for c in self.inputs]})"
        )
