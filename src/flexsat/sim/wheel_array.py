r"""A reaction-wheel array on a three-axis spacecraft (:class:`ReactionWheelArray`, put in the
loop by :class:`flexsat.sim.hardware.Hardware` like any actuator): N wheels with spin axes
the columns of G (3 × N, unit vectors, rank 3), each wheel's absolute spin rate Ω_a,i a state.

With r the wheels' reaction-torque commands (the motor torques are τ_w = −r, the body feels
−G τ_w = G r), ω the body rate and h_w = G J_w Ω_a the wheels' momentum in body axes, the body
and wheel equations are (Hughes, *Spacecraft Attitude Dynamics*, Wiley 1986, §3.3, gyrostat
with axisymmetric rotors; Schaub & Junkins, *Analytical Mechanics of Space Systems*, AIAA
2003, §4.5.1)

.. math::

    I \dot\omega + \omega \times (I\omega + h_w) = G r + G C_v \Omega_{rel}, \qquad
    J_{w,i} \dot\Omega_{a,i} = -r_i - c_{v,i} \Omega_{rel,i}, \qquad
    \Omega_{rel} = \Omega_a - G^T \omega,

(C_v = diag(c_v); the viscous bearing torque −c_v Ω_rel acts on the wheel and, reacted, on
the body;
I is the body's inertia without the wheels' spin inertia about their axes). The wrapped
plant keeps ω × Iω (its own nonlinear force); the array adds the gyroscopic torque
−ω × h_w as a force on the plant's torque input. The total angular momentum,
C(β)ᵀ (I ω + h_w), is constant without external torque (:meth:`WheelArrayPlant.momentum`).

**Command distribution**: the law's body torque c goes to the wheels as r = G⁺ c with the
Moore–Penrose pseudo-inverse G⁺ = Gᵀ (G Gᵀ)⁻¹ (the minimum-norm wheel torques giving G r =
c exactly, N ≥ 3 wheels spanning the three axes; for N = 3 it is G⁻¹). The distribution is
made by the law's wrapper (:class:`flexsat.sim.hardware.HardwareLaw`), which then gates each
wheel at its speed limit (a wheel at |Ω_rel,i| ≥ max_speed gets no command that would raise
|Ω_rel,i|).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.dynamics.plant import Channel, Plant, find_channel
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = ["ReactionWheelArray", "WheelArrayPlant", "pyramid_axes"]


def _per_wheel(value: Any, n: int, field: str, positive: bool, inf_ok: bool) -> FloatArray:
    v = np.broadcast_to(np.asarray(value, float), (n,)).copy() if np.ndim(value) == 0 else None
    if v is None:
        v = np.asarray(value, float)
    if v.shape != (n,):
        raise FieldError(field, f"one value or one per wheel ({n}), got shape {v.shape}")
    ok = (np.isfinite(v) | (inf_ok & (v == np.inf))) & ((v > 0) if positive else (v >= 0))
    if not np.all(ok):
        raise FieldError(field, f"must be {'> 0' if positive else '>= 0'}, got {value!r}")
    return v


@dataclass(frozen=True)
class ReactionWheelArray:
    """N reaction wheels on a three-axis torque channel (module docstring).

    Parameters
    ----------
    axes : array_like (3, N)
        Spin-axis unit vectors in body axes, G; rank 3.
    inertia : float or (N,)
        Spin inertia of each wheel, J_w, kg m².
    max_speed : float or (N,)
        Speed limit on |Ω_rel|, rad/s; inf for none.
    viscous : float or (N,)
        Bearing viscous friction c_v, N m s/rad.
    rate_output : str
        The plant's body-rate output (3 wide).
    """

    axes: npt.ArrayLike
    inertia: npt.ArrayLike
    max_speed: npt.ArrayLike = np.inf
    viscous: npt.ArrayLike = 0.0
    rate_output: str = "rate"

    def __post_init__(self) -> None:
        G = np.asarray(self.axes, float)
        if G.ndim != 2 or G.shape[0] != 3 or G.shape[1] < 3 or not np.all(np.isfinite(G)):
            raise FieldError("axes", f"must be 3 × N, N >= 3, finite, got shape {G.shape}")
        if not np.allclose(np.linalg.norm(G, axis=0), 1.0, rtol=0, atol=1e-12):
            raise FieldError("axes", "each column must be a unit vector")
        if np.linalg.matrix_rank(G) < 3:
            raise FieldError("axes", "the wheels must span the three body axes (rank 3)")
        n = G.shape[1]
        object.__setattr__(self, "axes", G)
        object.__setattr__(self, "inertia", _per_wheel(self.inertia, n, "inertia", True, False))
        object.__setattr__(
            self, "max_speed", _per_wheel(self.max_speed, n, "max_speed", True, True)
        )
        object.__setattr__(self, "viscous", _per_wheel(self.viscous, n, "viscous", False, False))

    @property
    def n_wheels(self) -> int:
        return int(np.shape(self.axes)[1])

    @property
    def distribution(self) -> FloatArray:
        """G⁺ = Gᵀ (G Gᵀ)⁻¹ (N × 3): body torque → the wheels' reaction commands."""
        return np.asarray(np.linalg.pinv(np.asarray(self.axes, float)), float)


