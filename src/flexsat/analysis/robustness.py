r"""Robust stability and sensitivity of a flexible loop over a box of modal frequencies and damping.

The uncertain loop
------------------
A continuous plant and a linear law :math:`u = K(s) y` (static or dynamic, e.g. an LQG
compensator) with **one command** (a SISO loop at the plant input, any number of measurements).
The plant's marginal part (rigid-body modes; kept exactly,
:func:`~flexsat.analysis.reduction.split_stable`) and the law are certain; each lightly damped
mode i of the plant's stable part is written in the companion coordinates of its 2 × 2 block, in
which the command enters the acceleration only (possible for one input), so that its
contribution to the plant is :math:`(C_{i0} + C_{i1}s)\,b_i / d_i(s)` with
:math:`d_i(s) = s^2 + 2\zeta_i\omega_i s + \omega_i^2`: the mode shape
(:math:`C_{i0}, C_{i1}, b_i`) is fixed and :math:`(\omega_i, \zeta_i)` range over a box
:math:`\omega_i \in \omega_{i0}[1 - f_i, 1 + f_i]`, :math:`\zeta_i \in \zeta_{i0}[1 - g_i, 1 + g_i]`
(the standard modal-parameter uncertainty of a structure; Gawronski, *Advanced Structural
Dynamics and Active Control of Structures*, Springer, 2004, Ch. 2).

With :math:`\chi = \chi_K \chi_u` the characteristic polynomial of the law and of the marginal
part, :math:`\chi_c` that of the law closed on the marginal part, and
:math:`N_K = \chi_K K` (polynomials; :math:`C\,\mathrm{adj}(sI - A)\,b = \det(sI - A + bC) -
\det(sI - A)`), the return difference gives the closed-loop characteristic polynomial
:math:`\chi_{cl}(s) = F(s)\prod_i d_i(s)` with

.. math::

    F(s) = \chi_c(s) + \sum_i \frac{q_i(s)}{d_i(s)}, \quad
    q_i = -\chi_u\, b_i\, N_K (C_{i0} + C_{i1} s), \qquad
    S(s) = \frac{1}{1 + L(s)} = \frac{\chi(s)}{F(s)} .

A guaranteed answer by zero exclusion
-------------------------------------
The closed loop is stable for every member of the (connected) box iff it is for one member and
:math:`0 \notin F(j\omega, \text{box})` for all ω >= 0 (the zero-exclusion principle; Barmish,
*New Tools for Robustness of Linear Systems*, Macmillan, 1994, §7.4; the degree of χ does not
change and :math:`d_i(j\omega) \ne 0` for ζ_i > 0). The frequency axis is covered by intervals
:math:`[\omega_1, \omega_2]` and, on each, the value set is enclosed rigorously:

* the certain polynomials and each mode's numerator :math:`q_i` lie in a disc about their
  value at the midpoint (Taylor's theorem: the exact first derivative there and a bound of the
  second from the coefficients);
* :math:`d_i(j\omega) = (\omega_i^2 - \omega^2) + 2j\zeta_i\omega_i\omega` lies, for every ω of
  the interval and every member of the box, in a convex pentagon (right/left edges at
  :math:`\omega_{hi}^2 - \omega_1^2`, :math:`\omega_{lo}^2 - \omega_2^2`, top at
  :math:`2\zeta_{hi}\omega_{hi}\omega_2`, bottom the chord of the concave lower boundary
  :math:`2\zeta_{lo}\omega_1\sqrt{x + \omega_1^2}`);
* the support function of the image of that pentagon under :math:`q/d` in a direction u,
  :math:`h(u) = \max \operatorname{Re}(\bar u\, q/d)`, is the maximum of a harmonic function,
  reached on the boundary: on each edge :math:`d(t) = d_0 + t e` it is a ratio of a linear and a
  quadratic polynomial in t, maximised in closed form.

Support functions add under Minkowski sums, so if :math:`\sum_k h_k(u) < 0` for some direction u,
0 lies outside the convex hull of the value set, hence outside the set: that interval is
certified, and :math:`-\sum_k h_k(u)` is a lower bound of :math:`|F|` on it, so
:math:`|S| \le \max|\chi| / (-\sum_k h_k(u))`. An interval that fails is bisected (a
branch-and-bound on frequency). Beyond a frequency W,
:math:`|L| \le |\chi_c - \chi|/|\chi| + \sum_i |q_i|/(|\chi|\,|d_i|) \le 1/2` with coefficient
bounds on the numerators, :math:`|\chi(j\omega)| \ge \prod_k(\omega - |r_k|)` and
:math:`|d_i| \ge \omega^2 - \omega_{hi}^2` — a product of factors ω/(ω − a) and 1/(ω ± a),
each decreasing — so |S| <= 2 there and nothing can cross. Floating-point rounding is covered
by a relative margin of 1e-9 on each test;
the frequency box of each mode is not split, so the bound's conservatism (the convex hull of
each mode's value set) does not shrink with refinement — its ratio to the dense sweep is
reported.

The dense sweep (:func:`sweep`) is independent: it builds the closed-loop state matrix of each
sampled member (vertices, random points and members with a mode tuned to each frequency) and
takes the eigenvalues of the whole batch at once (``numpy.linalg.eigvals`` on the stacked
matrices), and |S| on a frequency grid.

Scope: continuous loops with one command (PD, Lyapunov Laws I/II, LQR, LQG compensators); a
sampled-data loop, a second command or a real (overdamped) plant pole is refused with its
reason. The law's polynomials come from eigenvalues (``numpy.poly``): fine for the compensators
of reduced models (tens of states), not for a law of hundreds of states.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.analysis.norms import system_matrices
from flexsat.analysis.reduction import modal_form, split_stable
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.units import FloatArray

__all__ = [
    "Certificate",
    "ModalLoop",
    "ParameterBox",
    "SweepResult",
    "certify",
    "modal_loop",
    "stability_margin",
    "sweep",
    "sweep_stability_margin",
]

ComplexArray = npt.NDArray[np.complex128]
_SAFETY = 1e-9  # relative rounding margin of every certified inequality


@dataclass(frozen=True)
class ModalLoop:
    r"""A SISO loop split into a certain part and uncertain modes (module docstring).

    Attributes
    ----------
    chi_den : ndarray
        Coefficients (highest power first) of :math:`\chi = \chi_K\chi_u`, the open-loop
        characteristic polynomial of the law and the plant's marginal part.
    chi_c : ndarray
        Of :math:`\chi_c`, the characteristic polynomial of the law closed on the marginal part.
    numerators : ndarray
        (modes, k): each mode's :math:`q_i(s)`, highest power first, zero-padded.
    omega0, zeta0 : ndarray
        Nominal frequency (rad/s) and damping ratio of each mode.
    marginal : tuple of ndarray
        (A_u, B_u, C_u) of the marginal part (measurements × states).
    mode_outputs : ndarray
        (modes, p, 2): each mode's output matrix in its companion coordinates.
    mode_inputs : ndarray
        (modes,): the input entry of each mode's acceleration row.
    law : tuple of ndarray
        (A_K, B_K, C_K, D_K) of the law on the measurements used (u = C_K ξ + D_K y).
    """

    chi_den: FloatArray
    chi_c: FloatArray
    numerators: FloatArray
    omega0: FloatArray
    zeta0: FloatArray
    marginal: tuple[FloatArray, FloatArray, FloatArray]
    mode_outputs: FloatArray
    mode_inputs: FloatArray
    law: tuple[FloatArray, FloatArray, FloatArray, FloatArray]

    @property
    def n_modes(self) -> int:
        return int(self.omega0.size)

    def closed_loop_matrices(self, omega: FloatArray, zeta: FloatArray) -> FloatArray:
        """Closed-loop state matrices of a batch of members: omega, zeta (N, modes) -> (N, n, n).

        States: the marginal part, each mode's (q, q̇), then the law's states."""
        Au, Bu, Cu = self.marginal
        Ak, Bk, Ck, Dk = self.law
        omega = np.atleast_2d(omega)
        zeta = np.atleast_2d(zeta)
        N, nm, nu, nk = omega.shape[0], self.n_modes, Au.shape[0], Ak.shape[0]
        n = nu + 2 * nm
        A = np.zeros((N, n + nk, n + nk))
        B = np.zeros(n)
        C = np.zeros((Dk.shape[1], n))
        A[:, :nu, :nu] = Au
        B[:nu], C[:, :nu] = Bu[:, 0], Cu
        for i in range(nm):
            k = nu + 2 * i
            A[:, k, k + 1] = 1.0
            A[:, k + 1, k] = -(omega[:, i] ** 2)
            A[:, k + 1, k + 1] = -2.0 * zeta[:, i] * omega[:, i]
            B[k + 1] = self.mode_inputs[i]
            C[:, k : k + 2] = self.mode_outputs[i]
        A[:, :n, :n] += np.outer(B, Dk[0] @ C)
        A[:, :n, n:] = np.outer(B, Ck[0])
        A[:, n:, :n] = Bk @ C
        A[:, n:, n:] = Ak
        return np.asarray(A, float)

    def characteristic(self, s: npt.ArrayLike, omega: FloatArray, zeta: FloatArray) -> FloatArray:
        """F(s) for members (N, modes) at points s (W,) -> (N, W) complex."""
        su = np.asarray(s, complex)
        om = np.atleast_2d(omega)[:, None, :]
        ze = np.atleast_2d(zeta)[:, None, :]
        sc = su[None, :, None]
        d = sc**2 + 2 * ze * om * sc + om**2
        q = np.stack([np.polyval(c, su) for c in self.numerators], -1)[None]
        return np.asarray(np.polyval(self.chi_c, su)[None] + (q / d).sum(axis=-1))

    def sensitivity(
        self, omega_rad_s: npt.ArrayLike, omega: FloatArray, zeta: FloatArray
    ) -> FloatArray:
        """|S(jω)| for members (N, modes) on frequencies (W,) -> (N, W)."""
        s = 1j * np.asarray(omega_rad_s, float)
        chi = np.abs(np.polyval(self.chi_den, s))[None]
        return np.asarray(chi / np.abs(self.characteristic(s, omega, zeta)))


def _law_numerators(Ak: FloatArray, Bk: FloatArray, Ck: FloatArray, Dk: FloatArray) -> FloatArray:
    r"""Coefficients of :math:`\chi_K(s) K_j(s)` per measurement j, (p, nk + 1): by the matrix
    determinant lemma :math:`C\,\mathrm{adj}(sI - A)\,b = \det(sI - A + bC) - \det(sI - A)`."""
    nk = Ak.shape[0]
    chi = np.real(np.poly(Ak)) if nk else np.ones(1)
    rows = []
    for j in range(Dk.shape[1]):
        row = Dk[0, j] * chi
        if nk:
            row = row + np.real(np.poly(Ak - np.outer(Bk[:, j], Ck[0]))) - chi
        rows.append(row)
    return np.array(rows).reshape(Dk.shape[1], nk + 1)


def modal_loop(plant: ct.StateSpace, law: ct.StateSpace, command: str | None = None) -> ModalLoop:
    """The loop of ``plant`` and a static ``law`` in the form of the module docstring.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous, labelled; its stable part must have complex modes only (lightly damped
        structure), its marginal part is kept exactly.
    law : control.StateSpace
        Static (no states), u = K y, inputs named after plant outputs, one output (the command,
        a plant input), as :func:`~flexsat.control.state_space_export.continuous_law` gives.
    command : str, optional
        The command to close the loop on when the law writes several.

    Raises
    ------
    FieldError
        For a dynamic or multi-command law, a discrete system, a feedthrough on the measurements,
        a real (non-oscillatory) pole or an undamped mode.
    """
    A, B, C, D, pdt = system_matrices(plant, "plant")
    Ak, Bk_all, Ck_all, Dk_all, kdt = system_matrices(law, "law")
    if pdt or kdt:
        raise FieldError("law", "the modal robustness analysis is for continuous loops (dt = 0)")
    cmds = list(law.output_labels)
    if command is None:
        if len(cmds) != 1:
            raise FieldError("command", f"the law writes {cmds}: name the one loop to analyse")
        command = cmds[0]
    if command not in cmds or command not in plant.input_labels:
        raise FieldError("command", f"{command!r} is not a command of both law and plant")
    meas = list(law.input_labels)
    missing = [m for m in meas if m not in plant.output_labels]
    if missing:
        raise FieldError("law", f"reads {missing}, which are not outputs of the plant")
    ii = list(plant.input_labels).index(command)
    ci = cmds.index(command)
    # measurements the law does not use (zero gain and zero state input) do not enter the loop
    used = [j for j in range(len(meas)) if Dk_all[ci, j] != 0 or np.any(Bk_all[:, j] != 0)]
    oi = [list(plant.output_labels).index(meas[j]) for j in used]
    law_used = (Ak, Bk_all[:, used], Ck_all[[ci]], Dk_all[np.ix_([ci], used)])
    Bs, Cs = B[:, [ii]], C[oi]
    if np.any(D[oi, ii] != 0):
        raise FieldError(
            "plant", "has a feedthrough from the command to a measurement the law uses"
        )
    import control as ct

    split = split_stable(ct.ss(A, Bs, Cs, np.zeros((len(oi), 1))))
    Au, Bu, Cu = split.unstable
    form = modal_form(split.stable)
    Am, Bm, Cm, _ = form.matrices
    omega0, zeta0 = form.frequencies_rad_s, form.damping_ratios
    if not form.blocks:
        raise FieldError(
            "plant", "has no lightly damped mode: there is nothing uncertain to analyse"
        )
    chi_u = np.real(np.poly(Au)) if Au.size else np.ones(1)
    NK = _law_numerators(*law_used)  # (p, nk + 1)
    outs, ins, numer = [], [], []
    for k, blk in enumerate(form.blocks):
        if blk.stop - blk.start != 2:
            raise FieldError(
                "plant",
                f"has a real pole at {-omega0[k]:.6g} rad/s: only lightly damped modes "
                "(complex pairs) are handled",
            )
        if zeta0[k] <= 0:
            raise FieldError(
                "plant", f"mode at {omega0[k]:.6g} rad/s is undamped: give damping > 0"
            )
        Ai, bi, Ci = Am[blk, blk], Bm[blk, 0], Cm[:, blk]
        # companion coordinates (q, q̇) with q = c·z, c ⟂ b: the command drives q̈ only
        nb = float(np.hypot(bi[0], bi[1]))
        c = np.array([-bi[1], bi[0]]) / nb if nb > 0 else np.array([1.0, 0.0])
        T = np.vstack([c, c @ Ai])
        b_acc = float((T @ bi)[1])
        Cc = np.linalg.solve(T.T, Ci.T).T
        outs.append(Cc)
        ins.append(b_acc)
        # q_i = −χ_u b (χ_K K·C0 + s χ_K K·C1)
        lin = np.polyadd(np.polymul(Cc[:, 1] @ NK, [1.0, 0.0]), Cc[:, 0] @ NK)
        numer.append(-b_acc * np.polymul(chi_u, lin))
    nk = Ak.shape[0]
    chi_den = np.polymul(chi_u, np.real(np.poly(Ak)) if nk else np.ones(1))
    Acu = np.block([[Au + Bu @ law_used[3] @ Cu, Bu @ law_used[2]], [law_used[1] @ Cu, Ak]])
    chi_c = np.real(np.poly(Acu)) if Acu.size else np.ones(1)
    width = max((q.size for q in numer), default=1)
    numerators = np.array([np.concatenate([np.zeros(width - q.size), q]) for q in numer])
    return ModalLoop(
        np.asarray(chi_den, float),
        np.asarray(chi_c, float),
        numerators.reshape(len(numer), width),
        omega0,
        zeta0,
        (Au, Bu, Cu),
        np.array(outs).reshape(len(outs), len(oi), 2),
        np.array(ins),
        law_used,
    )


@dataclass(frozen=True)
class ParameterBox:
    """Relative ± ranges of each mode's frequency and damping ratio (0.1 = ±10 %).

    Attributes
    ----------
    frequency, damping : ndarray
        One value per mode (a scalar broadcasts), in [0, 1).
    """

    frequency: FloatArray
    damping: FloatArray

    @classmethod
    def uniform(cls, loop: ModalLoop, frequency: float, damping: float = 0.0) -> ParameterBox:
        """The same relative range on every mode of ``loop``."""
        return cls.of(loop, np.full(loop.n_modes, frequency), np.full(loop.n_modes, damping))

    @classmethod
    def of(cls, loop: ModalLoop, frequency: npt.ArrayLike, damping: npt.ArrayLike) -> ParameterBox:
        """Per-mode ranges, checked against ``loop``."""
        out = []
        for name, v in (("frequency", frequency), ("damping", damping)):
            a = np.broadcast_to(np.asarray(v, float), (loop.n_modes,)).copy()
            if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a >= 1):
                raise FieldError(name, f"relative ranges must be in [0, 1), got {a}")
            out.append(a)
        return cls(out[0], out[1])

    def bounds(self, loop: ModalLoop) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(ω_lo, ω_hi, ζ_lo, ζ_hi) per mode."""
        w, z = loop.omega0, loop.zeta0
        return (
            w * (1 - self.frequency),
            w * (1 + self.frequency),
            z * (1 - self.damping),
            z * (1 + self.damping),
        )

    def scaled(self, k: float) -> ParameterBox:
        return ParameterBox(self.frequency * k, self.damping * k)


