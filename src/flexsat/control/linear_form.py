r"""The compiled-loop form of a linear control law ("linear form", issue #10).

Every law that is linear in its measurements — with gains, references and feedforward that may
vary in time and per case — is handed to the compiled inner loop as arrays only:

.. math::

    e_k = y_k - y_{ref,k}, \qquad
    u_k = u_{ff,k} + C_k \xi_k + D_k e_k, \qquad
    \xi_{k+1} = A_k \xi_k + B_k e_k,

with the law's internal state ξ starting at :math:`\xi_0 = K_0 e_0` when :math:`K_0` is given
(the LQG estimate started from the first measurement, :math:`\hat x_0 = C^+ y_0`) and at 0
otherwise. Every array carries two leading axes (T, C): T in {1, n_t} (constant or
time-indexed, a scheduled gain) and C in {1, n_cases} (shared or per case). y is the
concatenation of the channels in ``reads`` (total width p), u of those in ``writes`` (width m).

A law whose natural recursion has affine terms — an estimator in absolute coordinates driven by
a reference torque, :math:`\hat x_{k+1} = A\hat x_k + B e_k + f_k`,
:math:`u_k = g_k + C\hat x_k + D e_k` — is brought to this form by the shift
:math:`\xi = \hat x - s` with the deterministic sequence :math:`s_{k+1} = A_k s_k + f_k`:
then :math:`\xi_{k+1} = A_k\xi_k + B_k e_k` and :math:`u_{ff,k} = g_k + C_k s_k`
(:func:`absorb_affine`). The two recursions are equal in exact arithmetic; in floating point
they differ by round-off, a few ulps of the larger of |x̂| and |s| per step, carried by the
compensator's own dynamics A.

:func:`run_linear_law` is the reference implementation (a plain numpy loop) the compiled loop
and every law's ``linear_form`` are tested against.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from flexsat.control.base import SlewLaw
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.base import Controller
    from flexsat.dynamics.plant import Channel
    from flexsat.units import FloatArray

#: a law's channels as given: a name, a (name, width) pair or a Channel, a sequence of these,
#: or a mapping {name: width}
ChannelItems: TypeAlias = (
    "str | Channel | Iterable[str | tuple[str, int] | Channel] | Mapping[str, int]"
)

__all__ = [
    "LinearLaw",
    "absorb_affine",
    "cases_of",
    "channel_spec",
    "per_case",
    "reference_tables",
    "run_controller",
    "run_linear_law",
    "sample_times",
    "split_channels",
    "stack_channels",
    "static_law",
]


def _names(names: Iterable[object], field: str) -> tuple[str, ...]:
    checked: list[str] = []
    for name in names:
        if not isinstance(name, str) or not name.isidentifier():
            raise FieldError(field, f"channel names must be identifiers, got {name!r}")
        checked.append(name)
    if len(set(checked)) != len(checked):
        raise FieldError(field, f"channel names must be distinct, got {tuple(checked)!r}")
    return tuple(checked)


def _sizes(sizes: Iterable[object], names: Sequence[str], field: str) -> tuple[int, ...]:
    given = tuple(sizes)
    if len(given) != len(names):
        raise FieldError(field, f"give one width per channel of {names!r}, got {given!r}")
    checked: list[int] = []
    for s in given:
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 1:
            raise FieldError(field, f"widths must be positive integers, got {given!r}")
        checked.append(int(s))
    return tuple(checked)


@dataclass(frozen=True)
class LinearLaw:
    r"""Arrays of a linear law for the compiled loop (module docstring).

    Attributes
    ----------
    Ak : (T, C, nk, nk) ndarray
        State transition of the law's internal state ξ.
    Bk : (T, C, nk, p) ndarray
        Error input of ξ.
    Ck : (T, C, m, nk) ndarray
        Output of ξ in the commands.
    Dk : (T, C, m, p) ndarray
        Direct feedthrough of the error e = y − y_ref.
    y_ref : (n_t, C, p) ndarray
        Reference subtracted from the measurements at each sample.
    u_ff : (n_t, C, m) ndarray
        Feedforward command at each sample.
    K0 : (C, nk, p) ndarray or None
        ξ₀ = K0 e₀ at the first sample; ξ₀ = 0 when None.
    reads, writes : tuple of str
        Measurement and command channel names, in the order of y and u.
    read_sizes, write_sizes : tuple of int
        Their widths (sum p and m).

    T ∈ {1, n_t} and C ∈ {1, n_cases} for every array, independently. The arrays are stored as
    float64 and made read-only; shapes and finiteness are checked, each error naming the field.
    """

    Ak: FloatArray
    Bk: FloatArray
    Ck: FloatArray
    Dk: FloatArray
    y_ref: FloatArray
    u_ff: FloatArray
    K0: FloatArray | None
    reads: tuple[str, ...]
    writes: tuple[str, ...]
    read_sizes: tuple[int, ...]
    write_sizes: tuple[int, ...]

    def __post_init__(self) -> None:
        reads = _names(self.reads, "reads")
        writes = _names(self.writes, "writes")
        object.__setattr__(self, "reads", reads)
        object.__setattr__(self, "writes", writes)
        object.__setattr__(self, "read_sizes", _sizes(self.read_sizes, reads, "read_sizes"))
        object.__setattr__(self, "write_sizes", _sizes(self.write_sizes, writes, "write_sizes"))
        p, m = sum(self.read_sizes), sum(self.write_sizes)
        fields = ["Ak", "Bk", "Ck", "Dk", "y_ref", "u_ff"] + ([] if self.K0 is None else ["K0"])
        arrays = {}
        for name in fields:
            arr = require_finite(getattr(self, name), name)
            ndim = 3 if name in ("y_ref", "u_ff", "K0") else 4
            if arr.ndim != ndim:
                raise FieldError(name, f"must have {ndim} axes, got shape {arr.shape}")
            arrays[name] = arr
        nk = arrays["Ak"].shape[-1]
        n_t = arrays["y_ref"].shape[0]
        tails = {
            "Ak": (nk, nk),
            "Bk": (nk, p),
            "Ck": (m, nk),
            "Dk": (m, p),
            "y_ref": (p,),
            "u_ff": (m,),
            "K0": (nk, p),
        }
        n_cases = max(arr.shape[-len(tails[k]) - 1] for k, arr in arrays.items())
        for name, arr in arrays.items():
            tail = tails[name]
            if arr.shape[-len(tail) :] != tail:
                raise FieldError(
                    name,
                    f"trailing axes must be {tail} (nk = {nk}, p = {p} from "
                    f"reads, m = {m} from writes), got shape {arr.shape}",
                )
            c = arr.shape[-len(tail) - 1]
            if c not in (1, n_cases):
                raise FieldError(name, f"case axis must be 1 or n_cases = {n_cases}, got {c}")
            if name in ("y_ref", "u_ff"):
                if arr.shape[0] != n_t:
                    raise FieldError(
                        name, f"time axis must be n_t = {n_t} (that of y_ref), got {arr.shape[0]}"
                    )
            elif name != "K0" and arr.shape[0] not in (1, n_t):
                raise FieldError(
                    name, f"time axis must be 1 (constant) or n_t = {n_t}, got {arr.shape[0]}"
                )
            if arr.flags.writeable:  # a caller's array: freeze a copy, not theirs
                arr = arr.copy()
                arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @property
    def n_t(self) -> int:
        return self.y_ref.shape[0]

    @property
    def n_states(self) -> int:
        """nk, the size of the law's internal state."""
        return self.Ak.shape[-1]

    @property
    def n_cases(self) -> int:
        """Largest case axis of the arrays (1 when every array is shared)."""
        arrays = [self.Ak, self.Bk, self.Ck, self.Dk]
        cases = [a.shape[1] for a in arrays] + [self.y_ref.shape[1], self.u_ff.shape[1]]
        return max(cases + ([] if self.K0 is None else [self.K0.shape[0]]))

    @property
    def p(self) -> int:
        return sum(self.read_sizes)

    @property
    def m(self) -> int:
        return sum(self.write_sizes)


