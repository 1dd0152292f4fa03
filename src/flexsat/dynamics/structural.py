r"""Any linear structure :math:`M\ddot q + D\dot q + Kq = Bu` as a plant with named channels.

A :class:`StructuralPlant` is a :class:`~flexsat.dynamics.second_order.SecondOrderModel` whose
inputs and outputs are named, unit-carrying :class:`~flexsat.dynamics.plant.Channel` s. It is
linear, so the whole of it is the exactly propagated part: with the state
:math:`x = [q, \dot q]`,

.. math::

    \dot x = \begin{bmatrix} 0 & I \\ -M^{-1}K & -M^{-1}D \end{bmatrix} x
           + \begin{bmatrix} 0 \\ M^{-1}B \end{bmatrix} u,
    \qquad y_i = c_{q,i}^T q + c_{v,i}^T \dot q

(:meth:`SecondOrderModel.first_order`). Channels are declared with :class:`Actuator` and
:class:`Sensor` specs and resolved against the coordinates they are built on:

- generalised coordinates (a SecondOrderModel, finite-element matrices): a spec's ``at`` is a
  dof (its index, or a ``(node, "rz")`` label when the dof labels are given) or, for a force or
  output that is not a single dof, an explicit influence vector over the coordinates;
- modal coordinates (a :class:`~flexsat.structures.modal_model.ModalModel`): ``at`` is a node
  (a node pair for a moment pair or a strain) and ``axis`` the direction, and the influence
  vectors are the model's mode shapes there (``force_input``, ``torque_input``,
  ``moment_pair``, and their collocated outputs).

Input kinds: ``force`` (N), ``torque`` (N m, on a rotation dof) and ``moment_pair`` (a
piezoelectric patch, Agrawal & Bang 1996 Eq. 36: equal and opposite
moments :math:`\pm a_1 u` at the two
rotation dofs of an element pair). Output kinds: ``displacement``
(m), ``rotation`` (rad) and ``strain``: the relative rotation :math:`\theta_b - \theta_a` of
the pair times ``gain`` (Agrawal & Bang 1996 Eq. 37, :math:`y = a_2 M`: with ``gain`` =
:math:`(t/2)/L_p` the surface strain averaged over a patch of length :math:`L_p`, as
``cases/agrawal_bang.py``; with :math:`EI/L_p` the bending moment, ``unit="N*m"``). A sensor with
``rate=True`` reads the velocity of the same quantity (unit per second).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Self, TypeAlias, cast

import numpy as np

from flexsat.dynamics.plant import Channel, Plant, find_channel
from flexsat.dynamics.second_order import SecondOrderModel
from flexsat.input_checks import FieldError, require_finite
from flexsat.units import parse_quantity

if TYPE_CHECKING:
    import numpy.typing as npt
    import scipy.sparse

    from flexsat.structures.modal_model import Direction, ModalModel
    from flexsat.units import FloatArray

    #: a dense matrix or a scipy.sparse one (:meth:`StructuralPlant.from_fe`)
    Matrix: TypeAlias = npt.ArrayLike | scipy.sparse.spmatrix | scipy.sparse.sparray

__all__ = ["Actuator", "ModalBlocks", "Sensor", "StructuralPlant"]

#: input kinds and their default SI unit
INPUT_KINDS = {"force": "N", "torque": "N*m", "moment_pair": "N*m"}
#: output kinds and their default SI unit (of the quantity; a rate adds "/s")
OUTPUT_KINDS = {"displacement": "m", "rotation": "rad", "strain": ""}


@dataclass(frozen=True)
class Actuator:
    """Spec of one input channel.

    Parameters
    ----------
    name : str
        Channel name (an identifier).
    kind : {"force", "torque", "moment_pair"}
    at : int, label, (a, b) pair or array_like (n,)
        Where it acts (module docstring): a dof or node; a pair of rotation dofs or nodes for a
        moment pair (+ at ``b``, − at ``a``); or an explicit influence vector.
    axis : str or array_like (3,), optional
        Direction of a force, axis of a torque or moment pair (modal coordinates only).
    gain : float
        Load per unit command (a_1 of Agrawal & Bang 1996 Eq. 36 for a moment pair); default 1.
    unit : str, optional
        Unit of the command (default N for a force, N m otherwise; a piezo voltage: "V").
    """

    name: str
    kind: str
    at: object
    axis: Direction | None = None
    gain: float = 1.0
    unit: str | None = None


@dataclass(frozen=True)
class Sensor:
    """Spec of one output channel.

    Parameters
    ----------
    name : str
        Channel name (an identifier).
    kind : {"displacement", "rotation", "strain"}
    at, axis : as :class:`Actuator` (a pair of rotation dofs or nodes for a strain).
    gain : float
        Output per unit of the quantity (a_2 (t/2)/L_p for a patch
        strain sensor, Agrawal & Bang 1996
        Eq. 37); default 1.
    rate : bool
        Read the velocity of the quantity instead (q̇ instead of q).
    unit : str, optional
        Unit of the output (default m, rad or dimensionless, with "/s" when ``rate``).
    """

    name: str
    kind: str
    at: object
    axis: Direction | None = None
    gain: float = 1.0
    rate: bool = False
    unit: str | None = None


@dataclass(frozen=True)
class ModalBlocks:
    r"""Decoupled modal structure of a plant: coordinate i obeys
    :math:`\ddot\eta_i + 2\zeta_i\omega_i\dot\eta_i + \omega_i^2\eta_i = b_i^T u`, so its
    exponential is a 2×2 block (state pair :math:`(\eta_i, \dot\eta_i)`, positions i and n + i).

    ``n_rigid`` counts the coordinates with ω = 0 (undamped rigid-body modes: a double
    integrator block).
    """

    frequencies: FloatArray  # ω, rad/s
    damping: FloatArray  # ζ (0 for a rigid mode)
    n_rigid: int


def _dense(matrix: Matrix) -> npt.ArrayLike:
    """A scipy.sparse matrix as a dense array; anything else as given."""
    return matrix.toarray() if hasattr(matrix, "toarray") else matrix


def _unit(unit: str, field: str) -> str:
    """The unit string, checked to parse (pint), so a typo fails at construction."""
    if not isinstance(unit, str):
        raise FieldError(field, f"unit must be a string, got {unit!r}")
    if unit:
        parse_quantity(unit, f"{field}: unit")
    return unit


def _rate_unit(unit: str) -> str:
    """Unit of the time derivative: "m" -> "m/s", "N*m" -> "(N*m)/s", "" -> "1/s"."""
    if unit == "":
        return "1/s"
    return f"{unit}/s" if unit.isidentifier() else f"({unit})/s"


class _Dofs:
    """Resolves specs on generalised coordinates (dof index, dof label or influence vector)."""

    def __init__(
        self, n: int, labels: Iterable[object] | None = None, fixed: Iterable[object] = ()
    ) -> None:
        def key(d: object) -> object:
            return tuple(d) if isinstance(d, (tuple, list)) else d

        self.n = n
        self.labels = None if labels is None else [key(d) for d in labels]
        if self.labels is not None and len(self.labels) != n:
            raise FieldError("dofs", f"{len(self.labels)} labels for {n} coordinates")
        self.fixed = {key(d) for d in fixed}

    def _dof(self, at: object, name: str) -> int | None:
        """Index of a dof, or None for a fixed (supported) one: a load there goes into the
        support and a sensor there reads zero."""
        if (tuple(at) if isinstance(at, (tuple, list)) else at) in self.fixed:
            return None
        if isinstance(at, (int, np.integer)) and not isinstance(at, bool):
            if not 0 <= at < self.n:
                raise FieldError(
                    name, f"dof {at} out of range (the model has {self.n} coordinates, 0-based)"
                )
            return int(at)
        key = tuple(at) if isinstance(at, (tuple, list)) else at
        if self.labels is not None and key in self.labels:
            return self.labels.index(key)
        raise FieldError(
            name,
            f"unknown dof {at!r} (give a 0-based index"
            + (", a dof label such as " + repr(self.labels[0]) if self.labels else "")
            + " or an influence vector)",
        )

    def vector(self, spec: Actuator | Sensor, pair: bool) -> FloatArray:
        name = spec.name
        if spec.axis is not None:
            raise FieldError(name, "axis applies to modal coordinates only (give the dof)")
        if pair:
            at = spec.at
            if (
                not isinstance(at, (tuple, list))
                or len(at) != 2
                or (self.labels is not None and tuple(at) in self.labels)
            ):
                raise FieldError(
                    name, f"a {spec.kind} needs a pair of rotation dofs (a, b), got {at!r}"
                )
            a, b = self._dof(at[0], name), self._dof(at[1], name)
            if a is None and b is None:
                raise FieldError(name, f"both dofs of the {spec.kind} are fixed (supports)")
            if a == b:
                raise FieldError(
                    name, f"the two dofs of a {spec.kind} must differ, got {at[0]!r} and {at[1]!r}"
                )
            v = np.zeros(self.n)
            for dof, sign in ((b, 1.0), (a, -1.0)):
                if dof is not None:
                    v[dof] = sign
            return v
        at = spec.at
        named = isinstance(at, (list, tuple)) and (
            tuple(at) in self.fixed or (self.labels is not None and tuple(at) in self.labels)
        )
        if isinstance(at, np.ndarray) or (isinstance(at, (list, tuple)) and not named):
            v = require_finite(at, f"{name}: at")
            if v.shape != (self.n,):
                raise FieldError(
                    name, f"an influence vector must have shape ({self.n},), got {v.shape}"
                )
            return v.astype(float)
        v = np.zeros(self.n)
        dof = self._dof(at, name)
        if dof is None:
            raise FieldError(
                name, f"dof {at!r} is fixed (a support): a {spec.kind} there does nothing"
            )
        v[dof] = 1.0
        return v


class _Modes:
    """Resolves specs on a ModalModel's modal coordinates (node, axis)."""

    def __init__(self, modal: ModalModel) -> None:
        self.modal = modal
        self.n = modal.n_modes

    def vector(self, spec: Actuator | Sensor, pair: bool) -> FloatArray:
        name, at, m = spec.name, spec.at, self.modal
        if spec.axis is None:
            raise FieldError(name, "give the axis (or direction) on a modal model")
        try:
            if pair:
                if not isinstance(at, (tuple, list)) or len(at) != 2:
                    raise ValueError(f"needs a node pair (node_a, node_b), got {at!r}")
                return m.moment_pair(at[0], at[1], spec.axis)
            node = cast(int, at)  # any spec may arrive here: the modal model checks the node id
            if spec.kind in ("force", "displacement"):
                return m.force_input(node, spec.axis)
            return m.torque_input(node, spec.axis)
        except ValueError as err:
            raise FieldError(name, f"{err}") from None


