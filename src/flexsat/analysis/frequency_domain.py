r"""Loops, frequency responses and sensitivity functions of a plant and a linear law.

Conventions (python-control's, with the sign of the feedback inside the law):

* the plant P and the law K are python-control ``StateSpace`` with labelled signals; the law's
  inputs are names of plant outputs (the measurements it reads), its outputs names of plant
  inputs (the commands it writes), and it *includes* the feedback sign: ``u = K y`` (a PD law
  is K = [−kp, −kd]);
* the loop transfer broken at the plant input is :math:`L_i = -K P` (m × m, from the command
  injected at the break to the command returning to it, sign flipped so that the loop is
  closed by negative unit feedback, :math:`S_i = (I + L_i)^{-1}`, :math:`T_i = L_i (I +
  L_i)^{-1}`), at the plant output :math:`L_o = -P K`; broken at one channel with every other
  loop closed it is the SISO lower linear fractional transformation of L over the others
  (Skogestad & Postlethwaite, *Multivariable Feedback Control*, 2nd ed., 2005, §4.9 and §9.2);
* the **sampled-data loop** is the discrete one: the plant discretised exactly by zero-order
  hold at the control period (Franklin, Powell & Workman, *Digital Control of Dynamic
  Systems*, 3rd ed., 1998, §4.3.3), the law's own discrete form, and a computation delay of
  d samples on the commands, :math:`u_k = v_{k-d}` (state-augmented: d states per command).
  Its frequency response is evaluated on the unit circle, :math:`z = e^{j\omega\,dt}`, for
  0 <= ω <= π/dt (the Nyquist frequency) only.

Frequencies cross the boundary with their unit: a pint Quantity, a unit string or a
:class:`~flexsat.units.FrequencyArray` (Hz or rad/s, converted with its 2π); a plain number is
refused, since it cannot say which it is. Every array returned is in rad/s and says so in its
name (``omega_rad_s``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from flexsat.analysis.norms import system_matrices
from flexsat.input_checks import FieldError
from flexsat.units import FrequencyArray, to_si_array

if TYPE_CHECKING:
    import control as ct
    from flexsat.units import FloatArray

__all__ = [
    "FrequencyResponse",
    "Loop",
    "ResponseEvaluator",
    "angular_frequencies",
    "block_modal_form",
    "build_loop",
    "close_other_channels",
    "default_grid",
    "delay_outputs",
    "frequency_grid",
    "frequency_response",
    "pole_grid",
    "sampled_plant",
]


# -- frequencies at the boundary -----------------------------------------------------------
def angular_frequencies(value: Any, field: str = "frequencies") -> FloatArray:
    """Frequencies in rad/s from a value that carries its unit.

    Parameters
    ----------
    value : pint.Quantity, str, FrequencyArray or sequence of str
        ``"2 Hz"``, ``Q_([1, 2], "Hz")``, ``FrequencyArray([1, 2], "rad/s")``; a cyclic
        frequency is converted with its 2π.
    field : str
        Name used in error messages.

    Returns
    -------
    ndarray
        ω, rad/s, >= 0 and finite.

    Raises
    ------
    FieldError
        For a plain number or array (Hz or rad/s cannot be told apart), a negative or
        non-finite frequency, or a unit that is not a frequency.
    """
    if isinstance(value, FrequencyArray):
        omega = np.asarray(value.to("rad/s").view(np.ndarray), float)
    elif isinstance(value, str) or hasattr(value, "units"):
        omega = np.asarray(to_si_array(value, "rad/s", field), float)
    elif isinstance(value, Sequence) and value and all(isinstance(v, str) for v in value):
        omega = np.array([float(to_si_array(v, "rad/s", field)) for v in value])
    else:
        raise FieldError(
            field,
            "give frequencies with their unit (a pint Quantity, a string such as '2 Hz' or a "
            f"FrequencyArray): a plain {type(value).__name__} cannot say Hz from rad/s",
        )
    if not np.all(np.isfinite(omega)) or np.any(omega < 0):
        raise FieldError(field, f"frequencies must be finite and >= 0, got {omega}")
    return omega


def frequency_grid(low: Any, high: Any, n: int = 500) -> FloatArray:
    """n logarithmically spaced frequencies, rad/s, from ``low`` to ``high`` (with units)."""
    lo = float(angular_frequencies(low, "low"))
    hi = float(angular_frequencies(high, "high"))
    if not 0 < lo < hi:
        raise FieldError("high", f"need 0 < low < high, got {lo:g} and {hi:g} rad/s")
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise FieldError("n", f"must be an integer >= 2, got {n!r}")
    return np.geomspace(lo, hi, n)


def default_grid(system: ct.StateSpace, n_per_decade: int = 200) -> FloatArray:
    """A log grid, rad/s, covering the system's poles and zeros two decades either side; for a
    discrete system it ends at the Nyquist frequency π/dt (included)."""
    A, _, _, _, dt = system_matrices(system)
    return pole_grid(np.linalg.eigvals(A) if A.size else np.zeros(0), dt, n_per_decade)


def pole_grid(poles: np.ndarray, dt: float, n_per_decade: int = 200) -> FloatArray:
    """:func:`default_grid` from the poles (s-plane, or z-plane when dt > 0) already known."""
    mags = np.abs(np.log(poles[poles != 0]) / dt) if dt else np.abs(poles)
    mags = mags[mags > 0]
    lo = 0.01 * float(mags.min()) if mags.size else 1e-3
    hi = 100.0 * float(mags.max()) if mags.size else 1e3
    if dt:
        hi = math.pi / dt
        lo = min(lo, 1e-3 * hi)
    n = max(2, int(n_per_decade * math.log10(hi / lo)) + 1)
    return np.geomspace(lo, hi, n)


# -- building systems ----------------------------------------------------------------------
def sampled_plant(plant: ct.StateSpace, dt: float) -> ct.StateSpace:
    """The plant's exact zero-order-hold equivalent at period dt, s, signals kept."""
    import control as ct

    A, B, C, D, pdt = system_matrices(plant, "plant")
    if pdt:
        raise FieldError("plant", f"must be continuous to be sampled, got dt = {pdt}")
    h = float(dt)
    if not (math.isfinite(h) and h > 0):
        raise FieldError("dt", f"must be a period > 0, s; got {dt!r}")
    import scipy.linalg as sla

    n, m = B.shape
    blk = np.zeros((n + m, n + m))
    blk[:n, :n], blk[:n, n:] = A * h, B * h
    E = sla.expm(blk)
    return ct.ss(
        E[:n, :n],
        E[:n, n:],
        C,
        D,
        h,
        states=plant.state_labels,
        inputs=plant.input_labels,
        outputs=plant.output_labels,
        name=plant.name,
    )


