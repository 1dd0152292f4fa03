r"""Spillover of the truncated modes on a reduced-order controller.

A law designed on a reduced model :math:`G_r` runs on the full plant G. The modes the model left
out (the *residual* modes) are still excited by the commands (control spillover, :math:`B_i`)
and still seen by the sensors (observation spillover, :math:`C_i`); together they close a loop
through the law that can destabilise them (Balas, "Feedback control of flexible systems", IEEE
Trans. AC-23(4), 1978, 673–679). This module closes the law on both models and reports:

* closed-loop stability and the disk margin of the loop at the plant input (SISO: α of
  :func:`~flexsat.analysis.margins.disk_margin`; MIMO: the multiloop lower bound of
  :func:`~flexsat.analysis.margins.disk_margins`), on the reduced model (what the design
  promised) and on the full plant (what it delivers);
* for each residual mode i — a mode of the full plant's stable part
  (:func:`~flexsat.analysis.reduction.modal_form`) with no open-loop pole of the reduced model
  within 1 % — its open-loop frequency and damping, the damping of the closed-loop pole of the
  full loop nearest to it, and its spillover gain
  :math:`\bar\sigma\big(K(j\omega_i)\,C_i(j\omega_i I - A_i)^{-1}B_i\big)`, the loop gain through
  that mode alone at its own frequency (> 1 with the wrong phase is how spillover destabilises).

The law may be continuous or discrete (then the loops are the sampled-data ones of
:func:`~flexsat.analysis.frequency_domain.build_loop`, with its computation delay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.analysis.frequency_domain import ResponseEvaluator, build_loop
from flexsat.analysis.margins import disk_margin, disk_margins
from flexsat.analysis.norms import system_matrices
from flexsat.analysis.reduction import modal_form, split_stable

if TYPE_CHECKING:
    import control as ct
    from flexsat.analysis.frequency_domain import Loop

__all__ = ["ResidualMode", "SpilloverReport", "spillover", "spillover_table"]


@dataclass(frozen=True)
class ResidualMode:
    """One mode of the full plant the reduced model does not have (module docstring)."""

    frequency_rad_s: float
    open_loop_damping: float
    closed_loop_damping: float
    spillover_gain: float


@dataclass(frozen=True)
class SpilloverReport:
    """The law on its design model and on the full plant (module docstring).

    Attributes
    ----------
    stable_reduced, stable_full : bool
    disk_margin_reduced, disk_margin_full : float
        α of the loop at the plant input (0 when that loop is unstable).
    least_damping_reduced, least_damping_full : float
        Least damping ratio of any closed-loop pole (negative: unstable).
    residual : tuple of ResidualMode
    """

    stable_reduced: bool
    stable_full: bool
    disk_margin_reduced: float
    disk_margin_full: float
    least_damping_reduced: float
    least_damping_full: float
    residual: tuple[ResidualMode, ...]


def _s_poles(loop: Loop) -> np.ndarray:
    p = np.linalg.eigvals(loop.closed_loop_A).astype(complex)
    return np.log(p) / loop.dt if loop.dt else p


def _damping(p: np.ndarray) -> np.ndarray:
    mag = np.abs(p)
    return np.where(mag > 0, -p.real / np.where(mag > 0, mag, 1.0), 1.0)


def _alpha(loop: Loop) -> float:
    if not loop.stable:
        return 0.0
    if loop.transfer.ninputs == 1:
        return disk_margin(loop).alpha
    return disk_margins(loop)[1].alpha


def spillover(
    full: ct.StateSpace, reduced: ct.StateSpace, law: ct.StateSpace, delay: int = 0
) -> SpilloverReport:
    """Close ``law`` on ``reduced`` and on ``full`` and compare (module docstring).

    Parameters
    ----------
    full, reduced : control.StateSpace
        Continuous plants with the same signal labels (the reduced one from
        :mod:`~flexsat.analysis.reduction`, or any model the law was designed on).
    law : control.StateSpace
        u = K y (:mod:`~flexsat.control.state_space_export`), continuous or discrete.
    delay : int
        Computation delay, samples (discrete law).
    """
    loop_r = build_loop(reduced, law, "input", delay)
    loop_f = build_loop(full, law, "input", delay)
    poles_f = _s_poles(loop_f)
    zeta_r = float(_damping(_s_poles(loop_r)).min(initial=1.0))
    zeta_f = float(_damping(poles_f).min(initial=1.0))
    form = modal_form(split_stable(full).stable)
    _, _, _, _, kdt = system_matrices(law, "law")
    Ared, _, _, _, _ = system_matrices(reduced, "reduced")
    red_eig = np.linalg.eigvals(Ared) if Ared.size else np.zeros(0, complex)
    Am, Bm, Cm, _ = form.matrices
    meas = [list(full.output_labels).index(m) for m in law.input_labels]
    cmds = [list(full.input_labels).index(c) for c in law.output_labels]
    Ak, Bk, Ck, Dk, _ = system_matrices(law, "law")
    K_eval = ResponseEvaluator(Ak, Bk, Ck, Dk, kdt)
    residual = []
    for k, blk in enumerate(form.blocks):
        lam = -form.damping_ratios[k] * form.frequencies_rad_s[k] + 1j * form.frequencies_rad_s[
            k
        ] * math.sqrt(max(0.0, 1 - form.damping_ratios[k] ** 2))
        if red_eig.size and np.min(np.abs(red_eig - lam)) <= 0.01 * abs(lam):
            continue
        w = float(form.frequencies_rad_s[k])
        Ai, Bi, Ci = Am[blk, blk], Bm[blk][:, cmds], Cm[meas][:, blk]
        Gi = Ci @ np.linalg.solve(1j * w * np.eye(Ai.shape[0]) - Ai, Bi)
        wk = min(w, math.pi / kdt) if kdt else w
        Kw = K_eval(np.array([wk]))[0]
        gain = float(np.linalg.norm(Kw @ Gi, 2))
        near = int(np.argmin(np.abs(poles_f - lam))) if poles_f.size else -1
        zcl = float(_damping(poles_f[[near]])[0]) if near >= 0 else math.nan
        residual.append(ResidualMode(w, float(form.damping_ratios[k]), zcl, gain))
    return SpilloverReport(
        loop_r.stable,
        loop_f.stable,
        _alpha(loop_r),
        _alpha(loop_f),
        zeta_r,
        zeta_f,
        tuple(residual),
    )


def spillover_table(report: SpilloverReport) -> str:
    """A plain-text summary of a :class:`SpilloverReport`."""
    lines = [
        f"{'':>14} {'stable':>7} {'disk α':>8} {'least ζ':>9}",
        f"{'design model':>14} {report.stable_reduced!s:>7} {report.disk_margin_reduced:8.3f} "
        f"{report.least_damping_reduced:9.4f}",
        f"{'full plant':>14} {report.stable_full!s:>7} {report.disk_margin_full:8.3f} "
        f"{report.least_damping_full:9.4f}",
        f"{'residual mode':>14} {'ω (rad/s)':>10} {'ζ open':>8} {'ζ closed':>9} {'|K G_i|':>9}",
    ]
    for r in report.residual:
        lines.append(
            f"{'':>14} {r.frequency_rad_s:10.4g} {r.open_loop_damping:8.4f} "
            f"{r.closed_loop_damping:9.4f} {r.spillover_gain:9.3g}"
        )
    return "\n".join(lines)
