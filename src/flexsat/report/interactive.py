"""Interactive figures of a report page: Bokeh, its JavaScript inlined, no network.

A kind describes its figures as data (:class:`Plot`: curves of x against y, each belonging to a
run); :func:`render` draws them all as one Bokeh document -- pan, box and wheel zoom, hover
read-outs, a legend whose entries hide their curve on a click -- under one row of check boxes,
one per run, that shows or hides a run in every figure at once. :func:`head` is the
``<script>``/``<style>`` block that must be in the page's head: BokehJS itself, inlined
(``bokeh.resources`` in ``inline`` mode, the core and widget bundles: the page opens offline,
with no file beside it).

Identical figures give identical text: Bokeh numbers its models from a counter that lives as
long as the process and names documents and their elements with random UUIDs, so
:func:`render` renames every id it produced, in order of first appearance
(:func:`stable_ids`).

Built on the documented API of Bokeh (``bokeh.plotting.figure``, ``bokeh.embed.components``,
``bokeh.resources.Resources``; Bokeh Development Team, *Bokeh: Python library for interactive
visualization*, 2012-).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np

if TYPE_CHECKING:
    from flexsat.units import FloatArray

#: the BokehJS bundles a report needs: the core (plots, tools) and the widgets (run toggles);
#: the tables, WebGL and MathJax bundles (2.3 MB more) are left out
BUNDLES: tuple[Literal["bokeh"], Literal["bokeh-widgets"]] = ("bokeh", "bokeh-widgets")

#: the colours of runs 0, 1, ... (matplotlib's "tab10", as the static figures use)
PALETTE = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)

#: the line dash of a curve's ``style``
DASHES = {"solid": "solid", "dashed": "dashed", "dotted": "dotted", "dashdot": "dashdot"}

#: the most points a curve keeps (longer ones are thinned keeping each block's extremes)
MAX_POINTS = 20_000


@dataclass(frozen=True)
class Curve:
    """One line of a figure.

    Attributes
    ----------
    run : str
        The run it belongs to (its colour, its toggle); "" for a curve of no run (a nominal,
        a bound), always shown, in grey.
    label : str
        Its legend entry.
    x, y : ndarray
        Its points (NaN breaks the line).
    style : str
        ``solid``, ``dashed``, ``dotted`` or ``dashdot`` (:data:`DASHES`).
    color : int or None
        Its colour's index in :data:`PALETTE` (default: its run's index; grey for no run).
    """

    run: str
    label: str
    x: FloatArray
    y: FloatArray
    style: str = "solid"
    color: int | None = None


@dataclass(frozen=True)
class Plot:
    """A figure: its curves, axis labels with their units, and reference lines.

    Attributes
    ----------
    title, x_label, y_label : str
    curves : tuple of Curve
    hlines, vlines : tuple of float
        Horizontal (a tolerance band) and vertical (an event time) reference lines.
    log_x, log_y : bool
        Logarithmic axes.
    """

    title: str
    x_label: str
    y_label: str
    curves: tuple[Curve, ...]
    hlines: tuple[float, ...] = field(default=())
    vlines: tuple[float, ...] = field(default=())
    log_x: bool = False
    log_y: bool = False


def head() -> str:
    """The page head's BokehJS (script and style elements), inlined (:data:`BUNDLES`).

    Only the inlined text is written, never the resources' file references: an extension
    imported into the same process (Panel, for the dashboard) adds its own script files to
    every ``Resources``, which would make the page load a sibling file."""
    from bokeh.core.templates import CSS_RESOURCES, JS_RESOURCES
    from bokeh.resources import Resources

    inline = Resources(mode="inline", components=list(BUNDLES))
    css = CSS_RESOURCES.render(css_raw=inline.css_raw, css_files=[])
    js = JS_RESOURCES.render(js_raw=inline.js_raw, js_files=[], hashes=inline.hashes)
    return f"{css}\n{js}"


def thin(x: FloatArray, y: FloatArray, limit: int = MAX_POINTS) -> tuple[FloatArray, FloatArray]:
    """At most about ``limit`` points of the curve (x, y): unchanged when it has fewer, else each
    block of consecutive points reduced to its first, least and greatest points in order, so
    that every peak stays on the figure."""
    n = x.size
    if n <= limit:
        return x, y
    size = int(np.ceil(3 * n / limit))
    keep = set()
    for start in range(0, n, size):
        block = y[start : start + size]
        keep.add(start)
        if np.isfinite(block).any():
            keep.add(start + int(np.nanargmin(block)))
            keep.add(start + int(np.nanargmax(block)))
    keep.add(n - 1)
    index = np.array(sorted(keep))
    return x[index], y[index]


def _figure(plot: Plot, runs: Sequence[str]) -> tuple[object, list[tuple[int, object]]]:
    """The Bokeh figure of ``plot`` and its run renderers as (run index, renderer)."""
    from bokeh.models.annotations import Span
    from bokeh.models.tools import HoverTool
    from bokeh.plotting import figure

    fig = figure(
        title=plot.title,
        x_axis_label=plot.x_label,
        y_axis_label=plot.y_label,
        x_axis_type="log" if plot.log_x else "linear",
        y_axis_type="log" if plot.log_y else "linear",
        height=330,
        sizing_mode="stretch_width",
        tools="pan,box_zoom,wheel_zoom,reset,save",
        active_scroll=None,
    )
    owned: list[tuple[int, object]] = []
    for curve in plot.curves:
        x, y = thin(np.asarray(curve.x, float), np.asarray(curve.y, float))
        index = runs.index(curve.run) if curve.run in runs else -1
        shade = curve.color if curve.color is not None else index
        color = PALETTE[shade % len(PALETTE)] if shade >= 0 else "#555555"
        renderer = fig.line(
            x,
            y,
            line_color=color,
            line_width=1.8 if curve.style == "solid" else 1.2,
            line_dash=DASHES.get(curve.style, "solid"),
            legend_label=curve.label,
        )
        renderer.name = curve.label  # the hover's "$name"
        renderer.tags = [f"run:{curve.run}"]  # what the toggles and a test find it by
        if index >= 0:
            owned.append((index, renderer))
    for level in plot.hlines:
        fig.add_layout(
            Span(location=level, dimension="width", line_dash="dotted", line_color="red")
        )
    for at in plot.vlines:
        fig.add_layout(Span(location=at, dimension="height", line_dash="dashed", line_color="grey"))
    fig.add_tools(
        HoverTool(
            tooltips=[("", "$name"), (plot.x_label, "$x{0.[000]}"), (plot.y_label, "$y{0.[0000]}")],
            line_policy="nearest",
        )
    )
    fig.legend.click_policy = "hide"
    fig.legend.label_text_font_size = "8pt"
    fig.legend.location = "top_right"
    return fig, owned


#: JavaScript of the run toggles: a renderer is shown while its run's box is ticked
_TOGGLE = """
const shown = new Set(toggles.active);
for (let i = 0; i < renderers.length; i++) {
  renderers[i].visible = shown.has(owners[i]);
}
"""

_UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def stable_ids(text: str) -> str:
    """``text`` (Bokeh's embedding of a document) with every model id and every UUID renamed
    ``fx1``, ``fx2``, ... in order of first appearance (module docstring).

    A model id is a quoted string that is somewhere the value of an ``"id"`` key, as Bokeh
    defines every model it serialises; only those strings are renamed, wherever they are
    referenced, never another string that merely looks alike.
    """
    model_ids = set(re.findall(r'"id":"(p\d+)"', text))
    names: dict[str, str] = {}

    def rename(old: str) -> str:
        return names.setdefault(old, f"fx{len(names) + 1}")

    pattern = re.compile(r'"(p\d+)"|' + _UUID.pattern)

    def swap(match: re.Match[str]) -> str:
        quoted = match.group(1)
        if quoted is None:
            return rename(match.group(0))
        return f'"{rename(quoted)}"' if quoted in model_ids else match.group(0)

    return pattern.sub(swap, text)


def render(plots: Sequence[Plot], runs: Sequence[str]) -> str:
    """The HTML (a ``<div>`` and a ``<script>``) of ``plots`` with one toggle per run of
    ``runs`` (none for a single run); needs :func:`head` in the page. Empty without plots."""
    if not plots:
        return ""
    from bokeh.embed import components
    from bokeh.layouts import column
    from bokeh.models.callbacks import CustomJS
    from bokeh.models.widgets import CheckboxGroup, Div

    figures, renderers, owners = [], [], []
    for plot in plots:
        fig, owned = _figure(plot, runs)
        figures.append(fig)
        for index, renderer in owned:
            owners.append(index)
            renderers.append(renderer)
    items: list[object] = []
    if len(runs) > 1:
        toggles = CheckboxGroup(
            labels=list(runs), active=list(range(len(runs))), inline=True, name="run-toggles"
        )
        toggles.js_on_change(
            "active",
            CustomJS(
                args={"toggles": toggles, "renderers": renderers, "owners": owners}, code=_TOGGLE
            ),
        )
        items = [Div(text="<b>Runs shown:</b>"), toggles]
    layout = column(*items, *figures, sizing_mode="stretch_width")
    script, div = components(layout)
    return stable_ids(f"{div}\n{script}")


__all__ = [
    "BUNDLES",
    "MAX_POINTS",
    "PALETTE",
    "Curve",
    "Plot",
    "head",
    "render",
    "stable_ids",
    "thin",
]