def _resolve(
    specs: Iterable[Actuator | Sensor], kinds: dict[str, str], role: str, locator: _Dofs | _Modes
) -> tuple[tuple[Channel, ...], list[FloatArray], list[bool]]:
    """Channels, their vectors over the coordinates, and (outputs) whether they read rates."""
    spec_type = Actuator if role == "input" else Sensor
    channels: list[Channel] = []
    vectors: list[FloatArray] = []
    rates: list[bool] = []
    seen: set[str] = set()
    for i, spec in enumerate(specs):
        if not isinstance(spec, spec_type):
            raise FieldError(f"{role}s[{i}]", f"must be a {spec_type.__name__}, got {spec!r}")
        name = spec.name
        Channel(name, "")  # checks the name is an identifier
        if name in seen:
            raise FieldError(name, f"duplicate {role} channel name")
        seen.add(name)
        if spec.kind not in kinds:
            raise FieldError(name, f"kind must be one of {', '.join(kinds)}, got {spec.kind!r}")
        gain = float(require_finite(spec.gain, f"{name}: gain"))
        if gain == 0.0:
            raise FieldError(name, "gain must be non-zero")
        pair = spec.kind in ("moment_pair", "strain")
        vectors.append(gain * locator.vector(spec, pair))
        rate = bool(getattr(spec, "rate", False))
        unit = kinds[spec.kind] if spec.unit is None else spec.unit
        unit = _rate_unit(unit) if rate and spec.unit is None else unit
        what = spec.kind.replace("_", " ") + (" rate" if rate else "")
        channels.append(Channel(name, _unit(unit, name), description=what))
        rates.append(rate)
    return tuple(channels), vectors, rates


