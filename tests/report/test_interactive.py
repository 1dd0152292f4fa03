"""Interactive figures (flexsat.report.interactive): identical figures give identical text
whatever Bokeh drew before; ids are renamed only where Bokeh defines a model; thinning keeps
every block's extremes; the head inlines BokehJS and loads nothing."""

from __future__ import annotations

import re

import numpy as np
import pytest

from flexsat.report.interactive import BUNDLES, Curve, Plot, head, render, stable_ids, thin

T = np.linspace(0.0, 10.0, 401)


def plots():
    return [
        Plot(
            "Hub angle",
            "time (s)",
            "angle (deg)",
            (
                Curve("Law I", "Law I", T, np.sin(T)),
                Curve("Law I", "Law I reference", T, 0 * T, "dashed"),
                Curve("Law II", "Law II", T, np.cos(T)),
                Curve("", "nominal", T, 0.5 + 0 * T),
            ),
            hlines=(0.1, -0.1),
            vlines=(5.0,),
        ),
        Plot("Energy", "time (s)", "J", (Curve("Law II", "Law II", T, 1 + T),), log_y=True),
    ]


def test_identical_figures_give_identical_text():
    from bokeh.plotting import figure

    first = render(plots(), ["Law I", "Law II"])
    figure().line([1, 2], [3, 4])  # Bokeh's id counter moves on in between
    assert render(plots(), ["Law I", "Law II"]) == first
    assert not re.search(r'"p\d+"', first)  # every model id renamed
    assert not re.search(r"[0-9a-f]{8}-[0-9a-f]{4}-", first)  # and every UUID


def test_the_toggles_name_every_run_and_a_single_run_has_none():
    text = render(plots(), ["Law I", "Law II"])
    assert '"labels":["Law I","Law II"]' in text and '"active":[0,1]' in text
    # each curve of a run tagged with it, the nominal (no run) tagged with none
    assert text.count('"run:Law I"') == 2 and text.count('"run:Law II"') == 2
    one = render(plots()[1:], ["Law II"])
    assert "CheckboxGroup" not in one and "Figure" in one
    assert render([], ["Law I"]) == ""


def test_only_ids_bokeh_defines_are_renamed():
    uuid = "aaaaaaaa-bbbb-cccc-dddd-eeeeeeeeeeee"
    text = '{"id":"p1001","label":"p1002","ref":{"id":"p1001"}} "p1003" ' + uuid
    out = stable_ids(text)
    assert out == '{"id":"fx1","label":"p1002","ref":{"id":"fx1"}} "p1003" fx2'


def test_thinning_keeps_every_peak_and_the_ends():
    x = np.arange(100_000, dtype=float)
    y = np.sin(x / 700.0) + (x == 31_337) * 5.0 - (x == 77_777) * 7.0
    tx, ty = thin(x, y, 3000)
    assert tx.size <= 3000 + 2 and np.all(np.diff(tx) > 0)
    assert tx[0] == 0 and tx[-1] == x[-1]
    assert ty.max() == y.max() and ty.min() == y.min()
    assert np.array_equal(ty, y[tx.astype(int)])  # points of the curve, not new ones
    short = np.arange(10.0)
    assert thin(short, short)[0] is short


def test_the_head_inlines_bokehjs_and_loads_nothing():
    from bokeh import __version__

    text = head()
    assert f"Bokeh {__version__}" in text or __version__ in text
    assert not re.search(r"<script\b[^>]*\bsrc=", text) and "<link" not in text
    assert BUNDLES == ("bokeh", "bokeh-widgets")


def test_the_head_stays_inline_when_the_dashboard_is_loaded_in_the_same_process():
    # Panel (flexsat serve) registers script files of its own with every bokeh Resources; a
    # report written after it was imported (a test run, a notebook) must still load nothing
    pytest.importorskip("panel")
    import panel  # noqa: F401
    from bokeh.resources import Resources

    assert Resources(mode="inline", components=list(BUNDLES)).js_files  # what Panel adds
    text = head()
    assert not re.search(r"<script\b[^>]*\bsrc=", text) and "<link" not in text
