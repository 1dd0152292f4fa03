"""James–Junkins differential correction of substructure scalings (James & Junkins, AAS 89-425,
1989 = Att. 6 of Junkins, Pollock & Rahman 1990, Eqs. 3–13).

Gauss-Newton on all scalings at once, ``P_{i+1} = P_i + (A^T W A)^-1 A^T W dQ``, fitting free
and forced response together: any of undamped frequencies, mode shapes (subset of dofs,
each with its own least-squares scale), damping ratios of the damped model, FRF real and
imaginary parts of ``(K + i w C - w^2 M)^-1`` between dof indices or H rows / B columns, and
the pseudo-measurements ``0_m, 0_k`` (orthogonality of measured shapes), ``0_n`` (their
normalisation) and ``0_p`` (the start scalings, a Tikhonov prior).  Output and input gains (Att. 6
Eqs. 6–7: strain-gauge factors in ``H``, motor current-to-torque constants in ``B``) multiply the
FRF items that name them and are fitted together with the structural scalings.  ``A = dQ/dP`` is
analytic (:meth:`CorrectionData.predict`); ``(A^T W A)^-1`` is the covariance.  Only the
a-priori blocks are scaled, so symmetry, sparsity and coupling pattern are kept.

The model is a :class:`~flexsat.identify.structural.SubstructureModel`
(``K(p) = K0 + sum p_k K_k``, likewise ``M(q)``, ``C(r)``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias, cast

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.analysis.sensitivity import modal_derivatives
from flexsat.identify.structural.substructures import SubstructureModel
from flexsat.identify.structural.validation import check_iterations
from flexsat.input_checks import FieldError, require_finite, require_numeric
from flexsat.units import FloatArray, UnitError, holds_quantity

__all__ = ["CorrectionData", "DifferentialCorrection", "differential_correction"]

IntArray: TypeAlias = npt.NDArray[np.int_]
ComplexArray: TypeAlias = npt.NDArray[np.complex128]
#: one FRF measurement as :class:`CorrectionData` stores it: output and input (a dof index or
#: a vector), omegas, complex values, complex SDs (real and imaginary parts), output and input
#: gain indices
FrfItem: TypeAlias = tuple[
    "int | FloatArray",
    "int | FloatArray",
    FloatArray,
    ComplexArray,
    ComplexArray,
    int | None,
    int | None,
]


def _modes_and_sigma(
    values: npt.ArrayLike,
    sigma: float | npt.ArrayLike | None,
    modes: npt.ArrayLike | None,
    name: str,
    prefix: str,
    unit: str,
) -> tuple[FloatArray, FloatArray, IntArray]:
    """A measured modal quantity in ``unit``: finite vector > 0, its SDs (> 0) and the model
    modes."""
    v = require_finite(values, name, unit)
    if v.ndim > 1 or v.size == 0 or np.any(v <= 0):
        raise FieldError(name, f"must be a non-empty vector of values > 0, got shape {v.shape}")
    v = v.ravel()
    if sigma is None:
        raise FieldError(
            f"{prefix}_sigma", "give the standard deviations (the weights W, Att. 6 Eq. 10)"
        )
    s = require_finite(sigma, f"{prefix}_sigma", unit)
    if s.ndim > 1 or (s.ndim == 1 and s.size != v.size):
        raise FieldError(f"{prefix}_sigma", f"must be a scalar or {v.size} values, got {s.shape}")
    s = np.broadcast_to(s, v.shape).astype(float)
    if np.any(s <= 0):
        raise FieldError(f"{prefix}_sigma", "must be > 0")
    return v, s, _mode_numbers(modes, v.size, f"{prefix}_modes")


def _mode_numbers(modes: npt.ArrayLike | None, count: int, name: str) -> IntArray:
    if modes is None:
        return np.arange(count)
    idx = np.asarray(modes).ravel()
    if (
        idx.dtype.kind not in "iu"
        or idx.size != count
        or np.any(idx < 0)
        or np.unique(idx).size != count
    ):
        raise FieldError(name, f"must be {count} distinct mode numbers (0-based integers)")
    return idx.astype(int)


def _dof_or_vector(value: int | npt.ArrayLike, n: int, name: str) -> FloatArray:
    """An FRF output/input: a dof index or an (n,) vector (a row of H, a column of B)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        if not 0 <= value < n:
            raise FieldError(name, f"must be a dof index in [0, {n}), got {value}")
        e = np.zeros(n)
        e[value] = 1.0
        return e
    v = require_numeric(value, name, "vector")
    if v.shape != (n,):
        raise FieldError(
            name, f"must be a dof index or a vector of {n} entries, got shape {v.shape}"
        )
    return v


def _gain_index(value: object, name: str, items: int) -> int | None:
    """An FRF item's optional gain: None or an index into mu (outputs) or nu (inputs), below
    the number of FRF ``items`` (each gain belongs to at least one item)."""
    if value is None:
        return None
    if (
        not isinstance(value, (int, np.integer))
        or isinstance(value, bool)
        or not 0 <= value < items
    ):
        raise FieldError(
            name,
            f"must be None or an index in [0, {items}) into the gain vector (one gain per FRF "
            f"item at most), got {value!r}",
        )
    return int(value)


