"""A dispersed batch of hub + appendage plants, built and propagated as arrays.

A Monte Carlo over the hub inertia, the appendages' bending stiffness EI or their tip bodies
(issue 22) needs one :class:`~flexsat.dynamics.hub_appendage.HubAppendage` per case: the
exact cantilever modes (a transcendental frequency equation per case), their Galerkin
integrals and the second-order matrices

    M_c = [[I_tot,c, n d_cᵀ], [n d_c, n 1]],   K_c = diag(0, n ω_c²),   D_c = diag(0, 2 n ζ_c ω_c)

(Junkins, Rahman & Bang, Att. 3 of Junkins, Pollock & Rahman 1990, Eqs. 5-7; the module
docstring of :mod:`flexsat.dynamics.hub_appendage`). :class:`DispersedHubAppendage` computes
them for every case at once: the roots and modes by
:func:`~flexsat.structures.beam.cantilever_modes_batch`, the integrals by one Gauss–Legendre
rule applied to an (n_cases, k, points) array, the matrices, the first-order form and the
output rows as stacked arrays. Case c equals ``HubAppendage(params_c)`` (its roots agree with
the scalar solver's to a few ulps, tested at 1e-12), and a case gives the same bits in any
batch (every operation is elementwise or one LAPACK/BLAS call per case), so a chunk of one
case, of seven or of the whole table runs the same numbers.

It is a :class:`~flexsat.dynamics.dispersion.DispersedPlant` (the engine propagates each case
with its own propagators) that also states, per case, what the compiled loop needs of a
hybrid plant: the matrices M_c, K_c, D_c (whence each case's modal coordinates,
:func:`flexsat.sim.compiled.modal_form`), the energy matrix Q_c = blockdiag(K_c, M_c), the
momentum row and the rigid inertia. With those a sweep's chunk runs the metrics-only loop
(:func:`flexsat.sim.compiled.run_reduced`) in each case's modal coordinates, O(n) per step,
as a shared plant does. ``plants[c]`` is the case's own :class:`HubAppendage`, made on first
use from the batch's integrals.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from functools import cached_property
from typing import TYPE_CHECKING, overload

import numpy as np

from flexsat.dynamics.dispersion import DispersedPlant
from flexsat.dynamics.hub_appendage import (
    HubAppendage,
    HubAppendageParams,
    ModalIntegrals,
    gauss_legendre,
)
from flexsat.input_checks import FieldError, require_count, require_nonneg
from flexsat.structures.beam import (
    CantileverModes,
    CantileverModesBatch,
    cantilever_modes_batch,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

#: the physical fields of :class:`HubAppendageParams` that may differ from case to case
CASE_FIELDS = ("hub_inertia", "hub_radius", "length", "EI", "rho", "tip_mass", "tip_inertia")


class DispersedHubAppendage(DispersedPlant):
    """Hub + appendage plants, one per case, as one batch (module docstring).

    Build it with :meth:`from_parameters` (the cases' parameters as arrays: the fast route)
    or :meth:`from_plants` (plants already built; what
    :func:`~flexsat.dynamics.dispersion.stack_plants` does with hub + appendage plants).

    Attributes
    ----------
    cases : dict of str to ndarray
        Each field of :data:`CASE_FIELDS` per case, (n_cases,), SI.
    damping : ndarray, shape (n_cases, n_modes)
        Modal damping ratios.
    omega, d, e, phi_tip : ndarray, shape (n_cases, n_modes)
        Cantilever frequencies (rad/s), rigid-elastic coupling (kg m), shear coupling (kg) and
        tip mode values of one appendage per case.
    G : ndarray, shape (n_cases, n_modes, n_modes)
        Rotational-stiffening matrices.
    """

    def __init__(
        self,
        cases: dict[str, FloatArray],
        n_appendages: int,
        n_modes: int,
        stiffening: bool,
        damping: FloatArray,
        integrals: dict[str, FloatArray],
        modes: Sequence[CantileverModes] | None = None,
        plants: Sequence[HubAppendage] | None = None,
    ) -> None:
        self.cases = cases
        self.n_appendages = require_count(n_appendages, "n_appendages")
        self.n_modes = require_count(n_modes, "n_modes")
        self.stiffening = bool(stiffening)
        self.damping = damping
        self.omega, self.d, self.e = integrals["omega"], integrals["d"], integrals["e"]
        self.phi_tip, self.G = integrals["phi_tip"], integrals["G"]
        self._n = int(damping.shape[0])
        self._modes = modes
        # a lazy sequence of the cases' plants where none were given
        self.plants = _CasePlants(self) if plants is None else tuple(plants)  # type: ignore[assignment]
        self.inputs = tuple(HubAppendage.inputs)
        self.outputs = tuple(HubAppendage.output_channels)
        self.recorded = tuple(HubAppendage.recorded)
        self.maneuver = HubAppendage.maneuver
        self.noise_channels = tuple(HubAppendage._noise_channels)
        self.nonlinear = self.stiffening
        self.integrator = "etd2rk"
        self.recorded_measurements = tuple(HubAppendage.recorded_measurements)
        self.recorded_disturbances = tuple(HubAppendage.recorded_disturbances)
        A, B = self._linear
        bad = np.flatnonzero(~(np.isfinite(A).all(axis=(1, 2)) & np.isfinite(B).all(axis=(1, 2))))
        if bad.size:
            raise FieldError(
                "A",
                f"case {int(bad[0])} has a non-finite entry in its linear part; check its "
                "dispersed parameters",
            )

    # -- construction --------------------------------------------------------------------------
    @classmethod
    def from_parameters(
        cls,
        params: HubAppendageParams,
        n_modes: int = 10,
        stiffening: bool = False,
        damping: npt.ArrayLike | None = None,
    ) -> DispersedHubAppendage:
        """The batch whose case c has the parameters ``params`` with every array field at its
        entry c (the fields of :data:`CASE_FIELDS` take (n_cases,) arrays; the others are
        shared).

        Parameters
        ----------
        params : HubAppendageParams
            Scalars shared by every case, or (n_cases,) arrays (their rules apply per entry).
        n_modes : int
            Cantilever modes per appendage.
        stiffening : bool
            The rotational-stiffening term (a nonlinear plant).
        damping : array_like, optional
            Modal damping ratios in place of ``params.damping``: one for every case and mode,
            (n_cases,) (every mode of a case) or (n_cases, n_modes).

        Raises
        ------
        ValueError
            Naming the field: arrays of different lengths, a rule of the parameters.
        """
        k = require_count(n_modes, "n_modes")
        raw = {f: np.atleast_1d(np.asarray(getattr(params, f), float)) for f in CASE_FIELDS}
        for f, v in raw.items():
            if v.ndim != 1:
                raise FieldError(f, f"give a number or one per case (n_cases,), got {v.shape}")
        n = max(v.size for v in raw.values())
        if damping is not None:
            zeta = require_nonneg(damping, "damping")
            n = max(n, zeta.shape[0] if zeta.ndim else 1)
        for f, v in raw.items():
            if v.size not in (1, n):
                raise FieldError(f, f"has {v.size} values, other fields {n}: one per case")
        cases = {f: np.ascontiguousarray(np.broadcast_to(v, (n,))) for f, v in raw.items()}
        if damping is None:
            zeta = np.atleast_1d(np.asarray(params.damping, float))
            if zeta.size not in (1, k):
                raise FieldError(
                    "damping", f"give one ratio or one per mode ({k}), got {zeta.size}"
                )
            zeta = np.broadcast_to(zeta, (n, k))
        else:
            zeta = np.asarray(zeta, float)
            zeta = (
                zeta.reshape(1, 1) if zeta.ndim == 0 else zeta[:, None] if zeta.ndim == 1 else zeta
            )
            if zeta.ndim != 2 or zeta.shape[0] not in (1, n) or zeta.shape[1] not in (1, k):
                raise FieldError(
                    "damping",
                    f"give (n_cases,) = ({n},) or (n_cases, n_modes) = ({n}, {k}) ratios, "
                    f"got shape {np.shape(damping)}",
                )
            zeta = np.broadcast_to(zeta, (n, k))
        modes = cantilever_modes_batch(
            cases["length"], cases["EI"], cases["rho"], cases["tip_mass"], cases["tip_inertia"], k
        )
        integrals = _modal_integrals(cases, params.n_appendages, modes, stiffening)
        per_case = [
            CantileverModes(
                float(modes.length[c]), modes.betas[c], modes.omegas[c], modes.coefficients[c]
            )
            for c in range(n)
        ]
        return cls(
            cases, params.n_appendages, k, stiffening, np.array(zeta), integrals, per_case, None
        )

    @classmethod
    def from_plants(cls, plants: Sequence[HubAppendage]) -> DispersedHubAppendage:
        """The batch of hub + appendage plants already built: their parameters and integrals
        stacked (no modes recomputed); ``plants`` are its cases.

        Raises
        ------
        ValueError
            Naming the field when the plants differ in n_modes, stiffening or n_appendages.
        """
        plants = tuple(plants)
        first = plants[0]
        for i, p in enumerate(plants):
            if not isinstance(p, HubAppendage):
                raise FieldError("plants", f"plants[{i}] is not a HubAppendage")
            for name, a, b in (
                ("n_modes", p.n_modes, first.n_modes),
                ("stiffening", p.stiffening, first.stiffening),
                ("n_appendages", p.params.n_appendages, first.params.n_appendages),
            ):
                if a != b:
                    raise FieldError(name, f"plants[{i}] has {name} {a!r}, plants[0] {b!r}")
        cases = {f: np.array([getattr(p.params, f) for p in plants], float) for f in CASE_FIELDS}
        quad = [p.modal_integrals for p in plants]
        integrals = {
            name: np.stack([np.asarray(q[name], float) for q in quad])
            for name in ("omega", "d", "e", "phi_tip", "G")
        }
        zeta = np.stack([p.damping_ratios for p in plants])
        return cls(
            cases,
            first.params.n_appendages,
            first.n_modes,
            first.stiffening,
            zeta,
            integrals,
            [q["modes"] for q in quad],
            plants,
        )

    def case_params(self, c: int) -> HubAppendageParams:
        """The parameters of case c."""
        values = {f: float(self.cases[f][c]) for f in CASE_FIELDS}
        zeta = self.damping[c]
        return HubAppendageParams(
            n_appendages=self.n_appendages,
            damping=float(zeta[0]) if np.all(zeta == zeta[0]) else tuple(zeta.tolist()),
            **values,
        )

    def case_integrals(self, c: int) -> ModalIntegrals:
        """The Galerkin integrals of case c (those of :class:`HubAppendage`)."""
        if self._modes is None:  # pragma: no cover - both constructors give the modes
            raise FieldError("modes", "this batch keeps no mode shapes")
        G = self.G[c]
        if np.isnan(G).any():  # a batch without stiffening: its G is computed when asked
            mode = self._modes[c]
            one = CantileverModesBatch(
                np.array([mode.length]),
                mode.betas[None],
                mode.omegas[None],
                mode.coefficients[None],
            )
            G = _stiffening_matrices(
                {f: v[c : c + 1] for f, v in self.cases.items()}, self.n_appendages, one
            )[0]
        return ModalIntegrals(
            modes=self._modes[c],
            omega=self.omega[c],
            d=self.d[c],
            e=self.e[c],
            phi_tip=self.phi_tip[c],
            G=G,
        )

    # -- second-order model, per case ---------------------------------------------------------
    @property
    def n_cases(self) -> int:
        return self._n

    @property
    def nx(self) -> int:
        return 2 * (self.n_modes + 1)

    @property
    def ndof(self) -> int:
        return self.n_modes + 1

    @cached_property
    def appendage_inertia(self) -> FloatArray:
        """Rigid inertia I_b of one appendage per case, kg m² (n_cases,)."""
        c = self.cases
        l0, l = c["hub_radius"], c["hub_radius"] + c["length"]
        return c["rho"] * (l**3 - l0**3) / 3 + c["tip_mass"] * l**2 + c["tip_inertia"]

    @cached_property
    def total_inertia(self) -> FloatArray:
        """Rigid inertia of each vehicle, I_hub + n I_b, kg m² (n_cases,)."""
        return self.cases["hub_inertia"] + self.n_appendages * self.appendage_inertia

    @property
    def hub_inertia(self) -> FloatArray:
        return self.cases["hub_inertia"]

    @cached_property
    def mass_matrix(self) -> FloatArray:
        n, k = self.n_appendages, self.n_modes
        M = np.zeros((self._n, k + 1, k + 1))
        M[:, 0, 0] = self.total_inertia
        M[:, 0, 1:] = M[:, 1:, 0] = n * self.d
        M[:, 1:, 1:] = n * np.eye(k)
        return M

    @cached_property
    def stiffness_matrix(self) -> FloatArray:
        K = np.zeros((self._n, self.ndof, self.ndof))
        i = np.arange(1, self.ndof)
        K[:, i, i] = self.n_appendages * self.omega**2
        return K

    @cached_property
    def damping_matrix(self) -> FloatArray:
        D = np.zeros((self._n, self.ndof, self.ndof))
        i = np.arange(1, self.ndof)
        D[:, i, i] = 2 * self.n_appendages * self.damping * self.omega
        return D

    @cached_property
    def mass_inverse(self) -> FloatArray:
        return np.linalg.inv(self.mass_matrix).astype(np.float64, copy=False)

    @cached_property
    def _linear(self) -> tuple[FloatArray, FloatArray]:
        """x' = A x + B u per case: A = [[0, 1], [−M⁻¹K, −M⁻¹D]], B = [0; M⁻¹ e_θ]."""
        k1, Minv = self.ndof, self.mass_inverse
        A = np.zeros((self._n, 2 * k1, 2 * k1))
        A[:, :k1, k1:] = np.eye(k1)
        A[:, k1:, :k1] = -Minv @ self.stiffness_matrix
        A[:, k1:, k1:] = -Minv @ self.damping_matrix
        B = np.zeros((self._n, 2 * k1, 1))
        B[:, k1:, 0] = Minv[:, :, 0]
        return A, B

    @cached_property
    def force_matrix(self) -> FloatArray | None:
        """B_f = [0; M⁻¹] per case with the stiffening on, else None."""
        if not self.stiffening:
            return None
        Bf = np.zeros((self._n, self.nx, self.ndof))
        Bf[:, self.ndof :] = self.mass_inverse
        return Bf

    # -- outputs ------------------------------------------------------------------------------
    def _output_coefficients(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray, float]:
        """(c_pos, c_vel, c_acc, c_u) per case (n_cases, ndof): those of
        :meth:`HubAppendage._output_coefficients` (root loads by force summation)."""
        c, nc, k1 = self.cases, self._n, self.ndof
        z = np.zeros((nc, k1))
        e0 = np.zeros((nc, k1))
        e0[:, 0] = 1.0
        l0, l = c["hub_radius"], c["hub_radius"] + c["length"]
        moment = np.concatenate([self.appendage_inertia[:, None], self.d], axis=1)
        shear0 = c["rho"] * (l**2 - l0**2) / 2 + c["tip_mass"] * l
        shear = np.concatenate([shear0[:, None], self.e], axis=1)
        table = {
            "theta": (e0, z, z),
            "theta_dot": (z, e0, z),
            "root_torque": (z, z, moment),
            "root_shear": (z, z, shear),
            "root_moment": (z, z, l0[:, None] * shear - moment),
            "tip_deflection": (np.concatenate([np.zeros((nc, 1)), self.phi_tip], axis=1), z, z),
        }
        if name not in table:
            raise FieldError(name, f"{type(self).__name__} has no output channel {name!r}")
        return (*table[name], 0.0)

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """(C, D, D_f) per case, (n_cases, 1, n_x), (n_cases, 1, 1) twice: y = c_p·pos +
        c_v·vel + c_a·acc with acc = A[ndof:] x + B[ndof:] (u + f_in); None for an
        acceleration output with the stiffening on (:meth:`HybridPlant.output_matrices`)."""
        c_pos, c_vel, c_acc, c_u = self._output_coefficients(name)
        if self.stiffening and np.any(c_acc):
            return None
        A, B = self._linear
        k1 = self.ndof
        C = np.concatenate([c_pos, c_vel], axis=1)[:, None, :] + c_acc[:, None, :] @ A[:, k1:]
        D = c_acc[:, None, :] @ B[:, k1:] + c_u
        return C, D, D.copy()

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        """Output ``name`` per case, x (..., n_cases, n_x), u and f_in (..., n_cases, 1)."""
        mats = self.output_matrices(name)
        if mats is None:
            return super().output(name, x, u, f_in)
        C, D, Df = mats
        y = np.einsum("...ci,ci->...c", x, C[:, 0]) + u[..., 0] * D[:, 0, 0]
        if f_in is not None and Df is not None:
            y = y + f_in[..., 0] * Df[:, 0, 0]
        return y

    # -- energies -----------------------------------------------------------------------------
    def _split(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        return x[..., : self.ndof], x[..., self.ndof :]

    def _stiffening_quadratic(self, pos: FloatArray) -> FloatArray:
        """s = qᵀ G q per case (the stiffening's inertia term), (..., n_cases)."""
        q = pos[..., 1:]
        return np.einsum("...ci,...ci->...c", np.einsum("...ci,cij->...cj", q, self.G), q)

    def energy(self, x: FloatArray) -> FloatArray:
        """Total mechanical energy per case (:meth:`HubAppendage.energy`), J, (..., n_cases)."""
        pos, vel = self._split(x)
        E = 0.5 * np.einsum(
            "...ci,...ci->...c", np.einsum("...ci,cij->...cj", vel, self.mass_matrix), vel
        )
        E = E + 0.5 * np.einsum(
            "...ci,...ci->...c", np.einsum("...ci,cij->...cj", pos, self.stiffness_matrix), pos
        )
        if self.stiffening:
            E = E + 0.5 * vel[..., 0] ** 2 * self._stiffening_quadratic(pos)
        return E

    def momentum(self, x: FloatArray) -> FloatArray:
        """Angular momentum about the hub axis per case (:meth:`HubAppendage.momentum`)."""
        pos, vel = self._split(x)
        h = np.einsum("...ci,ci->...c", vel, self.mass_matrix[:, 0])
        if self.stiffening:
            h = h + vel[..., 0] * self._stiffening_quadratic(pos)
        return h

    def vibration_energy(self, x: FloatArray, energy: FloatArray | None = None) -> FloatArray:
        """E − h² / (2 I_tot) per case (:meth:`HybridPlant.vibration_energy`), J."""
        _, vel = self._split(x)
        h = np.einsum("...ci,ci->...c", vel, self.mass_matrix[:, 0])
        E = self.energy(x) if energy is None else energy
        return E - 0.5 * h**2 / self.total_inertia

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """dE/dt = θ' u − x'ᵀ D x' per case (:meth:`HybridPlant.power`), W."""
        _, vel = self._split(x)
        Dv = np.einsum("...ci,cij->...cj", vel, self.damping_matrix)
        return vel[..., 0] * np.asarray(u, float)[..., 0] - np.einsum("...ci,...ci->...c", Dv, vel)

    @cached_property
    def energy_matrix(self) -> FloatArray | None:  # type: ignore[override]
        """Q_c = blockdiag(K_c, M_c) per case, (n_cases, n_x, n_x); None with the stiffening."""
        if self.stiffening:
            return None
        k1 = self.ndof
        Q = np.zeros((self._n, 2 * k1, 2 * k1))
        Q[:, :k1, :k1], Q[:, k1:, k1:] = self.stiffness_matrix, self.mass_matrix
        return Q

    @cached_property
    def momentum_row(self) -> FloatArray:
        """Row r_c of h = r_c · x per case, [0, M_c[0]], (n_cases, n_x)."""
        return np.concatenate([np.zeros((self._n, self.ndof)), self.mass_matrix[:, 0]], axis=1)

    def initial_state(self, n_cases: int) -> FloatArray:
        return np.zeros((self._n, self.nx))


class _CasePlants(Sequence[HubAppendage]):
    """``plants`` of a batch built from parameters: case c's :class:`HubAppendage`, made on
    first use from the batch's integrals and kept."""

    def __init__(self, batch: DispersedHubAppendage) -> None:
        self._batch = batch
        self._made: dict[int, HubAppendage] = {}

    def __len__(self) -> int:
        return self._batch.n_cases

    @overload
    def __getitem__(self, i: int) -> HubAppendage: ...
    @overload
    def __getitem__(self, i: slice) -> Sequence[HubAppendage]: ...
    def __getitem__(self, i: int | slice) -> HubAppendage | Sequence[HubAppendage]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        n = len(self)
        if not -n <= i < n:
            raise IndexError(i)
        i %= n
        if i not in self._made:
            b = self._batch
            self._made[i] = HubAppendage.from_modal_integrals(
                b.case_params(i), b.case_integrals(i), b.n_modes, b.stiffening
            )
        return self._made[i]

    def __iter__(self) -> Iterator[HubAppendage]:
        return (self[i] for i in range(len(self)))


def _modal_integrals(
    cases: dict[str, FloatArray], n_appendages: int, modes: CantileverModesBatch, stiffening: bool
) -> dict[str, FloatArray]:
    r"""The Galerkin integrals of :meth:`HubAppendage._modal_integrals` for every case.

    The couplings in closed form: with u = βξ, z = βL, E = e^{−z}, c = cos z, s = sin z the
    basis g = (e^{−u}, e^{−(z−u)}, cos u, sin u) of :class:`~flexsat.structures.beam.
    CantileverModes` integrates to

    .. math::

        \int_0^L g\,d\xi = \frac{1}{\beta}(1 - E,\ 1 - E,\ s,\ 1 - c),\qquad
        \int_0^L \xi g\,d\xi = \frac{1}{\beta^2}(1 - (1 + z)E,\ z - 1 + E,\
            z s + c - 1,\ s - z c),

    so e = ρ a·∫g + m φ(L) and d = ρ (l0 a·∫g + a·∫ξg) + m l φ(L) + J φ'(L) cost no
    quadrature (the scalar model's Gauss rule of max(200, 24 k) points integrates these
    smooth functions to round-off: the two agree to ~1e-15 relative, tested at 1e-12). The
    stiffening matrices G (products of two modes) by that Gauss rule, only for a stiffening
    batch (:func:`_stiffening_matrices`); NaN otherwise (a case's own plant computes its G
    when asked, :meth:`DispersedHubAppendage.case_integrals`).
    """
    z = modes.betas * modes.length[:, None]
    b = modes.betas
    E, c, s = np.exp(-z), np.cos(z), np.sin(z)
    integral = np.stack([1.0 - E, 1.0 - E, s, 1.0 - c], -1) / b[..., None]
    moment = np.stack([1.0 - (1.0 + z) * E, z - 1.0 + E, z * s + c - 1.0, s - z * c], -1)
    moment = moment / (b * b)[..., None]
    a = modes.coefficients
    rho, m, J = cases["rho"][:, None], cases["tip_mass"][:, None], cases["tip_inertia"][:, None]
    l0 = cases["hub_radius"][:, None]
    l = l0 + cases["length"][:, None]
    phi_l = (a * np.stack([E, np.ones_like(z), c, s], -1)).sum(-1)
    dphi_l = b * (a * np.stack([-E, np.ones_like(z), -s, c], -1)).sum(-1)
    area, first = (a * integral).sum(-1), (a * moment).sum(-1)
    d = rho * (l0 * area + first) + m * l * phi_l + J * dphi_l
    e = rho * area + m * phi_l
    G = (
        _stiffening_matrices(cases, n_appendages, modes)
        if stiffening
        else np.full(z.shape + z.shape[-1:], np.nan)
    )
    return {"omega": modes.omegas, "d": d, "e": e, "phi_tip": phi_l, "G": G}


def _stiffening_matrices(
    cases: dict[str, FloatArray], n_appendages: int, modes: CantileverModesBatch
) -> FloatArray:
    """G = n (M_s − K_g) per case (:mod:`flexsat.dynamics.hub_appendage`), by the Gauss rule of
    :meth:`HubAppendage._modal_integrals`, (n_cases, k, k)."""
    k = modes.betas.shape[1]
    s, w = gauss_legendre(max(200, 24 * k))
    station = 0.5 * (s + 1.0)  # ξ / L
    L = cases["length"][:, None]
    weight = 0.5 * L * w  # (n, p)
    x = cases["hub_radius"][:, None] + L * station
    l = (cases["hub_radius"] + cases["length"])[:, None]
    rho, m = cases["rho"][:, None], cases["tip_mass"][:, None]
    phi, dphi = modes.evaluate(station, 0), modes.evaluate(station, 1)  # (n, k, p)
    phi_l = modes.evaluate(np.ones(1), 0)[..., 0]
    spin = rho[..., None] * ((phi * weight[:, None, :]) @ phi.swapaxes(-1, -2))
    spin = spin + m[..., None] * phi_l[:, :, None] * phi_l[:, None, :]
    tension = rho * (l**2 - x**2) / 2 + m * l
    geometric = (dphi * (weight * tension)[:, None, :]) @ dphi.swapaxes(-1, -2)
    return n_appendages * (spin - geometric)


__all__ = ["CASE_FIELDS", "DispersedHubAppendage"]