def delay_outputs(system: ct.StateSpace, samples: int) -> ct.StateSpace:
    r"""A discrete system followed by a delay of ``samples`` periods on every output,
    :math:`u_k = v_{k-d}`, as d states per output (a shift register), signals kept."""
    import control as ct

    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 0:
        raise FieldError("delay", f"must be a whole number of samples >= 0, got {samples!r}")
    A, B, C, D, dt = system_matrices(system, "law")
    d = int(samples)
    if d == 0:
        return system
    if not dt:
        raise FieldError("delay", "a delay in samples needs a discrete system")
    n, p, m = A.shape[0], C.shape[0], B.shape[1]
    nd = d * p
    # register z = [v_{k-1}, ..., v_{k-d}]; output u_k = v_{k-d}
    Ad = np.zeros((n + nd, n + nd))
    Bd = np.zeros((n + nd, m))
    Ad[:n, :n], Bd[:n] = A, B
    Ad[n : n + p, :n], Bd[n : n + p] = C, D
    for k in range(1, d):
        Ad[n + k * p : n + (k + 1) * p, n + (k - 1) * p : n + k * p] = np.eye(p)
    Cd = np.zeros((p, n + nd))
    Cd[:, n + (d - 1) * p :] = np.eye(p)
    states = list(system.state_labels) + [
        f"{out}_delayed[{k + 1}]" for k in range(d) for out in system.output_labels
    ]
    return ct.ss(
        Ad,
        Bd,
        Cd,
        np.zeros((p, m)),
        dt,
        states=states,
        inputs=system.input_labels,
        outputs=system.output_labels,
        name=system.name,
    )