def run_linear_law(law: LinearLaw, Y: npt.ArrayLike) -> FloatArray:
    """Commands of a linear law for a measurement sequence: the reference implementation.

    Parameters
    ----------
    law : LinearLaw
    Y : (n_t, n_cases, p) array_like
        Measurements at the samples, channels concatenated in ``law.reads`` order; n_cases is 1
        or ``law.n_cases`` or any count when every array of the law is shared.

    Returns
    -------
    (n_t, n_cases, m) ndarray
        u_k = u_ff,k + C_k ξ_k + D_k e_k, ξ_{k+1} = A_k ξ_k + B_k e_k (module docstring).
    """
    Y = require_finite(Y, "Y")
    if Y.ndim != 3 or Y.shape[0] != law.n_t or Y.shape[2] != law.p:
        raise FieldError(
            "Y", f"must have shape (n_t, n_cases, p) = ({law.n_t}, n_cases, {law.p}), got {Y.shape}"
        )
    nc = max(Y.shape[1], law.n_cases)
    if Y.shape[1] not in (1, nc) or law.n_cases not in (1, nc):
        raise FieldError("Y", f"has {Y.shape[1]} cases, the law {law.n_cases}")
    U = np.empty((law.n_t, nc, law.m))
    xi = np.zeros((nc, law.n_states))

    def at(arr: FloatArray, k: int) -> FloatArray:
        return arr[min(k, arr.shape[0] - 1)]

    for k in range(law.n_t):
        e = Y[k] - law.y_ref[k]
        if k == 0 and law.K0 is not None:
            xi = np.einsum("cij,cj->ci", law.K0, np.broadcast_to(e, (nc, law.p)))
        U[k] = (
            law.u_ff[k]
            + np.einsum("cij,cj->ci", at(law.Ck, k), xi)
            + np.einsum("cij,cj->ci", at(law.Dk, k), np.broadcast_to(e, (nc, law.p)))
        )
        xi = np.einsum("cij,cj->ci", at(law.Ak, k), xi) + np.einsum(
            "cij,cj->ci", at(law.Bk, k), np.broadcast_to(e, (nc, law.p))
        )
    return U


