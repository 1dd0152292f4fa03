r"""Any python-control ``StateSpace`` as a compensator between named channels (issue #10).

The compensator maps the error between named measurement channels and optional references to
named command channels. A discrete system runs as it is; a continuous one is discretised by
zero-order hold at the control period, which is exact for an error held between samples (the
simulator samples once per period), the convention of the LQG estimator
(:func:`~flexsat.control.lqg.zoh`; Franklin, Powell & Workman, *Digital Control of Dynamic
Systems*, 3rd ed., §4.3.3 Eq. 4.58):

.. math::

    e_k = y_k - r, \qquad u_k = C x_k + D e_k, \qquad x_{k+1} = \Phi x_k + \Gamma e_k,
    \qquad \Phi = e^{A\,dt},\; \Gamma = \int_0^{dt} e^{As}\,ds\,B

(:math:`\Phi = A, \Gamma = B` for a discrete system), starting from :math:`x_0 = 0`. This is
already the compiled-loop form (:mod:`~flexsat.control.linear_form`) with constant matrices and
y_ref = r.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import Controller
from flexsat.control.linear_form import (
    LinearLaw,
    channel_spec,
    sample_times,
    split_channels,
    stack_channels,
)
from flexsat.control.lqg import DT_TOL, zoh
from flexsat.input_checks import FieldError, require_finite, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    import control as ct
    from flexsat.control.linear_form import ChannelItems
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["StateSpaceCompensator"]


def _state_space(system: ct.StateSpace | ct.TransferFunction) -> ct.StateSpace:
    # python-control takes ~1 s to import: load it when a compensator is built, not with
    # flexsat.control
    import control as ct

    if isinstance(system, ct.TransferFunction):
        return ct.ss(system)
    if not isinstance(system, ct.StateSpace):
        raise FieldError(
            "system",
            "must be a python-control StateSpace (or TransferFunction), got "
            f"{type(system).__name__}",
        )
    return system


def reference_histories(
    references: Mapping[str, QuantityArrayLike] | None,
    names: Sequence[str],
    sizes: Sequence[int],
    units: Sequence[str | None],
) -> FloatArray:
    """r (C, p) from {channel: value}; a missing channel has reference 0."""
    given = {} if references is None else dict(references)
    unknown = sorted(set(given) - set(names))
    if unknown:
        raise FieldError(
            "references", f"{unknown[0]!r} is not a measurement channel (they are {list(names)})"
        )
    cols: list[FloatArray] = []
    n_cases = 1
    for name, size, unit in zip(names, sizes, units):
        field = f"references.{name}"
        r = require_finite(given.get(name, 0.0), field, unit)
        if r.ndim == 0:
            r = np.full((1, size), float(r))
        elif size == 1 and r.ndim == 1:
            r = r[:, None]
        elif size > 1 and r.shape[-1:] == (size,) and r.ndim <= 2:
            r = r.reshape(-1, size)
        else:
            raise FieldError(
                field,
                "must be a scalar, or have shape (n_cases,) for a one-wide "
                f"channel, (size,) or (n_cases, size) for one {size} wide; got "
                f"{r.shape}",
            )
        if r.shape[0] != 1 and n_cases not in (1, r.shape[0]):
            raise FieldError(field, f"has {r.shape[0]} cases, another reference {n_cases}")
        n_cases = max(n_cases, r.shape[0])
        cols.append(r)
    return np.concatenate([np.broadcast_to(c, (n_cases, c.shape[1])) for c in cols], axis=-1)


class StateSpaceCompensator(Controller):
    """A python-control system as a law from measurement errors to commands (module docstring).

    Parameters
    ----------
    system : control.StateSpace or control.TransferFunction
        p inputs (the measurement errors, channels concatenated in order) and m outputs (the
        commands). Continuous (dt = 0): discretised by zero-order hold at ``dt``. Discrete: its
        sampling time must be the control period (``dt=True``, an unspecified period, takes
        ``dt``).
    measurements, commands : sequence of str or Channel
        Channels read and written, in the order of the system's inputs and outputs; a name is
        one value wide, a :class:`~flexsat.dynamics.plant.Channel` has its width and unit.
    dt : float, str or pint.Quantity, optional
        Control period, s; required for a continuous system, checked against a discrete one.
    references : mapping {channel: value}, optional
        Value subtracted from a measurement channel (default 0): shape () or (n_cases,) for a
        one-wide channel, (size,) or (n_cases, size) for a wider one; in the Channel's unit
        (a Quantity or a unit string is converted), SI numbers for a channel given by name.
    """

    def __init__(
        self,
        system: ct.StateSpace | ct.TransferFunction,
        measurements: ChannelItems,
        commands: ChannelItems,
        dt: QuantityArrayLike | None = None,
        references: Mapping[str, QuantityArrayLike] | None = None,
    ) -> None:
        sys = _state_space(system)
        self.system = sys
        names, sizes, units = channel_spec(measurements, "measurements")
        cnames, csizes, _ = channel_spec(commands, "commands")
        if sum(sizes) != sys.ninputs:
            raise FieldError(
                "measurements",
                f"their widths {sizes} sum to {sum(sizes)}, the system has {sys.ninputs} inputs",
            )
        if sum(csizes) != sys.noutputs:
            raise FieldError(
                "commands",
                f"their widths {csizes} sum to {sum(csizes)}, the system "
                f"has {sys.noutputs} outputs",
            )
        self.reads, self.read_sizes = names, sizes
        self.writes, self.write_sizes = cnames, csizes
        A, B = np.asarray(sys.A, float), np.asarray(sys.B, float)
        C, D = np.asarray(sys.C, float), np.asarray(sys.D, float)
        if sys.dt in (0, None):
            if dt is None:
                raise FieldError(
                    "dt",
                    "a continuous system needs the control period to be "
                    "discretised (zero-order hold)",
                )
            self.dt = float(require_positive(dt, "dt", "s"))
            A, B = zoh(A, B, self.dt)
        elif sys.dt is True:
            if dt is None:
                raise FieldError(
                    "dt",
                    "the system is discrete with an unspecified sampling time "
                    "(dt=True); give the control period",
                )
            self.dt = float(require_positive(dt, "dt", "s"))
        else:
            self.dt = float(sys.dt)
            if dt is not None:
                period = float(require_positive(dt, "dt", "s"))
                if abs(period - self.dt) > DT_TOL * self.dt:
                    raise FieldError(
                        "system.dt",
                        f"the discrete system samples every {self.dt:g} "
                        f"s, the control period dt is {period:g} s",
                    )
        self.matrices = (A, B, C, D)
        self.r = reference_histories(references, names, sizes, units)

    @property
    def n_states(self) -> int:
        return self.matrices[0].shape[0]

    def _batched(self) -> list[tuple[int, ...]]:
        return [(self.r.shape[0],)]

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        return {"x": np.zeros((n_cases, self.n_states)), "t": np.full(n_cases, np.nan)}

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray | dict[str, FloatArray], dict[str, FloatArray]]:
        x = np.asarray(state["x"], float)
        nc = x.shape[0]
        t_prev = np.asarray(state["t"], float)
        started = np.isfinite(t_prev)
        gap = t - t_prev[started]
        if gap.size and np.any(np.abs(gap - self.dt) > DT_TOL * self.dt):
            raise FieldError(
                "dt",
                f"the compensator runs at a period of {self.dt:g} s but was "
                f"called {float(np.max(gap)):g} s after its previous sample",
            )
        e = stack_channels(y, self.reads, self.read_sizes, nc) - self.r
        A, B, C, D = self.matrices
        u = x @ C.T + e @ D.T
        out = {"x": x @ A.T + e @ B.T, "t": np.full(nc, float(t))}
        commands = split_channels(u, self.writes, self.write_sizes)
        return (commands[self.writes[0]] if len(self.writes) == 1 else commands), out

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        """Constant matrices (Φ, Γ, C, D), y_ref = r, no feedforward, x₀ = 0."""
        period, grid = sample_times(dt, times)
        if abs(period - self.dt) > DT_TOL * self.dt:
            raise FieldError(
                "dt",
                f"the compensator runs at a period of {self.dt:g} s, the run "
                f"samples every {period:g} s",
            )
        if self.r.shape[0] not in (1, n_cases):
            raise FieldError(
                "references", f"have {self.r.shape[0]} cases, the run has n_cases = {n_cases}"
            )
        A, B, C, D = (M[None, None] for M in self.matrices)
        y_ref = np.broadcast_to(self.r, (len(grid),) + self.r.shape)
        u_ff = np.zeros((len(grid), 1, C.shape[2]))
        return LinearLaw(
            A,
            B,
            C,
            D,
            y_ref,
            u_ff,
            None,
            self.reads,
            self.writes,
            self.read_sizes,
            self.write_sizes,
        )
