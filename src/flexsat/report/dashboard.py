r"""``flexsat serve``: a live design dashboard for the TAMU hub (Panel on a Bokeh server).

The page (:func:`dashboard`) holds the gains of a law of the TAMU hub with four appendages
(Junkins, Rahman & Bang 1990; the laws and what is computed are those of
:mod:`flexsat.report.dashboard_model`), entered in the papers' units (oz-in/rad, oz-in-s/rad),
and, for every change of a gain, of the law or of the hardware switch:

* the 40° maneuver run again through the one engine (:func:`flexsat.sim.simulate`, compiled
  loop): hub angle and its reference (deg), applied and commanded torque (oz-in), tip
  deflection of an appendage (in);
* its settling time (0.5° band), overshoot, peak torque and peak tip deflection;
* the margins of the sampled loop broken at the torque: phase margin, gain margin, delay
  margin and balanced disk margin α (Seiler, Packard & Gahinet, "An introduction to disk
  margins", IEEE Control Systems Magazine 40(5), 2020, 78–95), and the loop gain |L(e^{jωT})|
  up to the Nyquist frequency;
* the server-side time the update took.

A gain that breaks a law's rule (a negative g1, α outside the reference's range), a maneuver
that diverges or an unstable loop is shown as its message in place of the numbers; the page
never shows a traceback.

Every number on the page has an element id (``settling-time``, ``phase-margin``,
``gain-margin``, ``delay-margin``, ``disk-margin``, ``update-count``, ``update-ms``, ...) so a
browser test (tests/report/test_dashboard.py) and the benchmark (benchmarks/bench_serve.py)
can read it. Everything is served from the local Bokeh server: the page needs no network.
"""

from __future__ import annotations

import html
import math
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.input_checks import FieldError
from flexsat.report.dashboard_model import (
    DEFAULT_GAINS,
    LAWS,
    USES,
    DesignPoint,
    Evaluation,
    SweepPoint,
    TamuDesign,
    sweep_values,
)

if TYPE_CHECKING:
    import panel as pn
    from bokeh.models import ColumnDataSource
    from bokeh.plotting import figure as Figure

__all__ = ["DISPLAY_UNITS", "SWEEP_POINTS", "Dashboard", "dashboard", "readout_html", "serve"]

#: points of a gain sweep
SWEEP_POINTS = 12

#: the unit each gain is entered in on the page (the papers'), and its label
DISPLAY_UNITS = {
    "g1": ("ozf*in/rad", "g1, position gain (oz-in/rad)"),
    "g2": ("ozf*in*s/rad", "g2, rate gain (oz-in-s/rad)"),
    "g3": ("", "g3, root-load gain (–)"),
    "alpha": ("", "α, reference switching fraction (–)"),
}


def _factor(unit: str) -> float:
    """SI per display unit (1 for a dimensionless one)."""
    from flexsat.units import si_factor

    return si_factor(unit) if unit else 1.0


def _cell(ident: str, label: str, value: str) -> str:
    return (
        f'<tr><th style="text-align:left;padding-right:1em">{html.escape(label)}</th>'
        f'<td id="{ident}">{html.escape(value)}</td></tr>'
    )


def _number(value: float, fmt: str, unit: str) -> str:
    if math.isinf(value):
        return "none (∞)"
    return f"{value:{fmt}} {unit}".rstrip()


def readout_html(evaluation: Evaluation, count: int, update_ms: float) -> str:
    """The numbers of an evaluation as an HTML table, each cell with its element id (module
    docstring); a message in place of the numbers a failed evaluation has not."""
    from flexsat.units import si_factor

    e = evaluation
    torque_unit, length_unit = si_factor("ozf*in"), si_factor("in")
    rows = []
    if e.error:
        rows.append(_cell("maneuver-error", "maneuver", e.error))
        settling = "no maneuver"
    elif e.settling_time_s is None:
        settling = "not settled within the run"
    else:
        settling = f"{e.settling_time_s:.3f} s"
    rows.append(_cell("settling-time", "settling time (0.5°)", settling))
    if not e.error:
        rows += [
            _cell("overshoot", "overshoot", f"{e.overshoot_deg:.3f} deg"),
            _cell("peak-torque", "peak torque", f"{e.peak_torque_Nm / torque_unit:.1f} oz-in"),
            _cell(
                "peak-tip",
                "peak tip deflection",
                f"{e.peak_tip_deflection_m / length_unit:.3f} in",
            ),
        ]
    if e.margins is not None and e.disk is not None:
        m = e.margins
        rows += [
            _cell("phase-margin", "phase margin", _number(m.phase_margin_deg, ".2f", "deg")),
            _cell(
                "gain-margin",
                "gain margin",
                "none (∞)"
                if math.isinf(m.gain_margin)
                else f"{m.gain_margin:.3f} ({m.gain_margin_db:.2f} dB)",
            ),
            _cell("delay-margin", "delay margin", _number(1e3 * m.delay_margin_s, ".2f", "ms")),
            _cell("disk-margin", "disk margin α", f"{e.disk.alpha:.4f}"),
        ]
    else:
        note = e.margin_note or "no loop (the law's gains were refused)"
        rows.append(_cell("phase-margin", "margins", note))
    rows += [
        _cell("update-ms", "server update", f"{update_ms:.0f} ms"),
        _cell("update-count", "updates", str(count)),
    ]
    return '<table id="readout">' + "".join(rows) + "</table>"