@dataclass(frozen=True)
class Loop:
    r"""A loop broken at a point: its transfer L and the closed loop it stands for.

    Attributes
    ----------
    transfer : control.StateSpace
        L (negative-feedback convention, module docstring), inputs and outputs named after the
        signals at the break.
    break_point : str
        ``"input"``, ``"output"`` or the one signal the loop is broken at.
    closed_loop_A : ndarray
        State matrix of the closed loop (plant states then law states), whose eigenvalues are
        the closed-loop poles (z-plane for a sampled loop).
    states : tuple of str
        Labels of those states.
    dt : float
        0 for a continuous loop, the control period (s) for a sampled one.
    """

    transfer: ct.StateSpace
    break_point: str
    closed_loop_A: FloatArray
    states: tuple[str, ...]
    dt: float

    @property
    def poles(self) -> npt.NDArray[np.complex128]:
        """Closed-loop poles (s-plane, or z-plane for a sampled loop)."""
        return np.linalg.eigvals(self.closed_loop_A).astype(complex)

    @property
    def stable(self) -> bool:
        """Whether every closed-loop pole is strictly inside the stability region."""
        p = self.poles
        if p.size == 0:
            return True
        return bool(np.all(np.abs(p) < 1.0) if self.dt else np.all(p.real < 0.0))

    def sensitivity(self) -> ct.StateSpace:
        r"""S = (I + L)^{-1} as a StateSpace."""
        return _feedback_identity(self.transfer, complementary=False)

    def complementary_sensitivity(self) -> ct.StateSpace:
        r"""T = L (I + L)^{-1} = I − S as a StateSpace."""
        return _feedback_identity(self.transfer, complementary=True)


def _feedback_identity(L: ct.StateSpace, complementary: bool) -> ct.StateSpace:
    import control as ct

    A, B, C, D, dt = system_matrices(L, "loop")
    m = D.shape[0]
    E = np.linalg.inv(np.eye(m) + D)
    As = A - B @ E @ C
    Bs, Cs, Ds = B @ E, -E @ C, E
    if complementary:
        Cs, Ds = -Cs, np.eye(m) - Ds
    return ct.ss(
        As,
        Bs,
        Cs,
        Ds,
        dt,
        states=L.state_labels,
        inputs=L.input_labels,
        outputs=L.output_labels,
        name=("T" if complementary else "S"),
    )


def _indices(available: Sequence[str], wanted: Sequence[str], field: str, role: str) -> list[int]:
    missing = [w for w in wanted if w not in available]
    if missing:
        raise FieldError(
            field,
            f"{role} {missing} are not signals of the plant (it has {list(available)})",
        )
    return [list(available).index(w) for w in wanted]


