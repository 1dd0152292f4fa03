r"""Second-order structural models, the common currency of the control designs (like MATLAB's
``mechss``).

A :class:`SecondOrderModel` is

.. math::

    M \ddot q + D \dot q + K q = B u, \qquad y = C_q q + C_v \dot q + D_{ff} u,

with M symmetric positive definite, K symmetric positive semi-definite (rigid modes allowed)
and D any real square matrix (proportional, general, or gyroscopic damping). The first-order
realisation uses the state :math:`x = [q, \dot q]`:

.. math::

    A = \begin{bmatrix} 0 & I \\ -M^{-1} K & -M^{-1} D \end{bmatrix}, \quad
    B_x = \begin{bmatrix} 0 \\ M^{-1} B \end{bmatrix}, \quad C_x = [C_q \;\; C_v], \quad
    D_x = D_{ff}.

The models of issues #2 and #3 convert to it: :meth:`SecondOrderModel.from_hub_appendage`
(the hub + appendage assumed-modes model), :meth:`SecondOrderModel.from_modal_model` (a free or
cantilevered :class:`~flexsat.structures.modal_model.ModalModel` with chosen inputs and
outputs) and :meth:`SecondOrderModel.from_hybrid` (a cantilevered ModalModel on a rigid hub,
the hybrid coordinates of the NPS simulator, Hailey, Sortun & Agrawal c. 1992 Eqs. 10, 16).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeAlias

import numpy as np
import scipy.linalg

from flexsat.input_checks import FieldError, require_count, require_finite, require_positive
from flexsat.structures.modal_model import hub_appendage_matrices

if TYPE_CHECKING:
    import numpy.typing as npt

    import control
    from flexsat.dynamics.hub_appendage import HubAppendage
    from flexsat.structures.modal_model import ModalModel, Output
    from flexsat.units import FloatArray, QuantityLike

    #: a continuous python-control ``StateSpace`` or its matrices (A, B, C, D)
    StateSpaceLike: TypeAlias = control.StateSpace | tuple[npt.ArrayLike, ...] | list[npt.ArrayLike]

__all__ = ["SecondOrderModel"]

#: relative tolerance of the symmetry and definiteness checks (roundoff of assembled or
#: transformed matrices is ~1e-14)
SYMMETRY_TOL = 1e-9


def rigid_eigenvalue_bound(lam: FloatArray) -> float:
    """Largest |λ| of eig(K, M) that is round-off of a rigid (λ = 0) mode.

    A backward-stable symmetric-definite solve perturbs each eigenvalue by about
    n·ε·λ_max (Golub & Van Loan, §8.7); a factor 100 covers the assembly of K and M. A fixed
    relative threshold (1e-9 λ_max) would take real elastic modes of a stiff finite-element
    model for rigid ones: the Agrawal–Bang FE model has λ_max = 4.9e11 and modes at 6.6 rad/s
    (λ = 44 > 1e-9 λ_max = 490 is false).
    """
    lam = np.asarray(lam, float)
    return (
        100.0 * max(lam.size, 1) * np.finfo(float).eps * max(np.abs(lam).max(initial=0.0), 1e-300)
    )


def _matrix(
    value: npt.ArrayLike, field: str, shape: tuple[int | None, int | None], names: str
) -> FloatArray:
    arr = require_finite(value, field)
    if arr.ndim == 1:  # a vector: one column (length n) or one row (length of the columns)
        if shape[0] is not None and arr.size == shape[0] and shape[1] in (None, 1):
            arr = arr[:, None]
        elif shape[1] is not None and arr.size == shape[1]:
            arr = arr[None, :]
    if arr.ndim != 2 or any(s is not None and a != s for a, s in zip(arr.shape, shape)):
        want = tuple("?" if s is None else s for s in shape)
        raise FieldError(field, f"must have shape {names} = {want}, got {np.shape(value)}")
    return arr.copy()


def _symmetric(arr: FloatArray, field: str) -> FloatArray:
    scale = max(np.abs(arr).max(initial=0.0), np.finfo(float).tiny)
    if np.abs(arr - arr.T).max(initial=0.0) > SYMMETRY_TOL * scale:
        raise FieldError(
            field,
            f"must be symmetric (max |{field} − {field}ᵀ| = "
            f"{np.abs(arr - arr.T).max():.3g}, max |{field}| = {scale:.3g})",
        )
    return 0.5 * (arr + arr.T)


@dataclass(frozen=True, eq=False, repr=False, init=False)
class SecondOrderModel:
    r"""Linear second-order model :math:`M\ddot q + D\dot q + Kq = Bu`,
    :math:`y = C_q q + C_v \dot q + D_{ff} u`.

    Parameters
    ----------
    M : array_like (n, n)
        Mass matrix, symmetric positive definite.
    D : array_like (n, n)
        Damping matrix (any real square matrix; symmetric for viscous damping).
    K : array_like (n, n)
        Stiffness matrix, symmetric positive semi-definite.
    B : array_like (n, m) or (n,)
        Input (generalized-force) matrix.
    Cq : array_like (p, n)
        Displacement output matrix.
    Cv : array_like (p, n), optional
        Velocity output matrix (default zero).
    Dff : array_like (p, m), optional
        Feedthrough (default zero).

    Notes
    -----
    The attributes are the checked matrices as read-only float arrays (``Cv`` and ``Dff`` the
    zero matrices when not given).

    Raises
    ------
    ValueError
        Message starting with the field name: non-finite entries, wrong shapes, M not symmetric
        positive definite, K not symmetric positive semi-definite.
    """

    M: FloatArray
    D: FloatArray
    K: FloatArray
    B: FloatArray
    Cq: FloatArray
    Cv: FloatArray
    Dff: FloatArray

    # the matrices arrive as any array_like and are stored checked: an explicit __init__ keeps
    # the attributes' types (FloatArray) apart from the parameters' (array_like, Cv/Dff None)
    def __init__(
        self,
        M: npt.ArrayLike,
        D: npt.ArrayLike,
        K: npt.ArrayLike,
        B: npt.ArrayLike,
        Cq: npt.ArrayLike,
        Cv: npt.ArrayLike | None = None,
        Dff: npt.ArrayLike | None = None,
    ) -> None:
        M = _matrix(M, "M", (None, None), "(n, n)")
        n = M.shape[0]
        if M.shape != (n, n) or n == 0:
            raise FieldError("M", f"must be a non-empty square matrix, got shape {M.shape}")
        M = _symmetric(M, "M")
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            raise FieldError(
                "M",
                "must be positive definite (smallest eigenvalue "
                f"{np.linalg.eigvalsh(M).min():.3g})",
            ) from None
        D = _matrix(D, "D", (n, n), "(n, n)")
        K = _symmetric(_matrix(K, "K", (n, n), "(n, n)"), "K")
        lam = np.linalg.eigvalsh(K)
        if lam.min(initial=0.0) < -SYMMETRY_TOL * max(np.abs(lam).max(initial=0.0), 1e-300):
            raise FieldError(
                "K", f"must be positive semi-definite (smallest eigenvalue {lam.min():.3g})"
            )
        B = _matrix(B, "B", (n, None), "(n, m)")
        Cq = _matrix(Cq, "Cq", (None, n), "(p, n)")
        p, m = Cq.shape[0], B.shape[1]
        Cv = np.zeros((p, n)) if Cv is None else _matrix(Cv, "Cv", (p, n), "(p, n)")
        Dff = np.zeros((p, m)) if Dff is None else _matrix(Dff, "Dff", (p, m), "(p, m)")
        for name, value in dict(M=M, D=D, K=K, B=B, Cq=Cq, Cv=Cv, Dff=Dff).items():
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        return (
            f"SecondOrderModel(n_dof={self.n_dof}, n_inputs={self.n_inputs}, "
            f"n_outputs={self.n_outputs})"
        )

    # ------------------------------------------------------------------------------------------
    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    @property
    def n_states(self) -> int:
        return 2 * self.n_dof

    @property
    def n_inputs(self) -> int:
        return self.B.shape[1]

    @property
    def n_outputs(self) -> int:
        return self.Cq.shape[0]

    def _replace(self, **changes: FloatArray) -> SecondOrderModel:
        fields = dict(M=self.M, D=self.D, K=self.K, B=self.B, Cq=self.Cq, Cv=self.Cv, Dff=self.Dff)
        fields.update(changes)
        return SecondOrderModel(**fields)

    # ------------------------------------------------------------------------------------------
    # first-order form
    def first_order(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""(A, B, C, D) of the realisation with state :math:`x = [q, \dot q]` (module docstring);
        :math:`M^{-1}` is applied by a Cholesky solve."""
        n = self.n_dof
        cho = scipy.linalg.cho_factor(self.M)
        rhs = scipy.linalg.cho_solve(cho, np.hstack([self.K, self.D, self.B]))
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -rhs[:, :n]
        A[n:, n:] = -rhs[:, n : 2 * n]
        Bx = np.vstack([np.zeros((n, self.n_inputs)), rhs[:, 2 * n :]])
        return A, Bx, np.hstack([self.Cq, self.Cv]), self.Dff.copy()

    def to_statespace(self) -> control.StateSpace:
        """python-control ``StateSpace`` of :meth:`first_order` (states ``q[i]``, ``q_dot[i]``)."""
        import control

        n = self.n_dof
        states = [f"q[{i}]" for i in range(n)] + [f"q_dot[{i}]" for i in range(n)]
        return control.ss(*self.first_order(), states=states)

    @classmethod
    def from_statespace(
        cls,
        sys: StateSpaceLike,
        n_dof: int | None = None,
        M: npt.ArrayLike | None = None,
        tol: float = 1e-10,
    ) -> SecondOrderModel:
        r"""Second-order model of a continuous realisation in :math:`[q, \dot q]` form.

        The realisation must read :math:`A = [[0, I], [A_{21}, A_{22}]]`,
        :math:`B = [0; B_2]` (to ``tol`` relative to the largest entry). With the mass matrix M
        (default the identity) the model is :math:`K = -M A_{21}`, :math:`D = -M A_{22}`,
        :math:`B = M B_2`, :math:`C_q, C_v` the two column blocks of C.

        Parameters
        ----------
        sys : control.StateSpace or (A, B, C, D)
        n_dof : int, optional
            Number of coordinates q (default half the states).
        M : array_like (n_dof, n_dof), optional
            Mass matrix; needed when :math:`-A_{21}` is not symmetric (e.g. the NPS Eq. 18
            realisation, whose :math:`M^{-1}K` is not).
        """
        A, B, C, Dff = _abcd(sys)
        nx = A.shape[0]
        if n_dof is None:
            if nx % 2:
                raise FieldError("n_dof", f"{nx} states is odd; give n_dof")
            n_dof = nx // 2
        n = require_count(n_dof, "n_dof")
        if 2 * n != nx:
            raise FieldError("n_dof", f"{n} coordinates need {2 * n} states, sys has {nx}")
        scale = max(np.abs(A).max(initial=0.0), 1.0)
        bscale = max(np.abs(B).max(initial=0.0), 1.0)
        if (
            np.abs(A[:n, :n]).max() > tol * scale
            or np.abs(A[:n, n:] - np.eye(n)).max() > tol * scale
            or np.abs(B[:n]).max(initial=0.0) > tol * bscale
        ):
            raise FieldError(
                "sys",
                "not in [q, q̇] form (need A = [[0, I], [·, ·]] and B = [0; ·]); "
                "transform the realisation first",
            )
        Mm = np.eye(n) if M is None else _matrix(M, "M", (n, n), "(n_dof, n_dof)")
        K = -Mm @ A[n:, :n]
        if M is None and np.abs(K - K.T).max() > SYMMETRY_TOL * max(np.abs(K).max(), 1e-300):
            raise FieldError(
                "sys",
                "−A21 is not symmetric; give the mass matrix M (K = −M A21 must be symmetric)",
            )
        return cls(Mm, -Mm @ A[n:, n:], K, Mm @ B[n:], C[:, :n], C[:, n:], Dff)

    def discretize(self, dt: QuantityLike, method: str = "zoh") -> control.StateSpace:
        """Discrete-time python-control ``StateSpace`` sampled at ``dt`` s.

        ``method`` is any of ``control.StateSpace.sample``'s ('zoh' exact for held inputs,
        'foh', 'bilinear'/'tustin', 'euler', 'backward_diff', 'impulse')."""
        step = float(require_positive(dt, "dt"))
        import control

        return control.ss(*self.first_order()).sample(step, method=method)

    # ------------------------------------------------------------------------------------------
    # modal form
    def frequencies(self) -> FloatArray:
        """Undamped natural frequencies √eig(K, M), rad/s, ascending (rigid modes as 0)."""
        lam = scipy.linalg.eigh(self.K, self.M, eigvals_only=True)
        return np.sqrt(np.clip(lam, 0.0, None))

    def modes(self) -> tuple[FloatArray, FloatArray]:
        r"""Undamped modes: frequencies ω (rad/s, ascending) and mass-normalised shapes Φ
        (columns, :math:`\Phi^T M \Phi = I`, :math:`\Phi^T K \Phi = \mathrm{diag}(\omega^2)`).

        Signs are fixed so that the largest-magnitude entry of each shape is positive.
        """
        lam, Phi = scipy.linalg.eigh(self.K, self.M)
        lam = np.where(np.abs(lam) <= rigid_eigenvalue_bound(lam), 0.0, lam)
        big = np.argmax(np.abs(Phi), axis=0)
        Phi = Phi * np.sign(Phi[big, np.arange(Phi.shape[1])])
        return np.sqrt(np.clip(lam, 0.0, None)), Phi

    def is_modal(self) -> bool:
        """True when M = I and K is diagonal with non-decreasing entries (already modal)."""
        n = self.n_dof
        k = np.diag(self.K)
        return (
            np.array_equal(self.M, np.eye(n))
            and np.count_nonzero(self.K - np.diag(k)) == 0
            and bool(np.all(np.diff(k) >= 0))
        )

    def modal(self, diagonal_damping: bool = False) -> SecondOrderModel:
        r"""Mass-normalised modal form :math:`\eta` with :math:`q = \Phi \eta`.

        .. math::

            \ddot\eta + \Phi^T D \Phi \,\dot\eta + \mathrm{diag}(\omega^2)\, \eta = \Phi^T B u,
            \qquad y = C_q \Phi \eta + C_v \Phi \dot\eta + D_{ff} u.

        Proportional (Rayleigh or modal) damping projects to a diagonal :math:`\Phi^T D \Phi`;
        general damping keeps its off-diagonal coupling unless ``diagonal_damping`` (the
        classical modal-damping approximation, off-diagonal terms dropped).
        """
        if self.is_modal():
            Dm = self.D
        else:
            w, Phi = self.modes()
            Dm = Phi.T @ self.D @ Phi
            model = SecondOrderModel(
                np.eye(self.n_dof),
                Dm,
                np.diag(w**2),
                Phi.T @ self.B,
                self.Cq @ Phi,
                self.Cv @ Phi,
                self.Dff,
            )
            return model.modal(diagonal_damping) if diagonal_damping else model
        if diagonal_damping:
            return self._replace(D=np.diag(np.diag(Dm)))
        return self

    def truncate(self, n_modes: int, method: str = "truncate") -> SecondOrderModel:
        r"""Keep the ``n_modes`` lowest-frequency modes of :meth:`modal`.

        ``method="truncate"`` drops the others; ``"residualize"`` adds their static response to
        the feedthrough (static correction / mode-acceleration method, exact at ω = 0):

        .. math::

            D_{ff} \mathrel{+}= C_{q,r}\, \mathrm{diag}(1/\omega_r^2)\, B_r

        over the dropped elastic modes r (their damping coupling with the kept modes, present
        only for non-proportional damping, is dropped with them).
        """
        modal = self.modal()
        k = require_count(n_modes, "n_modes")
        if k > modal.n_dof:
            raise FieldError("n_modes", f"the model has {modal.n_dof} modes, got {k}")
        if method not in ("truncate", "residualize"):
            raise FieldError("method", f"must be 'truncate' or 'residualize', got {method!r}")
        keep = slice(0, k)
        Dff = modal.Dff
        if method == "residualize" and k < modal.n_dof:
            w2 = np.diag(modal.K)[k:]
            if np.any(w2 <= 0):
                raise FieldError("n_modes", "residualize cannot drop a rigid (ω = 0) mode")
            Dff = Dff + (modal.Cq[:, k:] / w2) @ modal.B[k:]
        return SecondOrderModel(
            modal.M[keep, keep],
            modal.D[keep, keep],
            modal.K[keep, keep],
            modal.B[keep],
            modal.Cq[:, keep],
            modal.Cv[:, keep],
            Dff,
        )

    # ------------------------------------------------------------------------------------------
    # constructors from the models of #2 and #3
    @classmethod
    def from_hub_appendage(cls, model: HubAppendage) -> SecondOrderModel:
        r"""Hub + appendage model (:class:`~flexsat.dynamics.hub_appendage.HubAppendage`) in
        its coordinates (θ, q_1 … q_k): input the hub torque, outputs θ and θ'.

        Same matrices as ``model.state_space`` / ``model.to_statespace()`` (rotational
        stiffening, a nonlinear term, is not part of the linear model).
        """
        n = model.ndof
        Cq, Cv = np.zeros((2, n)), np.zeros((2, n))
        Cq[0, 0] = Cv[1, 0] = 1.0
        return cls(
            model.mass_matrix,
            model.damping_matrix,
            model.stiffness_matrix,
            model.torque_input[:, None],
            Cq,
            Cv,
        )

    @classmethod
    def from_modal_model(
        cls, modal: ModalModel, inputs: Sequence[npt.ArrayLike] = (), outputs: Sequence[Output] = ()
    ) -> SecondOrderModel:
        r"""Modal model of a flexible body (``ModalModel.to_second_order``): M = I,
        D = diag(2ζω), K = diag(ω²) with the given modal influence inputs and
        (vector, 'displacement' | 'velocity') outputs."""
        M, D, K, B, Cq, Cv = modal.to_second_order(inputs, outputs)
        return cls(M, D, K, B, Cq, Cv)

    @classmethod
    def from_hybrid(
        cls,
        modal: ModalModel,
        hub_inertia: float,
        axis: int | str = "z",
        inputs: Iterable[npt.ArrayLike] = (),
        outputs: Sequence[Output] | None = None,
    ) -> SecondOrderModel:
        r"""Rigid hub carrying a cantilevered modal model, in hybrid coordinates (θ, η)
        (Hailey, Sortun & Agrawal c. 1992 Eqs. 10, 16;
        ``flexsat.structures.modal_model.hub_appendage_matrices``):

        .. math::

            \begin{bmatrix} I_{zz} & L^T \\ L & I \end{bmatrix} \ddot{\begin{bmatrix}\theta \\
            \eta\end{bmatrix}} + \mathrm{diag}(0, 2\zeta\omega)\,\dot{[\,\cdot\,]}
            + \mathrm{diag}(0, \omega^2)\,[\,\cdot\,] = \begin{bmatrix} T \\ \Phi^T f
            \end{bmatrix}.

        Input 0 is the hub torque T; ``inputs`` adds modal influence vectors (m,) on the
        appendage (e.g. ``modal.force_input``). Outputs: θ and θ' by default; otherwise a
        sequence of (row (m + 1,), 'displacement' | 'velocity') on (θ, η).
        """
        M, D, K = hub_appendage_matrices(modal, hub_inertia, axis=axis)
        n = M.shape[0]
        cols = [np.eye(n, 1)]
        for i, given in enumerate(inputs):
            v = require_finite(given, f"inputs[{i}]")
            if v.shape != (n - 1,):
                raise FieldError(
                    f"inputs[{i}]", f"must have shape (m,) = ({n - 1},), got {v.shape}"
                )
            cols.append(np.concatenate([[0.0], v])[:, None])
        B = np.hstack(cols)
        if outputs is None:
            Cq, Cv = np.zeros((2, n)), np.zeros((2, n))
            Cq[0, 0] = Cv[1, 0] = 1.0
        else:
            Cq, Cv = np.zeros((len(outputs), n)), np.zeros((len(outputs), n))
            for i, item in enumerate(outputs):
                values, kind = item
                row = require_finite(values, f"outputs[{i}]")
                if row.shape != (n,) or kind not in ("displacement", "velocity"):
                    raise FieldError(
                        f"outputs[{i}]",
                        f"must be (row of shape ({n},), "
                        f"'displacement' or 'velocity'), got {item!r}",
                    )
                (Cq if kind == "displacement" else Cv)[i] = row
        return cls(M, D, K, B, Cq, Cv)


def _abcd(sys: StateSpaceLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(A, B, C, D) float arrays of a StateSpace or a 4-tuple, continuous only."""
    if isinstance(sys, (tuple, list)):
        if len(sys) != 4:
            raise FieldError("sys", f"give a StateSpace or (A, B, C, D), got {len(sys)} items")
        A, B, C, D = sys
    else:
        dt = getattr(sys, "dt", 0)
        if dt not in (0, None):
            raise FieldError("sys", f"must be continuous-time, got dt = {dt}")
        A, B, C, D = sys.A, sys.B, sys.C, sys.D
    Af = require_finite(A, "A")
    if Af.ndim != 2 or Af.shape[0] != Af.shape[1]:
        raise FieldError("A", f"must be square, got shape {Af.shape}")
    nx = Af.shape[0]
    Bf = _matrix(B, "B", (nx, None), "(n, m)")
    Cf = _matrix(C, "C", (None, nx), "(p, n)")
    return Af, Bf, Cf, _matrix(D, "D", (Cf.shape[0], Bf.shape[1]), "(p, m)")