def _poly_disc(
    coef: FloatArray, w1: FloatArray, w2: FloatArray
) -> tuple[npt.NDArray[np.complex128], FloatArray]:
    r"""p(jω_m) and a radius covering p(jω) on [w1, w2] by Taylor's theorem:
    :math:`\delta |p'(j\omega_m)| + \tfrac{\delta^2}{2} \sum_k k(k-1)|c_k| \omega_2^{k-2}`
    (δ the half-width; the derivative is taken in ω)."""
    wm = 0.5 * (w1 + w2)
    half = 0.5 * (w2 - w1)
    deg = coef.size - 1
    curve = np.zeros_like(w2)
    for c, k in zip(coef, range(deg, -1, -1)):
        if k > 1:
            curve = curve + k * (k - 1) * abs(c) * w2 ** (k - 2)
    slope = np.abs(np.polyval(np.polyder(coef), 1j * wm)) if deg > 0 else np.zeros_like(w2)
    radius = half * slope + 0.5 * half**2 * curve
    return np.asarray(np.polyval(coef, 1j * wm), complex), np.asarray(radius, float)


def _edge_max(v: ComplexArray, d0: ComplexArray, e: ComplexArray) -> FloatArray:
    r"""max over t in [0, 1] of Re(v d)/|d|², d = d0 + t e (broadcast arrays)."""
    a = (v * d0).real
    b = (v * e).real
    g = np.abs(d0) ** 2
    h = (d0 * np.conj(e)).real
    ee = np.abs(e) ** 2
    qa, qb, qc = b * ee, 2 * a * ee, -(b * g - 2 * a * h)

    def f(t: FloatArray) -> FloatArray:
        return np.asarray((a + b * t) / (g + 2 * h * t + ee * t * t))

    best = np.maximum(f(np.zeros_like(a)), f(np.ones_like(a)))
    disc = qb * qb - 4 * qa * qc
    ok = disc >= 0
    sq = np.sqrt(np.where(ok, disc, 0.0))
    tiny = np.abs(qa) <= 1e-14 * (np.abs(qb) + np.abs(qc) + 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        lin = np.where(qb != 0, -qc / np.where(qb != 0, qb, 1.0), 0.0)
        r1 = np.where(tiny, lin, (-qb + sq) / np.where(tiny, 1.0, 2 * qa))
        r2 = np.where(tiny, lin, (-qb - sq) / np.where(tiny, 1.0, 2 * qa))
    for r in (r1, r2):
        valid = ok & np.isfinite(r)
        t = np.clip(np.where(valid, r, 0.0), 0.0, 1.0)
        best = np.maximum(best, f(t))
    return best


def _pentagon(
    w1: FloatArray, w2: FloatArray, lo: FloatArray, hi: FloatArray, zlo: FloatArray, zhi: FloatArray
) -> ComplexArray:
    """Vertices (N, modes, 5) of the convex pentagon holding d_i(jω) (module docstring)."""
    w1, w2 = w1[:, None], w2[:, None]
    A1, A2 = lo**2, hi**2
    x1, xm, x2 = A1 - w2**2, A1 - w1**2, A2 - w1**2
    ylo1 = 2 * zlo * w1 * np.sqrt(A1)
    ylo2 = 2 * zlo * w1 * np.sqrt(A2)
    ytop = 2 * zhi * hi * w2
    return np.stack(
        [x1 + 1j * ytop, x1 + 1j * ylo1, xm + 1j * ylo1, x2 + 1j * ylo2, x2 + 1j * ytop], -1
    )


def _segment_distance(p: ComplexArray, q: ComplexArray) -> FloatArray:
    """Distance from 0 to the segments [p, q]."""
    e = q - p
    ee = np.abs(e) ** 2
    t = np.clip(-(p * np.conj(e)).real / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
    return np.asarray(np.abs(p + t * e))


def _directions(center: npt.NDArray[np.complex128]) -> npt.NDArray[np.complex128]:
    """Unit directions (N, m): around −F(jω_m) and a uniform fan."""
    base = -center / np.where(np.abs(center) > 0, np.abs(center), 1.0)
    fan = np.exp(1j * np.linspace(-math.pi / 2, math.pi / 2, 17))
    uni = np.exp(2j * math.pi * np.arange(16) / 16)
    return np.concatenate([base[:, None] * fan[None], np.broadcast_to(uni, (center.size, 16))], 1)


def _interval_bounds(
    loop: ModalLoop, box: ParameterBox, w1: FloatArray, w2: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """(certified lower bound of |F|, or <= 0 when not certified; upper bound of |χ_u|)."""
    lo, hi, zlo, zhi = box.bounds(loop)
    c0, r0 = _poly_disc(loop.chi_c, w1, w2)
    wm = 0.5 * (w1 + w2)
    nominal = loop.characteristic(1j * wm, loop.omega0, loop.zeta0)[0] if wm.size else c0
    U = _directions(nominal)  # (N, m)
    H = (np.conj(U) * c0[:, None]).real + r0[:, None]
    scale = np.abs(c0) + r0
    V = _pentagon(w1, w2, lo, hi, zlo, zhi)  # (N, n, 5)
    P0, P1 = V, np.roll(V, -1, axis=-1)
    mind = _segment_distance(P0, P1).min(axis=-1)  # (N, n)
    for i in range(loop.n_modes):
        qc, qr = _poly_disc(loop.numerators[i], w1, w2)
        md = mind[:, i]
        bad = md <= 0
        inv = np.where(bad, np.inf, 1.0 / np.where(bad, 1.0, md))
        v = U * np.conj(qc)[:, None]  # (N, m)
        h = np.full(U.shape, -np.inf)
        for k in range(5):
            d0 = P0[:, i, k][:, None]
            e = (P1[:, i, k] - P0[:, i, k])[:, None]
            h = np.maximum(
                h, _edge_max(v, np.broadcast_to(d0, v.shape), np.broadcast_to(e, v.shape))
            )
        H = H + np.where(bad[:, None], np.inf, h + (qr * inv)[:, None])
        scale = scale + np.where(bad, np.inf, (np.abs(qc) + qr) * inv)
    lower = (-H).max(axis=1) - _SAFETY * scale
    cd, rd = _poly_disc(loop.chi_den, w1, w2)
    chi_max = np.abs(cd) + rd
    return np.where(np.isfinite(lower), lower, -np.inf), chi_max


def _tail(loop: ModalLoop, box: ParameterBox) -> tuple[float, float]:
    r"""A frequency W and ε <= 1/2 with |L(jω)| <= ε for every ω >= W and member.

    :math:`|L| \le |\chi_c - \chi| / |\chi| + \sum_i |q_i| / (|\chi|\,|d_i|)` with
    :math:`|p(j\omega)| \le \sum_k |c_k|\omega^k`, :math:`|\chi(j\omega)| \ge \prod_k (\omega -
    |r_k|)` and :math:`|d_i| \ge \omega^2 - \omega_{hi}^2`: each term is a product of factors
    ω/(ω − a) and 1/(ω ± a), all decreasing beyond the largest root (the law is proper and the
    plant strictly proper at the measurements), so the bound at W holds beyond it."""
    _, hi, _, _ = box.bounds(loop)
    roots = np.abs(np.roots(loop.chi_den)) if loop.chi_den.size > 1 else np.zeros(0)
    rest = np.asarray(np.polysub(loop.chi_c, loop.chi_den), float)
    top = max(float(hi.max(initial=0.0)), float(roots.max(initial=0.0)), 1e-3)
    W = 10.0 * top

    def mag(coef: FloatArray, w: float) -> float:
        return float(np.sum(np.abs(coef) * w ** np.arange(coef.size - 1, -1, -1)))

    for _ in range(200):
        den = float(np.prod(W - roots)) if roots.size else 1.0
        eps = mag(rest, W) / den
        eps += sum(mag(q, W) / (den * (W**2 - h**2)) for q, h in zip(loop.numerators, hi))
        if eps <= 0.5:
            return W, eps
        W *= 2.0
    raise FieldError("law", "the loop gain does not roll off: no frequency beyond which |L| < 1/2")


@dataclass(frozen=True)
class Certificate:
    """The guaranteed answer over a box (module docstring).

    Attributes
    ----------
    stable : bool
        True: every member of the box is closed-loop stable (certified). False: not certified
        (a member may still be stable; ``failed_at_rad_s`` is where exclusion failed, or NaN
        when the nominal loop itself is unstable).
    sensitivity_bound : float
        A guaranteed upper bound of sup over the box of ‖S‖∞ (inf when not certified).
    sensitivity_lower : float
        max |S| found at members evaluated during the search (a lower bound of that sup).
    worst_rad_s : float
        Frequency of the bound's worst interval.
    n_intervals : int
        Frequency intervals evaluated.
    failed_at_rad_s : float
    """

    stable: bool
    sensitivity_bound: float
    sensitivity_lower: float
    worst_rad_s: float
    n_intervals: int
    failed_at_rad_s: float


def _member_lower(loop: ModalLoop, box: ParameterBox, w: FloatArray) -> tuple[float, float]:
    """max |S(jω)| at ω = w over the nominal member and members with each mode tuned to ω."""
    lo, hi, zlo, _ = box.bounds(loop)
    tuned = np.clip(w[:, None], lo, hi)
    best, where = 0.0, float("nan")
    s = 1j * w[:, None]
    chi = np.abs(np.polyval(loop.chi_den, 1j * w))
    q = np.stack([np.polyval(c, 1j * w) for c in loop.numerators], -1)
    for om, ze in ((np.broadcast_to(loop.omega0, tuned.shape), loop.zeta0), (tuned, zlo)):
        d = s**2 + 2 * ze * om * s + om**2
        F = np.polyval(loop.chi_c, 1j * w) + (q / d).sum(axis=1)
        val = chi / np.abs(F)
        k = int(np.argmax(val))
        if val[k] > best:
            best, where = float(val[k]), float(w[k])
    return best, float(where)


def certify(
    loop: ModalLoop,
    box: ParameterBox,
    tol: float = 0.05,
    max_intervals: int = 20_000,
    performance: bool = True,
) -> Certificate:
    """Certify stability over ``box`` and bound sup ‖S‖∞ (module docstring).

    Parameters
    ----------
    loop : ModalLoop
    box : ParameterBox
    tol : float
        Refine the frequency intervals until the bound is within (1 + tol) of the lower
        estimate or cannot improve (the hull's conservatism stays).
    max_intervals : int
        Budget of interval evaluations.
    performance : bool
        False: stop once stability is certified.
    """
    if not (isinstance(tol, float | int) and 0 < tol < 1):
        raise FieldError("tol", f"must be a number in (0, 1), got {tol!r}")
    if isinstance(max_intervals, bool) or not isinstance(max_intervals, int) or max_intervals < 1:
        raise FieldError("max_intervals", f"must be a whole number >= 1, got {max_intervals!r}")
    A0 = loop.closed_loop_matrices(loop.omega0[None], loop.zeta0[None])[0]
    if A0.size and np.max(np.linalg.eigvals(A0).real) >= 0:
        return Certificate(False, math.inf, math.inf, math.nan, 0, math.nan)
    W, eps = _tail(loop, box)
    lo, hi, _, _ = box.bounds(loop)
    w_min = 1e-4 * float(min(lo.min(initial=W), W))
    grid = np.unique(np.concatenate([[0.0], np.geomspace(w_min, W, 400), lo, hi, loop.omega0]))
    grid = grid[grid <= W]
    w1, w2 = grid[:-1], grid[1:]
    bound = 1.0 / (1.0 - eps)
    worst = W
    lower = 0.0
    done_bounds: list[FloatArray] = []
    done_w1: list[FloatArray] = []
    done_w2: list[FloatArray] = []
    count = 0
    for _ in range(200):
        if w1.size == 0:
            break
        count += w1.size
        fl, chi = _interval_bounds(loop, box, w1, w2)
        lb, _ = _member_lower(loop, box, 0.5 * (w1 + w2))
        lower = max(lower, lb)
        ok = fl > 0
        fail = ~ok
        tiny = (w2 - w1) <= 1e-5 * np.maximum(w2, 1e-300)
        if np.any(fail & tiny) or (np.any(fail) and count > max_intervals):
            k = int(np.flatnonzero(fail & tiny)[0]) if np.any(fail & tiny) else int(np.argmax(fail))
            return Certificate(False, math.inf, lower, float(w1[k]), count, float(w1[k]))
        sb = np.where(ok, chi / np.where(ok, fl, 1.0), np.inf)
        refine = fail.copy()
        if performance and count <= max_intervals:
            refine |= ok & (sb > (1 + tol) * max(lower, 1.0)) & ((w2 - w1) > 1e-6 * w2)
        keep = ~refine
        done_bounds.append(sb[keep])
        done_w1.append(w1[keep])
        done_w2.append(w2[keep])
        mid = 0.5 * (w1[refine] + w2[refine])
        w1, w2 = np.concatenate([w1[refine], mid]), np.concatenate([mid, w2[refine]])
    if w1.size:  # the rounds are spent: the intervals still open are evaluated as they are
        fl, chi = _interval_bounds(loop, box, w1, w2)
        if np.any(fl <= 0):
            at = float(w1[fl <= 0][0])
            return Certificate(False, math.inf, lower, at, count, at)
        done_bounds.append(chi / fl)
        done_w1.append(w1)
        done_w2.append(w2)
    allb = np.concatenate(done_bounds)
    k = int(np.argmax(allb))
    if allb[k] > bound:
        bound = float(allb[k])
        worst = float(0.5 * (np.concatenate(done_w1)[k] + np.concatenate(done_w2)[k]))
    return Certificate(True, bound, max(lower, 1.0), worst, count, math.nan)


def stability_margin(
    loop: ModalLoop, shape: ParameterBox, k_max: float = 0.99, steps: int = 14
) -> float:
    """The largest scale k (box = k · shape, k <= k_max) certified stable, by bisection.

    Raises
    ------
    FieldError
        When the shape would push a damping ratio to zero at k_max (the box must stay damped).
    """
    if np.any(shape.frequency * k_max >= 1) or np.any(shape.damping * k_max >= 1):
        raise FieldError("k_max", "the scaled box must keep every ω and ζ above zero")
    if certify(loop, shape.scaled(k_max), performance=False, max_intervals=4000).stable:
        return k_max
    a, b = 0.0, k_max
    if not certify(loop, shape.scaled(0.0), performance=False).stable:
        return 0.0
    for _ in range(steps):
        m = 0.5 * (a + b)
        if certify(loop, shape.scaled(m), performance=False, max_intervals=4000).stable:
            a = m
        else:
            b = m
    return a


@dataclass(frozen=True)
class SweepResult:
    """A dense sweep of members of a box (module docstring).

    Attributes
    ----------
    n_members : int
    max_real_pole : float
        The largest real part of any closed-loop pole of any member.
    all_stable : bool
    sensitivity_peak : float
        max over members and the frequency grid of |S(jω)| (a lower bound of sup ‖S‖∞).
    worst_omega, worst_zeta : ndarray
        The member with the largest pole real part.
    """

    n_members: int
    max_real_pole: float
    all_stable: bool
    sensitivity_peak: float
    worst_omega: FloatArray
    worst_zeta: FloatArray


def _members(
    loop: ModalLoop, box: ParameterBox, n: int, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    lo, hi, zlo, zhi = box.bounds(loop)
    m = loop.n_modes
    corner = rng.integers(0, 2, size=(n, m)).astype(float)
    uniform = rng.random((n, m))
    pick = rng.random((n, m)) < 0.5
    t = np.where(pick, corner, uniform)
    om = lo + t * (hi - lo)
    # damping: 70 % of the draws at the lowest ratio (the least damped corner), the rest uniform
    at_low = rng.random((n, m)) < 0.7
    ze = zlo + np.where(at_low, 0.0, rng.random((n, m))) * (zhi - zlo)
    # every mode tuned onto the others' frequencies, lowest damping: the resonant alignments
    extra_w = [np.clip(np.full(m, w), lo, hi) for w in np.concatenate([lo, hi, loop.omega0])]
    om = np.vstack([om, np.array(extra_w), loop.omega0[None], lo[None], hi[None]])
    ze = np.vstack([ze, np.broadcast_to(zlo, (len(extra_w) + 3, m))])
    return om, ze


def sweep(
    loop: ModalLoop,
    box: ParameterBox,
    n_members: int = 2000,
    seed: int = 0,
    n_frequencies: int = 3000,
    chunk: int = 500,
) -> SweepResult:
    """Sample the box densely and evaluate the batch of closed loops (module docstring)."""
    for name, value in (("n_members", n_members), ("n_frequencies", n_frequencies)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise FieldError(name, f"must be a whole number >= 1, got {value!r}")
    rng = np.random.default_rng(seed)
    om, ze = _members(loop, box, n_members, rng)
    lo, hi, _, _ = box.bounds(loop)
    top = 10 * float(hi.max(initial=1.0))
    grid = np.unique(
        np.concatenate(
            [np.geomspace(1e-3 * float(lo.min(initial=1.0)), top, n_frequencies), lo, hi]
        )
    )
    worst_re, worst_k, peak = -math.inf, 0, 0.0
    for start in range(0, om.shape[0], chunk):
        o, z = om[start : start + chunk], ze[start : start + chunk]
        eig = np.linalg.eigvals(loop.closed_loop_matrices(o, z))
        re = eig.real.max(axis=1) if eig.size else np.full(o.shape[0], -math.inf)
        k = int(np.argmax(re))
        if re[k] > worst_re:
            worst_re, worst_k = float(re[k]), start + k
        stable = re < 0
        if np.any(stable):
            os_, zs = o[stable], z[stable]
            for k0 in range(0, os_.shape[0], 50):  # (members, frequencies, modes) in memory
                S = loop.sensitivity(grid, os_[k0 : k0 + 50], zs[k0 : k0 + 50])
                peak = max(peak, float(S.max()))
    return SweepResult(om.shape[0], worst_re, worst_re < 0, peak, om[worst_k], ze[worst_k])


def sweep_stability_margin(
    loop: ModalLoop,
    shape: ParameterBox,
    k_max: float = 0.99,
    steps: int = 14,
    n_members: int = 400,
    seed: int = 0,
) -> float:
    """The smallest scale k at which the sweep finds an unstable member (k_max when none): an
    upper estimate of the true margin, to set against :func:`stability_margin`."""
    if sweep(loop, shape.scaled(k_max), n_members, seed, n_frequencies=2).all_stable:
        return k_max
    a, b = 0.0, k_max
    for _ in range(steps):
        m = 0.5 * (a + b)
        if sweep(loop, shape.scaled(m), n_members, seed, n_frequencies=2).all_stable:
            a = m
        else:
            b = m
    return b
