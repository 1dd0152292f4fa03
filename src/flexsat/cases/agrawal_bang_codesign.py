r"""PPF gains (and filter tuning) together with piezo placement on the Agrawal–Bang L structure:
a reference co-design problem (issue 23, deliverable 6).

The structure, the piezo pairs and the PPF bank are those of :mod:`flexsat.cases.agrawal_bang`
and :mod:`flexsat.control.ppf` (B. N. Agrawal and H. Bang, *Adaptive Structures for Large
Precision Antennas*, Acta Astronautica 1996, IAF-94.1.4.202, Eqs. 2–8): each patch is a
pair of equal and opposite moments a₁u at its end nodes (modal influence a₁ (Φ_θ,b − Φ_θ,a)),
its sensor the collocated surface strain a₂ (t/2)(θ_b − θ_a)/L_p, one second-order filter per
(pair, mode) tuned to the mode, u = Eᵀ G ξ. Here the pairs are chosen among ``candidates``
patch locations (the published placement, :data:`flexsat.cases.agrawal_bang.DEFAULT_PATCHES`,
among them), and the filters' gains (and, with ``tune_filters``, their frequencies) are
designed for the chosen set.

**Closed loop and responses.** With x = [η, η̇, ξ, ξ̇] and Ā(p) = A₀(ν) + B K(g) (Eq. 8; ν_ij =
ω_f,ij / ω_j the filter tuning ratios, g the gains), a white force disturbance w of unit
intensity (N² s) at the tip of structure 2 in the plane of the L enters as B_w = [0; Φ_tipᵀ;
0; 0]. The performance output is z = [Eᵗ; √ρ u], Eᵗ the tip error of Agrawal & Bang's Eq. 33
(m) and ρ the control weight (m²/(N m)²). The responses, with their gradients by the
Lyapunov adjoint (K. Zhou, J. C. Doyle and K. Glover, *Robust and Optimal Control*, Prentice
Hall 1996, §4.4; one controllability Gramian L_c and one adjoint per response), are

.. math::

    \|T_{wz}\|_2^2 = \mathrm{tr}(C_z L_c C_z^T),\quad
    \bar A L_c + L_c \bar A^T + B_w B_w^T = 0,\qquad
    \frac{\partial \|T_{wz}\|_2^2}{\partial p}
      = 2\,\mathrm{tr}\Big(L_o \frac{\partial\bar A}{\partial p} L_c\Big)
      + 2\,\mathrm{tr}\Big(C_z L_c \frac{\partial C_z^T}{\partial p}\Big),\quad
    \bar A^T L_o + L_o \bar A + C_z^T C_z = 0,

* ``h2`` — ‖T_wz‖₂, m/(N s^½) (the RMS tip error, with the control term, per unit force
  intensity);
* ``effort_1`` … ``effort_<n>`` — σ_i = sqrt(K_i L_c K_iᵀ), the RMS moment of pair i, N m
  (the same formula with C = K_i, the pair's command row; ∂σ/∂p = ∂σ²/∂p / (2σ));
* ``stiffness_margin`` — λ_min(S)/ω₁², S = Ω − B_a Eᵀ G E C_s the static closed-loop stiffness
  of Eq. 6 (the PPF stability condition: with G ≥ 0 and positive damping, S > 0 ⇔ stable),
  gradient φᵀ (∂S/∂g) φ (Eq. 26) for a simple λ_min; independent of ν (each filter passes a
  static signal with unit gain).

The Lyapunov equations are solved in balanced coordinates x = D x̃ (D the diagonal of powers
of two of :func:`scipy.linalg.matrix_balance`, an exact scaling) and mapped back: the modal and
filter states differ by orders of magnitude, and balancing lowers the solves' round-off from
~1e-10 to ~1e-14 relative (measured through central differences, docs). Units: with the
case's a₁ = a₂ = 1 a command is a patch moment (N m) and a sensor signal a strain, so g_ij is
in N m per unit strain. Where a pair's gains are all zero σ_i = 0 and its gradient is reported
as zero (σ_i has a minimum there).

**Box and stability.** Gains are bounded to 0 <= g_ij <= ḡ_i with
ḡ_i = ``gain_fraction`` / (n_a n_t r_i c_iᵀ Ω⁻¹ c_i) (c_i the sensor row, r_i = a₁/a₂ of the
pair): then ‖Ω^{-½} (Ω − S) Ω^{-½}‖ <= Σ_i n_t ḡ_i r_i c_iᵀ Ω⁻¹ c_i = ``gain_fraction`` < 1, so S
stays positive definite over the whole box and every design an optimiser visits is a stable
loop (the H2 norm is finite there); the designer's margin is the constraint λ_min(S) >= m ω₁².

**Discrete placement.** :meth:`AgrawalBangCodesign.for_selection` builds the same problem for
another set of candidates; :func:`placement_codesign` chooses the set by
:func:`flexsat.design.placement_design.place_then_optimize` (greedy, exchange or exhaustive)
with the nested continuous optimum as the score. Every candidate's patch ends are nodes of one
mesh (the case built with all candidates' patches), so every set is judged on the same
finite-element model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla

from flexsat.cases.agrawal_bang import DEFAULT_PATCHES, AgrawalBangCase, agrawal_bang
from flexsat.cases.agrawal_bang_ppf import ZETA_F, tip_error_rows
from flexsat.control.ppf import PPFModel, ppf_feedback, ppf_state_matrices, replicate_matrix
from flexsat.design.describe import DesignFeature, sorted_poles
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.design.placement_design import PlacementDesign, nested_score, place_then_optimize
from flexsat.input_checks import FieldError, require_positive_scalar
from flexsat.units import FloatArray, to_si

__all__ = [
    "CANDIDATES",
    "PUBLISHED_GAIN",
    "PUBLISHED_SELECTION",
    "AgrawalBangCodesign",
    "placement_codesign",
]

#: candidate patch locations (structure 1 or 2, start from that structure's root, m): the
#: published placement (:data:`~flexsat.cases.agrawal_bang.DEFAULT_PATCHES`) first, then
#: patches spread along both structures, none overlapping another (2 in patches)
CANDIDATES: tuple[tuple[int, float], ...] = (
    *((b, float(to_si(s, "m"))) for b, s in DEFAULT_PATCHES),
    (1, 0.25),
    (1, 0.5),
    (1, 0.75),
    (2, 0.15),
    (2, 0.6),
)
#: the published placement: the first three candidates
PUBLISHED_SELECTION = (0, 1, 2)
#: the published gains: every g_ij = 100 (Agrawal & Bang 1996, Tables 1–3, initial gains)
PUBLISHED_GAIN = 100.0


def _lyap(A: FloatArray, Q: FloatArray) -> FloatArray:
    """X with A X + X Aᵀ + Q = 0 (Bartels–Stewart), symmetrised."""
    X = sla.solve_continuous_lyapunov(A, -Q)
    return np.asarray(0.5 * (X + X.T), dtype=float)


@dataclass
class AgrawalBangCodesign:
    """The co-design problem for one set of pairs (module docstring); fields SI.

    Attributes
    ----------
    selection : tuple of int
        Indices into ``candidates`` of the pairs used (default: the published placement).
    candidates : tuple of (structure, start m)
        Candidate patch locations.
    n_modes : int
        Modes of the model (Agrawal & Bang: 3).
    tuned_modes : int or None
        Filters per pair, tuned to the first ``tuned_modes`` modes (default: every mode, as
        the paper). A filter whose gain is zero does nothing, so a design with the higher
        filters at zero gain is the same design with fewer filters.
    zeta_f : float
        Filter damping ratio in (0, 1] (not published; 0.1 as
        :mod:`flexsat.cases.agrawal_bang_ppf`).
    tune_filters : bool
        Also design the tuning ratios ν_ij = ω_f,ij/ω_j (else ν = 1: the paper's tuning).
    control_weight : float
        ρ on u² in z, m²/(N m)².
    stiffness_margin : float
        The designer's margin m: λ_min(S) >= m ω₁² (problem()'s constraint).
    effort_max : float
        RMS moment bound of each pair, N m (problem()'s constraint).
    gain_fraction : float
        The box's share of the static stability limit (module docstring), in (0, 1).
    ratio_bounds : (lower, upper)
        Bounds of ν.
    start_gain : float
        Every g_ij at the start.
    """

    selection: tuple[int, ...] = PUBLISHED_SELECTION
    candidates: tuple[tuple[int, float], ...] = CANDIDATES
    n_modes: int = 3
    tuned_modes: int | None = None
    zeta_f: float = ZETA_F
    tune_filters: bool = False
    control_weight: float = 1e-6
    stiffness_margin: float = 0.5
    effort_max: float = 2.0
    gain_fraction: float = 0.9
    ratio_bounds: tuple[float, float] = (0.7, 2.0)
    start_gain: float = PUBLISHED_GAIN
    _case: AgrawalBangCase = field(init=False, repr=False)
    _memo: dict[bytes, dict[str, tuple[float, FloatArray]]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in ("zeta_f", "control_weight", "stiffness_margin", "effort_max", "start_gain"):
            require_positive_scalar(getattr(self, name), name)
        if not self.zeta_f <= 1:
            raise FieldError("zeta_f", f"must be in (0, 1] (a damping ratio), got {self.zeta_f}")
        if not 0 < self.gain_fraction < 1:
            raise FieldError("gain_fraction", f"must lie in (0, 1), got {self.gain_fraction!r}")
        if not self.stiffness_margin < 1:
            raise FieldError(
                "stiffness_margin", f"must be < 1 (a share of ω₁²), got {self.stiffness_margin}"
            )
        lo, hi = self.ratio_bounds
        if not 0 < lo < 1 < hi:
            raise FieldError("ratio_bounds", f"must be 0 < lower < 1 < upper, got {(lo, hi)}")
        if isinstance(self.n_modes, bool) or not isinstance(self.n_modes, int):
            raise FieldError("n_modes", f"must be an integer, got {self.n_modes!r}")
        if not 1 <= self.n_modes <= 6:
            raise FieldError("n_modes", f"must be 1 to 6, got {self.n_modes}")
        nt = self.n_modes if self.tuned_modes is None else self.tuned_modes
        if isinstance(nt, bool) or not isinstance(nt, int) or not 1 <= nt <= self.n_modes:
            raise FieldError(
                "tuned_modes", f"must be an integer 1 to n_modes = {self.n_modes}, got {nt!r}"
            )
        self.n_tuned = nt
        self.candidates = _candidate_list(self.candidates)
        self._case = _candidate_case(self.candidates)
        sel = tuple(self.selection)
        if not sel or any(
            isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(self.candidates)
            for k in sel
        ):
            raise FieldError(
                "selection",
                f"must be indices 0 to {len(self.candidates) - 1} of the candidates, got {sel!r}",
            )
        if len(set(sel)) != len(sel):
            raise FieldError("selection", f"must not repeat a candidate, got {sel!r}")
        self.selection = sel
        self._build()

    # -- the model of the selected pairs ------------------------------------------------------
    def _build(self) -> None:
        case, m = self._case, self.n_modes
        modal = case.modal_model(m)
        pairs = case.piezo_pairs(m)
        self.model = PPFModel.from_pairs(
            modal.frequencies, modal.damping, [pairs[k] for k in self.selection]
        )
        na, nt = self.model.n_actuators, self.n_tuned
        self.E = replicate_matrix(na, nt)
        w = self.model.omega
        # the box of the gains (module docstring)
        reach = np.array(
            [self.model.ratio[i] * np.sum(self.model.sensors[i] ** 2 / w**2) for i in range(na)]
        )
        self.gain_upper = self.gain_fraction / (na * nt * reach)
        tip = case.tip_node
        Bw = np.column_stack(
            [modal.displacement_output(tip, "x"), modal.displacement_output(tip, "y")]
        )
        nx = 2 * m + 2 * na * nt
        self.Bw = np.zeros((nx, 2))
        self.Bw[m : 2 * m] = Bw
        self.Cz_structure = np.zeros((2, nx))
        self.Cz_structure[:, :m] = tip_error_rows(case, m)[:2]

    @property
    def n_actuators(self) -> int:
        return self.model.n_actuators

    @property
    def names(self) -> tuple[str, ...]:
        na, nt = self.n_actuators, self.n_tuned
        gains = tuple(f"g{i + 1}{j + 1}" for i in range(na) for j in range(nt))
        if not self.tune_filters:
            return gains
        return gains + tuple(f"nu{i + 1}{j + 1}" for i in range(na) for j in range(nt))

    def split(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(gains, tuning ratios) of a design vector."""
        nf = self.n_actuators * self.n_tuned
        x = np.asarray(x, dtype=float)
        nu = x[nf : 2 * nf] if self.tune_filters else np.ones(nf)
        return x[:nf], nu

    def published_design(self) -> FloatArray:
        """Every g_ij = 100 (and ν = 1): the paper's gains on this problem's pairs."""
        nf = self.n_actuators * self.n_tuned
        nu = np.ones(nf if self.tune_filters else 0)
        return np.concatenate([np.full(nf, PUBLISHED_GAIN), nu])

    def matrices(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(Ā, C_z, K) of a design."""
        g, nu = self.split(x)
        m = self.n_modes
        A0, B = ppf_state_matrices(
            self.model.omega,
            self.model.zeta,
            self.model.actuators,
            self.model.sensors,
            np.tile(self.model.omega[: self.n_tuned], self.n_actuators) * nu,
            np.full(g.size, self.zeta_f),
            self.E,
        )
        K = ppf_feedback(g, self.E, m)
        Cz = np.vstack([self.Cz_structure, np.sqrt(self.control_weight) * K])
        return A0 + B @ K, Cz, K

    def _derivatives(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """∂Ā/∂p (P, n, n) and ∂K/∂p (P, n_a, n) (∂C_z = [0; √ρ ∂K])."""
        g, nu = self.split(x)
        m, na, nt = self.n_modes, self.n_actuators, self.n_tuned
        nf = na * nt
        nx = 2 * m + 2 * nf
        P = len(self.names)
        dA = np.zeros((P, nx, nx))
        dK = np.zeros((P, na, nx))
        act = np.argmax(self.E, axis=1)
        Ba = self.model.actuators
        for k in range(nf):
            dK[k, act[k], 2 * m + k] = 1.0
            dA[k, m : 2 * m, 2 * m + k] = Ba[:, act[k]]
        if self.tune_filters:
            wf0 = np.tile(self.model.omega[:nt], na)
            EC = self.E @ self.model.sensors
            for k in range(nf):
                w0, wf = wf0[k], wf0[k] * nu[k]
                row = 2 * m + nf + k
                dA[nf + k, row, :m] = 2 * wf * w0 * EC[k]
                dA[nf + k, row, 2 * m + k] = -2 * wf * w0
                dA[nf + k, row, 2 * m + nf + k] = -2 * self.zeta_f * w0
        return dA, dK

    # -- responses ----------------------------------------------------------------------------
    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        """``h2``, ``effort_<i>``, ``stiffness_margin`` with their gradients (module docstring)."""
        key = np.asarray(x, dtype=float).tobytes()
        if key not in self._memo:
            self._memo.clear()
            self._memo[key] = self._evaluate(np.array(x, dtype=float))
        return self._memo[key]

    def _evaluate(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        Abar, Cz, K = self.matrices(x)
        alpha = float(np.linalg.eigvals(Abar).real.max())
        if not alpha < 0:
            raise FieldError(
                "x", f"the closed loop is unstable (max Re λ = {alpha:.3g} 1/s): no H2 norm"
            )
        dA, dK = self._derivatives(x)
        # solve in balanced coordinates x = D x̃ (D a diagonal of powers of 2: exact scaling;
        # the filter and modal states differ by orders of magnitude), then map back
        d = sla.matrix_balance(Abar, permute=False, separate=True)[1][0]
        Ab = Abar * d[None, :] / d[:, None]
        Bb = self.Bw / d[:, None]
        Lc = _lyap(Ab, Bb @ Bb.T) * np.outer(d, d)
        AT = np.ascontiguousarray(Ab.T)
        rho = self.control_weight

        def squared(C: FloatArray, dC: FloatArray) -> tuple[float, FloatArray]:
            Cb = C * d[None, :]
            Lo = _lyap(AT, Cb.T @ Cb) / np.outer(d, d)
            value = float(np.sum((C @ Lc) * C))
            # tr(L_o ∂Ā L_c) = ⟨∂Ā, L_o L_c⟩ (L_o, L_c symmetric); tr(C L_c ∂Cᵀ) = ⟨∂C, C L_c⟩
            P = dA.shape[0]
            grad = 2 * (dA.reshape(P, -1) @ (Lo @ Lc).ravel()) + 2 * (
                dC.reshape(P, -1) @ (C @ Lc).ravel()
            )
            return value, grad

        nz = Cz.shape[0]
        dCz = np.zeros((len(self.names), nz, Abar.shape[0]))
        dCz[:, 2:] = np.sqrt(rho) * dK
        h2sq, dh2sq = squared(Cz, dCz)
        h2 = np.sqrt(h2sq)
        out: dict[str, tuple[float, FloatArray]] = {"h2": (float(h2), dh2sq / (2 * h2))}
        for i in range(self.n_actuators):
            var, dvar = squared(K[i : i + 1], dK[:, i : i + 1])
            sigma = np.sqrt(max(var, 0.0))
            grad = dvar / (2 * sigma) if sigma > 0 else np.zeros_like(dvar)
            out[f"effort_{i + 1}"] = (float(sigma), grad)
        g, _ = self.split(x)
        S = self.stiffness(g)
        lam, phi = np.linalg.eigh(S)
        w1sq = self.model.omega[0] ** 2
        dS = self._stiffness_gradient()
        dlam = np.zeros(len(self.names))
        dlam[: g.size] = np.einsum("l,klm,m->k", phi[:, 0], dS, phi[:, 0])
        out["stiffness_margin"] = (float(lam[0] / w1sq), dlam / w1sq)
        return out

    def stiffness(self, g: FloatArray) -> FloatArray:
        """S = Ω − B_a (Eᵀ G E) C_s (Eq. 6), symmetrised."""
        s = np.asarray(g, float) @ self.E
        Ba, Cs = self.model.actuators, self.model.sensors
        S = np.diag(self.model.omega**2) - Ba @ np.diag(s) @ Cs
        return np.asarray(0.5 * (S + S.T), dtype=float)

    def _stiffness_gradient(self) -> FloatArray:
        Ba, Cs = self.model.actuators, self.model.sensors
        outer = -np.einsum("ki,il->ikl", Ba, Cs)
        outer = 0.5 * (outer + np.swapaxes(outer, -1, -2))
        return np.asarray(outer[np.argmax(self.E, axis=1)], dtype=float)

    # -- the design problem -------------------------------------------------------------------
    def problem(self) -> DesignProblem:
        """min ‖T_wz‖₂ s.t. λ_min(S) >= m ω₁², σ_i <= effort_max, the box (module docstring)."""
        na, nt = self.n_actuators, self.n_tuned
        variables = []
        for i in range(na):
            ub = float(self.gain_upper[i])
            for j in range(nt):
                start = min(self.start_gain, 0.5 * ub)
                variables.append(
                    DesignVariable(f"g{i + 1}{j + 1}", start, 0.0, ub, scale=ub / 10, unit="N*m")
                )
        if self.tune_filters:
            lo, hi = self.ratio_bounds
            for i in range(na):
                for j in range(nt):
                    variables.append(DesignVariable(f"nu{i + 1}{j + 1}", 1.0, lo, hi, scale=1.0))
        x0 = np.array([v.value for v in variables])
        h0 = self.responses(x0)["h2"][0]

        def response(name: str, sign: float, offset: float) -> Any:
            def value(x: FloatArray) -> tuple[float, FloatArray]:
                v, gr = self.responses(x)[name]
                return sign * (v - offset), sign * gr

            return value

        constraints = [
            Constraint(
                "stiffness margin",
                response("stiffness_margin", -1.0, self.stiffness_margin),
                scale=self.stiffness_margin,
            )
        ]
        for i in range(na):
            constraints.append(
                Constraint(
                    f"effort {i + 1}",
                    response(f"effort_{i + 1}", 1.0, self.effort_max),
                    scale=self.effort_max,
                    unit="N*m",
                )
            )
        return DesignProblem(
            tuple(variables),
            Objective("h2", response("h2", 1.0, 0.0), scale=h0, unit="m/N/s**0.5"),
            tuple(constraints),
        )

    def report_metrics(self, x: FloatArray) -> dict[str, float]:
        """The published design's ‖T_wz‖₂ (the published placement, a filter per mode and
        pair, every g_ij = 100, ν = 1),
        the design's ratio to it, and the closed loop's lowest damping ratios."""
        published = dataclasses.replace(
            self, selection=PUBLISHED_SELECTION, tuned_modes=None, tune_filters=False
        )
        h_pub = published.responses(published.published_design())["h2"][0]
        h = self.responses(x)["h2"][0]
        out = {"h2_published": h_pub, "h2_over_published": h / h_pub}
        out.update({f"damping_mode_{j + 1}": z for j, z in enumerate(self.mode_damping(x))})
        return out

    def mode_damping(self, x: FloatArray) -> list[float]:
        """Per structural mode j, the least damping ratio among the closed-loop pole pairs
        within a factor 1.5 of ω_j (the mode and the filters tuned to it)."""
        lam = np.linalg.eigvals(self.matrices(x)[0])
        lam = lam[lam.imag > 0]
        zeta, freq = -lam.real / np.abs(lam), np.abs(lam)
        out = []
        for w in self.model.omega:
            near = (freq > w / 1.5) & (freq < 1.5 * w)
            out.append(float(zeta[near].min()) if near.any() else float("nan"))
        return out

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]:
        """The design ``x`` as a structure and a controller (:mod:`flexsat.design.describe`):
        the modes and the chosen patches, the gains (and tuning ratios), the closed-loop poles,
        the eigenvalues of S and each mode's least closed-loop damping."""
        x = np.asarray(x, dtype=float)
        g, nu = self.split(x)
        cands = [self.candidates[k] for k in self.selection]
        names = self.names[: g.size]
        return {
            "frequencies": DesignFeature(
                "structure",
                self.model.omega / (2 * np.pi),
                "Hz",
                labels=tuple(f"mode {j + 1}" for j in range(self.n_modes)),
                note="clamped L, the candidates' mesh",
            ),
            "patch starts": DesignFeature(
                "structure",
                np.array([start for _, start in cands]),
                "m",
                labels=tuple(
                    f"pair {k} (structure {b})" for k, (b, _) in zip(self.selection, cands)
                ),
                note="2 in patches, start from the structure's root",
            ),
            "gains": DesignFeature(
                "control",
                g,
                "N*m",
                labels=names,
                note="g_ij: pair i's filter tuned to mode j, u = Eᵀ G ξ",
            ),
            "tuning ratios": DesignFeature(
                "control",
                nu,
                "",
                labels=tuple(n.replace("g", "nu", 1) for n in self.names[: g.size]),
            ),
            "closed-loop poles": DesignFeature(
                "control", sorted_poles(np.linalg.eigvals(self.matrices(x)[0])), "1/s"
            ),
            "eigenvalues of S": DesignFeature(
                "control",
                np.linalg.eigvalsh(self.stiffness(g)),
                "rad**2/s**2",
                note="S = Ω − B_a Eᵀ G E C_s (Eq. 6): the PPF loop is stable while S > 0",
            ),
            "least damping per mode": DesignFeature(
                "control",
                np.array(self.mode_damping(x)),
                "",
                labels=tuple(f"mode {j + 1}" for j in range(self.n_modes)),
                note="the least damping ratio of the closed-loop poles within a factor 1.5",
            ),
        }

    def for_selection(self, selection: tuple[int, ...]) -> AgrawalBangCodesign:
        """The same problem on another set of candidates."""
        return dataclasses.replace(self, selection=tuple(selection))


_CASES: dict[tuple[tuple[int, float], ...], AgrawalBangCase] = {}


def _candidate_list(raw: object) -> tuple[tuple[int, float], ...]:
    """``candidates`` as (structure 1|2, finite start in m) pairs, else a FieldError."""
    if isinstance(raw, (str, bytes)) or not hasattr(raw, "__iter__"):
        raise FieldError("candidates", f"must be a list of (structure, start) pairs, got {raw!r}")
    out = []
    for j, item in enumerate(raw):
        if isinstance(item, (str, bytes)) or not hasattr(item, "__len__") or len(item) != 2:
            raise FieldError(f"candidates[{j}]", f"must be a (structure, start) pair, got {item!r}")
        b, start = item
        if isinstance(b, bool) or b not in (1, 2):
            raise FieldError(f"candidates[{j}]", f"structure must be 1 or 2, got {b!r}")
        try:
            x = float(start)
        except (TypeError, ValueError):
            raise FieldError(
                f"candidates[{j}]", f"start must be a number (m), got {start!r}"
            ) from None
        if not np.isfinite(x):
            raise FieldError(f"candidates[{j}]", f"start must be finite, got {start!r}")
        out.append((int(b), x))
    return tuple(out)


def _candidate_case(candidates: tuple[tuple[int, float], ...]) -> AgrawalBangCase:
    """The case meshed with every candidate's patch ends as nodes (one model for all sets)."""
    if candidates not in _CASES:
        if not candidates:
            raise FieldError("candidates", "give at least one (structure, start) location")
        base = agrawal_bang()
        lengths = (base.beam1_length, base.beam2_length)
        for j, (b, s) in enumerate(candidates):
            if b not in (1, 2):
                raise FieldError(f"candidates[{j}]", f"structure must be 1 or 2, got {b!r}")
            if not 0 <= s <= lengths[b - 1] - base.patch_length + 1e-12:
                raise FieldError(
                    f"candidates[{j}]",
                    f"the patch must lie on structure {b}: start in [0, "
                    f"{lengths[b - 1] - base.patch_length:.4f}] m, got {s}",
                )
        for i in range(len(candidates)):
            for j in range(i):
                (bi, si), (bj, sj) = candidates[i], candidates[j]
                if bi == bj and abs(si - sj) < base.patch_length:
                    raise FieldError(
                        f"candidates[{i}]", f"overlaps candidates[{j}] on structure {bi}"
                    )
        case = dataclasses.replace(base, patches=candidates)
        case.modal_model()
        _CASES[candidates] = case
    return _CASES[candidates]


def placement_codesign(
    reference: AgrawalBangCodesign,
    size: int = 3,
    search: str = "exchange",
    method: str = "slsqp",
    scores: dict[tuple[int, ...], float] | None = None,
    **optimize_kwargs: Any,
) -> PlacementDesign:
    """Choose ``size`` pairs among the reference's candidates by ``search`` (greedy, exchange,
    exhaustive) with the nested continuous optimum as the score
    (:func:`~flexsat.design.placement_design.nested_score`: minus the optimal ‖T_wz‖₂ of the
    set, a set refused when its optimum's KKT residual exceeds 1e-6), then the gains of the
    chosen set (:func:`~flexsat.design.placement_design.place_then_optimize`).

    ``scores``: a dict (sorted selection -> score) the nested optima are kept in and looked up
    from, so that several searches over one candidate list solve each set once (the score is
    a function of the set alone).
    """
    if (
        isinstance(size, bool)
        or not isinstance(size, int)
        or not 1 <= size <= len(reference.candidates)
    ):
        raise FieldError(
            "size", f"must be an integer 1 to {len(reference.candidates)}, got {size!r}"
        )
    memo = {} if scores is None else scores

    def problem_for(selection: tuple[Any, ...]) -> DesignProblem:
        return reference.for_selection(tuple(int(k) for k in selection)).problem()

    nested = nested_score(problem_for, method, **optimize_kwargs)

    def score(selection: tuple[Any, ...]) -> float:
        key = tuple(sorted(int(k) for k in selection))
        if key not in memo:
            memo[key] = nested(key)
        return memo[key]

    return place_then_optimize(
        range(len(reference.candidates)),
        size,
        score,
        problem_for,
        search=search,
        method=method,
        **optimize_kwargs,
    )
