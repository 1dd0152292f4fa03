r"""What the design dashboard (``flexsat serve``, :mod:`flexsat.report.dashboard`) computes for a
design point, without any web library: one TAMU maneuver and its loop margins.

A :class:`DesignPoint` is a law of the TAMU hub with four appendages (Junkins, Rahman & Bang
1990, the case :func:`flexsat.cases.tamu.tamu`) and its gains:

* Control Law II, the Lyapunov tracking law (Att. 3 Eq. 17),
  :math:`u = u_{ref} - [g_1(\theta-\theta_{ref}) + g_2(\dot\theta-\dot\theta_{ref}) +
  g_3((l_0S_0 - M_0) - I_b\ddot\theta_{ref})]`, tracking the smoothed bang-bang reference whose
  switching fraction is α;
* Control Law I, the Lyapunov regulator (Att. 3 Eq. 11), :math:`u = -[g_1(\theta-\theta_f) +
  g_2\dot\theta + g_3(l_0S_0 - M_0)]` (α unused);
* PD tracking the same reference with its torque fed forward (Hailey, Sortun & Agrawal c. 1992
  Eq. 29), :math:`u = u_{ref} - g_1(\theta-\theta_{ref}) - g_2(\dot\theta-\dot\theta_{ref})`
  (g3 unused).

:meth:`TamuDesign.evaluate` runs the 40° maneuver through the one engine
(:func:`flexsat.sim.simulate`, its compiled loop) with or without the experiment's hardware
effects (friction, encoder quantisation, random torque), and computes the margins of the loop
that runs: the law's exact discrete form at 75 Hz (its zero-order hold,
:func:`~flexsat.control.state_space_export.discrete_law`) on the plant's exact zero-order-hold
equivalent, broken at the torque (:func:`~flexsat.analysis.frequency_domain.build_loop`):
gain, phase and delay margins (:func:`~flexsat.analysis.margins.loop_margins`) and the balanced
disk margin (:func:`~flexsat.analysis.margins.disk_margin`). The loop is the plant's linear
part: bearing friction, quantisation and saturation are nonlinear and left out of the margins
(they are in the maneuver).

Bad input never raises from :meth:`TamuDesign.evaluate`: a gain that breaks a law's rule, a
maneuver that diverges or a loop that is unstable comes back as text in the
:class:`Evaluation` (``error``, ``margin_note``), which the dashboard shows where the numbers
would be.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.analysis.margins import DiskMargin, LoopMargins
    from flexsat.cases.tamu import TamuCase
    from flexsat.control.base import Controller
    from flexsat.dynamics.hub_appendage import HubAppendage
    from flexsat.sim import SimConfig
    from flexsat.units import FloatArray, QuantityLike

__all__ = [
    "DEFAULT_GAINS",
    "GAIN_UNITS",
    "LAWS",
    "USES",
    "DesignPoint",
    "Evaluation",
    "SweepPoint",
    "TamuDesign",
    "design_point",
    "sweep_values",
]

#: the laws a design point can use: key -> label
LAWS = {
    "law_ii": "Control Law II (Lyapunov tracking)",
    "law_i": "Control Law I (Lyapunov regulator)",
    "pd": "PD tracking the shaped reference",
}

#: the gains each law uses (the others are shown disabled)
USES = {
    "law_ii": ("g1", "g2", "g3", "alpha"),
    "law_i": ("g1", "g2", "g3"),
    "pd": ("g1", "g2", "alpha"),
}

#: frequencies of the loop-gain plot: 0.01 Hz up to the 75 Hz loop's Nyquist frequency, rad/s
_LOOP_POINTS = 400


#: the README's Law II gains (a good TAMU maneuver), the dashboard's starting point
DEFAULT_GAINS: dict[str, QuantityLike] = {
    "g1": "3000 ozf*in/rad",
    "g2": "800 ozf*in*s/rad",
    "g3": 0.0,
    "alpha": 0.2,
}

#: SI unit of each gain ("" dimensionless)
GAIN_UNITS = {"g1": "N*m/rad", "g2": "N*m*s/rad", "g3": "", "alpha": ""}


@dataclass(frozen=True)
class DesignPoint:
    """A law and its gains, SI (:func:`design_point` converts quantities with units).

    Attributes
    ----------
    law : str
        A key of :data:`LAWS`.
    g1 : float
        Position gain, N m/rad (the law checks >= 0).
    g2 : float
        Rate gain, N m s/rad (the law checks >= 0).
    g3 : float
        Root-load gain of the Lyapunov laws, dimensionless (the law checks > −4).
    alpha : float
        Switching fraction of the smoothed bang-bang reference (the reference checks its range).
    hardware : bool
        Simulate the experiment's friction, encoder quantisation and random torque.
    """

    law: str
    g1: float
    g2: float
    g3: float
    alpha: float
    hardware: bool = True

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise FieldError("law", f"must be one of {sorted(LAWS)}, got {self.law!r}")
        for name in GAIN_UNITS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise FieldError(name, f"must be a number in SI units, got {value!r}")
            if not math.isfinite(value):
                raise FieldError(name, f"must be finite, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not isinstance(self.hardware, bool):
            raise FieldError("hardware", f"must be true or false, got {self.hardware!r}")


def design_point(
    law: str = "law_ii",
    g1: QuantityLike = DEFAULT_GAINS["g1"],
    g2: QuantityLike = DEFAULT_GAINS["g2"],
    g3: QuantityLike = DEFAULT_GAINS["g3"],
    alpha: QuantityLike = DEFAULT_GAINS["alpha"],
    hardware: bool = True,
) -> DesignPoint:
    """A :class:`DesignPoint` from gains given as SI numbers, unit strings
    (``"3000 ozf*in/rad"``) or pint Quantities, converted once here; defaults
    :data:`DEFAULT_GAINS`."""
    from flexsat.units import to_si

    given = {"g1": g1, "g2": g2, "g3": g3, "alpha": alpha}
    si = {name: to_si(value, GAIN_UNITS[name], name) for name, value in given.items()}
    return DesignPoint(law, si["g1"], si["g2"], si["g3"], si["alpha"], hardware)


@dataclass(frozen=True)
class Evaluation:
    """A design point's maneuver and margins (SI; module docstring).

    Attributes
    ----------
    point : DesignPoint
    time_s, angle_rad, reference_rad, torque_Nm, command_Nm, tip_deflection_m : ndarray
        Time histories of the maneuver (empty when ``error`` is set): hub angle, its reference,
        applied and commanded torque, tip deflection of appendage 1.
    settling_time_s : float or None
        Time after which the angle stays within 0.5° of the target (None: not within the run).
    overshoot_deg, peak_torque_Nm, peak_tip_deflection_m : float
        The engine's maneuver metrics (NaN when ``error`` is set).
    margins : LoopMargins or None
        Gain, phase and delay margins of the sampled loop at the torque.
    disk : DiskMargin or None
        Its balanced disk margin.
    loop_omega_rad_s : ndarray
        Frequencies of ``loop_response``, rad/s.
    loop_response : ndarray (complex)
        L(e^{jω dt}) at those frequencies (empty when the loop could not be built).
    error : str
        Why there is no maneuver ("" when there is one).
    margin_note : str
        Why there are no margins ("" when there are).
    simulate_s, margins_s : float
        Wall time of the maneuver and of the margins, s.
    """

    point: DesignPoint
    time_s: FloatArray
    angle_rad: FloatArray
    reference_rad: FloatArray
    torque_Nm: FloatArray
    command_Nm: FloatArray
    tip_deflection_m: FloatArray
    settling_time_s: float | None
    overshoot_deg: float
    peak_torque_Nm: float
    peak_tip_deflection_m: float
    margins: LoopMargins | None
    disk: DiskMargin | None
    loop_omega_rad_s: FloatArray = field(default_factory=lambda: np.zeros(0))
    loop_response: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    error: str = ""
    margin_note: str = ""
    simulate_s: float = 0.0
    margins_s: float = 0.0


def _with_gain(point: DesignPoint, gain: str, value: float) -> DesignPoint:
    """``point`` with one gain changed."""
    g = {name: float(getattr(point, name)) for name in GAIN_UNITS}
    g[gain] = value
    return DesignPoint(point.law, g["g1"], g["g2"], g["g3"], g["alpha"], point.hardware)


def _empty() -> FloatArray:
    return np.zeros(0)


def _failed(point: DesignPoint, message: str) -> Evaluation:
    """An evaluation with no maneuver and no margins, saying why."""
    nan = math.nan
    return Evaluation(point, *(_empty(),) * 6, None, nan, nan, nan, None, None, error=message)


@dataclass(frozen=True)
class SweepPoint:
    """One point of a gain sweep (:meth:`TamuDesign.sweep`).

    Attributes
    ----------
    value : float
        The swept gain, SI.
    settling_time_s : float or None
        None: not settled within the run, or no maneuver (``note``).
    phase_margin_deg, disk_alpha : float or None
        Margins of the sampled loop (None: unstable or no loop, ``note``).
    note : str
        Why a number is missing ("" when none is).
    """

    value: float
    settling_time_s: float | None
    phase_margin_deg: float | None
    disk_alpha: float | None
    note: str = ""


def sweep_values(point: DesignPoint, gain: str, n: int = 12) -> FloatArray:
    """n values of ``gain`` about the point's: 0.5× to 2× its value (geometric) for g1 and g2,
    −2 to 2 for g3, 0.02 to 0.25 for α (the reference's whole range)."""
    if gain not in GAIN_UNITS:
        raise FieldError("gain", f"must be one of {sorted(GAIN_UNITS)}, got {gain!r}")
    if gain == "g3":
        return np.linspace(-2.0, 2.0, n)
    if gain == "alpha":
        return np.linspace(0.02, 0.25, n)
    value = float(getattr(point, gain))
    if value <= 0:
        raise FieldError(gain, f"a sweep about {gain} = {value:g} needs a value > 0")
    return value * np.geomspace(0.5, 2.0, n)


class TamuDesign:
    """The TAMU 40° maneuver as a function of a :class:`DesignPoint` (module docstring).

    Parameters
    ----------
    case : TamuCase, optional
        Default :func:`flexsat.cases.tamu.tamu` (Att. 3 Table 1, 10 modes per appendage).
    duration : float
        Length of the maneuver run, s.
    """

    def __init__(self, case: TamuCase | None = None, duration: float = 15.0) -> None:
        from flexsat.cases.tamu import tamu
        from flexsat.dynamics.linear_model import plant_state_space
        from flexsat.input_checks import require_positive_scalar

        self.case = tamu() if case is None else case
        self.duration = require_positive_scalar(duration, "duration", "s")
        self.model: HubAppendage = self.case.model()
        self.plant: ct.StateSpace = plant_state_space(self.model)
        self.configs: dict[bool, SimConfig] = {
            True: self.case.sim_config(duration=self.duration),
            False: self.case.sim_config(duration=self.duration, friction=False, noise=False),
        }
        self.dt = self.configs[True].dt
        self.loop_omega_rad_s = np.geomspace(2 * math.pi * 0.01, math.pi / self.dt, _LOOP_POINTS)

    def law(self, point: DesignPoint) -> Controller:
        """The point's law on this case (raises FieldError for a gain that breaks its rule)."""
        from flexsat.control import PD

        case = self.case
        if point.law == "law_ii":
            return case.law_ii(point.g1, point.g2, point.g3, alpha=point.alpha)
        if point.law == "law_i":
            return case.law_i(point.g1, point.g2, point.g3)
        return PD(point.g1, point.g2, reference=case.reference(point.alpha))

    def _batched_law(self, points: list[DesignPoint]) -> Controller:
        """One law for several points of one law (gains on the leading case axis)."""
        from flexsat.control import PD

        g = {k: np.array([getattr(p, k) for p in points]) for k in GAIN_UNITS}
        case, kind = self.case, points[0].law
        if kind == "law_ii":
            return case.law_ii(g["g1"], g["g2"], g["g3"], alpha=g["alpha"])
        if kind == "law_i":
            return case.law_i(g["g1"], g["g2"], g["g3"])
        return PD(g["g1"], g["g2"], reference=case.reference(g["alpha"]))

    def sweep(
        self, point: DesignPoint, gain: str, values: FloatArray, chunk: int = 4
    ) -> Iterator[list[SweepPoint]]:
        """``point`` with ``gain`` set to each of ``values``: the maneuvers in batches of
        ``chunk`` cases (one :func:`~flexsat.sim.simulate` call each, metrics only, every case
        with the run's own noise seed: each is bit for bit the point run alone, and the points
        differ by their gain only), and each point's margins; yields each batch's points as it
        is done (a caller shows the progress)."""
        from flexsat.sim import SimulationDiverged, simulate

        for start in range(0, len(values), chunk):
            points = [_with_gain(point, gain, float(v)) for v in values[start : start + chunk]]
            refused: dict[int, str] = {}
            laws: dict[int, Controller] = {}
            for i, p in enumerate(points):
                try:
                    laws[i] = self.law(p)
                except FieldError as exc:
                    refused[i] = str(exc)
            settling: dict[int, float] = {}
            valid = [i for i in range(len(points)) if i not in refused]
            if valid:
                law = self._batched_law([points[i] for i in valid])
                try:
                    config = self.configs[point.hardware]
                    metrics = simulate(
                        self.model,
                        law,
                        config,
                        seeds=np.full(len(valid), config.seed),  # one noise draw for all
                        metrics_only=True,
                    ).metrics["settling_time_s"]
                    settling = {i: float(metrics[k]) for k, i in enumerate(valid)}
                except SimulationDiverged as exc:
                    refused.update({i: str(exc) for i in valid})
            yield [
                self._sweep_point(getattr(p, gain), i, laws, settling, refused)
                for i, p in enumerate(points)
            ]

    def _sweep_point(
        self,
        value: float,
        i: int,
        laws: dict[int, Controller],
        settling: dict[int, float],
        refused: dict[int, str],
    ) -> SweepPoint:
        if i in refused:
            return SweepPoint(value, None, None, None, refused[i])
        time_s = settling[i] if math.isfinite(settling[i]) else None
        margins, disk, _, note = self._margins(laws[i], response=False)
        if margins is None or disk is None:
            return SweepPoint(value, time_s, None, None, note)
        return SweepPoint(value, time_s, margins.phase_margin_deg, disk.alpha)

    def evaluate(self, point: DesignPoint) -> Evaluation:
        """Run the maneuver and compute the margins of ``point`` (never raises for bad gains)."""
        from flexsat.sim import SimulationDiverged, simulate

        try:
            law = self.law(point)
        except FieldError as exc:
            return _failed(point, str(exc))
        start = time.perf_counter()
        try:
            result = simulate(self.model, law, self.configs[point.hardware], compiled=True)
        except SimulationDiverged as exc:
            return _failed(point, str(exc))
        simulate_s = time.perf_counter() - start
        ds = result.dataset.isel(case=0)
        metric = {k: float(v[0]) for k, v in result.metrics.items()}
        settling = metric["settling_time_s"]
        start = time.perf_counter()
        margins, disk, response, note = self._margins(law)
        return Evaluation(
            point,
            np.asarray(ds["time"].values, float),
            np.asarray(ds["theta"].values, float),
            np.asarray(ds["theta_ref"].values, float),
            np.asarray(ds["torque"].values, float),
            np.asarray(ds["torque_command"].values, float),
            np.asarray(ds["tip_deflection"].values, float),
            settling if math.isfinite(settling) else None,
            metric["overshoot_deg"],
            metric["peak_torque_Nm"],
            metric["peak_tip_deflection_m"],
            margins,
            disk,
            self.loop_omega_rad_s if response.size else _empty(),
            response,
            margin_note=note,
            simulate_s=simulate_s,
            margins_s=time.perf_counter() - start,
        )

    def _margins(
        self, law: Controller, response: bool = True
    ) -> tuple[LoopMargins | None, DiskMargin | None, np.ndarray, str]:
        from flexsat.analysis.frequency_domain import build_loop, frequency_response
        from flexsat.analysis.margins import UnstableLoopError, disk_margin, loop_margins
        from flexsat.control.state_space_export import discrete_law

        loop = build_loop(self.plant, discrete_law(law, self.dt), "torque")
        values = (
            frequency_response(loop.transfer, omega_rad_s=self.loop_omega_rad_s).values[:, 0, 0]
            if response
            else np.zeros(0, complex)
        )
        try:
            return loop_margins(loop), disk_margin(loop), values, ""
        except UnstableLoopError as exc:
            return None, None, values, str(exc)