def build_loop(
    plant: ct.StateSpace,
    law: ct.StateSpace,
    break_at: str = "input",
    delay: int = 0,
) -> Loop:
    r"""The loop of ``plant`` and ``law`` broken at ``break_at`` (module docstring).

    Parameters
    ----------
    plant : control.StateSpace
        Continuous, or discrete at the law's period; labelled signals.
    law : control.StateSpace
        u = K y, inputs named after plant outputs, outputs after plant inputs. A continuous
        plant with a discrete law is sampled (:func:`sampled_plant`) at the law's period.
    break_at : str
        ``"input"`` (L = −K P, every command), ``"output"`` (L = −P K, every measurement), or
        the name of one command or measurement: that channel broken, every other loop closed.
    delay : int
        Computation delay of the law, whole samples (sampled loops only).

    Returns
    -------
    Loop
    """
    import control as ct

    Ak, Bk, Ck, Dk, kdt = system_matrices(law, "law")
    _, _, _, _, pdt = system_matrices(plant, "plant")
    if kdt and not pdt:
        plant = sampled_plant(plant, kdt)
    elif pdt and not kdt:
        raise FieldError("law", "is continuous but the plant is discrete: sample the law too")
    elif pdt and abs(pdt - kdt) > 1e-9 * kdt:
        raise FieldError("plant", f"samples every {pdt:g} s, the law every {kdt:g} s")
    if delay:
        law = delay_outputs(law, delay)
        Ak, Bk, Ck, Dk, kdt = system_matrices(law, "law")
    A, B, C, D, dt = system_matrices(plant, "plant")
    meas = list(law.input_labels)
    cmds = list(law.output_labels)
    oi = _indices(plant.output_labels, meas, "law", "its inputs (measurements)")
    ii = _indices(plant.input_labels, cmds, "law", "its outputs (commands)")
    Bs, Cs, Ds = B[:, ii], C[oi], D[np.ix_(oi, ii)]
    n, nk = A.shape[0], Ak.shape[0]
    plant_states = [str(s) for s in plant.state_labels]
    law_states = [f"{law.name}.{s}" for s in law.state_labels]
    # loop at the plant input: states [x, xk]; input the command injected at the break
    Ai = np.block([[A, np.zeros((n, nk))], [Bk @ Cs, Ak]])
    Bi = np.vstack([Bs, Bk @ Ds])
    Ci = -np.hstack([Dk @ Cs, Ck])
    Di = -Dk @ Ds
    # loop at the plant output: states [x, xk]; input the measurement injected at the break
    Ao = np.block([[A, Bs @ Ck], [np.zeros((nk, n)), Ak]])
    Bo = np.vstack([Bs @ Dk, Bk])
    Co = -np.hstack([Cs, Ds @ Ck])
    Do = -Ds @ Dk
    if break_at == "input":
        mats, names = (Ai, Bi, Ci, Di), cmds
    elif break_at == "output":
        mats, names = (Ao, Bo, Co, Do), meas
    elif break_at in cmds:
        mats, names = close_other_channels((Ai, Bi, Ci, Di), cmds.index(break_at)), [break_at]
    elif break_at in meas:
        mats, names = close_other_channels((Ao, Bo, Co, Do), meas.index(break_at)), [break_at]
    else:
        raise FieldError(
            "break_at",
            f"must be 'input', 'output', a command {cmds} or a measurement {meas}; got "
            f"{break_at!r}",
        )
    La, Lb, Lc, Ld = mats
    transfer = ct.ss(
        La, Lb, Lc, Ld, dt, inputs=names, outputs=names, states=plant_states + law_states, name="L"
    )
    E = np.linalg.inv(np.eye(Di.shape[0]) + Di)
    closed = Ai - Bi @ E @ Ci
    return Loop(transfer, break_at, closed, tuple(plant_states + law_states), dt)


