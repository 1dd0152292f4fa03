"""Control of Bainum & Reddy's free-free beam in orbit (Bainum & Reddy 1979, NASA CR-158684,
Howard University): Ch. II controllability Cases 1-4 (:func:`chapter2_case`) and its numerical
example (:func:`chapter2_example`); Ch. III decoupling (:func:`decoupling_gains`) and the
per-mode linear regulator in closed form (:func:`modal_riccati`, :func:`modal_lqr_gains`).

The beam model is :mod:`flexsat.cases.bainum`. Sign convention of the gains (the report's,
Ch. III eq 3): f = K_pos x + K_rate x', so the closed loop is x'' + F x = G (K_pos x +
K_rate x').
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.analysis.controllability import (
    RepeatedFrequencyResult,
    controllability_rank,
    pbh_test,
    repeated_frequency_test,
)
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    pass
from flexsat.cases.bainum import (
    PUBLISHED,
    BainumBeam,
    bainum,
    check_modal_input,
    check_stiffness,
    closed_loop_matrix,
    first_order,
    published_matrix,
    sorted_poles,
)

__all__ = [
    "CH2_LAYOUTS",
    "ClosedLoop",
    "ControllabilityCase",
    "chapter2_case",
    "chapter2_example",
    "chapter3_case",
    "decoupling_gains",
    "modal_lqr_gains",
    "modal_riccati",
]


# -- Ch. II: controllability cases 1-4 and the numerical example --------------------------------
#: (pitch in the model, bending modes, actuator positions ξ/l), Bainum & Reddy 1979 Ch. II §3
CH2_LAYOUTS = {
    1: (True, 2, (-0.5,)),
    2: (False, 2, (-0.5, 0.5, 0.0)),
    3: (True, 1, (-0.5, 0.5)),
    4: (True, 2, (-0.5, 0.5, 0.0)),
}


@dataclass(frozen=True)
class ControllabilityCase:
    """A Ch. II case: the reduced pair of eq 17, ``stiffness`` = diag(A), ``B``, and the tests."""

    case: int
    stiffness: np.ndarray
    B: np.ndarray
    positions: tuple[float, ...]
    kalman_rank: int
    blocks: RepeatedFrequencyResult
    uncontrollable: np.ndarray  # PBH on the first-order 2n-state model

    @property
    def n(self) -> int:
        return self.stiffness.size

    @property
    def controllable(self) -> bool:
        return self.kalman_rank == self.n


def chapter2_case(
    case: int,
    c: float | None = None,
    d: float | None = None,
    beam: BainumBeam | None = None,
    midspan: str = "exact",
) -> ControllabilityCase:
    """Ch. II Case 1-4: reduced pair (A, B) of eq 17 and its controllability.

    Parameters
    ----------
    case : {1, 2, 3, 4}
        Layout of :data:`CH2_LAYOUTS`.
    c, d : float, optional
        (ω_1/ω_c)² and (ω_2/ω_c)² (default the beam's, 3200 and 28800); pitch is κ = 3, so
        Case 4 loses controllability exactly when d = 3 (ω_2 = √3 ω_c).
    beam : BainumBeam, optional
        Influence coefficients a = ``pitch_influence`` and b = 2·``modal_influence``.
    midspan : {"exact", "published"}
        Mode-1 value at the midspan actuator: the Appendix A shape (-1.21564, erratum) or the
        report's -√2 (e = √2/(M_1 l ω_c²), Ch. II §3, Cases 2 and 4).

    Returns
    -------
    ControllabilityCase
        Kalman rank of the reduced pair (n x np, Balas' reduction), the repeated-
        frequency block test, and PBH uncontrollable eigenvalues of the full 2n-state model.
    """
    if case not in CH2_LAYOUTS:
        raise FieldError("case", f"must be one of {sorted(CH2_LAYOUTS)}, got {case!r}")
    if midspan not in ("exact", "published"):
        raise FieldError("midspan", f"must be 'exact' or 'published', got {midspan!r}")
    beam = bainum() if beam is None else beam
    pitch, k, positions = CH2_LAYOUTS[case]
    F = beam.ratios(k)
    for i, (name, value) in enumerate((("c", c), ("d", d))[:k]):
        if value is not None:
            F[i] = float(require_finite(value, name))
    B = beam.actuator_matrix(positions, k, pitch=pitch)
    if midspan == "published":
        B[int(pitch), np.asarray(positions) == 0.0] = -np.sqrt(2.0) * beam.modal_influence
    kappa = np.concatenate([[3.0], F]) if pitch else F
    A_full, B_full = first_order(kappa, B)
    return ControllabilityCase(
        case,
        kappa,
        B,
        positions,
        controllability_rank(np.diag(kappa), B),
        repeated_frequency_test(kappa, B),
        pbh_test(A_full, B_full),
    )


@dataclass(frozen=True)
class ClosedLoop:
    """A closed loop x'' + F x = G (K_pos x + K_rate x') and its poles."""

    stiffness: np.ndarray
    G: np.ndarray
    K_pos: np.ndarray
    K_rate: np.ndarray
    matrix: np.ndarray = field(repr=False)
    poles: np.ndarray


def _closed_loop(stiffness, G, K_pos, K_rate) -> ClosedLoop:
    M = closed_loop_matrix(stiffness, G, K_pos, K_rate)
    G = np.asarray(G, dtype=float)
    G = G.reshape(-1, 1) if G.ndim == 1 else G
    return ClosedLoop(
        np.asarray(stiffness, float),
        G,
        np.asarray(K_pos, float),
        np.asarray(K_rate, float),
        M,
        sorted_poles(M),
    )


def chapter2_example(
    gains: npt.ArrayLike = PUBLISHED["ch2_gains"], beam: BainumBeam | None = None
) -> ClosedLoop:
    """Ch. II §4: Case 1 (one actuator at ξ = -l/2, pitch + 2 modes) with the
    printed rate feedback f = K1 x1' + K2 x2' + K3 x3' (the Ch. II §4 errata applied: the equations
    are built from eq 16).

    Poles with the printed gains: -0.171737 ± 1.723625j, -0.565594 ± 56.562701j,
    -0.169485 ± 169.703929j. The gains are not a decoupling design (one actuator
    cannot decouple three coordinates); they match uncoupled ζ = 0.1, 0.01, 0.001.
    """
    beam = bainum() if beam is None else beam
    K = require_finite(gains, "gains").reshape(1, -1)
    if K.shape != (1, 3):
        raise FieldError("gains", f"must be the three rate gains K1, K2, K3, got {gains!r}")
    G = beam.actuator_matrix(CH2_LAYOUTS[1][2], 2)
    return _closed_loop(beam.stiffness(2), G, np.zeros((1, 3)), K)


# -- Ch. III: decoupling and per-mode linear regulator ------------------------------------------
def _svd_rank(M: np.ndarray, rtol: float) -> int:
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0


def decoupling_gains(
    G: npt.ArrayLike,
    stiffness: npt.ArrayLike,
    damping_ratio: npt.ArrayLike = 1.0,
    target_stiffness: npt.ArrayLike | None = None,
    damping: npt.ArrayLike | None = None,
    rtol: float = 1e-8,
) -> tuple[np.ndarray, np.ndarray]:
    """Decoupling state feedback of Ch. III §2 (eqs 1-13).

    For ``x'' + E x' + F x = G f`` (E = ``damping``, default 0; F = diag(``stiffness``)) and
    f = L x + K x' (eq 3), the closed loop x'' + (E - GK) x' + (F - GL) x = 0 is decoupled with
    E - GK = Z = diag(2 ζ_i √W_i) and F - GL = W = diag(``target_stiffness``, default F):
    column by column G K_i = (E - Z)_i and G L_i = (F - W)_i (eq 12).

    Each column is solvable iff rank G = rank [G | column] (Rouché-Capelli; the report's rule
    "rank must be n when n > m", Ch. III §2, is impossible); the solution is unique iff
    rank G = m (columns of G), otherwise the minimum-norm one is returned. Ranks count singular
    values above ``rtol`` · σ_max.

    Parameters
    ----------
    G : (n, m) array_like
        Modal input matrix (eq 9: A⁻¹D; the beam's B_act).
    stiffness : (n,) array_like
        F = diag(A⁻¹C), e.g. (3, 3200, 28800).
    damping_ratio : float or (n,) array_like
        ζ of each decoupled coordinate; 1 = critical (the report's choice, Ch. III §4).
    target_stiffness, damping : optional
        W (default F: rate feedback only, L = 0) and E (default 0).

    Returns
    -------
    K_pos, K_rate : (m, n) ndarray
        L and K of eq 3.

    Raises
    ------
    ValueError
        Bad shapes or values; ``G``: a column has no solution (decoupling impossible with these
        actuators), with the rank numbers.
    """
    F = check_stiffness(stiffness)
    n = F.size
    G = check_modal_input(G, n)
    W = F if target_stiffness is None else check_stiffness(target_stiffness, "target_stiffness")
    if W.size != n:
        raise FieldError("target_stiffness", f"must have {n} entries, got {W.size}")
    if np.any(W < 0):
        raise FieldError("target_stiffness", f"must be >= 0, got {W.tolist()}")
    zeta = np.broadcast_to(require_finite(damping_ratio, "damping_ratio"), (n,))
    if np.any(zeta < 0):
        raise FieldError("damping_ratio", f"must be >= 0, got {damping_ratio!r}")
    E = np.zeros((n, n)) if damping is None else require_finite(damping, "damping")
    if E.shape != (n, n):
        raise FieldError("damping", f"must be {n}x{n}, got shape {E.shape}")
    rhs_rate = E - np.diag(2 * zeta * np.sqrt(W))
    rhs_pos = np.diag(F) - np.diag(W)
    rank_G = _svd_rank(G, rtol)
    for name, rhs in (("rate", rhs_rate), ("position", rhs_pos)):
        for i in range(n):
            r = _svd_rank(np.column_stack([G, rhs[:, i]]), rtol)
            if r > rank_G:
                raise FieldError(
                    "G",
                    f"decoupling impossible: {name} column {i + 1} is not in the range of G "
                    f"(rank G = {rank_G}, rank [G | column] = {r}); move or add actuators",
                )
    G_pinv = np.linalg.pinv(G, rcond=rtol)
    return G_pinv @ rhs_pos, G_pinv @ rhs_rate


def modal_riccati(
    stiffness: npt.ArrayLike,
    Q1: npt.ArrayLike = 1.0,
    Q2: npt.ArrayLike | None = None,
    R: npt.ArrayLike = 1.0,
    D: npt.ArrayLike = 0.0,
) -> tuple[np.ndarray, ...]:
    """Closed-form 2x2 Riccati solution of one modal coordinate (Ch. III eqs 19-27).

    For x'' + D x' + F x = u', cost ∫ (Q1 x² + Q2 x'² + R u'²) dτ, the stabilizing S of
    ``-SA - AᵀS + S b R⁻¹ bᵀ S - Q = 0`` (eq 24) is

    - S12 = R [-F + √(F² + Q1/R)]                 (eq 25)
    - S22 = R [-D + √(D² + (Q2 + 2 S12)/R)]       (eq 26)
    - S11 = F S22 + D S12 + S12 S22 / R          (eq 27)

    with the + roots. Eq 25 (and 26) cancel catastrophically when F² ≫ Q1/R; they are
    evaluated as Q1/(F + √(F² + Q1/R)) for F > 0. The control is
    u' = -(S12 x + S22 x')/R (eq 28 has R = 1).

    Parameters
    ----------
    stiffness : float or array_like
        F_i (any real; vectorized).
    Q1, Q2 : float or array_like
        Position and rate weights, >= 0. ``Q2=None`` is F: rates "penalized by a factor of
        frequency squared" (Ch. III §4), the report's choice with Q1 = R = 1.
    R : float or array_like
        Control weight, > 0.
    D : float or array_like
        Modal damping D_i (0 for the beam).

    Returns
    -------
    S11, S12, S22 : ndarray
        Pitch (F = 3, Q = diag(1, 3), R = 1): 5.7658957, 0.16227766, 1.8233363.

    Raises
    ------
    ValueError
        ``R`` not > 0 (not positive definite), ``Q1``/``Q2`` negative, or no stabilizing
        solution (a coordinate the weights do not see, e.g. F = 0 with Q1 = 0).
    """
    F = np.asarray(require_finite(stiffness, "stiffness"), dtype=float)
    Q1 = require_finite(Q1, "Q1")
    Q2 = F if Q2 is None else require_finite(Q2, "Q2")
    R = require_finite(R, "R")
    D = require_finite(D, "D")
    if np.any(R <= 0):
        raise FieldError("R", f"must be > 0 (positive definite control weight), got {R.tolist()}")
    for name, Q in (("Q1", Q1), ("Q2", Q2)):
        if np.any(Q < 0):
            raise FieldError(name, f"must be >= 0 (positive semidefinite weight), got {Q.tolist()}")
    F, Q1, Q2, R, D = np.broadcast_arrays(F, Q1, Q2, R, D)
    q = Q1 / R
    root = np.sqrt(F * F + q)
    with np.errstate(divide="ignore", invalid="ignore"):
        S12 = R * np.where(F > 0, q / (F + root), root - F)
        p = (Q2 + 2 * S12) / R
        rootd = np.sqrt(D * D + p)
        S22 = R * np.where(D > 0, p / (D + rootd), rootd - D)
    S11 = F * S22 + D * S12 + S12 * S22 / R
    # closed loop s² + (D + S22/R) s + (F + S12/R): Hurwitz iff both coefficients > 0
    bad = ~((D + S22 / R > 0) & (F + S12 / R > 0))
    if np.any(bad):
        raise ValueError(
            f"Q1, Q2: no stabilizing solution for coordinate(s) "
            f"{np.flatnonzero(np.atleast_1d(bad)).tolist()} (the weights do not "
            f"see an undamped or unstable coordinate, e.g. F = 0 with Q1 = 0)"
        )
    return S11, S12, S22


def modal_lqr_gains(
    G: npt.ArrayLike,
    stiffness: npt.ArrayLike,
    Q1: npt.ArrayLike = 1.0,
    Q2: npt.ArrayLike | None = None,
    R: npt.ArrayLike = 1.0,
    D: npt.ArrayLike = 0.0,
    rcond: float = 1e-8,
) -> tuple[np.ndarray, np.ndarray]:
    """Per-mode linear regulator mapped to the actuators (Ch. III eqs 16-28).

    x'' + D x' + F x = G f = u' (eq 16-17 with E = G); each coordinate gets
    u'_i = -(S_i12 x_i + S_i22 x_i')/R_i (:func:`modal_riccati`) and f = G⁻¹ u' (eq 18), i.e.
    K_pos = -G⁻¹ diag(S12/R), K_rate = -G⁻¹ diag(S22/R) in the report's f = K_pos x + K_rate x'.

    Raises
    ------
    ValueError
        ``G`` not square (#actuators ≠ #coordinates: use the full 2n x 2n regulator,
        :func:`flexsat.control.lqr`, Ch. V) or singular (σ_min ≤ ``rcond`` σ_max, e.g. the
        exact-shape symmetric five-actuator layout of Ch. III Case 2); and the
        errors of :func:`modal_riccati`.
    """
    F = check_stiffness(stiffness)
    n = F.size
    G = check_modal_input(G, n)
    if G.shape != (n, n):
        raise FieldError(
            "G",
            "per-mode regulator needs as many actuators as coordinates "
            f"(u = E⁻¹u', eq 18), got shape {G.shape}; use the full regulator",
        )
    s = np.linalg.svd(G, compute_uv=False)
    if s[-1] <= rcond * s[0]:
        raise FieldError(
            "G",
            f"singular (σ_min/σ_max = {s[-1] / s[0]:.3g} <= {rcond:g}): these "
            f"actuators cannot drive every coordinate independently",
        )
    _, S12, S22 = modal_riccati(F, Q1, Q2, R, D)
    R = np.broadcast_to(np.asarray(R, dtype=float), (n,))
    return (np.linalg.solve(G, -np.diag(S12 / R)), np.linalg.solve(G, -np.diag(S22 / R)))


def chapter3_case(
    case: int, beam: BainumBeam | None = None, shapes: str = "published"
) -> tuple[np.ndarray, np.ndarray]:
    """(stiffness, G) of Ch. III Case 1 (pitch + 2 modes, actuators -l/2, +l/2, +l/4; Ch. III §4)
    or Case 2 (pitch + 4 modes, -l/2, -l/4, 0, +l/4, +l/2; Ch. III §4).

    ``shapes="published"``: the printed G with the errata (G13 = -29.76); ``"exact"``: built
    from the Appendix A shapes (Case 2 is then singular: symmetric forces drive only modes 1
    and 3).
    """
    if case not in (1, 2):
        raise FieldError("case", f"must be 1 or 2, got {case!r}")
    if shapes not in ("published", "exact"):
        raise FieldError("shapes", f"must be 'published' or 'exact', got {shapes!r}")
    beam = bainum() if beam is None else beam
    k = 2 if case == 1 else 4
    if shapes == "published":
        G = published_matrix(f"ch3_case{case}_G")
    else:
        G = beam.actuator_matrix(PUBLISHED[f"ch3_case{case}_positions"], k)
    return beam.stiffness(k), G
