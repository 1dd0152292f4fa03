r"""The controller summary of a report: gains, closed-loop poles, margins and norms of each law
that has a linear form, on the loop that actually runs.

For each run, the law as it runs (:func:`flexsat.control.state_space_export.discrete_law`: its
own discrete recursion at the control period, zero-order hold included, with the computation
delay) closes the loop with the plant's linear part sampled exactly
(:func:`flexsat.analysis.frequency_domain.build_loop`, broken at the plant input, every
command). The summary gives

- the gains: the static gain matrix K of u = K y (the feedback sign included), or the order of a
  dynamic compensator and its H∞ norm;
- the closed-loop poles (s-plane, :math:`s = \ln z / T`) with natural frequency, damping ratio
  and the plant mode that participates most (:mod:`flexsat.analysis.loop_modes`);
- for one command, the gain, phase and delay margins of the sampled-data loop and its disk
  margin (:mod:`flexsat.analysis.margins`; Seiler, Packard & Gahinet, "An introduction to disk
  margins", IEEE Control Systems Magazine 40(5), 2020, 78–95); for several, the loop-at-a-time
  and multiloop disk margins;
- the H∞ norms of the sensitivity S = (I + L)⁻¹ and of T = I − S (the peak sensitivity
  :math:`M_s = \|S\|_\infty` bounds the disk margin from below: α ≥ 1/M_s), and the H2 norm of T
  (:mod:`flexsat.analysis.norms`).

A law without a constant linear form (a nonlinear, scheduled or per-case law), a plant without
a linear part, or an unstable closed loop gets a line saying so, never a number.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.analysis.loop_modes import ClosedLoopPole
    from flexsat.analysis.margins import DiskMargin, LoopMargins

#: at most this many closed-loop pole pairs are listed per law (the lowest in frequency)
MAX_POLES = 12

#: what the section cites (its methods)
CITATIONS = (
    'P. Seiler, A. Packard and P. Gahinet, "An introduction to disk margins", IEEE Control '
    "Systems Magazine 40(5), 2020, 78–95 (disk margins)",
    'I. J. Pérez-Arriaga, G. C. Verghese and F. C. Schweppe, "Selective modal analysis with '
    'applications to electric power systems, Part I", IEEE Trans. Power Apparatus and Systems '
    "PAS-101(9), 1982, 3117–3125 (participation factors)",
    "G. F. Franklin, J. D. Powell and A. Emami-Naeini, Feedback Control of Dynamic Systems, "
    "7th ed., Pearson, 2015, §6.4 (gain, phase and delay margins)",
)


@dataclass(frozen=True)
class LawSummary:
    """The linear summary of one run's law (module docstring).

    Attributes
    ----------
    run : str
    law : str
        The law's class name.
    reason : str
        Why there is no summary ("" when there is one).
    gains : list of (output, input, gain)
        The static gain entries (none for a dynamic law).
    law_states : int
        States of the law as it runs (delay states included).
    law_hinf : float or None
        H∞ norm of a dynamic law (None: static, or not stable).
    poles : tuple of ClosedLoopPole
    margins : LoopMargins or None
        Classical margins (one command only).
    disk : tuple of DiskMargin
        Per command (loop at a time), then the multiloop margin where there are several.
    sensitivity_peak, complementary_peak : float
        ‖S‖∞ and ‖T‖∞.
    complementary_h2 : float
        ‖T‖₂.
    dt : float
        Control period, s.
    """

    run: str
    law: str
    reason: str = ""
    gains: tuple[tuple[str, str, float], ...] = ()
    law_states: int = 0
    law_hinf: float | None = None
    poles: tuple[ClosedLoopPole, ...] = ()
    margins: LoopMargins | None = None
    disk: tuple[DiskMargin, ...] = ()
    sensitivity_peak: float = math.nan
    complementary_peak: float = math.nan
    complementary_h2: float = math.nan
    dt: float = 0.0


def summarise_law(
    run: str, plant: ct.StateSpace, law: Any, dt: float, delay: int = 0
) -> LawSummary:
    """The summary of ``law`` closing the loop on ``plant`` (module docstring).

    Parameters
    ----------
    run : str
        The run's label.
    plant : control.StateSpace
        The plant's linear part (continuous, labelled signals;
        :func:`flexsat.dynamics.linear_model.plant_state_space`).
    law : Controller
    dt : float
        Control period, s.
    delay : int
        Computation delay, whole samples.
    """
    from flexsat.analysis.frequency_domain import build_loop
    from flexsat.analysis.loop_modes import closed_loop_poles
    from flexsat.analysis.margins import disk_margin, disk_margins, loop_margins
    from flexsat.analysis.norms import h2_norm, hinf_norm
    from flexsat.control.state_space_export import discrete_law

    name = type(law).__name__
    try:
        K = discrete_law(law, dt, delay)
        loop = build_loop(plant, K, "input")
    except FieldError as exc:
        return LawSummary(run, name, reason=exc.rule)
    if not loop.stable:
        worst = max(loop.poles, key=abs)
        return LawSummary(
            run,
            name,
            reason=f"the sampled closed loop is unstable (pole z = {worst:.4g}): no margins",
            law_states=K.nstates,
            dt=dt,
        )
    gains: tuple[tuple[str, str, float], ...] = ()
    law_hinf = None
    if K.nstates == 0:
        D = np.asarray(K.D, float)
        gains = tuple(
            (K.output_labels[i], K.input_labels[j], float(D[i, j]))
            for i in range(D.shape[0])
            for j in range(D.shape[1])
            if D[i, j] != 0.0
        )
    elif np.all(np.abs(np.linalg.eigvals(np.asarray(K.A, float))) < 1.0):
        law_hinf = hinf_norm(K).value
    if K.noutputs == 1:
        margins: LoopMargins | None = loop_margins(loop)
        disks: tuple[DiskMargin, ...] = (disk_margin(loop),)
    else:
        margins = None
        per_channel, multi = disk_margins(loop)
        disks = (*per_channel, multi)
    S, T = loop.sensitivity(), loop.complementary_sensitivity()
    return LawSummary(
        run,
        name,
        gains=gains,
        law_states=K.nstates,
        law_hinf=law_hinf,
        poles=closed_loop_poles(loop),
        margins=margins,
        disk=disks,
        sensitivity_peak=hinf_norm(S).value,
        complementary_peak=hinf_norm(T).value,
        complementary_h2=h2_norm(T),
        dt=dt,
    )


def summarise_laws(
    plant: ct.StateSpace, laws: Mapping[str, Any], dt: float, delay: int = 0
) -> tuple[LawSummary, ...]:
    """:func:`summarise_law` of every run's law (``laws``: label to law)."""
    return tuple(summarise_law(run, plant, law, dt, delay) for run, law in laws.items())