def pyramid_axes(beta: float, n: int = 4) -> FloatArray:
    """Spin axes of ``n`` wheels on a pyramid of half-angle ``beta`` (rad) about body z:
    g_i = (sin β cos φ_i, sin β sin φ_i, cos β), φ_i = 2π i / n."""
    phi = 2 * np.pi * np.arange(n) / n
    return np.array(
        [np.sin(beta) * np.cos(phi), np.sin(beta) * np.sin(phi), np.full(n, np.cos(beta))]
    )


class WheelArrayPlant(Plant):
    """A three-axis plant with a wheel array on its torque channel ``channel`` (module
    docstring): x = [plant's x, Ω_a]; inputs: the plant's, ``channel`` replaced by
    ``<channel>_wheels`` (r, N wide); outputs: the plant's and ``<channel>_wheel_speed``
    (Ω_rel, N wide). Propagated by the engine's exponential integrators (the plant's own
    step, if any, is not used: the array's states ride along)."""

    def __init__(self, plant: Plant, channel: str, array: ReactionWheelArray) -> None:
        owner = type(plant).__name__
        ch = find_channel(plant.inputs, channel, "input", owner)
        if ch.size != 3:
            raise FieldError(
                f"actuators[{channel}]",
                f"a wheel array needs a torque 3 wide, {channel!r} is {ch.size}",
            )
        if plant.n_cases != 1:
            raise FieldError(
                "hardware", f"{owner}: a wheel array needs a shared plant (not dispersed)"
            )
        mats = plant.output_matrices(array.rate_output)
        if mats is None or np.asarray(mats[0]).shape[0] != 3 or np.any(mats[1]):
            raise FieldError(
                f"actuators[{channel}].rate_output",
                f"{array.rate_output!r} must be a linear 3-wide rate of the state",
            )
        self.inner, self.array, self.channel = plant, array, channel
        n, m, N = plant.nx, plant.n_inputs, array.n_wheels
        self._n, self._N = n, N
        A, B = plant.linear_part()
        G = np.asarray(array.axes, float)
        Jw, cv = np.asarray(array.inertia), np.asarray(array.viscous)
        self._Cw = np.asarray(mats[0], float)  # ω = C_w x
        j = plant.input_slices[channel]
        self._j = j
        self.inputs = tuple(
            Channel(
                f"{channel}_wheels",
                "N*m",
                N,
                "wheel reaction-torque commands r (the body feels G r)",
            )
            if c.name == channel
            else c
            for c in plant.inputs
        )
        # the inner's input u = P w + T x (the channel's 3 columns from r and the viscous term)
        P = np.zeros((m, sum(c.size for c in self.inputs)))
        col = 0
        for c in self.inputs:
            if c.name == f"{channel}_wheels":
                P[j, col : col + N] = G
            else:
                s = plant.input_slices[c.name]
                P[s, col : col + c.size] = np.eye(c.size)
            col += c.size
        self._wcol = slice(
            sum(
                c.size
                for c in self.inputs[: [c.name for c in self.inputs].index(f"{channel}_wheels")]
            ),
            None,
        )
        self._wcol = slice(self._wcol.start, self._wcol.start + N)
        Om = np.zeros((N, n + N))  # Ω_rel over x
        Om[:, n:] = np.eye(N)
        Om[:, :n] = -G.T @ self._Cw
        Tx = np.zeros((m, n + N))
        Tx[j] = G @ (cv[:, None] * Om)  # the reacted bearing torque on the body: + G c_v Ω_rel
        self._P, self._T = P, Tx
        Ah = np.zeros((n + N, n + N))
        Bh = np.zeros((n + N, P.shape[1]))
        Ah[:n, :n] = A
        Ah[:n] += B @ Tx
        Bh[:n] = B @ P
        Ah[n:] -= (cv / Jw)[:, None] * Om
        Bh[n:, self._wcol] = -np.diag(1 / Jw)
        self._A, self._B, self._Bin = Ah, Bh, B
        self._Om = Om
        self.outputs = tuple(plant.outputs) + (
            Channel(f"{channel}_wheel_speed", "rad/s", N, "wheel speeds relative to the body"),
        )
        self.recorded = tuple(plant.recorded) + (f"{channel}_wheel_speed",)
        self.nonlinear = True
        self.integrator = getattr(plant, "integrator", None) or "exp_rk4"
        self.maneuver = None
        self._rows: dict[str, Any] = {}

    @property
    def nx(self) -> int:
        return self._n + self._N

    @property
    def n_cases(self) -> int:
        return 1

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        return self._A, self._B

    @property
    def force_matrix(self) -> FloatArray:
        """[[B_f, B], [0, 0]]: the plant's force and the gyroscopic torque on its input."""
        Bf = self.inner.force_matrix
        nf = 0 if Bf is None else Bf.shape[1]
        out = np.zeros((self.nx, nf + self._Bin.shape[1]))
        if Bf is not None:
            out[: self._n, :nf] = Bf
        out[: self._n, nf:] = self._Bin
        return out

    def wheel_momentum(self, x: FloatArray) -> FloatArray:
        """h_w = G J_w Ω_a, body axes (..., 3)."""
        G = np.asarray(self.array.axes, float)
        return (x[..., self._n :] * np.asarray(self.array.inertia)) @ G.T

    def plant_input(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """The plant's input (the array's linear part, without the gyroscopic torque)."""
        return u @ self._P.T + x @ self._T.T

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        xi = x[..., : self._n]
        f_in = self.inner.nonlinear_force(xi, self.plant_input(x, u))
        w = xi @ self._Cw.T
        gyro = np.zeros(x.shape[:-1] + (self._Bin.shape[1],))
        gyro[..., self._j] = -np.cross(w, self.wheel_momentum(x))
        return np.concatenate([np.broadcast_to(f_in, x.shape[:-1] + f_in.shape[-1:]), gyro], -1)

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        if name == f"{self.channel}_wheel_speed":
            return self._Om, np.zeros((self._N, self._P.shape[1])), None
        mats = self.inner.output_matrices(name)
        if mats is None:
            return None
        C, D, _ = mats
        Cx = np.zeros((C.shape[0], self.nx))
        Cx[:, : self._n] = C
        return Cx + D @ self._T, D @ self._P, None

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        if self.output_matrices(name) is not None:
            return super().output(name, x, u, f_in)
        return self.inner.output(name, x[..., : self._n], self.plant_input(x, u))

    def initial_state(self, n_cases: int) -> FloatArray:
        return self.settled(self.inner.initial_state(n_cases))

    def settled(self, x: FloatArray) -> FloatArray:
        """``x`` of the plant with each wheel at rest relative to the body (Ω_rel = 0)."""
        x = np.asarray(x, float)
        out = np.zeros(x.shape[:-1] + (self.nx,))
        out[..., : self._n] = x[..., : self._n]
        out[..., self._n :] = (x[..., : self._n] @ self._Cw.T) @ np.asarray(self.array.axes, float)
        return out

    def state_from(self, **values: Any) -> FloatArray:
        """The spacecraft's initial values as its own ``state_from`` takes them, each wheel at
        rest relative to the body; a whole ``state`` (n_x,) gives the wheel speeds too."""
        if "state" not in values:
            return self.settled(self.inner.state_from(**values))
        v = require_finite(values["state"], "state")
        if v.shape != (self.nx,):
            raise FieldError(
                "state",
                f"must have {self.nx} entries (the spacecraft's {self._n} and "
                f"{self.nx - self._n} wheel speeds), got shape {v.shape}",
            )
        out = v.copy()
        out[: self._n] = self.inner.state_from(**{**values, "state": v[: self._n]})
        return out

    @property
    def initial_values(self) -> tuple[str, ...]:
        return tuple(getattr(self.inner, "initial_values", ()))

    def normalize(self, x: FloatArray) -> FloatArray:
        norm = getattr(self.inner, "normalize", None)
        if norm is None:
            return x
        out = np.array(x, float)
        out[..., : self._n] = norm(out[..., : self._n])
        return out

    def momentum(self, x: FloatArray) -> FloatArray | None:
        """The plant's momentum (inertial axes) plus C(β)ᵀ h_w."""
        from flexsat.dynamics.rigid_spacecraft import dcm

        h = self.inner.momentum(x[..., : self._n])
        if h is None:
            return None
        xi = x[..., : self._n]
        beta = self.inner.output("attitude", xi, np.zeros(xi.shape[:-1] + (self._Bin.shape[1],)))
        return np.asarray(
            h + np.einsum("...ji,...j->...i", dcm(beta), self.wheel_momentum(x)), float
        )

    def energy(self, x: FloatArray) -> FloatArray | None:
        """The plant's energy plus Σ ½ J_w Ω_a² (the wheels' spin)."""
        e = self.inner.energy(x[..., : self._n])
        if e is None:
            return None
        return np.asarray(
            e + 0.5 * np.sum(np.asarray(self.array.inertia) * x[..., self._n :] ** 2, -1), float
        )
