"""Vadali & Kim's tethered-subsatellite retrieval (AIAA 90-1197; Junkins, Pollock & Rahman 1990,
Att. 12): the Shuttle case and the published numbers
of each example, :func:`closed_loop` (one law on the tether, through the engine's continuous-law
or sampled mode) and :func:`rerun` (an example under continuous feedback, DOP853).

The case (Att. 12, "Tension Control Law Design Based on Decoupled Equations of Motion"): circular
orbit at 220 km (Ω = 0.07068 rad/min), reference length
L = 20 km, subsatellite 22.7 kg; start λ = 1, θ = φ = 5°, at rest.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from flexsat.dynamics.tether import ClosedLoopRun, TetheredSubsatellite, TetherScales
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt
    import xarray as xr

    from flexsat.control.tether_laws import CoupledTetherLaw, DecoupledTetherLaw, TetherRateLaw
    from flexsat.sim.config import SimConfig

    #: the tether laws a case run takes
    TetherLaw = DecoupledTetherLaw | CoupledTetherLaw | TetherRateLaw

SOURCE = "Junkins, Pollock & Rahman 1990, Att. 12"
#: settling bands of a retrieval: |θ| within the runs' initial 5° (rad), |λ − λ_f| within 2 %
#: of the length change (:func:`flexsat.analysis.settling.settling_time`)
SETTLING_PITCH_BAND = np.radians(5.0)
SETTLING_LENGTH_FRACTION = 0.02
#: the paper's scales (Att. 12 "Tension Control Law Design Based on Decoupled Equations of Motion")
PAPER_SCALES: dict[str, str] = dict(mass="22.7 kg", length="20 km", altitude="220 km")
#: [λ, θ, φ, λ', θ', φ'] at the start of every example (Att. 12 "Tension Control Law Design Based on
#: Decoupled Equations of Motion")
INITIAL = (1.0, np.radians(5.0), np.radians(5.0), 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Example:
    """One published retrieval: law, gains, final length, the window and the printed numbers
    (nondimensional unless the key says; None where the paper gives none)."""

    key: str
    law: str
    gains: dict[str, float]
    final_length: float
    orbits: float
    published: dict[str, float]
    locator: str


#: the examples of Figs. 2-8
EXAMPLES = {
    e.key: e
    for e in (
        Example(
            "V10",
            "decoupled",
            dict(K1=1.0, K2=0.0, K3=3.0),
            0.01,
            2.0,
            dict(
                initial_tension=4.0,
                initial_tension_N=2.52,
                thrust_index_2_orbits=0.9,
                thrust_impulse_2_orbits_Ns=481.0,
                settling_orbits=2.0,
            ),
            "Figs. 2-3",
        ),
        Example(
            "V11",
            "coupled",
            dict(K1=1.0, K2=0.0, K3=3.0, K4=2.0),
            0.01,
            2.0,
            dict(thrust_index_2_orbits=0.24, thrust_impulse_2_orbits_Ns=128.4, max_pitch_deg=29.3),
            "Figs. 4-5",
        ),
        Example(
            "V12",
            "coupled",
            dict(K1=1.0, K2=0.0, K3=3.0, K4=3.0),
            0.01,
            2.0,
            dict(thrust_index_2_orbits=0.258),
            "Figs. 4-5",
        ),
        Example(
            "V13 K1=1.0",
            "coupled",
            dict(K1=1.0, K2=0.0, K3=3.0, K4=2.0),
            0.001,
            6.0,
            dict(final_pitch_deg=180.0),
            "Fig. 6",
        ),
        Example(
            "V13 K1=0.9",
            "coupled",
            dict(K1=0.9, K2=0.0, K3=3.0, K4=2.0),
            0.001,
            2.0,
            dict(max_pitch_deg=21.9),
            "Fig. 7",
        ),
        Example(
            "V15",
            "rate",
            dict(K1=0.25, K2=0.01, K3=1.0),
            0.01,
            3.0,
            dict(initial_rate_m_s=30.0),
            "'A Tether Rate Control Law', Fig. 8",
        ),
    )
}


def make_law(
    law: str,
    gains: Mapping[str, npt.ArrayLike],
    final_length: npt.ArrayLike,
    scales: TetherScales | None = None,
    printed_sign: bool = False,
) -> TetherLaw:
    """The law ``decoupled`` (controller 1), ``coupled`` (controller 2) or ``rate`` with
    ``gains`` (K1 ... as the law takes them) and the nondimensional final length."""
    from flexsat.control.tether_laws import CoupledTetherLaw, DecoupledTetherLaw, TetherRateLaw

    if law == "decoupled":
        return DecoupledTetherLaw(
            final_length=final_length, scales=scales, printed_sign=printed_sign, **gains
        )
    if law == "coupled":
        return CoupledTetherLaw(final_length=final_length, scales=scales, **gains)
    if law == "rate":
        return TetherRateLaw(final_length=final_length, scales=scales, **gains)
    raise FieldError("law", f"must be 'decoupled', 'coupled' or 'rate', got {law!r}")


def paper_scales() -> TetherScales:
    """The paper's tether: 22.7 kg, 20 km, a 220 km orbit (Att. 12, the numerical examples)."""
    return TetherScales(**PAPER_SCALES)