def run_controller(
    law: Controller,
    times: npt.ArrayLike,
    Y: npt.ArrayLike,
    read_sizes: Sequence[int] | None = None,
    write_sizes: Sequence[int] | None = None,
) -> FloatArray:
    """Commands of any :class:`~flexsat.control.base.Controller` called sample by sample, the
    Python path the linear form must reproduce.

    Parameters
    ----------
    law : Controller
        Its ``reads``/``writes`` give the channel order; widths from ``read_sizes`` /
        ``write_sizes`` when it has them, else 1.
    times : (n_t,) array
        Sample times, s (the law's reference is tabulated on them first, as the engine does).
    Y : (n_t, n_cases, p) array
        Measurements, channels concatenated in ``law.reads`` order.
    read_sizes, write_sizes : tuple of int, optional
        Channel widths (the plant's), for a law that does not declare them.

    Returns
    -------
    (n_t, n_cases, m) ndarray
    """
    times = np.asarray(times, float)
    Y = np.asarray(Y, float)
    nc = Y.shape[1]
    rs: Sequence[int] = read_sizes or tuple(getattr(law, "read_sizes", (1,) * len(law.reads)))
    ws: Sequence[int] = write_sizes or tuple(getattr(law, "write_sizes", (1,) * len(law.writes)))
    if isinstance(law, SlewLaw) and law.reference is not None:
        law.tabulate_reference(times)  # as the engine: laws without a reference may be frozen
    state = law.initial_state(nc)
    U = np.empty((len(times), nc, sum(ws)))
    for k, t in enumerate(times):
        u, state = law(t, split_channels(Y[k], law.reads, rs), state)
        if not isinstance(u, Mapping):
            u = {law.writes[0]: u}
        U[k] = stack_channels(u, law.writes, ws, nc)
    return U