def _figure(title: str, y_label: str, x_label: str = "time (s)", log_x: bool = False) -> Figure:
    from bokeh.plotting import figure

    return figure(
        title=title,
        x_axis_label=x_label,
        y_axis_label=y_label,
        height=260,
        width=560,
        x_axis_type="log" if log_x else "linear",
        tools="pan,wheel_zoom,box_zoom,reset,hover,save",
    )


class Dashboard:
    """One browser session's page: widgets, readouts and plots (module docstring).

    Parameters
    ----------
    design : TamuDesign
        The case, its model and the loop's plant, shared by every session of a server.
    """

    def __init__(self, design: TamuDesign) -> None:
        import panel as pn
        from bokeh.models import ColumnDataSource

        self.design = design
        self.count = 0
        self.last_update_s = 0.0
        self.sweep_started = 0.0
        self.law = pn.widgets.Select(
            label="law", options={label: key for key, label in LAWS.items()}, value="law_ii"
        )
        self.gains: dict[str, pn.widgets.FloatInput] = {}
        for name, (unit, label) in DISPLAY_UNITS.items():
            start = _default_display(name, unit)
            self.gains[name] = pn.widgets.FloatInput(
                label=label, value=start, step=0.05 if name == "alpha" else 100.0, width=260
            )
        self.hardware = pn.widgets.Checkbox(
            label="hardware effects (friction, 0.01° encoder, random torque)", value=True
        )
        self.readout = pn.pane.HTML("", sizing_mode="stretch_width")
        self.sources: dict[str, ColumnDataSource] = {
            key: ColumnDataSource(data=dict.fromkeys(columns, np.zeros(0)))
            for key, columns in (
                ("angle", ("t", "theta", "ref")),
                ("torque", ("t", "applied", "command")),
                ("tip", ("t", "tip")),
                ("loop", ("f", "gain_db", "one")),
                ("sweep", ("x", "settling", "pm")),
            )
        }
        self.figures = self._figures()
        for widget in (self.law, *self.gains.values(), self.hardware):
            widget.param.watch(self._changed, "value")
        self.sweep_gain = pn.widgets.Select(
            label="sweep", options={DISPLAY_UNITS[k][1]: k for k in DISPLAY_UNITS}, value="g1"
        )
        self.sweep_button = pn.widgets.Button(label=f"sweep {SWEEP_POINTS} values", width=260)
        self.progress = pn.indicators.Progress(value=0, max=SWEEP_POINTS, width=260)
        self.sweep_status = pn.pane.HTML(_status("no sweep yet"))
        self.sweep_figures = self._sweep_figures()
        self.sweep_button.on_click(self._sweep_clicked)
        self.update()

    def _figures(self) -> list[Figure]:
        s = self.sources
        angle = _figure("hub angle", "angle (deg)")
        angle.line(
            "t",
            "ref",
            source=s["angle"],
            color="gray",
            line_dash="dashed",
            legend_label="reference",
        )
        angle.line("t", "theta", source=s["angle"], color="navy", legend_label="hub angle")
        angle.legend.location = "bottom_right"
        torque = _figure("hub torque", "torque (oz-in)")
        torque.line("t", "command", source=s["torque"], color="gray", legend_label="commanded")
        torque.line("t", "applied", source=s["torque"], color="firebrick", legend_label="applied")
        tip = _figure("tip deflection", "deflection (in)")
        tip.line("t", "tip", source=s["tip"], color="darkgreen")
        loop = _figure(
            "loop gain |L| at the torque (75 Hz, exact hold)",
            "|L| (dB)",
            x_label="frequency (Hz)",
            log_x=True,
        )
        loop.line("f", "one", source=s["loop"], color="gray", line_dash="dotted")
        loop.line("f", "gain_db", source=s["loop"], color="purple")
        return [angle, torque, tip, loop]

    def _sweep_figures(self) -> list[Figure]:
        source = self.sources["sweep"]
        settling = _figure("sweep: settling time", "settling time (s)", x_label="swept gain")
        settling.scatter("x", "settling", source=source, size=7, color="navy")
        settling.line("x", "settling", source=source, color="navy")
        margin = _figure("sweep: phase margin", "phase margin (deg)", x_label="swept gain")
        margin.scatter("x", "pm", source=source, size=7, color="purple")
        margin.line("x", "pm", source=source, color="purple")
        return [settling, margin]

    def _start_sweep(self) -> Iterator[list[SweepPoint]] | None:
        """Reset the sweep's plots and progress; the design's sweep of the widgets' point, or
        None (and the reason shown) when the point cannot be swept."""
        point, gain = self.point(), str(self.sweep_gain.value)
        self.sources["sweep"].data = {"x": [], "settling": [], "pm": []}
        self.progress.value = 0
        try:
            values = sweep_values(point, gain, SWEEP_POINTS)
        except FieldError as exc:
            self.sweep_status.object = _status(str(exc))
            return None
        self.sweep_started = time.perf_counter()
        for figure in self.sweep_figures:
            figure.xaxis.axis_label = DISPLAY_UNITS[gain][1]
        self.sweep_status.object = _status(f"sweep of {gain} running: 0 of {SWEEP_POINTS}")
        return self.design.sweep(point, gain, values)

    def _show_sweep(self, chunk: list[SweepPoint]) -> None:
        gain = str(self.sweep_gain.value)
        factor = _factor(DISPLAY_UNITS[gain][0])
        self.sources["sweep"].stream(
            {
                "x": [p.value / factor for p in chunk],
                "settling": [_or_nan(p.settling_time_s) for p in chunk],
                "pm": [_or_nan(p.phase_margin_deg) for p in chunk],
            }
        )
        done = int(self.progress.value or 0) + len(chunk)
        self.progress.value = done
        took = time.perf_counter() - self.sweep_started
        state = "done" if done == SWEEP_POINTS else "running"
        self.sweep_status.object = _status(
            f"sweep of {gain} {state}: {done} of {SWEEP_POINTS} in {took:.1f} s"
        )

    def run_sweep(self) -> None:
        """The sweep, here and now (what the button runs in the background)."""
        steps = self._start_sweep()
        for chunk in steps or ():
            self._show_sweep(chunk)

    def _sweep_clicked(self, *_: Any) -> None:
        """The sweep with the page live: the batches run in a worker thread and a periodic
        callback of the session (which holds the document's lock) shows each one done."""
        import queue
        import threading

        import panel as pn

        steps = self._start_sweep()
        if steps is None:
            return
        done: queue.Queue[list[SweepPoint] | str | None] = queue.Queue()

        def work() -> None:
            try:
                for chunk in steps:
                    done.put(chunk)
                done.put(None)
            except Exception as exc:  # shown on the page; the session goes on
                done.put(f"sweep stopped: {exc}")

        self.sweep_button.disabled = True
        threading.Thread(target=work, daemon=True).start()
        callback: Any = None

        def show() -> None:
            while not done.empty():
                item = done.get_nowait()
                if isinstance(item, list):
                    self._show_sweep(item)
                    continue
                if isinstance(item, str):
                    self.sweep_status.object = _status(item)
                self.sweep_button.disabled = False
                callback.stop()
                return

        callback = pn.state.add_periodic_callback(show, period=100)

    def point(self) -> DesignPoint:
        """The design point the widgets show, in SI."""
        values = {
            name: float(self.gains[name].value or 0.0) * _factor(unit)
            for name, (unit, _) in DISPLAY_UNITS.items()
        }
        return DesignPoint(
            str(self.law.value),
            values["g1"],
            values["g2"],
            values["g3"],
            values["alpha"],
            bool(self.hardware.value),
        )

    def _changed(self, *_: Any) -> None:
        self.update()

    def update(self) -> Evaluation:
        """Evaluate the widgets' design point and show it (plots and readouts)."""
        start = time.perf_counter()
        used = USES[str(self.law.value)]
        for name, widget in self.gains.items():
            widget.disabled = name not in used
        evaluation = self.design.evaluate(self.point())
        self._show(evaluation)
        self.count += 1
        self.last_update_s = time.perf_counter() - start
        self.readout.object = readout_html(evaluation, self.count, 1e3 * self.last_update_s)
        return evaluation

    def _show(self, e: Evaluation) -> None:
        from flexsat.units import si_factor

        torque, length = si_factor("ozf*in"), si_factor("in")
        t = e.time_s
        self.sources["angle"].data = {
            "t": t,
            "theta": np.degrees(e.angle_rad),
            "ref": np.degrees(e.reference_rad),
        }
        self.sources["torque"].data = {
            "t": t,
            "applied": e.torque_Nm / torque,
            "command": e.command_Nm / torque,
        }
        self.sources["tip"].data = {"t": t, "tip": e.tip_deflection_m / length}
        with np.errstate(divide="ignore"):
            gain_db = 20 * np.log10(np.abs(e.loop_response))
        self.sources["loop"].data = {
            "f": e.loop_omega_rad_s / (2 * math.pi),
            "gain_db": gain_db,
            "one": np.zeros_like(gain_db),
        }

    def view(self) -> pn.viewable.Viewable:
        """The page's layout."""
        import panel as pn

        header = pn.pane.Markdown(
            "# flexsat design dashboard: TAMU hub with four appendages\n"
            "The 40° maneuver of Junkins, Rahman & Bang (1990) at 75 Hz, run again through "
            "the simulation engine for every change; margins of the sampled loop at the torque.",
            sizing_mode="stretch_width",
        )
        controls = pn.Column(self.law, *self.gains.values(), self.hardware, width=300)
        plots = pn.GridBox(*(pn.pane.Bokeh(f) for f in self.figures), ncols=2)
        sweep = pn.Column(
            pn.pane.Markdown("### Gain sweep (0.5× to 2× g1 or g2; g3 −2 to 2; α 0.02 to 0.25)"),
            self.sweep_gain,
            self.sweep_button,
            self.progress,
            self.sweep_status,
            width=300,
        )
        sweep_plots = pn.Row(*(pn.pane.Bokeh(f) for f in self.sweep_figures))
        return pn.Column(header, pn.Row(controls, self.readout), plots, pn.Row(sweep, sweep_plots))