def _start_gains(values: npt.ArrayLike | None, count: int, name: str, kind: str) -> FloatArray:
    """Start values of the ``count`` output (``mu0``) or input (``nu0``) gains: default 1, > 0."""
    if values is None:
        return np.ones(count)
    v = require_numeric(values, name, "vector").ravel()
    if v.size != count:
        used = (
            f"one per {kind} 0..{count - 1} of data.frf" if count else f"data.frf names no {kind}"
        )
        raise FieldError(name, f"must have {count} entries ({used}), got {v.size}")
    if np.any(v <= 0):
        raise FieldError(name, "must be > 0 (gains relative to the a-priori H rows / B columns)")
    return v


@dataclass(frozen=True, eq=False)
class CorrectionData:
    """Measurements ``Q`` of the Att. 6 differential correction (Eq. 12), each with its SD.

    Every quantity is optional; the weights are ``W = diag(1/sigma^2)`` (Eq. 10).  Mode numbers
    are 0-based, ascending undamped frequency of the model.

    Parameters
    ----------
    frequencies, frequency_sigma, frequency_modes
        ``lambda``: undamped natural frequencies, rad/s, of a subset of modes.
    shapes, shape_sigma, shape_dofs, shape_modes
        ``psi``: (d, s) measured shape components at ``shape_dofs`` (default all dofs).  Each
        measured shape has an arbitrary scale: it is compared with ``c_r phi_r`` restricted to
        the dofs, ``c_r`` the least-squares scale (``phi_r^T psi_r / phi_r^T phi_r``).
    damping_ratios, damping_sigma, damping_modes
        ``zeta``: ``-Re(s)/|s|`` of the damped eigenvalue ``s`` nearest (in modulus) to the
        undamped frequency of each mode.
    frf : list of (output, input, omegas, values, sigma[, output_gain, input_gain])
        ``h^r, h^i`` (and ``R^r, R^i`` near resonance): receptances ``mu_og nu_ig c^T (K + i w C
        - w^2 M)^-1 b``, output and input each a dof index or an (n,) vector (a row of H, a
        column of B); complex values; ``sigma`` (scalar or per point) the SD of the real and of
        the imaginary part, or complex ``sd_real + 1j * sd_imag`` to weight them apart (away
        from resonance the imaginary part carries the damping, whose form a model may not
        have).  ``output_gain``, ``input_gain`` (default None: a calibrated sensor / input,
        factor 1) index the output gains ``mu`` and input gains ``nu``: Att. 6 Eq. 6 with
        ``H0 = 0`` and ``H_l`` the a-priori rows of gauge ``l``, Eq. 7 with ``B0 = 0`` and
        ``B_m`` the a-priori columns of motor ``m``.  Items may share a gain (one gauge, several
        inputs).
    orthogonality_sigma : float, optional
        ``0_m, 0_k``: pseudo-measurements ``psi_i^T M psi_j = 0`` and ``psi_i^T K psi_j = 0``
        (i < j) of the measured shapes, each divided by the geometric mean of its two diagonal
        terms in the nominal model (``p = q = 1``); needs shapes on all dofs.
    normalization_sigma : float, optional
        ``0_n``: pseudo-measurements ``psi_i^T M psi_i / psi_i^T M(1) psi_i = 1``: the measured
        shapes keep the normalisation they have with the nominal mass (Att. 6 scales them with
        the analytical mass, Att. 6 "Mode Shapes"); needs shapes on all dofs.
    """

    # the fields hold the checked arrays; the constructor takes array_like (see __init__ below)
    frequencies: FloatArray | None = None
    frequency_sigma: FloatArray | None = None
    frequency_modes: IntArray | None = None
    shapes: FloatArray | None = None
    shape_sigma: FloatArray | None = None
    shape_dofs: IntArray | None = None
    shape_modes: IntArray | None = None
    damping_ratios: FloatArray | None = None
    damping_sigma: FloatArray | None = None
    damping_modes: IntArray | None = None
    frf: Sequence[FrfItem] = ()
    orthogonality_sigma: float | None = None
    normalization_sigma: float | None = None

    if TYPE_CHECKING:
        # what the constructor accepts (the generated __init__ at run time)
        def __init__(
            self,
            frequencies: npt.ArrayLike | None = ...,
            frequency_sigma: npt.ArrayLike | None = ...,
            frequency_modes: npt.ArrayLike | None = ...,
            shapes: npt.ArrayLike | None = ...,
            shape_sigma: npt.ArrayLike | None = ...,
            shape_dofs: npt.ArrayLike | None = ...,
            shape_modes: npt.ArrayLike | None = ...,
            damping_ratios: npt.ArrayLike | None = ...,
            damping_sigma: npt.ArrayLike | None = ...,
            damping_modes: npt.ArrayLike | None = ...,
            frf: Sequence[Sequence[Any]] = ...,
            orthogonality_sigma: float | None = ...,
            normalization_sigma: float | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name, prefix, unit in (
            ("frequencies", "frequency", "rad/s"),
            ("damping_ratios", "damping", ""),
        ):
            if getattr(self, name) is None:
                continue
            v, s, modes = _modes_and_sigma(
                getattr(self, name),
                getattr(self, f"{prefix}_sigma"),
                getattr(self, f"{prefix}_modes"),
                name,
                prefix,
                unit,
            )
            if name == "damping_ratios" and np.any(v >= 1):
                # zeta = -Re(s)/|s| of a complex (oscillating) eigenvalue: below 1
                raise FieldError(name, f"must be < 1 (an underdamped mode), got {v}")
            set_(self, name, v)
            set_(self, f"{prefix}_sigma", s)
            set_(self, f"{prefix}_modes", modes)
        if self.shapes is not None:
            y = require_numeric(self.shapes, "shapes", "matrix")
            if y.ndim == 1:
                y = y[:, None]
            if y.ndim != 2 or y.size == 0:
                raise FieldError("shapes", f"must be a (dofs, modes) matrix, got shape {y.shape}")
            if self.shape_sigma is None:
                raise FieldError("shape_sigma", "give the standard deviations (the weights W)")
            s = require_numeric(self.shape_sigma, "shape_sigma")
            try:
                s = np.broadcast_to(s, y.shape).astype(float)
            except ValueError:
                raise FieldError(
                    "shape_sigma",
                    f"must be a scalar or shaped like shapes {y.shape}, got {s.shape}",
                ) from None
            if np.any(s <= 0):
                raise FieldError("shape_sigma", "must be > 0")
            if self.shape_dofs is not None:
                dofs = np.asarray(self.shape_dofs).ravel()
                if (
                    dofs.dtype.kind not in "iu"
                    or dofs.size != y.shape[0]
                    or np.unique(dofs).size != dofs.size
                    or np.any(dofs < 0)
                ):
                    raise FieldError(
                        "shape_dofs",
                        f"must be {y.shape[0]} distinct dof indices (one per row of shapes)",
                    )
                set_(self, "shape_dofs", dofs.astype(int))
            set_(self, "shapes", y)
            set_(self, "shape_sigma", s)
            set_(self, "shape_modes", _mode_numbers(self.shape_modes, y.shape[1], "shape_modes"))
        for name in ("orthogonality_sigma", "normalization_sigma"):
            value = getattr(self, name)
            if value is None:
                continue
            if np.ndim(value) != 0 or float(require_numeric(value, name)) <= 0:
                raise FieldError(name, "must be a scalar > 0")
            if self.shapes is None or self.shape_dofs is not None:
                raise FieldError(name, "needs measured shapes on all dofs (shape_dofs=None)")
            if name == "orthogonality_sigma" and self.shapes.shape[1] < 2:
                raise FieldError(name, "needs at least two measured shapes")
            set_(self, name, float(value))
        frf = self.frf
        if isinstance(frf, tuple) and len(frf) in (5, 7) and np.ndim(frf[2]) == 1:
            frf = [frf]
        if not isinstance(frf, Sequence) or isinstance(frf, (str, bytes)):
            raise FieldError(
                "frf",
                "must be a list of (output, input, omegas, values, sigma[, output_gain, "
                f"input_gain]), got {type(frf).__name__}",
            )
        items = []
        for i, item in enumerate(frf):
            if not isinstance(item, (tuple, list)) or len(item) not in (5, 7):
                raise FieldError(
                    f"frf[{i}]",
                    "must be (output, input, omegas, values, sigma[, output_gain, input_gain])",
                )
            out, inp, w, h, sd, og, ig = (*item, None, None)[:7]  # 5-tuples: no gains
            og = _gain_index(og, f"frf[{i}].output_gain", len(frf))
            ig = _gain_index(ig, f"frf[{i}].input_gain", len(frf))
            w = require_numeric(w, f"frf[{i}].omegas", "vector").ravel()
            h = np.asarray(h)
            if h.dtype.kind not in "biufc":
                raise FieldError(f"frf[{i}].values", "must be a numeric (complex) vector")
            h = h.astype(complex).ravel()
            if not np.all(np.isfinite(h)):
                raise FieldError(
                    f"frf[{i}].values",
                    "must be finite (no NaN or inf), got "
                    f"{int(np.sum(~np.isfinite(h)))} non-finite entries",
                )
            if w.size == 0 or h.shape != w.shape:
                raise FieldError(
                    f"frf[{i}]",
                    "omegas and values must be equal-length non-empty "
                    f"vectors, got {w.size} and {h.size}",
                )
            if np.any(w <= 0):
                raise FieldError(f"frf[{i}].omegas", "must be > 0 rad/s")
            if holds_quantity(sd, strings=True):
                raise UnitError(
                    f"frf[{i}].sigma",
                    "takes plain numbers in the unit of the values, got a quantity",
                )
            sd = np.asarray(sd)
            if sd.dtype.kind not in "biufc" or not np.all(np.isfinite(sd)):
                raise FieldError(f"frf[{i}].sigma", "must be finite numbers")
            if sd.dtype.kind != "c":
                sd = sd + 1j * sd  # the same SD for the real and the imaginary part
            if (
                sd.ndim > 1
                or (sd.ndim == 1 and sd.size != w.size)
                or np.any(sd.real <= 0)
                or np.any(sd.imag <= 0)
            ):
                raise FieldError(f"frf[{i}].sigma", f"must be a scalar or {w.size} values, > 0")
            items.append((out, inp, w, h, np.broadcast_to(sd, w.shape).astype(complex), og, ig))
        set_(self, "frf", items)
        if (
            self.frequencies is None
            and self.shapes is None
            and self.damping_ratios is None
            and not items
        ):
            raise FieldError(
                "frequencies",
                "no measurement given: give at least one kind of frequencies, shapes, "
                "damping_ratios or frf",
            )

    @property
    def n_output_gains(self) -> int:
        """Length of ``mu``: the largest ``output_gain`` of :attr:`frf` + 1 (0 without)."""
        return 1 + max((item[5] for item in self.frf if item[5] is not None), default=-1)

    @property
    def n_input_gains(self) -> int:
        """Length of ``nu``: the largest ``input_gain`` of :attr:`frf` + 1 (0 without)."""
        return 1 + max((item[6] for item in self.frf if item[6] is not None), default=-1)

    @property
    def _shape_pairs(self) -> list[tuple[int, int]]:
        s = 0 if self.shapes is None else self.shapes.shape[1]
        return [(i, j) for i in range(s) for j in range(i + 1, s)]

    @property
    def measured(self) -> FloatArray:
        """Measured ``Q`` stacked: lambda, psi (by mode), zeta, FRF (per element real then
        imaginary), 0_m, 0_k, 0_n."""
        parts = [
            self.frequencies,
            None if self.shapes is None else self.shapes.T.ravel(),
            self.damping_ratios,
        ]
        parts += [np.concatenate([item[3].real, item[3].imag]) for item in self.frf]
        if self.orthogonality_sigma is not None:
            parts.append(np.zeros(2 * len(self._shape_pairs)))
        if self.normalization_sigma is not None:
            assert self.shapes is not None  # normalization_sigma needs shapes (__post_init__)
            parts.append(np.ones(self.shapes.shape[1]))
        return np.concatenate([x for x in parts if x is not None] + [np.zeros(0)])

    @property
    def sigma(self) -> FloatArray:
        """Standard deviations of :attr:`measured`, same order."""
        parts = [
            self.frequency_sigma,
            None if self.shape_sigma is None else self.shape_sigma.T.ravel(),
            self.damping_sigma,
        ]
        parts += [np.concatenate([item[4].real, item[4].imag]) for item in self.frf]
        if self.orthogonality_sigma is not None:
            parts.append(np.full(2 * len(self._shape_pairs), self.orthogonality_sigma))
        if self.normalization_sigma is not None:
            assert self.shapes is not None  # normalization_sigma needs shapes (__post_init__)
            parts.append(np.full(self.shapes.shape[1], self.normalization_sigma))
        return np.concatenate([x for x in parts if x is not None] + [np.zeros(0)])

    def check_model(self, model: SubstructureModel) -> None:
        """Refuse data that do not fit ``model``: shapes, dofs and mode numbers beyond its
        dofs, damping ratios without damping blocks, FRF outputs and inputs that are not one
        of its dofs or a vector over them."""
        if not isinstance(model, SubstructureModel):
            raise FieldError("model", f"must be a SubstructureModel, got {type(model).__name__}")
        n = model.n_dofs
        if self.shapes is not None:
            if self.shape_dofs is None and self.shapes.shape[0] != n:
                raise FieldError(
                    "shapes",
                    f"without shape_dofs must have one row per dof ({n}), "
                    f"got {self.shapes.shape[0]}",
                )
            if self.shape_dofs is not None and self.shape_dofs.max() >= n:
                raise FieldError("shape_dofs", f"must be dof indices < {n}")
        for name in ("frequency_modes", "shape_modes", "damping_modes"):
            modes = getattr(self, name)
            if modes is not None and modes.size and modes.max() >= n:
                raise FieldError(name, f"must be model mode numbers < {n} (its dofs)")
        if self.damping_ratios is not None and model.n_damping == 0:
            raise FieldError("damping_ratios", "the model has no damping blocks (C_blocks)")
        for i, (out, inp, *_) in enumerate(self.frf):
            _dof_or_vector(out, n, f"frf[{i}].output")
            _dof_or_vector(inp, n, f"frf[{i}].input")

    def predict(
        self,
        model: SubstructureModel,
        p: npt.ArrayLike | None = None,
        q: npt.ArrayLike | None = None,
        r: npt.ArrayLike | None = None,
        mu: npt.ArrayLike | None = None,
        nu: npt.ArrayLike | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Calculated ``Q`` (Att. 6 Eq. 12) and its Jacobian ``A = dQ/dP`` (Eq. 13).

        ``mu``, ``nu``: output and input gains (Eqs. 6–7), default 1, at least
        :attr:`n_output_gains` and :attr:`n_input_gains` entries.  Analytic derivatives with
        respect to ``P = (p, q, r, mu, nu)`` (Eq. 8):

        - frequencies: ``d(w^2)/dx = phi^T (dK - w^2 dM) phi`` (mass-normalised ``phi``);
        - shapes: Nelson's method (:func:`flexsat.analysis.sensitivity.modal_derivatives`),
          then the derivative of the least-squares scale ``c``;
        - damping ratios: ``ds = -x^T (dK + s dC + s^2 dM) x / x^T (C + 2 s M) x`` for the
          quadratic eigenproblem ``(K + s C + s^2 M) x = 0`` (symmetric: plain transpose);
        - FRF: ``dh = -g u^T dZ v``, ``Z = K + i w C - w^2 M``, ``u = Z^-1 c``, ``v = Z^-1 b``,
          ``g = mu_og nu_ig``; the FRF is linear in each gain, ``dh/dmu_og = h / mu_og`` (and
          likewise ``nu_ig``), formed as the product of the other factors (no division);
        - 0_m, 0_k, 0_n: linear in ``q`` and ``p``; the gains enter the FRF only.

        Returns
        -------
        values : (N,) in the order of :attr:`measured`; jacobian : (N, P + Q + R + S + T), S and
        T the lengths of ``mu`` and ``nu``.
        """
        self.check_model(model)
        n, P, Q, R = model.n_dofs, model.n_stiffness, model.n_mass, model.n_damping
        ps, qs, rs = (
            model.check_scalings(p, P, "p"),
            model.check_scalings(q, Q, "q"),
            model.check_scalings(r, R, "r"),
        )
        gains = []
        for name, given, kind, pos in (("mu", mu, "output", 5), ("nu", nu, "input", 6)):
            v = (
                np.ones(getattr(self, f"n_{kind}_gains"))
                if given is None
                else require_numeric(given, name, "vector").reshape(-1)
            )
            for i, item in enumerate(self.frf):
                gain = cast("int | None", item[pos])  # the output or input gain index
                if gain is not None and gain >= v.size:
                    raise FieldError(
                        f"frf[{i}].{kind}_gain",
                        f"must be < {v.size} (the length of {name}), got {gain}",
                    )
            gains.append(v)
        mu, nu = gains
        S, T = mu.size, nu.size
        K, M, C = model.K(ps), model.M(qs), model.C(rs)
        values: list[npt.NDArray[Any]] = []
        jac: list[npt.NDArray[Any]] = []
        needed = sorted(
            set(
                np.concatenate(
                    [m for m in (self.frequency_modes, self.shape_modes) if m is not None]
                    + [np.zeros(0, int)]
                ).tolist()
            )
        )
        if needed:
            zero = np.zeros((n, n))
            md = modal_derivatives(
                K,
                M,
                np.array(model.K_blocks + [zero] * Q),
                np.array([zero] * P + model.M_blocks),
                modes=needed,
            )
            col = {int(mode): i for i, mode in enumerate(md.indices)}
        if self.frequencies is not None:
            assert self.frequency_modes is not None  # set with the frequencies (__post_init__)
            c = [col[int(mode)] for mode in self.frequency_modes]
            if np.any(md.frequencies[c] <= 0):
                raise FieldError("frequency_modes", "a measured mode is a rigid-body mode (w = 0)")
            values.append(md.frequencies[c])
            jac.append(np.hstack([md.frequency_gradient[:, c].T, np.zeros((len(c), R))]))
        if self.shapes is not None:
            dofs = np.arange(n) if self.shape_dofs is None else self.shape_dofs
            assert self.shape_modes is not None  # set with the shapes (__post_init__)
            for s, mode in enumerate(self.shape_modes):
                f = md.modes[dofs, col[int(mode)]]
                df = md.mode_gradient[:, dofs, col[int(mode)]]
                y = self.shapes[:, s]
                ff = f @ f
                scale = f @ y / ff
                d_scale = (df @ y - 2.0 * scale * (df @ f)) / ff
                values.append(scale * f)
                jac.append(
                    np.hstack([(np.outer(d_scale, f) + scale * df).T, np.zeros((dofs.size, R))])
                )
        if self.damping_ratios is not None:
            assert self.damping_modes is not None  # set with the damping ratios (__post_init__)
            values_z, jac_z = _damping_ratios(model, K, M, C, self.damping_modes)
            values.append(values_z)
            jac.append(jac_z)
        for i, (out, inp, w, _, _, og, ig) in enumerate(self.frf):
            cvec = _dof_or_vector(out, n, f"frf[{i}].output")
            bvec = _dof_or_vector(inp, n, f"frf[{i}].input")
            g_out = 1.0 if og is None else mu[og]
            g_in = 1.0 if ig is None else nu[ig]
            h = np.empty(w.size, complex)
            dh = np.empty((w.size, P + Q + R), complex)
            for k, wk in enumerate(w):
                Z = K - wk**2 * M + 1j * wk * C
                try:
                    u, v = np.linalg.solve(Z, np.column_stack([cvec, bvec])).T
                except np.linalg.LinAlgError:
                    raise FieldError(
                        f"frf[{i}].omegas",
                        f"{wk} rad/s is an undamped resonance of "
                        "the model (K - w^2 M + i w C singular)",
                    ) from None
                h[k] = cvec @ v
                dh[k] = (
                    [-(u @ Kg @ v) for Kg in model.K_blocks]
                    + [wk**2 * (u @ Mg @ v) for Mg in model.M_blocks]
                    + [-1j * wk * (u @ Cg @ v) for Cg in model.C_blocks]
                )
            dh = np.hstack([g_out * g_in * dh, np.zeros((w.size, S + T))])
            if og is not None:
                dh[:, P + Q + R + og] = g_in * h
            if ig is not None:
                dh[:, P + Q + R + S + ig] = g_out * h
            h = g_out * g_in * h
            values.append(np.concatenate([h.real, h.imag]))
            jac.append(np.vstack([dh.real, dh.imag]))
        if self.orthogonality_sigma is not None or self.normalization_sigma is not None:
            psi = self.shapes
            assert psi is not None  # both pseudo-measurements need shapes (__post_init__)
            # psi^T B psi of every block, [fixed part, blocks...], for M and K
            assert model.M0 is not None and model.K0 is not None  # zeros when not given
            forms_m = [psi.T @ B @ psi for B in [model.M0] + model.M_blocks]
            forms_k = [psi.T @ B @ psi for B in [model.K0] + model.K_blocks]
            nominal_m, nominal_k = np.diag(sum(forms_m)), np.diag(sum(forms_k))
            pairs = self._shape_pairs
            if self.orthogonality_sigma is not None:
                for forms, nominal, scalings, offset, count in (
                    (forms_m, nominal_m, qs, P, Q),
                    (forms_k, nominal_k, ps, 0, P),
                ):
                    norm = np.array([1.0 / np.sqrt(nominal[i] * nominal[j]) for i, j in pairs])
                    grad = (
                        np.array([[B[i, j] for B in forms[1:]] for i, j in pairs]).reshape(
                            len(pairs), count
                        )
                        * norm[:, None]
                    )
                    values.append(
                        np.array([forms[0][i, j] for i, j in pairs]) * norm + grad @ scalings
                    )
                    block = np.zeros((len(pairs), P + Q + R))
                    block[:, offset : offset + count] = grad
                    jac.append(block)
            if self.normalization_sigma is not None:
                grad = (
                    np.array([np.diag(B) for B in forms_m[1:]]).T.reshape(-1, Q)
                    / nominal_m[:, None]
                )
                values.append(np.diag(forms_m[0]) / nominal_m + grad @ qs)
                jac.append(
                    np.hstack([np.zeros((grad.shape[0], P)), grad, np.zeros((grad.shape[0], R))])
                )
        # only the FRF rows depend on the gains: the other blocks get zero gain columns
        return np.concatenate(values), np.vstack(
            [np.pad(block, ((0, 0), (0, P + Q + R + S + T - block.shape[1]))) for block in jac]
        )


def _damping_ratios(
    model: SubstructureModel, K: FloatArray, M: FloatArray, C: FloatArray, modes: IntArray
) -> tuple[FloatArray, FloatArray]:
    """Damping ratios of the damped modes paired with the undamped ``modes``, and gradients."""
    n = model.n_dofs
    w0 = np.sqrt(np.clip(sla.eigh(K, M, eigvals_only=True), 0.0, None))
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    s_all, Z = sla.eig(A)
    # one of each conjugate pair; overdamped (real) roots have no damping ratio below 1
    cand = np.nonzero(s_all.imag > 0)[0]
    pick = [int(cand[np.argmin(np.abs(np.abs(s_all[cand]) - w0[mode]))]) for mode in modes]
    if len(set(pick)) != len(pick):
        raise FieldError(
            "damping_modes",
            "two modes pair with the same damped eigenvalue (close modes or heavy damping)",
        )
    values, jac = (
        np.empty(len(pick)),
        np.empty((len(pick), model.n_stiffness + model.n_mass + model.n_damping)),
    )
    for row, i in enumerate(pick):
        s, x = s_all[i], Z[:n, i]
        ds = -np.array(
            [x @ Kg @ x for Kg in model.K_blocks]
            + [s**2 * (x @ Mg @ x) for Mg in model.M_blocks]
            + [s * (x @ Cg @ x) for Cg in model.C_blocks]
        ) / (x @ (C + 2.0 * s * M) @ x)
        a = abs(s)
        da = (s.real * ds.real + s.imag * ds.imag) / a
        values[row] = -s.real / a
        jac[row] = -(ds.real * a - s.real * da) / a**2
    return values, jac


@dataclass(frozen=True)
class DifferentialCorrection:
    """Result of :func:`differential_correction`.

    Attributes
    ----------
    model : SubstructureModel with blocks scaled by the estimates (its nominal is the updated
        model: same symmetry, sparsity and coupling pattern as the a-priori one).
    p, q, r : stiffness, mass and damping scalings.
    mu, nu : output and input gains (Att. 6 Eqs. 6–7), indexed as in ``CorrectionData.frf``.
    covariance : (P+Q+R+S+T, P+Q+R+S+T) ``(A^T W A)^-1`` at the solution over ``(p, q, r, mu,
        nu)``, prior rows included (zeros for held parameters).
    residual_history : weighted sum of squares ``dQ^T W dQ`` (+ prior rows) of the a-priori
        model and after each accepted step.
    residuals : (N,) final ``Q_measured - Q_calculated`` (order of ``CorrectionData.measured``).
    iterations : Gauss-Newton steps taken; converged : bool.
    """

    model: SubstructureModel
    p: FloatArray
    q: FloatArray
    r: FloatArray
    mu: FloatArray
    nu: FloatArray
    covariance: FloatArray
    residual_history: list[float]
    residuals: FloatArray
    iterations: int
    converged: bool


def differential_correction(
    model: SubstructureModel,
    data: CorrectionData,
    p0: npt.ArrayLike | None = None,
    q0: npt.ArrayLike | None = None,
    r0: npt.ArrayLike | None = None,
    fixed_stiffness: npt.ArrayLike = (),
    fixed_mass: npt.ArrayLike = (),
    fixed_damping: npt.ArrayLike = (),
    prior_sigma: npt.ArrayLike | None = None,
    n_iter: int = 50,
    tol: float = 1e-10,
    mu0: npt.ArrayLike | None = None,
    nu0: npt.ArrayLike | None = None,
    fixed_output_gains: npt.ArrayLike = (),
    fixed_input_gains: npt.ArrayLike = (),
) -> DifferentialCorrection:
    """Att. 6 differential correction of the substructure scalings and gains (Eqs. 3–13).

    Gauss-Newton ``P_{i+1} = P_i + (A^T W A)^-1 A^T W dQ`` (Eqs. 9–11) on ``P = (p, q, r, mu,
    nu)`` (Eq. 8): the scalings of ``M, C, K`` (Eqs. 3–5) and the output and input gains of
    ``H`` and ``B`` (Eqs. 6–7) that the FRF items of ``data`` name; ``dQ = Q_measured -
    Q_calculated`` over whichever measurements ``data`` holds (Eq. 12): undamped frequencies,
    mode shapes, damping ratios, FRF real and imaginary parts, and the pseudo-measurements
    ``0_m, 0_k, 0_n``; ``A = dQ/dP`` analytically (Eq. 13, :meth:`CorrectionData.predict`).
    A step that raises the weighted sum of squares, or takes a gain to <= 0, is halved (up to
    30 times).

    ``prior_sigma`` adds the pseudo-measurement ``0_p``: the start values as measurements of
    the free parameters with that SD (Tikhonov regularisation of the change).

    What identifies what: frequencies, shapes and damping ratios are unchanged by scaling
    ``K, M, C`` together, so free-response data fix ratios only; the FRF (forced response)
    fixes the scale.  A gain multiplies its FRF items like ``1 / (K, M, C)`` does, so if every
    FRF item carries a gain the scale needs the mass (or a calibrated item, gains None); if
    every item carries both an output and an input gain, only their products are determined.
    A parameter combination the data do not determine raises ``ValueError`` naming it (or give
    ``prior_sigma``).  Because only the a-priori blocks are scaled, the updated ``K, M, C``
    keep their symmetry, sparsity and coupling pattern.

    Parameters
    ----------
    model : SubstructureModel
    data : CorrectionData
    p0, q0, r0 : start (a-priori) scalings, default 1.
    fixed_stiffness, fixed_mass, fixed_damping : indices of scalings held at the start value.
    prior_sigma : scalar or (P+Q+R+S+T,), optional
        SD of the parameters ``(p, q, r, mu, nu)`` about their start values (``0_p``).
    n_iter : maximum steps.  tol : convergence when every parameter moves less than ``tol``.
    mu0, nu0 : start output and input gains (> 0), default 1; exactly
        ``data.n_output_gains`` and ``data.n_input_gains`` entries.
    fixed_output_gains, fixed_input_gains : indices of gains held at the start value (e.g. a
        calibrated gauge or motor).

    Returns
    -------
    DifferentialCorrection
    """
    if not isinstance(data, CorrectionData):
        raise FieldError("data", "must be a CorrectionData")
    data.check_model(model)
    n_iter, tol = check_iterations(n_iter, tol)
    P, Q, R = model.n_stiffness, model.n_mass, model.n_damping
    S, T = data.n_output_gains, data.n_input_gains
    G = P + Q + R  # the gains' first column
    x0 = np.concatenate(
        [
            model.check_scalings(p0, P, "p0"),
            model.check_scalings(q0, Q, "q0"),
            model.check_scalings(r0, R, "r0"),
            _start_gains(mu0, S, "mu0", "output_gain"),
            _start_gains(nu0, T, "nu0", "input_gain"),
        ]
    )
    for name, start in (("p0", x0[:P]), ("q0", x0[P : P + Q])):
        if np.any(start <= 0):
            raise FieldError(
                name, f"must be > 0 (a substructure's stiffness or mass is scaled), got {start}"
            )
    names = (
        [f"p[{k}]" for k in range(P)]
        + [f"q[{k}]" for k in range(Q)]
        + [f"r[{k}]" for k in range(R)]
        + [f"mu[{k}]" for k in range(S)]
        + [f"nu[{k}]" for k in range(T)]
    )
    held = []
    for name, fixed, count, offset, kind in (
        ("fixed_stiffness", fixed_stiffness, P, 0, "block"),
        ("fixed_mass", fixed_mass, Q, P, "block"),
        ("fixed_damping", fixed_damping, R, P + Q, "block"),
        ("fixed_output_gains", fixed_output_gains, S, G, "gain"),
        ("fixed_input_gains", fixed_input_gains, T, G + S, "gain"),
    ):
        idx = np.asarray(fixed).ravel()
        if isinstance(fixed, (str, bytes)) or (
            idx.size and (idx.dtype.kind not in "iu" or np.any(idx < 0) or np.any(idx >= count))
        ):
            raise FieldError(name, f"must be {kind} indices in [0, {count})")
        held += (offset + idx.astype(int)).tolist()
    free = np.setdiff1d(np.arange(x0.size), held)
    if free.size == 0:
        raise FieldError(
            "fixed_stiffness",
            "every parameter is held (with fixed_mass, fixed_damping, fixed_output_gains "
            "and fixed_input_gains): nothing to correct",
        )
    free_gains = free[free >= G]
    sd_prior = None
    if prior_sigma is not None:
        s = require_numeric(prior_sigma, "prior_sigma")
        if s.ndim > 1 or (s.ndim == 1 and s.size != x0.size) or np.any(s <= 0):
            raise FieldError("prior_sigma", f"must be a scalar or {x0.size} values, > 0")
        sd_prior = np.broadcast_to(s, x0.shape)[free]
    measured, sd = data.measured, data.sigma
    if sd_prior is None and measured.size < free.size:
        raise FieldError(
            "data",
            f"{measured.size} measurements for {free.size} free parameters: "
            "more parameters than data; add measurements, hold parameters, or give "
            "prior_sigma (0_p)",
        )

    def evaluate(x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        calc, A = data.predict(model, x[:P], x[P : P + Q], x[P + Q : G], x[G : G + S], x[G + S :])
        res = (measured - calc) / sd
        rows = A[:, free] / sd[:, None]
        if sd_prior is not None:
            res = np.concatenate([res, (x0 - x)[free] / sd_prior])
            rows = np.vstack([rows, np.diag(1.0 / sd_prior)])
        return res, rows, measured - calc

    x = x0.copy()
    res, rows, dQ = evaluate(x)
    history, converged, it = [float(res @ res)], False, 0
    through_zero: list[str] = []  # gains that the last iteration's refused trials took to <= 0
    while it < n_iter:
        through_zero = []
        # column-normalised SVD: the rank test does not depend on the parameters' units
        scale = np.linalg.norm(rows, axis=0)
        if np.any(scale == 0):
            bad = [names[k] for k in free[scale == 0]]
            raise FieldError("data", f"{bad} do not affect any measurement; hold them or add data")
        U, s, Vt = np.linalg.svd(rows / scale, full_matrices=False)
        if s[-1] < 1e-8 * s[0]:
            v = Vt[-1] / scale
            v /= np.abs(v).max()
            combo = " + ".join(f"{c:.2f} {names[k]}" for c, k in zip(v, free) if abs(c) > 0.05)
            raise FieldError(
                "data",
                "the parameters are not identifiable from these measurements "
                f"(condition number {s[0] / max(s[-1], 1e-300):.2g}; changing "
                f"{combo} leaves them unchanged); add FRF data (the absolute "
                "scale; with gains free, items from calibrated sensors or inputs, "
                "gain None), hold parameters, or give prior_sigma (0_p)",
            )
        step = (Vt.T @ ((U.T @ res) / s)) / scale
        if np.abs(step).max() < tol:
            converged = True
            break
        t = 1.0
        for _ in range(30):
            trial = x.copy()
            trial[free] += t * step
            found = None
            if np.any(trial[free_gains] <= 0):
                # a gain's sign is fixed by its a-priori H row / B column: outside the model
                through_zero = [names[k] for k in free_gains if trial[k] <= 0]
            else:
                try:
                    found = evaluate(trial)
                except ValueError:  # K or M indefinite at the trial point: shorten the step
                    pass
            # round-off margin: at the minimum a full step may not lower the cost exactly
            if found is not None and found[0] @ found[0] <= history[-1] * (1.0 + 1e-12):
                break
            t *= 0.5
        else:
            # no shorter step lowers the cost: a minimum to round-off if the Gauss-Newton
            # step is below 1e-3 of its own standard deviation (predicted decrease < 1e-6)
            converged = float(np.sum((U.T @ res) ** 2)) < 1e-6
            break
        x, it = trial, it + 1
        res, rows, dQ = found
        history.append(float(res @ res))
        if t * np.abs(step).max() < tol:
            converged = True
            break
    if through_zero:
        # the last steps were cut short at zero: the fit creeps toward a gain of 0, where the
        # data want the opposite sign (a near-interior minimum's steps never reach zero)
        raise ValueError(
            f"{', '.join(through_zero)}: the data want a gain <= 0 (steps there "
            f"refused; {x[names.index(through_zero[0])]:.3g} after {it} steps): check "
            "the sign of its H row / B column, or start nearer"
        )
    cov = np.zeros((x0.size, x0.size))
    cov[np.ix_(free, free)] = np.linalg.inv(rows.T @ rows)
    p, q, r = x[:P], x[P : P + Q], x[P + Q : G]
    return DifferentialCorrection(
        model.scaled(p, q, r), p, q, r, x[G : G + S], x[G + S :], cov, history, dQ, it, converged
    )