def close_other_channels(
    mats: tuple[FloatArray, FloatArray, FloatArray, FloatArray], i: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    r"""(A, B, C, D) of channel i of a square loop with every other channel closed by −I:
    with the others' return :math:`r_o = C_o x + D_{oi} w + D_{oo} u_o` and
    :math:`u_o = -r_o`, :math:`u_o = -(I + D_{oo})^{-1}(C_o x + D_{oi} w)`."""
    A, B, C, D = mats
    m = D.shape[0]
    o = [j for j in range(m) if j != i]
    if not o:
        return mats
    E = np.linalg.inv(np.eye(len(o)) + D[np.ix_(o, o)])
    Bo, Co = B[:, o], C[o]
    Uo_x = -E @ Co  # u_o per x
    Uo_w = -E @ D[np.ix_(o, [i])]  # u_o per w
    A1 = A + Bo @ Uo_x
    B1 = B[:, [i]] + Bo @ Uo_w
    C1 = C[[i]] + D[np.ix_([i], o)] @ Uo_x
    D1 = D[np.ix_([i], [i])] + D[np.ix_([i], o)] @ Uo_w
    return A1, B1, C1, D1


# -- frequency responses -------------------------------------------------------------------
# eigenvalues whose condition number ‖x_i‖‖y_i‖/|y_iᴴx_i| exceeds this (accuracy worse than
# ~1e-12 relative) are treated as part of a (nearly) defective cluster
_ILL_CONDITIONED = 1e4
# the transformation to (block-)diagonal form must stay below this condition number
_MAX_CONDITION = 1e6


def _clusters(lam: np.ndarray, bad: np.ndarray, scale: float) -> list[list[int]]:
    """Groups of eigenvalue indices around each (nearly) defective cluster: ill-conditioned
    eigenvalues within 1e-4 scale of each other are linked, and every eigenvalue inside the
    group's disk (twice its radius) joins it."""
    idx = [int(i) for i in np.flatnonzero(bad)]
    groups: list[list[int]] = []
    for i in idx:
        near = [g for g in groups if np.min(np.abs(lam[g] - lam[i])) <= 1e-4 * scale]
        merged = [i] + [j for g in near for j in g]
        groups = [g for g in groups if g not in near] + [merged]
    out = []
    for g in groups:
        c = np.mean(lam[g])
        r = 2.0 * float(np.max(np.abs(lam[g] - c))) + 1e-12 * scale
        out.append([int(j) for j in np.flatnonzero(np.abs(lam - c) <= r)])
    return out


def _invariant_basis(A: np.ndarray, start: np.ndarray, centre: complex, offset: float) -> Any:
    """Orthonormal basis of the invariant subspace of a cluster of eigenvalues around
    ``centre``, by subspace inverse iteration shifted ``offset`` off the centre: each step
    shrinks the other eigenvalues' components by about offset / their distance; the shift is
    not closer, since a Jordan block's chain loses ε/offset to cancellation each step. None if
    the residual ‖AU − U(UᴴAU)‖ does not fall to round-off."""
    import scipy.linalg as sla

    n = start.shape[0]
    scale = max(float(np.linalg.norm(A, 1)), 1e-300)
    shift = centre + offset * (0.6 + 0.8j)
    lu = sla.lu_factor(A - shift * np.eye(n), check_finite=False)
    U = np.linalg.qr(start)[0]
    for _ in range(8):
        U = np.linalg.qr(sla.lu_solve(lu, U, check_finite=False))[0]
        R = A @ U - U @ (U.conj().T @ A @ U)
        if float(np.linalg.norm(R, 1)) <= 1e-12 * scale * n:
            return U
    return None


def block_modal_form(
    A: FloatArray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[list[int]]] | None:
    r"""A similarity :math:`W^{-1} A W` that is diagonal except for small blocks on (nearly)
    defective eigenvalue clusters, or None when no such W with κ(W) < 1e6 is found.

    The eigenvectors of the well-conditioned eigenvalues are kept; each cluster of
    ill-conditioned eigenvalues (a rigid mode's Jordan block) is replaced by an orthonormal
    basis of its invariant subspace, found by subspace inverse iteration (Golub & Van Loan,
    *Matrix Computations*, 4th ed., 2013, §7.3 and §7.6.3 on block diagonalisation).

    Returns
    -------
    (λ, W, W^{-1}, clusters)
        The eigenvalues (in the order of W's columns), W and its inverse; the clusters are
        lists of column indices of W whose block of :math:`W^{-1} A W` is full; every other
        column j is an eigenvector of λ_j.
    """
    n = A.shape[0]
    lam, V = np.linalg.eig(A)
    with np.errstate(over="ignore", invalid="ignore"):  # κ of a defective V overflows to ∞
        try:
            Vinv = np.linalg.inv(V)
        except np.linalg.LinAlgError:
            Vinv = None
        if Vinv is not None and np.linalg.norm(V, 1) * np.linalg.norm(Vinv, 1) < _MAX_CONDITION:
            return lam, V, Vinv, []
        if Vinv is None:
            bad = np.ones(n, bool)
        else:
            bad = ~(np.linalg.norm(Vinv, axis=1) * np.linalg.norm(V, axis=0) <= _ILL_CONDITIONED)
    scale = max(float(np.linalg.norm(A, 1)), 1e-300)
    clusters = _clusters(lam, bad, scale)
    W = V.astype(complex)
    for g in clusters:
        c = complex(np.mean(lam[g]))
        others = np.abs(np.delete(lam, g) - c)
        gap = float(others.min()) if others.size else scale
        spread = float(np.max(np.abs(lam[g] - c)))
        U = _invariant_basis(A, V[:, g], c, max(1e-3 * gap, 2.0 * spread))
        if U is None:
            return None
        W[:, g] = U
    try:
        Winv = np.linalg.inv(W)
    except np.linalg.LinAlgError:
        return None
    if not np.linalg.norm(W, 1) * np.linalg.norm(Winv, 1) < _MAX_CONDITION:
        return None
    return lam, W, Winv, clusters


class ResponseEvaluator:
    r"""G at many frequencies from one factorisation of A.

    With a well-conditioned eigenvector matrix (κ(V) < 1e6) the response is
    :math:`D + (CV)\,\mathrm{diag}(1/(x - \lambda_i))\,(V^{-1}B)`, O(n(p + m)) per frequency.
    With (nearly) defective clusters (a rigid mode's Jordan block) the ill-conditioned
    eigenvectors are replaced by a basis of each cluster's invariant subspace
    (:func:`block_modal_form`): the diagonal part as above plus, per cluster of k eigenvalues,
    one k × k solve per frequency, all frequencies at once. Failing that, the complex Schur form
    :math:`A = ZTZ^H` and one triangular solve of :math:`(xI - T)` per frequency, O(n² m),
    which is backward stable whatever the eigenvectors (Laub, "Efficient multivariable
    frequency response computations", IEEE TAC 26(2), 1981, 407–408).

    Attributes
    ----------
    method : str
        ``"modal"``, ``"block"`` or ``"schur"`` (``"static"`` without states).
    condition : float
        κ₁ of the transformation used (1 for Schur's unitary one).
    poles : ndarray
        The eigenvalues of A (s- or z-plane), from the same factorisation.
    """

    def __init__(
        self, A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray, dt: float
    ) -> None:
        import scipy.linalg as sla

        self.D, self.dt, self.n = D, dt, A.shape[0]
        self.modal = False
        self.method, self.condition = "static", 1.0
        self.poles = np.zeros(0, complex)
        self.blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        if not self.n:
            return
        form = block_modal_form(A)
        if form is not None:
            lam, W, Winv, clusters = form
            self.condition = float(np.linalg.norm(W, 1) * np.linalg.norm(Winv, 1))
            self.modal = not clusters
            self.method = "block" if clusters else "modal"
            in_block = [j for g in clusters for j in g]
            diag = np.setdiff1d(np.arange(self.n), in_block)
            CW, WB = C @ W, Winv @ B
            self.lam, self.poles = lam[diag], lam
            self.CV, self.VB = CW[:, diag], WB[diag]
            for g in clusters:
                T = Winv[g] @ A @ W[:, g]
                self.blocks.append((T, CW[:, g], WB[g]))
        else:
            self.method = "schur"
            T, Z = sla.schur(A.astype(complex), output="complex")
            self.T, self.CZ, self.ZB = T, C @ Z, Z.conj().T @ B
            self.poles = np.diag(T).copy()

    def __call__(self, omega_rad_s: FloatArray) -> np.ndarray:
        """(n_w, p, m) complex response at the frequencies, rad/s."""
        import scipy.linalg as sla

        w = np.asarray(omega_rad_s, float)
        x = np.exp(1j * w * self.dt) if self.dt else 1j * w
        G = np.broadcast_to(self.D.astype(complex), (w.size,) + self.D.shape).copy()
        if not self.n:
            return G
        if self.method != "schur":
            with np.errstate(divide="ignore", invalid="ignore"):
                inv = 1.0 / (x[:, None] - self.lam[None, :])
            G += np.einsum("pi,wi,im->wpm", self.CV, inv, self.VB)
            for T, CW, WB in self.blocks:
                k = T.shape[0]
                shifted = x[:, None, None] * np.eye(k) - T
                try:
                    G += CW @ np.linalg.solve(shifted, np.broadcast_to(WB, (w.size,) + WB.shape))
                except np.linalg.LinAlgError:  # a pole on the axis at one of the frequencies
                    for j in range(w.size):
                        try:
                            G[j] += CW @ np.linalg.solve(shifted[j], WB)
                        except np.linalg.LinAlgError:
                            G[j] = np.inf
            return G
        shifted = -self.T
        diag = np.diag(self.T)
        for k, xk in enumerate(x):
            np.fill_diagonal(shifted, xk - diag)
            try:
                solved = sla.solve_triangular(shifted, self.ZB, check_finite=False)
            except np.linalg.LinAlgError:  # a pole on the axis at this frequency: infinite
                G[k] = np.inf
                continue
            G[k] += self.CZ @ solved
        return G


@dataclass(frozen=True)
class FrequencyResponse:
    """Complex frequency response G(jω) (or G(e^{jω dt})) on a grid.

    Attributes
    ----------
    omega_rad_s : (n_w,) ndarray
        Frequencies, rad/s.
    values : (n_w, p, m) complex ndarray
    inputs, outputs : tuple of str
        Signal labels of the columns and rows.
    """

    omega_rad_s: FloatArray
    values: np.ndarray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]

    def magnitude(self) -> FloatArray:
        """|G|, (n_w, p, m)."""
        return np.abs(self.values)

    def phase_deg(self) -> FloatArray:
        """Phase of every entry, degrees, unwrapped along frequency."""
        return np.degrees(np.unwrap(np.angle(self.values), axis=0))

    def singular_values(self) -> FloatArray:
        """σ_i(G), (n_w, min(p, m)), in decreasing order."""
        return np.linalg.svd(self.values, compute_uv=False)


