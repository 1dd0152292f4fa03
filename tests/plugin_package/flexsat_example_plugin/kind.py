r"""A scenario kind from outside flexsat: the pulse-width study of the two carts.

``kind: pulse_tuning`` moves the carts (:class:`~flexsat_example_plugin.plant.TwoMassSpring`)
with the bang-off-bang force (:class:`~flexsat_example_plugin.law.BangOffBang`) once per pulse
width t1 and reports the elastic vibration left after the move beside its closed form. For the
elastic coordinate q = x1 − x2 (ω² = k (1/m1 + 1/m2)), a force pulse F of width t1 on cart 1
followed, t1 + tc later, by −F leaves the amplitude

.. math::

    A = \frac{4 F}{m_1 \omega^2}
        \left|\sin\frac{\omega t_1}{2}\,\sin\frac{\omega (t_1 + t_c)}{2}\right|,

zero when t1 is a whole number of elastic periods (Singh and Vadali, "Robust time-optimal
control: frequency domain approach", Journal of Guidance, Control, and Dynamics 17(2),
346-353, 1994). The measured amplitude is :math:`\sqrt{q^2 + (\dot q/\omega)^2}` at the end of
the run (the carts are undamped)::

    kind: pulse_tuning
    name: Two carts, three pulse widths
    carts: {m1: 1 kg, m2: 1 kg, k: 19.739208802178716 N/m}
    force: 1 N
    coast: 0.3 s
    duration: 4 s
    control_rate: 100 Hz
    pulse_widths: [0.5 s, 0.75 s, 1 s]

It is one class in one module, registered by one entry point (``flexsat.kinds``); flexsat is
not edited.
"""

from __future__ import annotations

import html
import math
from typing import Literal

from pydantic import Field, model_validator

from flexsat.scenarios import Run, ScenarioKind, Simulation, quantity
from flexsat.scenarios.datasets import SimulatedRuns
from flexsat.scenarios.fields import Document
from flexsat.sim import SimConfig
from flexsat_example_plugin.case import WieBernstein
from flexsat_example_plugin.law import BangOffBang
from flexsat_example_plugin.plant import TwoMassSpring


class PulseTuning(Document):
    """A ``kind: pulse_tuning`` file (module docstring)."""

    kind: Literal["pulse_tuning"]
    name: str
    case: Literal["wie_bernstein"] = "wie_bernstein"
    carts: TwoMassSpring.Parameters
    force: quantity("N")
    coast: quantity("s") = 0.0
    duration: quantity("s", positive=True)
    control_rate: quantity("Hz", positive=True)
    pulse_widths: list[quantity("s", positive=True)] = Field(min_length=1, max_length=50)

    @model_validator(mode="after")
    def _fits(self) -> PulseTuning:
        longest = 2 * max(self.pulse_widths) + self.coast
        if longest > self.duration:
            raise ValueError(
                f"duration: {self.duration:g} s ends before the longest move "
                f"(2 t1 + tc = {longest:g} s)"
            )
        return self


class PulseTuningResult(SimulatedRuns):
    """The runs, with the measured and predicted residual amplitudes per pulse width."""

    def metrics_records(self) -> list[dict]:
        s = self.scenario
        carts = TwoMassSpring(**s.carts.model_dump())
        omega = math.sqrt(carts.k * (1 / carts.m1 + 1 / carts.m2))
        records = []
        for label, width, result in zip(self.labels, s.pulse_widths, self.results):
            ds = result.dataset
            q = float(ds["x1"].values[0, -1] - ds["x2"].values[0, -1])
            qd = float(ds["v1"].values[0, -1] - ds["v2"].values[0, -1])
            predicted = (
                4
                * s.force
                / (carts.m1 * omega**2)
                * abs(math.sin(omega * width / 2) * math.sin(omega * (width + s.coast) / 2))
            )
            records.append(
                {
                    "run": label,
                    "pulse_width_s": width,
                    "residual_amplitude_m": math.hypot(q, qd / omega),
                    "predicted_amplitude_m": predicted,
                    "distance_m": s.force * width * (width + s.coast) / (carts.m1 + carts.m2),
                }
            )
        return records

    def sections(self, ds, figures: list[str]) -> str:
        rows = "".join(
            f"<tr><td>{html.escape(r['run'])}</td><td>{r['residual_amplitude_m']:.4g}</td>"
            f"<td>{r['predicted_amplitude_m']:.4g}</td></tr>"
            for r in self.metrics_records()
        )
        return (
            "<h2>Residual vibration</h2><table><tr><th>pulse</th><th>measured (m)</th>"
            f"<th>closed form (m)</th></tr>{rows}</table>"
        )


class PulseTuningKind(ScenarioKind):
    """``kind: pulse_tuning``: one bang-off-bang move per pulse width (module docstring)."""

    kind = "pulse_tuning"
    document = PulseTuning

    def steps(self, scenario: PulseTuning) -> int:
        return len(scenario.pulse_widths)

    def plan(self, scenario: PulseTuning):
        plant = TwoMassSpring(**scenario.carts.model_dump())
        config = SimConfig(duration=scenario.duration, control_rate=scenario.control_rate)
        labels, results = [], []
        for index, width in enumerate(scenario.pulse_widths):
            law = BangOffBang(scenario.force, width, scenario.coast, dt=config.dt)
            labels.append(f"t1 = {width:g} s")
            run = Run(labels[-1], Simulation(plant, law, config), f"pulse_widths[{index}]")
            results.append((yield run))
        return PulseTuningResult(scenario, tuple(labels), tuple(results), WieBernstein.source)


__all__ = ["PulseTuning", "PulseTuningKind", "PulseTuningResult"]