def absorb_affine(
    A: FloatArray,
    C: FloatArray,
    g: FloatArray,
    F: FloatArray,
    v: FloatArray,
    s0: npt.ArrayLike | None = None,
) -> FloatArray:
    r"""Shift an affine recursion into the linear form (module docstring).

    For :math:`x_{k+1} = A_k x_k + B_k e_k + F v_k`, :math:`u_k = g_k + C_k x_k + D_k e_k` with
    :math:`x_0 = K_0 e_0 + s_0`, returns :math:`u_{ff,k} = g_k + C_k s_k` where
    :math:`s_{k+1} = A_k s_k + F v_k`; the law then runs on ξ = x − s. The forcing is given
    factored (F constant, v narrow: a reference torque and angle per case) so that no
    (n_t, n_cases, nk) array is formed.

    Parameters
    ----------
    A : (T, C, nk, nk);  C : (T, C, m, nk);  g : (n_t, C, m);  F : (nk, q);  v : (n_t, C, q)
    s0 : (C, nk) or None (zero)

    Returns
    -------
    (n_t, C, m) ndarray
    """
    n_t, nk = g.shape[0], A.shape[-1]
    nc = max(A.shape[1], C.shape[1], g.shape[1], v.shape[1], 1 if s0 is None else np.shape(s0)[0])
    s = np.zeros((nc, nk)) if s0 is None else np.broadcast_to(s0, (nc, nk))
    u = np.empty((n_t, nc, g.shape[-1]))
    shared = A.shape[:2] == (1, 1) and C.shape[:2] == (1, 1)
    for k in range(n_t):
        if shared:  # one (n_cases, nk) x (nk, nk) product per step
            u[k] = g[k] + s @ C[0, 0].T
            s = s @ A[0, 0].T + v[k] @ F.T
        else:
            Ak, Ck = A[min(k, A.shape[0] - 1)], C[min(k, C.shape[0] - 1)]
            u[k] = g[k] + np.einsum("cij,cj->ci", Ck, s)
            s = np.einsum("cij,cj->ci", Ak, s) + v[k] @ F.T
    return u


def static_law(
    Dk: FloatArray,
    y_ref: FloatArray,
    u_ff: FloatArray,
    reads: tuple[str, ...],
    writes: tuple[str, ...],
    read_sizes: tuple[int, ...] | None = None,
    write_sizes: tuple[int, ...] | None = None,
) -> LinearLaw:
    """A law without internal state (nk = 0): u = u_ff + D (y − y_ref); widths default to 1."""
    m, p = np.shape(Dk)[2:]
    empty = np.zeros((1, 1, 0, 0))
    return LinearLaw(
        empty,
        np.zeros((1, 1, 0, p)),
        np.zeros((1, 1, m, 0)),
        Dk,
        y_ref,
        u_ff,
        None,
        reads,
        writes,
        read_sizes or (1,) * len(reads),
        write_sizes or (1,) * len(writes),
    )


# -- channels and case axes shared by the laws ------------------------------------------------
def channel_spec(
    items: ChannelItems, field: str
) -> tuple[tuple[str, ...], tuple[int, ...], tuple[str | None, ...]]:
    """Names, widths and units of a law's channels.

    ``items`` is a sequence whose entries are a channel name (width 1, values in SI numbers), a
    pair (name, width), or a :class:`~flexsat.dynamics.plant.Channel` (its width and unit); or a
    mapping {name: width}.
    """
    entries: Iterable[object]
    if isinstance(items, Mapping):
        entries = tuple(items.items())
    elif isinstance(items, Iterable) and not isinstance(items, str):
        entries = items
    else:  # one name or one Channel
        entries = (items,)
    names: list[object] = []
    sizes: list[object] = []
    units: list[str | None] = []
    for item in entries:
        if isinstance(item, str):
            names.append(item)
            sizes.append(1)
            units.append(None)
        elif isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str):
            names.append(item[0])
            sizes.append(item[1])
            units.append(None)
        elif hasattr(item, "name") and hasattr(item, "size") and hasattr(item, "unit"):
            names.append(item.name)
            sizes.append(item.size)
            units.append(item.unit)
        else:
            raise FieldError(field, f"give channel names or Channels, got {item!r}")
    if not names:
        raise FieldError(field, "give at least one channel")
    checked = _names(names, field)
    return checked, _sizes(sizes, checked, field), tuple(units)


def stack_channels(
    y: Mapping[str, npt.ArrayLike],
    names: Iterable[str],
    sizes: Iterable[int],
    n_cases: int,
    field: str = "y",
) -> FloatArray:
    """Concatenate channel values {name: (n_cases,) or (n_cases, size)} to (n_cases, p)."""
    cols = []
    for name, size in zip(names, sizes):
        try:
            v = np.asarray(y[name], float)
        except KeyError:
            raise FieldError(
                name, f"channel {name!r} not among the values given {sorted(y)}"
            ) from None
        shape = (n_cases,) if size == 1 else (n_cases, size)
        try:
            v = np.broadcast_to(v, shape)
        except ValueError:
            raise FieldError(
                name, f"values must have shape {shape} (n_cases, width), got {v.shape}"
            ) from None
        cols.append(v.reshape(n_cases, size))
    return np.concatenate(cols, axis=-1)