def _number(value: float, digits: int = 4) -> str:
    if value is None or math.isnan(value):
        return "–"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    return f"{value:.{digits}g}"


def _pole(pole: complex) -> str:
    """A pole pair as ``re ± im j`` (a real pole as its value)."""
    return f"{pole.real:.4g} ± {pole.imag:.4g}j" if pole.imag > 0 else f"{pole.real:.4g}"


def _margins_rows(s: LawSummary) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    m = s.margins
    if m is not None:
        rows += [
            ("Gain margin", f"{_number(m.gain_margin)} ({_number(m.gain_margin_db, 3)} dB)"),
            (
                "Phase margin (deg)",
                f"{_number(m.phase_margin_deg)} at {_number(m.gain_crossover_rad_s)} rad/s",
            ),
            (
                "Delay margin (s)",
                f"{_number(m.delay_margin_s)}"
                + (
                    f" ({m.delay_margin_samples} whole sample"
                    f"{'' if m.delay_margin_samples == 1 else 's'})"
                    if m.delay_margin_samples is not None
                    else ""
                ),
            ),
        ]
    names = [f"channel {i + 1}" for i in range(len(s.disk) - 1)] + ["all channels at once"]
    for label, d in zip(names if len(s.disk) > 1 else ["loop"], s.disk):
        lo, hi = d.gain_range
        rows.append(
            (
                f"Disk margin α ({label})",
                f"{_number(d.alpha)}: gains [{_number(lo)}, {_number(hi)}], "
                f"±{_number(d.phase_deg, 3)} deg",
            )
        )
    rows += [
        ("Peak sensitivity ‖S‖∞", _number(s.sensitivity_peak)),
        ("‖T‖∞", _number(s.complementary_peak)),
        ("‖T‖₂", _number(s.complementary_h2)),
    ]
    return rows


def _table(headings: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(h)}</th>" for h in headings)
    body = "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _law_html(s: LawSummary) -> str:
    esc = html.escape
    if s.reason:
        return f"<h3>{esc(s.run)} ({esc(s.law)})</h3><p>No linear summary: {esc(s.reason)}.</p>"
    if s.gains:
        gains = _table(
            ("command", "measurement", "gain"), [(o, i, _number(g, 6)) for o, i, g in s.gains]
        )
    else:
        norm = "" if s.law_hinf is None else f", ‖K‖∞ = {_number(s.law_hinf)}"
        gains = f"<p>Dynamic compensator with {s.law_states} states{esc(norm)}.</p>"
    pairs = [p for p in s.poles if p.pole.imag >= 0]
    shown = pairs[:MAX_POLES]
    more = (
        f"<p>The {len(shown)} lowest of {len(pairs)} poles (pairs counted once); the least "
        f"damped of all has ζ = {_number(min(p.damping_ratio for p in pairs))}.</p>"
        if len(pairs) > len(shown)
        else ""
    )
    poles = _table(
        ("pole s (1/s)", "ω_n (rad/s)", "ζ", "mode", "plant share"),
        [
            (
                f"{p.pole.real:.4g} ± {p.pole.imag:.4g}j"
                if p.pole.imag > 0
                else f"{p.pole.real:.4g}",
                _number(p.natural_frequency_rad_s),
                _number(p.damping_ratio),
                p.mode,
                f"{p.plant_share:.2f}",
            )
            for p in shown
        ],
    )
    return (
        f"<h3>{esc(s.run)} ({esc(s.law)}), sampled at {_number(1 / s.dt)} Hz</h3>"
        f"<h4>Gains (u = K y)</h4>{gains}"
        f"<h4>Margins and norms of the sampled-data loop, broken at the plant input</h4>"
        f"{_table(('quantity', 'value'), _margins_rows(s))}"
        f"<h4>Closed-loop poles</h4>{poles}{more}"
    )


def summary_html(summaries: Sequence[LawSummary]) -> str:
    """The report section of ``summaries`` ("" without any)."""
    if not summaries:
        return ""
    return (
        "<h2>Controller summary</h2>"
        "<p>Each law as it runs (its discrete form at the control period, zero-order hold and "
        "computation delay included) closing the loop with the plant's linear part, sampled "
        "exactly.</p>" + "".join(_law_html(s) for s in summaries)
    )


__all__ = [
    "CITATIONS",
    "MAX_POLES",
    "LawSummary",
    "summarise_law",
    "summarise_laws",
    "summary_html",
]