def frequency_response(
    system: ct.StateSpace,
    frequencies: Any = None,
    *,
    omega_rad_s: FloatArray | None = None,
    delay_s: float = 0.0,
) -> FrequencyResponse:
    r"""G(jω) of a continuous system, :math:`G(e^{j\omega dt})` of a discrete one.

    Parameters
    ----------
    system : control.StateSpace
    frequencies : Quantity, str or FrequencyArray, optional
        Where to evaluate (with units, :func:`angular_frequencies`); default
        :func:`default_grid`.
    omega_rad_s : array, optional
        The same in rad/s, for a grid this module built (the name says the unit).
    delay_s : float
        A pure delay, s, multiplying the response by :math:`e^{-j\omega\tau}`.

    Raises
    ------
    FieldError
        For a discrete system asked beyond its Nyquist frequency π/dt.
    """
    A, B, C, D, dt = system_matrices(system)
    if frequencies is not None and omega_rad_s is not None:
        raise FieldError("omega_rad_s", "give frequencies or omega_rad_s, not both")
    if frequencies is not None:
        w = angular_frequencies(frequencies)
    elif omega_rad_s is not None:
        w = np.asarray(omega_rad_s, float)
        if w.ndim != 1 or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise FieldError("omega_rad_s", "must be a 1-D array of finite frequencies >= 0")
    else:
        w = default_grid(system)
    w = np.atleast_1d(w)
    if dt and np.any(w > math.pi / dt * (1 + 1e-12)):
        raise FieldError(
            "frequencies",
            f"a sampled system's response is defined up to its Nyquist frequency π/dt = "
            f"{math.pi / dt:g} rad/s, got up to {float(w.max()):g} rad/s",
        )
    G = ResponseEvaluator(A, B, C, D, dt)(w)
    if delay_s:
        G = G * np.exp(-1j * w * float(delay_s))[:, None, None]
    return FrequencyResponse(w, G, tuple(system.input_labels), tuple(system.output_labels))