#: how the law meets the tether: continuous feedback (the paper's), or held samples
INTEGRATORS = ("continuous", "sampled")

#: DOP853 right-hand-side evaluations per radian of the closed loop's fastest oscillation at
#: the continuous mode's rtol 1e-10 (accuracy-limited: 140-900 measured for K1 = 1 ... 1e6,
#: tests/cases/test_tether_cost.py), and per unit of its fastest decay (stability-limited:
#: 1-17 measured)
EVALUATIONS_PER_RADIAN = 1000.0
EVALUATIONS_PER_DECAY = 20.0


def closed_loop_rhs(law: TetherLaw, x: np.ndarray) -> np.ndarray:
    """x' of the closed loop (Eq. 4 with the law), nondimensional, at x (..., 6): λ' is the
    law's under rate control (then x[..., 3] is ignored and its rate is 0)."""
    from flexsat.dynamics.tether import accelerations

    u, F = law.nondimensional(x)
    if law.writes[0] == "reel_rate":
        x = np.concatenate([x[..., :3], u[..., None] + 0 * x[..., :1], x[..., 4:]], -1)
        acc = accelerations(x, 0.0, F)
        return np.stack([u, x[..., 4], x[..., 5], 0 * u, acc[..., 1], acc[..., 2]], -1)
    return np.concatenate([x[..., 3:], accelerations(x, u, F)], -1)