def _or_nan(value: float | None) -> float:
    return math.nan if value is None else value


def _status(text: str) -> str:
    return f'<span id="sweep-status">{html.escape(text)}</span>'


def _default_display(name: str, unit: str) -> float:
    from flexsat.units import to_si

    si_unit = {"g1": "N*m/rad", "g2": "N*m*s/rad"}.get(name, "")
    return to_si(DEFAULT_GAINS[name], si_unit, name) / _factor(unit)


def dashboard(design: TamuDesign | None = None) -> pn.viewable.Viewable:
    """A new page (one per browser session) on ``design`` (default a new TAMU design)."""
    return Dashboard(TamuDesign() if design is None else design).view()


def serve(
    port: int,
    address: str = "127.0.0.1",
    show: bool = False,
    ready: Callable[[str], None] | None = None,
) -> None:
    """Serve the dashboard on ``address:port`` until interrupted.

    The case and the compiled loop are prepared (one maneuver run) before the server listens,
    so the first page answers as fast as the next ones; ``ready(url)`` is called then.

    Raises
    ------
    OSError
        When the port cannot be bound (in use, or not allowed).
    """
    import socket

    with socket.socket() as probe:  # a port in use is said now, not after the warm-up
        probe.bind((address, port))
    import panel as pn

    design = TamuDesign()
    Dashboard(design)  # one page built and evaluated: the compiled loop is loaded (or compiled) now
    server = pn.serve(
        {"/": lambda: dashboard(design)},
        port=port,
        address=address,
        # the page's own origin; listening on every interface, any host's page may connect
        websocket_origin="*"
        if address in ("0.0.0.0", "::")
        else [f"{address}:{port}", f"localhost:{port}"],
        show=show,
        start=False,
        title="flexsat design dashboard",
        verbose=False,
    )
    if ready is not None:
        ready(f"http://{address}:{port}/")
    server.start()
    server.io_loop.start()
