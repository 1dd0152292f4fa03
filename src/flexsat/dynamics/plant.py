"""The one plant protocol every simulated system implements.

A plant is a continuous system with a leading case axis,

    x' = A x + B u + B_f f(x, u),        u = [u_1, …, u_m]  (its input channels, concatenated)

split into a linear part (A, B), propagated exactly by matrix exponentials, and a nonlinear
remainder written as a generalized force f (n_cases, n_f) entering through a constant matrix B_f
(n_x, n_f): low-rank where the nonlinearity is (a hub bearing, the gyroscopic terms of a few
coordinates), so the exponential integrator only forms φ-products with those columns
(:func:`flexsat.sim.integrators.phi_products`). A plant whose state lives on a manifold (a unit
quaternion) may instead supply its own one-step integrator (:meth:`Plant.step`).

Inputs and outputs are named :class:`Channel` s with SI units. A size-1 channel's values have
shape (n_cases,), a wider channel's (n_cases, size); every method also accepts extra leading
axes (time × case) so that outputs and energies are computed after the time loop in large
array products. A law reads measurement channels by name and writes input channels by name
(:class:`flexsat.control.base.Controller`); the engine checks both against the plant before the
run.

How to add a system: subclass :class:`Plant`, give ``inputs``, ``outputs``, ``nx`` and
:meth:`linear_part`, :meth:`output` (or :meth:`output_matrices` for linear outputs), and, if it
is nonlinear, ``force_matrix`` and :meth:`nonlinear_force`; docs/design.md ("Adding a system")
walks through it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike

#: Kind of a channel located on a structure -> its SI unit (what a test records or applies at a
#: node). "strain" is the relative rotation of the two ends of a gauge patch
#: (:meth:`~flexsat.structures.modal_model.ModalModel.strain_output`), rad.
STRUCTURAL_KINDS = {
    "displacement": "m",
    "velocity": "m/s",
    "acceleration": "m/s^2",
    "rotation": "rad",
    "strain": "rad",
    "force": "N",
    "torque": "N*m",
}
#: directions of a located channel: a translation direction or a rotation axis
AXES = ("x", "y", "z")


@dataclass(frozen=True)
class Channel:
    """A named input or output: of a plant, or of a test at a point of a structure.

    Parameters
    ----------
    name : str
        Identifier used by laws, sensors, actuators and the recorded dataset. A channel
        located on a structure may have any non-blank name (a test's default,
        ``"displacement 5z"``, is the universal-file id).
    unit : str
        SI unit of its values (a pint expression: ``"N*m"``, ``"rad/s"``, ``""``).
    size : int
        Width: 1 for a scalar channel (values (..., n_cases)), 3 for a body-axis torque, 4 for
        a quaternion (values (..., n_cases, size)).
    description : str
        One line for reports and error messages.
    kind, node, direction, node_a
        Where a test channel sits on a structure (None for a plant's own channels): what it
        measures or applies (one of :data:`STRUCTURAL_KINDS`), at which node id, along or
        about which axis (:data:`AXES`), and for a strain gauge the first end ``node_a`` of the
        patch (``node`` the second). Build one with :meth:`at`.
    """

    name: str
    unit: str
    size: int = 1
    description: str = ""
    kind: str | None = None
    node: int | None = None
    direction: str | None = None
    node_a: int | None = None

    def __post_init__(self) -> None:
        if self.kind is None:
            if not isinstance(self.name, str) or not self.name.isidentifier():
                raise ValueError(f"channel name: must be an identifier, got {self.name!r}")
        elif not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(f"channel name: must be a non-blank string, got {self.name!r}")
        if not isinstance(self.size, int) or self.size < 1:
            raise FieldError(self.name, f"size must be a positive integer, got {self.size!r}")
        if self.kind is not None or self.node is not None or self.direction is not None:
            self._check_location()

    def _check_location(self) -> None:
        if self.kind not in STRUCTURAL_KINDS:
            raise FieldError("kind", f"must be one of {tuple(STRUCTURAL_KINDS)}, got {self.kind!r}")
        if self.direction not in AXES:
            raise FieldError("direction", f"must be 'x', 'y' or 'z', got {self.direction!r}")
        for name in ("node", "node_a"):
            value = getattr(self, name)
            if value is None and name == "node_a":
                continue
            if not isinstance(value, (int, np.integer)) or isinstance(value, bool):
                raise FieldError(name, f"must be an integer node id, got {value!r}")
            object.__setattr__(self, name, int(value))
        if self.kind == "strain" and self.node_a is None:
            raise FieldError("node_a", "a strain channel needs both ends of the patch")

    @classmethod
    def at(
        cls,
        kind: str,
        node: int,
        direction: str,
        unit: str | None = None,
        node_a: int | None = None,
        name: str = "",
    ) -> Channel:
        """A test channel at a point of a structure: ``kind`` at ``node`` along ``direction``,
        in ``unit`` (default the kind's SI unit), named ``"<kind> <node><direction>"`` unless
        ``name`` is given."""
        if kind not in STRUCTURAL_KINDS:
            raise FieldError("kind", f"must be one of {tuple(STRUCTURAL_KINDS)}, got {kind!r}")
        return cls(
            name or f"{kind} {node}{direction}",
            STRUCTURAL_KINDS[kind] if unit is None else unit,
            kind=kind,
            node=node,
            direction=direction,
            node_a=node_a,
        )


@dataclass(frozen=True)
class ManeuverChannels:
    """The channels a single-axis maneuver is read on (a plant's :attr:`Plant.maneuver`).

    A plant that declares them gets the maneuver metrics of
    :func:`flexsat.sim.metrics.maneuver_metrics` (settling time and overshoot of ``angle``
    against the law's ``target``, peak rate error of ``rate`` against the law's reference, peak
    ``torque``, peak ``deflection``, residual vibration energy) and starts at rest at the law's
    reference start angle unless an initial state is given. It must also give
    ``vibration_energy(x)``.

    Parameters
    ----------
    angle : str
        Output channel of the maneuver angle, rad (a state coordinate).
    rate : str
        Output channel of its rate, rad/s.
    torque : str
        Size-1 input channel that drives it, N m.
    deflection : str
        Output channel of the peak elastic deflection, m.
    """

    angle: str = "theta"
    rate: str = "theta_dot"
    torque: str = "torque"
    deflection: str = "tip_deflection"


def channel_slices(channels: tuple[Channel, ...]) -> dict[str, slice]:
    """Where each channel sits in the concatenated vector of ``channels``."""
    out: dict[str, slice] = {}
    start = 0
    for ch in channels:
        out[ch.name] = slice(start, start + ch.size)
        start += ch.size
    return out


def find_channel(channels: tuple[Channel, ...], name: str, role: str, owner: str) -> Channel:
    """The channel called ``name``, or a ValueError naming it and listing the known ones."""
    for ch in channels:
        if ch.name == name:
            return ch
    known = ", ".join(c.name for c in channels) or "none"
    raise FieldError(name, f"{owner} has no {role} channel {name!r} (its {role} channels: {known})")


class Plant(ABC):
    """Continuous plant x' = A x + B u + B_f f(x, u) with named channels (module docstring).

    Subclasses set ``inputs``, ``outputs`` and ``nx`` and implement :meth:`linear_part` and
    either :meth:`output_matrices` (outputs linear in x, u and f) or :meth:`output`.
    """

    #: input channels, in the order of the concatenated input vector u
    inputs: tuple[Channel, ...] = ()
    #: output channels (what sensors measure and what is recorded)
    outputs: tuple[Channel, ...] = ()
    #: outputs recorded by default, in addition to the inputs (names of ``outputs``)
    recorded: tuple[str, ...] = ()
    #: the channels of a single-axis maneuver (:class:`ManeuverChannels`): declared by a plant
    #: whose runs are read as slews of one angle (the maneuver metrics); None otherwise
    maneuver: ManeuverChannels | None = None

    @property
    def noise_channels(self) -> tuple[str, ...]:
        """Channels with a per-case Gaussian noise stream, in stream order (outputs for sensor
        noise, inputs for random disturbances); fixing the order keeps every case's noise
        bit-reproducible from its seed whatever else is measured. Default: every output but
        the whole ``state``, then every input."""
        given: tuple[str, ...] | None = getattr(self, "_noise_channels", None)
        if given is not None:
            return given
        return tuple(c.name for c in self.outputs if c.name != "state") + tuple(
            c.name for c in self.inputs
        )

    @noise_channels.setter
    def noise_channels(self, names: Iterable[str]) -> None:
        self._noise_channels = tuple(names)

    #: True when f is not identically zero
    nonlinear: bool = False

    @property
    @abstractmethod
    def nx(self) -> int:
        """Length of the state vector."""

    @property
    def n_cases(self) -> int:
        """Number of parameter cases the plant carries (1 unless dispersed)."""
        return 1

    @cached_property
    def n_inputs(self) -> int:
        """Width m of the concatenated input vector."""
        return sum(ch.size for ch in self.inputs)

    @cached_property
    def input_slices(self) -> dict[str, slice]:
        return channel_slices(self.inputs)

    @abstractmethod
    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B): (n_x, n_x) and (n_x, m), or with a leading case axis when dispersed."""

    @property
    def force_matrix(self) -> FloatArray | None:
        """B_f (n_x, n_f) of the nonlinear force, or None for a linear plant."""
        return None

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """f(x, u), shape (..., n_f); the plant's own nonlinear terms only (disturbance
        forces such as bearing friction are added by the engine on their input channel)."""
        raise NotImplementedError(f"{type(self).__name__} is linear: it has no nonlinear force")

    def force_jacobian(self, x: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """(∂f/∂x, ∂f/∂u) at (x, u), shapes (..., n_f, n_x) and (..., n_f, m); None when the
        plant gives no analytic Jacobian (callers then difference :meth:`nonlinear_force`)."""
        return None

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """(C, D, D_f) with y = C x + D u + D_f f_in for a linear output, where f_in (..., m)
        is any extra force added on the input channels (friction), D_f None when f_in does not
        reach it; None when the output is nonlinear (then :meth:`output` computes it)."""
        return None

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        """Value of output channel ``name`` at states x (..., n_x), inputs u (..., m) and extra
        input-channel force f_in (..., m) or None; shape (...,) or (..., size).

        Raises
        ------
        ValueError
            Naming ``name`` when the plant has no such output channel.
        """
        size = self._size(name)  # an unknown name is a ValueError naming it, before the matrices
        mats = self.output_matrices(name)
        if mats is None:
            raise NotImplementedError(
                f"{type(self).__name__}.output: {name!r} has no output matrices and no output()"
            )
        C, D, Df = mats
        y: FloatArray = x @ C.T + u @ D.T
        if f_in is not None and Df is not None:
            y = y + f_in @ Df.T
        return y[..., 0] if size == 1 else y

    def _size(self, name: str) -> int:
        return find_channel(self.outputs, name, "output", type(self).__name__).size

    def initial_state(self, n_cases: int) -> FloatArray:
        """Rest state, (n_cases, n_x)."""
        return np.zeros((n_cases, self.nx))

    def state_from(self, **values: QuantityArrayLike) -> FloatArray:
        """Initial state (n_x,) from named initial values (a scenario's ``initial``), SI.

        Every plant takes ``state`` (the whole vector) and any output channel that reads state
        coordinates directly (rows of C that are unit vectors, no feedthrough: ``pitch``,
        ``z1_rate``, ...); plants with nonlinear coordinates add their own names (an attitude as
        1-2-3 Euler angles). Entries not given are at rest.

        Raises
        ------
        ValueError
            Naming an unknown value or a wrong shape.
        """
        from flexsat.input_checks import require_finite

        x = self.initial_state(1)[0].copy()
        if "state" in values:
            v = require_finite(values["state"], "state")
            if v.shape != (self.nx,):
                raise FieldError("state", f"must have {self.nx} entries, got shape {v.shape}")
            x = v.copy()
        for name, value in values.items():
            if name == "state":
                continue
            index = self._state_coordinates(name)
            if index is None:
                raise FieldError(
                    name,
                    f"not an initial value of {type(self).__name__} (it "
                    f"takes: {', '.join(self.initial_values)})",
                )
            unit = find_channel(self.outputs, name, "output", type(self).__name__).unit
            v = np.atleast_1d(require_finite(value, name, unit))
            if v.shape != index.shape:
                raise FieldError(name, f"must have {index.size} entries, got shape {v.shape}")
            x[index] = v
        return x

    def _state_coordinates(self, name: str) -> npt.NDArray[np.intp] | None:
        """Indices of the state entries output ``name`` reads one to one, or None."""
        if name not in {c.name for c in self.outputs}:
            return None
        mats = self.output_matrices(name)
        if mats is None:
            return None
        C, D, _ = mats
        if np.any(D) or not np.all((C == 0) | (C == 1)) or not np.all(C.sum(axis=1) == 1):
            return None
        return np.argmax(C, axis=1)

    @property
    def initial_values(self) -> tuple[str, ...]:
        """Names :meth:`state_from` accepts."""
        return ("state",) + tuple(
            c.name
            for c in self.outputs
            if c.name != "state" and self._state_coordinates(c.name) is not None
        )

    def normalize(self, x: FloatArray) -> FloatArray:
        """Project a state back onto its manifold after a step (identity by default)."""
        return x

    #: set by plants with their own integrator: ``step(x, u, h)`` advances one step h with u
    #: held; None uses the engine's exponential integrators
    step: Callable[[FloatArray, FloatArray, float], FloatArray] | None = None

    def energy(self, x: FloatArray) -> FloatArray | None:
        """Total mechanical energy, J, shape (...,); None where undefined."""
        return None

    #: Q (n_x, n_x), symmetric, with :meth:`energy` E(x) = ½ xᵀ Q x, for a plant whose energy
    #: is that quadratic form (a linear structure: Q = blockdiag(K, M) for x = [q, q']); None
    #: otherwise. The compiled loop evaluates it per sample instead of recording the states
    energy_matrix: FloatArray | None = None

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray | None:
        """Rate of :meth:`energy` along the motion, dE/dt = (work rate of the inputs) −
        (dissipation), W, shape (...,), at states x (..., n_x) and inputs u (..., m); None where
        undefined. :func:`flexsat.testing.check_plant` compares it with ∇E · ẋ."""
        return None

    def momentum(self, x: FloatArray) -> FloatArray | None:
        """Total angular momentum in inertial axes, N m s, shape (..., 3) or (...,) for a
        planar plant; None where undefined."""
        return None


__all__ = ["Channel", "ManeuverChannels", "Plant", "channel_slices", "find_channel"]