def closed_loop_rates(law: TetherLaw, x: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(fastest oscillation |Im s|, fastest decay or growth |Re s|) per case of the closed
    loop linearised at the nondimensional state x (6,) or (n_cases, 6), rad per unit τ: the
    eigenvalues s of its Jacobian, by central differences (step 1e-6 relative)."""
    x = np.broadcast_to(np.asarray(x, float), (max(law.n_cases, 1), 6)).copy()
    jac = np.empty(x.shape + (6,))
    for i in range(6):
        h = 1e-6 * np.maximum(1.0, np.abs(x[:, i]))
        up, down = x.copy(), x.copy()
        up[:, i] += h
        down[:, i] -= h
        jac[..., i] = (closed_loop_rhs(law, up) - closed_loop_rhs(law, down)) / (2 * h[:, None])
    if not np.isfinite(jac).all():  # gains so large that the rates overflow
        return np.full(len(x), np.inf), np.full(len(x), np.inf)
    s = np.linalg.eigvals(jac)
    return np.abs(s.imag).max(-1), np.abs(s.real).max(-1)


def continuous_evaluations(law: TetherLaw, initial: npt.ArrayLike, tau_end: float) -> float:
    r"""Estimated right-hand-side evaluations of a continuous-law run of ``law`` from
    ``initial`` to τ = ``tau_end``: an explicit Runge-Kutta method takes steps h with
    h|s| bounded by its accuracy on an oscillation (|Im s|) or its stability on a decay
    (|Re s|) (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4, and II, §IV.2), so

    .. math:: n pprox 	au_{end}\,(c_{osc}\max|\mathrm{Im}\,s| + c_{dec}\max|\mathrm{Re}\,s|)

    with the eigenvalues s of the linearised closed loop at the start and at the target
    (λ_f, at rest), the fastest over both and the cases; c from :data:`EVALUATIONS_PER_RADIAN`
    and :data:`EVALUATIONS_PER_DECAY` (measured). A scale, not a count: it decides whether a
    run can finish, before it starts."""
    start = np.asarray(initial, float)
    target = np.zeros((max(law.n_cases, 1), 6))
    target[:, 0] = np.broadcast_to(law.final_length, target.shape[:1])
    cost = 0.0
    for x in (start, target):
        osc, dec = closed_loop_rates(law, x)
        cost = max(cost, float(np.max(EVALUATIONS_PER_RADIAN * osc + EVALUATIONS_PER_DECAY * dec)))
    return tau_end * cost


def check_continuous_cost(law: TetherLaw, initial: npt.ArrayLike, tau_end: float) -> None:
    """Refuse a continuous-law run whose :func:`continuous_evaluations` exceed
    :data:`flexsat.limits.MAX_ADAPTIVE_EVALUATIONS` (stiff gains would make the adaptive
    integrator crawl for hours).

    Raises
    ------
    flexsat.input_checks.FieldError
        Naming ``gains``.
    """
    from flexsat import limits
    from flexsat.input_checks import FieldError

    n = continuous_evaluations(law, initial, tau_end)
    if not n <= limits.MAX_ADAPTIVE_EVALUATIONS:
        gains = ", ".join(
            f"{g} = {np.max(getattr(law, g)):.3g}"
            for g in ("K1", "K2", "K3", "K4")
            if hasattr(law, g)
        )
        raise FieldError(
            "gains",
            f"{gains} make a closed loop so fast that integrating it over "
            f"{tau_end / (2 * np.pi):.3g} orbits takes about {n:.3g} evaluations, above the "
            f"limit {limits.MAX_ADAPTIVE_EVALUATIONS:,} (flexsat.limits."
            "MAX_ADAPTIVE_EVALUATIONS): smaller gains, fewer orbits, or integrator: sampled",
        )


def closed_loop(
    law: str,
    gains: Mapping[str, npt.ArrayLike],
    final_length: float,
    initial: npt.ArrayLike,
    tau: npt.ArrayLike,
    integrator: str = "continuous",
    printed_sign: bool = False,
    scales: TetherScales | None = None,
) -> ClosedLoopRun:
    """The law named ``law`` (:func:`make_law`: gains, λ_f nondimensional, ``printed_sign``)
    on the tether of ``scales`` (default the unit scales) from ``initial``: :func:`run_law` of
    it."""
    controller = make_law(law, gains, final_length, scales=scales, printed_sign=printed_sign)
    return run_law(controller, initial, tau, integrator)


def run_law(
    law: TetherLaw, initial: npt.ArrayLike, tau: npt.ArrayLike, integrator: str = "continuous"
) -> ClosedLoopRun:
    r"""A tether law on the tether (Eq. 4), through :func:`flexsat.sim.engine.simulate`.

    The plant is the SI one of the law's :class:`~flexsat.dynamics.tether.TetherScales` (by
    default the unit scales Ω = 1 rad/s, m = 1 kg, L = 1 m, where τ is the time and λ the
    length); grid, initial state and results are in the paper's nondimensional variables.
    :func:`tether_simulation` says what is simulated, :func:`closed_loop_run` reads the result
    (a scenario hands the first to the runner and reads its outcome with the second).

    Parameters
    ----------
    law : DecoupledTetherLaw, CoupledTetherLaw or TetherRateLaw
        Gains may be arrays over cases; the plant takes the law's scales (the run is the same
        in τ for any: Eq. 4 is scale-free).
    initial : array_like (6,) or (n_cases, 6)
        [λ, θ, φ, λ', θ', φ'] at τ = 0; λ' is ignored under the rate law (it is the law's).
    tau : (n_t,) array
        Uniform output grid from 0: the recorded samples (``continuous``: the law acts inside
        the integrator, DOP853 at rtol 1e-10) or the control samples (``sampled``: the commands
        held between them, a digital controller; the hold costs accuracy, docs/tether.md).
    integrator : {"continuous", "sampled"}

    Returns
    -------
    ClosedLoopRun
        With the thrust index ∫|F̂|dτ on the grid (trapezoidal with the sign changes split,
        :func:`flexsat.control.tether_laws.thrust_index`: O(Δτ²), 1e-6 on 2000 samples an
        orbit).

    Raises
    ------
    ValueError
        For a bad grid, mode or state, or a tether that collapses (naming τ).
    """
    from flexsat.sim.engine import simulate

    plant, config, options = tether_simulation(law, initial, tau, integrator)
    return closed_loop_run(law, tau, simulate(plant, law, config, **options).dataset)


def tether_simulation(
    law: TetherLaw, initial: npt.ArrayLike, tau: npt.ArrayLike, integrator: str = "continuous"
) -> tuple[TetheredSubsatellite, SimConfig, dict[str, Any]]:
    """What :func:`run_law` simulates: the plant, the configuration and the options of
    :func:`flexsat.sim.engine.simulate` (case count, SI initial state, recorded states), with
    the arguments of :func:`run_law`.

    Raises
    ------
    ValueError
        For a bad grid, mode or state, or gains too stiff for the continuous integrator
        (:func:`check_continuous_cost`).
    """
    from flexsat.input_checks import FieldError, require_finite
    from flexsat.sim.config import SimConfig

    if integrator not in INTEGRATORS:
        raise FieldError("integrator", f"must be one of {INTEGRATORS}, got {integrator!r}")
    grid = np.asarray(tau, float)
    if grid.ndim != 1 or grid.size < 2 or grid[0] != 0 or not np.allclose(np.diff(grid), grid[1]):
        raise FieldError("tau", f"must be a uniform grid from 0 of >= 2 times, got {grid!r}")
    start = require_finite(initial, "initial")
    if start.ndim not in (1, 2) or start.shape[-1] != 6:
        raise FieldError(
            "initial", f"must be [λ, θ, φ, λ', θ', φ'] (6,) or (n_cases, 6), got {start.shape}"
        )
    if integrator == "continuous":
        check_continuous_cost(law, start, float(grid[-1]))
    rate = law.writes[0] == "reel_rate"
    scales = law.scales
    plant = TetheredSubsatellite(scales, control="rate" if rate else "tension")
    x0 = scales.state_to_si(np.asarray(initial, float))
    config = SimConfig(
        duration=grid[-1] / scales.orbit_rate,
        control_rate=scales.orbit_rate / grid[1],
        substeps=1,
        law_mode="continuous" if integrator == "continuous" else "sampled",
    )
    options = {
        "n_cases": max(law.n_cases, 1 if x0.ndim == 1 else x0.shape[0]),
        "initial_state": np.delete(x0, 3, axis=-1) if rate else x0,
        "record_states": True,
    }
    return plant, config, options


def closed_loop_run(law: TetherLaw, tau: npt.ArrayLike, dataset: xr.Dataset) -> ClosedLoopRun:
    """The simulated run of :func:`tether_simulation` (its ``dataset``, recorded states) in the
    paper's nondimensional variables on the grid ``tau``, with the running thrust index."""
    from flexsat.control.tether_laws import thrust_index

    grid = np.asarray(tau, float)
    scales, rate = law.scales, law.writes[0] == "reel_rate"
    x = scales.state_from_si(dataset["state"].values)
    u = (
        dataset["reel_rate"].values / scales.speed
        if rate
        else dataset["tension"].values / scales.force
    )
    F = dataset["thrust"].values / scales.force
    if rate:
        x = np.insert(x, 3, u, axis=-1)
    # the grid is uniform: each interval's ∫|F̂| from one call, then the running sum
    pieces = thrust_index(grid[:2], np.stack([F[:, :-1], F[:, 1:]], -1))
    index = np.concatenate([np.zeros((len(F), 1)), np.cumsum(pieces, axis=-1)], axis=-1)
    return ClosedLoopRun(grid, x, np.stack([u, F], -1), index)


@cache
def rerun(key: str, samples_per_orbit: int = 2000) -> ClosedLoopRun:
    """Example ``key`` of :data:`EXAMPLES` rerun under continuous feedback."""
    e = EXAMPLES[key]
    tau = np.linspace(0.0, 2 * np.pi * e.orbits, int(samples_per_orbit * e.orbits) + 1)
    return closed_loop(e.law, e.gains, e.final_length, INITIAL, tau)


def measures(
    run: ClosedLoopRun, final_length: float, scales: TetherScales, law: str
) -> dict[str, Any]:
    """The paper's measures of a run (numbers or None, JSON-ready): initial tension (T̂, N) or
    retrieval rate (m/s, positive inward), thrust index and
    impulse, maximum and final pitch, final length and roll, settling (orbits), V1 at start
    and end."""
    from flexsat.analysis.settling import reported, settling_time

    x = run.state[0]
    u0 = float(run.control[0, 0, 0])
    rate = law == "rate"  # every record has every key (one metrics table): None is n/a
    out = {
        "initial_tension": None if rate else u0,
        "initial_tension_N": None if rate else u0 * scales.force,
        "initial_rate_m_s": -u0 * scales.speed if rate else None,
    }
    index = float(run.thrust_index[0, -1])
    # settled: pitch within the initial 5° and length within 2 % of its change, together
    # ("λ and θ reach their final values in nearly two orbits", Att. 12 Figs. 2-3, read so)
    lam, theta = x[:, 0], x[:, 1]
    settle = settling_time(
        run.tau,
        (theta, lam - final_length),
        (SETTLING_PITCH_BAND, SETTLING_LENGTH_FRACTION * abs(lam[0] - final_length)),
    )
    # the paper's window for the index is two orbits (Att. 12 Figs. 2-5)
    two = (
        float(np.interp(4 * np.pi, run.tau, run.thrust_index[0]))
        if run.tau[-1] >= 4 * np.pi * (1 - 1e-12)
        else None
    )
    out.update(
        thrust_index=index,
        thrust_impulse_Ns=index * scales.impulse,
        thrust_index_2_orbits=two,
        thrust_impulse_2_orbits_Ns=None if two is None else two * scales.impulse,
        max_pitch_deg=float(np.degrees(np.abs(x[:, 1]).max())),
        final_pitch_deg=float(np.degrees(x[-1, 1])),
        final_roll_deg=float(np.degrees(x[-1, 2])),
        final_length=float(x[-1, 0]),
        final_length_m=float(x[-1, 0] * scales.length),
        settling_orbits=reported(settle / (2 * np.pi)),
        V1_initial=float(run.integral_of_motion[0, 0]),
        V1_final=float(run.integral_of_motion[0, -1]),
    )
    return out


__all__ = [
    "EVALUATIONS_PER_DECAY",
    "EVALUATIONS_PER_RADIAN",
    "EXAMPLES",
    "INTEGRATORS",
    "check_continuous_cost",
    "closed_loop",
    "closed_loop_rates",
    "closed_loop_rhs",
    "closed_loop_run",
    "continuous_evaluations",
    "Example",
    "INITIAL",
    "PAPER_SCALES",
    "SETTLING_LENGTH_FRACTION",
    "SETTLING_PITCH_BAND",
    "SOURCE",
    "make_law",
    "measures",
    "paper_scales",
    "rerun",
    "run_law",
    "tether_simulation",
]