class StructuralPlant(Plant):
    r"""A linear structure :math:`M\ddot q + D\dot q + Kq = Bu` with named channels (module
    docstring); state :math:`x = [q, \dot q]`.

    Build it with :meth:`from_second_order`, :meth:`from_modal_model` or :meth:`from_fe`; the
    constructor takes the resolved matrices.

    Parameters
    ----------
    model : SecondOrderModel
        M, D, K and the input matrix B (one column per input channel) and output rows Cq, Cv
        (one row per output channel); its Dff must be zero (structural outputs do not read u).
    inputs, outputs : tuple of Channel
        The channels, in the order of B's columns and of the output rows.
    """

    def __init__(
        self, model: SecondOrderModel, inputs: Iterable[Channel], outputs: Iterable[Channel]
    ) -> None:
        if not isinstance(model, SecondOrderModel):
            raise FieldError("model", f"must be a SecondOrderModel, got {type(model).__name__}")
        self.inputs, self.outputs = tuple(inputs), tuple(outputs)
        if len(self.inputs) != model.n_inputs or any(c.size != 1 for c in self.inputs):
            raise FieldError(
                "inputs", f"{len(self.inputs)} size-1 channels for {model.n_inputs} columns of B"
            )
        if len(self.outputs) != model.n_outputs or any(c.size != 1 for c in self.outputs):
            raise FieldError(
                "outputs", f"{len(self.outputs)} size-1 channels for {model.n_outputs} output rows"
            )
        if np.any(model.Dff):
            raise FieldError("model", "Dff must be zero (outputs read q and q̇ only)")
        for role, chans in (("input", self.inputs), ("output", self.outputs)):
            names = [c.name for c in chans]
            for name in names:
                if names.count(name) > 1:
                    raise FieldError(name, f"duplicate {role} channel name")
        self.model = model
        self.recorded = tuple(c.name for c in self.outputs)
        # the whole state as one more output: what a state-feedback law reads
        self.outputs += (Channel("state", "", model.n_states, "[q, q̇] (SI per coordinate)"),)

    # -- constructors --------------------------------------------------------------------------
    @classmethod
    def _build(
        cls,
        M: npt.ArrayLike,
        D: npt.ArrayLike,
        K: npt.ArrayLike,
        locator: _Dofs | _Modes,
        inputs: Iterable[Actuator],
        outputs: Iterable[Sensor],
    ) -> Self:
        in_ch, b_cols, _ = _resolve(inputs, INPUT_KINDS, "input", locator)
        out_ch, rows, rates = _resolve(outputs, OUTPUT_KINDS, "output", locator)
        n = locator.n
        B = np.column_stack(b_cols) if b_cols else np.zeros((n, 0))
        R = np.vstack(rows) if rows else np.zeros((0, n))
        rate = np.array(rates, dtype=bool)[:, None]
        Cq, Cv = np.where(rate, 0.0, R), np.where(rate, R, 0.0)
        return cls(SecondOrderModel(M, D, K, B, Cq, Cv), in_ch, out_ch)

    @classmethod
    def from_second_order(
        cls,
        model: SecondOrderModel,
        inputs: Iterable[Actuator] = (),
        outputs: Iterable[Sensor] = (),
        dofs: Iterable[object] | None = None,
    ) -> Self:
        """Channels on the coordinates q of ``model`` (its own B, Cq, Cv are not used).

        ``inputs`` are :class:`Actuator` s, ``outputs`` :class:`Sensor` s; ``dofs`` optionally
        labels the coordinates (e.g. ``[("hub", "rz"), (3, "uy"), ...]``) so specs may name
        them."""
        if not isinstance(model, SecondOrderModel):
            raise FieldError("model", f"must be a SecondOrderModel, got {type(model).__name__}")
        return cls._build(model.M, model.D, model.K, _Dofs(model.n_dof, dofs), inputs, outputs)

    @classmethod
    def from_fe(
        cls,
        M: Matrix,
        K: Matrix,
        inputs: Iterable[Actuator] = (),
        outputs: Iterable[Sensor] = (),
        D: Matrix | None = None,
        dofs: Iterable[object] | None = None,
        fixed: Iterable[object] = (),
    ) -> Self:
        """Finite-element (or any generalised-coordinate) matrices M, K and damping D (default
        zero); dense or scipy.sparse. ``dofs`` labels the rows, e.g. ``Assembly.dofs``
        ((node, "uy"), (node, "rz"), ...), so that specs can say ``at=(12, "rz")``; ``fixed``
        labels supported dofs (not in the matrices): one end of a moment pair or strain pair may
        sit there (a patch at a clamped root, Agrawal & Bang 1996 §4), contributing nothing."""
        Md, Kd = _dense(M), _dense(K)
        n = np.shape(Md)[0] if np.ndim(Md) == 2 else 0
        Dd = np.zeros((n, n)) if D is None else _dense(D)
        return cls._build(Md, Dd, Kd, _Dofs(n, dofs, fixed), inputs, outputs)

    @classmethod
    def from_modal_model(
        cls, modal: ModalModel, inputs: Iterable[Actuator] = (), outputs: Iterable[Sensor] = ()
    ) -> Self:
        r"""Modal coordinates η of a :class:`~flexsat.structures.modal_model.ModalModel`:
        M = I, D = diag(2ζω), K = diag(ω²) (``ModalModel.to_second_order``); specs name nodes
        and axes (module docstring). :attr:`modal_blocks` then gives (ω, ζ)."""
        M, D, K, *_ = modal.to_second_order()
        return cls._build(M, D, K, _Modes(modal), inputs, outputs)

    # -- the plant protocol --------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return self.model.n_states

    @cached_property
    def _first_order(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        A, B, C, _ = self.model.first_order()
        for arr in (A, B, C):
            arr.flags.writeable = False
        return A, B, C

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B) of the first-order form (module docstring)."""
        A, B, _ = self._first_order
        return A, B

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """(C (1, 2n), D = 0 (1, m), None): every output is linear in the state."""
        find_channel(self.outputs, name, "output", type(self).__name__)
        if name == "state":
            return np.eye(self.nx), np.zeros((self.nx, self.n_inputs)), None
        i = [c.name for c in self.outputs].index(name)
        return self._first_order[2][i : i + 1], np.zeros((1, self.n_inputs)), None

    def derivative(self, x: npt.ArrayLike, u: npt.ArrayLike) -> FloatArray:
        """ẋ = A x + B u for states (..., 2n) and inputs (..., m)."""
        A, B = self.linear_part()
        return np.asarray(x, float) @ A.T + np.asarray(u, float) @ B.T

    def energy(self, x: FloatArray) -> FloatArray:
        r"""Mechanical energy :math:`\tfrac12\dot q^T M\dot q + \tfrac12 q^T K q`, J, (...,)."""
        x = np.asarray(x, dtype=float)
        n = self.model.n_dof
        q, v = x[..., :n], x[..., n:]
        return 0.5 * np.einsum("...i,ij,...j->...", v, self.model.M, v) + 0.5 * np.einsum(
            "...i,ij,...j->...", q, self.model.K, q
        )

    @property
    def energy_matrix(self) -> FloatArray:
        r"""Q = blockdiag(K, M) of :meth:`energy` = :math:`\tfrac12 x^T Q x`, x = [q, q̇]."""
        n = self.model.n_dof
        Q = np.zeros((2 * n, 2 * n))
        Q[:n, :n], Q[n:, n:] = self.model.K, self.model.M
        return Q

    @energy_matrix.setter
    def energy_matrix(self, Q: FloatArray | None) -> None:
        raise AttributeError(
            f"energy_matrix: {type(self).__name__}'s is blockdiag(K, M) of its model (read-only)"
        )

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray:
        r"""Rate of :meth:`energy`, :math:`\dot q^T B u - \dot q^T D \dot q` (the work of the
        inputs less the dissipation), W, (...,)."""
        x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
        v = x[..., self.model.n_dof :]
        return np.einsum("...i,ij,...j->...", v, self.model.B, u) - np.einsum(
            "...i,ij,...j->...", v, self.model.D, v
        )

    @cached_property
    def modal_blocks(self) -> ModalBlocks | None:
        """(ω, ζ, n_rigid) when the coordinates are decoupled modes (M = I, K and D diagonal,
        as from :meth:`from_modal_model` or a truncated modal model), else None; a rigid
        coordinate (ω = 0) must be undamped."""
        m = self.model
        n = m.n_dof
        k, d = np.diag(m.K), np.diag(m.D)
        if (
            not np.array_equal(m.M, np.eye(n))
            or np.count_nonzero(m.K - np.diag(k))
            or np.count_nonzero(m.D - np.diag(d))
            or np.any(d[k == 0] != 0)
        ):
            return None
        w = np.sqrt(k)
        zeta = np.divide(d, 2 * w, out=np.zeros(n), where=w > 0)
        return ModalBlocks(w, zeta, int(np.count_nonzero(w == 0)))

    def __repr__(self) -> str:
        return (
            f"StructuralPlant(n_dof={self.model.n_dof}, inputs="
            f"{[c.name for c in self.inputs]}, outputs={[c.name for c in self.outputs]})"
        )