def cases_of(y: Mapping[str, npt.ArrayLike], names: Iterable[str], sizes: Iterable[int]) -> int:
    """Largest case count among the values of channels ``names`` in ``y`` (1 for scalars);
    a channel missing from ``y`` is left to :func:`stack_channels` to report."""
    n = 1
    for name, size in zip(names, sizes):
        if name in y:
            shape = np.shape(y[name])
            lead = shape[: len(shape) - (size > 1)]
            n = max(n, lead[0] if lead else 1)
    return n


def split_channels(
    u: FloatArray, names: Iterable[str], sizes: Iterable[int]
) -> dict[str, FloatArray]:
    """Inverse of :func:`stack_channels` on the last axis: {name: (...,) or (..., size)}."""
    out, start = {}, 0
    for name, size in zip(names, sizes):
        out[name] = u[..., start] if size == 1 else u[..., start : start + size]
        start += size
    return out


def per_case(
    value: npt.ArrayLike, n_cases: int, field: str, tail: tuple[int, ...] = ()
) -> FloatArray:
    """``value`` with one case axis (1 or n_cases) before the trailing axes ``tail``."""
    arr = np.asarray(value, float)
    lead = arr.shape[: arr.ndim - len(tail)] if tail else arr.shape
    if arr.shape[arr.ndim - len(tail) :] != tail or len(lead) > 1:
        raise FieldError(field, f"must have shape {tail} or (n_cases, *{tail}), got {arr.shape}")
    c = lead[0] if lead else 1
    if c not in (1, n_cases):
        raise FieldError(field, f"has {c} cases, the run has n_cases = {n_cases}")
    return arr.reshape((c,) + tail)


def sample_times(dt: float, times: npt.ArrayLike) -> tuple[float, FloatArray]:
    """The control period (s, > 0) and the sample times (s, 1-D, increasing) of a run."""
    dt = float(require_finite(dt, "dt", "s"))
    if dt <= 0:
        raise FieldError("dt", f"must be > 0, got {dt!r}")
    times = require_finite(times, "times", "s")
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0):
        raise FieldError(
            "times", f"must be a 1-D increasing array of sample times, got shape {times.shape}"
        )
    return dt, times


def reference_tables(
    law: SlewLaw, times: FloatArray, n_cases: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(θ_ref, θ'_ref, θ''_ref, u_ref) of a single-axis law at every sample, each (n_t, C) with
    C in {1, n_cases}: what :meth:`~flexsat.control.base.SlewLaw.reference_at` returns after
    :meth:`~flexsat.control.base.SlewLaw.tabulate_reference` (the same expression), or a step
    to ``law.target`` when the law has no reference."""
    n_t = times.shape[0]
    if law.reference is None:
        target = per_case(law.target, n_cases, "target")
        z = np.zeros((n_t, target.shape[0]))
        return target + z, z, z, z
    table = getattr(law, "_table", None)
    if table is not None and table[0].shape == times.shape and np.array_equal(table[0], times):
        # the simulator tabulated the reference on these samples: its arrays, read-only (a
        # LinearLaw keeps them without a copy: a batch's tables are its largest law arrays)
        values = [np.asarray(v, float).view() for v in table[1:]]
        for v in values:
            v.flags.writeable = False
    else:
        r = law.reference(times[:, None])
        values = [getattr(r, name) for name in ("theta", "theta_dot", "theta_ddot", "u")]
    out: list[FloatArray] = []
    for value in values:
        v = np.asarray(value, float)
        v = np.broadcast_to(v, np.broadcast_shapes(v.shape, (n_t, 1)))
        if v.ndim != 2 or v.shape[1] not in (1, n_cases):
            raise FieldError(
                "reference", f"has {v.shape[-1]} cases, the run has n_cases = {n_cases}"
            )
        out.append(v)
    theta, theta_dot, theta_ddot, u = out
    return theta, theta_dot, theta_ddot, u
