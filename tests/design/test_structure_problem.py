"""Claims about :mod:`flexsat.design.structure_problem`: design variables on an FE description.

Gradients are checked against the five-point central difference
g' ≈ [−g(x+2h) + 8 g(x+h) − 8 g(x−h) + g(x−2h)] / 12h, h = 1e-3 |x| (as in
tests/analysis/test_fe_sensitivity.py): truncation h⁴|g⁽⁵⁾|/30 ≈ 1e-12 relative for power-law
dependences, round-off ≈ 1.5 ε_g |g| / h with ε_g ≈ 1e-13 for frequencies (shift-invert with a
Rayleigh-Ritz refinement), ≈ 1.5e-10 |g|/|x|. The acceptance bound of issue 23 is 1e-6
relative to max(|g'|, |g|/|x|) (a response that barely sees a variable is measured against the
scale below which the round-off of the difference would dominate; for a separation f_j − f_i,
|g| is f_i + f_j, whose round-off the difference carries).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.structure_problem import (
    MassVariable,
    MaterialVariable,
    SectionShape,
    SectionVariable,
    StructureProblem,
    parse_response,
)
from flexsat.input_checks import FieldError
from flexsat.structures.fe_description import (
    ClampSpec,
    ElementSpec,
    FEDescription,
    MassSpec,
    NodeSpec,
    RigidLinkSpec,
)
from flexsat.structures.sections import Material, Section

ALU = Material(E=70e9, rho=2700.0, nu=0.33)
STEEL = Material(E=200e9, rho=7800.0, G=80e9)  # an explicit G: E moves alone
ACCEPT = 1e-6  # issue 23: analytic gradient vs central differences, relative
REL_STEP = 1e-3

SHAPES = {
    "tube": SectionShape("tube", {"outer_diameter": 0.04, "thickness": 0.002}),
    "circ": SectionShape("circle", {"diameter": 0.02}),
    "rect": SectionShape("rectangle", {"width": 0.025, "height": 0.015}),
    "gen": SectionShape("general", {"area": 2e-4, "Iy": 3e-9, "Iz": 5e-9, "J": 6e-9}),
}


def _sections(shapes=SHAPES):
    return {k: s.section({}) for k, s in shapes.items()}


def mixed(free: bool = False) -> FEDescription:
    """A braced cantilever using every section shape: tube frames and a tube rod, a circle, a
    rectangle and a general-section frame, an offset tip mass with inertia, and a mass on a
    node rigidly linked to the tip (``free``: no clamps, a free-free body)."""
    nodes = [NodeSpec(i, (0.5 * i, 0.0, 0.0)) for i in range(5)]
    nodes += [NodeSpec(5, (1.0, 0.6, 0.1)), NodeSpec(6, (2.0, 0.0, 0.12))]
    z = (0.0, 0.0, 1.0)
    elements = [
        ElementSpec("frame", (0, 1), "alu", "tube", z),
        ElementSpec("frame", (1, 2), "alu", "tube", z),
        ElementSpec("frame", (2, 3), "alu", "circ", z),
        ElementSpec("frame", (3, 4), "steel", "rect", z),
        ElementSpec("rod", (5, 2), "alu", "tube"),
        ElementSpec("frame", (5, 3), "alu", "gen", z),
        ElementSpec("frame", (0, 5), "alu", "rect", z),
    ]
    masses = [
        MassSpec(4, 0.4, (2e-4, 3e-4, 4e-4), (0.0, 0.03, 0.05)),
        MassSpec(6, 0.3),
        MassSpec(0, 2.0, (0.05, 0.06, 0.07)),
    ]
    return FEDescription(
        nodes,
        {"alu": ALU, "steel": STEEL},
        _sections(),
        elements,
        masses=masses,
        rigid_links=[RigidLinkSpec(4, (6,))],
        clamps=[] if free else [ClampSpec(0)],
        n_modes=6,
    )


def every_variable() -> tuple:
    return (
        SectionVariable("D", "tube", "outer_diameter", 0.04, 0.02, 0.08),
        SectionVariable("t", "tube", "thickness", 0.002, 0.001, 0.004),
        SectionVariable("d", "circ", "diameter", 0.02, 0.01, 0.04),
        SectionVariable("b", "rect", "width", 0.025, 0.01, 0.05),
        SectionVariable("h", "rect", "height", 0.015, 0.01, 0.05),
        SectionVariable("A", "gen", "area", 2e-4, 1e-4, 4e-4),
        SectionVariable("Iy", "gen", "Iy", 3e-9, 1e-9, 1e-8),
        SectionVariable("Iz", "gen", "Iz", 5e-9, 1e-9, 1e-8),
        SectionVariable("J", "gen", "J", 6e-9, 1e-9, 1e-8),
        MassVariable("m_tip", 0, "mass", 0.4, 0.1, 1.0),
        MassVariable("m_linked", 1, "mass", 0.3, 0.1, 1.0),
        MassVariable("Jz_tip", 0, "inertia", 4e-4, 3e-4, 4.5e-4, axis="z"),
        MaterialVariable("E_alu", "alu", "E", 70e9, 50e9, 90e9),  # G = E / 2(1 + ν) follows
        MaterialVariable("E_steel", "steel", "E", 200e9, 150e9, 250e9),
        MaterialVariable("rho_steel", "steel", "density", 7800.0, 7000.0, 9000.0),
    )


RESPONSES = ("mass", "frequency_hz_1", "frequency_hz_3", "separation_hz_1_2", "separation_hz_2_4")


def central_gradients(problem: StructureProblem, x: np.ndarray) -> dict[str, np.ndarray]:
    """The five-point central difference of every response (module notes), by name."""
    names = list(problem.responses(x))
    out = {name: np.zeros(x.size) for name in names}
    for k in range(x.size):
        h = REL_STEP * abs(x[k])
        values = []
        for step in (2 * h, h, -h, -2 * h):
            y = x.copy()
            y[k] += step
            r = problem.responses(y)
            values.append(np.array([r[name][0] for name in names]))
        d = (-values[0] + 8 * values[1] - 8 * values[2] + values[3]) / (12 * h)
        for i, name in enumerate(names):
            out[name][k] = d[i]
    return out


@pytest.mark.parametrize("free", [False, True], ids=["clamped", "free-free"])
def test_every_response_and_variable_kind_matches_central_differences(free):
    problem = StructureProblem(mixed(free), SHAPES, every_variable(), RESPONSES)
    x = problem.x0 * np.linspace(1.0, 1.05, problem.x0.size)  # off the model's own values
    got = problem.responses(x)
    assert set(got) == {
        "mass",
        "frequency_hz_1",
        "frequency_hz_2",
        "frequency_hz_3",
        "frequency_hz_4",
        "separation_hz_1_2",
        "separation_hz_2_4",
    }
    differences = central_gradients(problem, x)
    for name, (value, gradient) in got.items():
        fd = differences[name]
        kind, pair = parse_response(name)
        if kind == "separation_hz":  # a difference: its round-off is that of f_i and f_j
            value = sum(got[f"frequency_hz_{k}"][0] for k in pair)
        scale = np.maximum(np.abs(fd), abs(value) / np.abs(x))
        err = np.abs(gradient - fd) / scale
        assert err.max() <= ACCEPT, (name, dict(zip(problem.names, err)))


def test_frequencies_are_the_elastic_modes_of_the_model_at_the_design():
    """frequency_hz_k of a free structure is its (6 + k)-th mode: the six rigid-body modes are
    not counted; the mass is the model's structural mass at the design."""
    problem = StructureProblem(mixed(True), SHAPES, every_variable(), RESPONSES)
    x = problem.x0 * 1.02
    structure = problem.structure(x)
    f = structure.assemble().modes(10, rigid_body_modes=6).frequencies_hz
    assert np.all(f[:6] == 0.0)
    got = problem.responses(x)
    for k in (1, 2, 3, 4):
        assert got[f"frequency_hz_{k}"][0] == pytest.approx(f[5 + k], rel=1e-10)
    assert got["separation_hz_2_4"][0] == pytest.approx(f[9] - f[7], rel=1e-10)
    assert got["mass"][0] == pytest.approx(structure.structural_mass(), rel=1e-14)
    # the design entered the model: the tube's wall and the tip mass as the vector says
    desc = problem.description_at(x)
    t = dict(zip(problem.names, x))["t"]
    assert desc.sections["tube"] == Section.tube(x[0], t)
    assert desc.masses[0].mass == dict(zip(problem.names, x))["m_tip"]


def _plate_boom(width: float, height: float) -> FEDescription:
    """A clamped rectangular boom: bending in y (Iz ∝ b³h) and in z (Iy ∝ bh³)."""
    nodes = [NodeSpec(i, (0.5 * i, 0.0, 0.0)) for i in range(5)]
    elements = [ElementSpec("frame", (i, i + 1), "alu", "r", (0, 0, 1)) for i in range(4)]
    return FEDescription(
        nodes,
        {"alu": ALU},
        {"r": Section.rectangle(width, height)},
        elements,
        masses=[MassSpec(4, 0.5)],
        clamps=[ClampSpec(0)],
        n_modes=4,
    )


def test_modes_are_numbered_by_order_and_a_swap_is_reported_by_mac():
    """Widening the section past its height swaps the two bending modes: mode 1 of the new
    design is the start's mode 2 (MAC ≈ 1), and its frequency is still the lowest one."""
    shapes = {"r": SectionShape("rectangle", {"width": 0.03, "height": 0.02})}
    width = SectionVariable("b", "r", "width", 0.015, 0.005, 0.05)
    problem = StructureProblem(
        _plate_boom(0.03, 0.02), shapes, (width,), ("frequency_hz_1", "frequency_hz_2")
    )
    same = problem.report_metrics(np.array([0.016]))
    assert same["mode_1_is_start_mode"] == 1 and same["mode_1_mac"] > 0.999
    swapped = problem.report_metrics(np.array([0.03]))
    assert swapped["mode_1_is_start_mode"] == 2 and swapped["mode_1_mac"] > 0.999
    assert swapped["mode_2_is_start_mode"] == 1 and swapped["mode_2_mac"] > 0.999
    r = problem.responses(np.array([0.03]))
    assert r["frequency_hz_1"][0] < r["frequency_hz_2"][0]


def test_a_design_at_a_crossing_is_refused_naming_the_modes():
    """A square section: the two bending frequencies coincide, the k-th frequency has no
    derivative there."""
    shapes = {"r": SectionShape("rectangle", {"width": 0.03, "height": 0.02})}
    width = SectionVariable("b", "r", "width", 0.015, 0.005, 0.05)
    problem = StructureProblem(_plate_boom(0.03, 0.02), shapes, (width,), ("frequency_hz_1",))
    with pytest.raises(FieldError, match="elastic modes 1 and 2 coincide") as info:
        problem.responses(np.array([0.02]))
    assert info.value.field == "model" and "separation_hz_1_2" in info.value.rule


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (
            {"variables": (SectionVariable("t", "tube", "thickness", 0.002, 0.001, 0.03),)},
            "variables.t.upper",
        ),
        (
            {"variables": (SectionVariable("D", "tube", "outer_diameter", 0.04, 0.003, 0.08),)},
            "variables.D.lower",
        ),
        (
            {"variables": (SectionVariable("x", "nope", "width", 1.0, 0.5, 2.0),)},
            "variables.x.section",
        ),
        (
            {"variables": (SectionVariable("x", "rect", "thickness", 1.0, 0.5, 2.0),)},
            "variables.x.property",
        ),
        (
            {"variables": (SectionVariable("x", "rect", "width", 0.1, 0.5, 2.0),)},
            "variables.x.start",
        ),
        (
            {"variables": (MassVariable("J", 0, "inertia", 4e-4, 1e-4, 1e-2, axis="z"),)},
            "variables.J.lower",
        ),
        ({"variables": (MassVariable("m", 7, "mass", 1.0, 0.5, 2.0),)}, "variables.m.mass"),
        (
            {"variables": (MaterialVariable("E", "ti", "E", 1e11, 5e10, 2e11),)},
            "variables.E.material",
        ),
        (
            {"variables": (MaterialVariable("E", "alu", "G", 1e11, 5e10, 2e11),)},
            "variables.E.property",
        ),
        ({"variables": (MassVariable("m", 0, "inertia", 1.0, 0.5, 2.0),)}, "variables.m.axis"),
        ({"responses_named": ("frequency_hz_7",)}, "frequency_hz_7"),
        ({"responses_named": ("frequency",)}, "response"),
    ],
    ids=[
        "wall-over-half",
        "diameter-under-wall",
        "section",
        "property",
        "start",
        "inertia-triangle",
        "mass-index",
        "material",
        "material-property",
        "inertia-axis",
        "mode-beyond",
        "name",
    ],
)
def test_bad_variables_and_responses_are_refused_by_name(change, field):
    options = {"variables": every_variable()[:2], "responses_named": ("mass",), **change}
    with pytest.raises(FieldError) as info:
        StructureProblem(mixed(), SHAPES, options["variables"], options["responses_named"])
    assert info.value.field == field


def test_response_names():
    assert parse_response("mass") == ("mass", ())
    assert parse_response("frequency_hz_12") == ("frequency_hz", (12,))
    assert parse_response("separation_hz_1_3") == ("separation_hz", (1, 3))
    for bad in ("frequency_hz_0", "separation_hz_2_2", "separation_hz_3_1", "f1", 3):
        with pytest.raises(FieldError):
            parse_response(bad)  # type: ignore[arg-type]


def test_the_problem_solves_to_a_kkt_point_through_the_api():
    """Minimum mass of the rectangular boom with a 3 Hz floor on its first frequency over
    (width, height): SLSQP from the model's values, KKT residual <= 1e-6, floor active."""
    from flexsat.design.optimize import optimize_design

    shapes = {"r": SectionShape("rectangle", {"width": 0.03, "height": 0.02})}
    variables = (
        SectionVariable("b", "r", "width", 0.03, 0.005, 0.05),
        SectionVariable("h", "r", "height", 0.02, 0.005, 0.05),
    )
    problem = StructureProblem(
        _plate_boom(0.03, 0.02), shapes, variables, ("mass", "frequency_hz_1", "separation_hz_1_2")
    )
    design = problem.problem(
        "mass", [("frequency_hz_1", 3.0, None), ("separation_hz_1_2", 0.5, None)]
    )
    result = optimize_design(design, "slsqp")
    assert result.kkt.residual <= 1e-6
    r = problem.responses(result.x)
    assert r["frequency_hz_1"][0] == pytest.approx(3.0, rel=1e-8)
    assert r["separation_hz_1_2"][0] == pytest.approx(0.5, rel=1e-6)


def test_describe_lists_the_models_elastic_frequencies_and_mass():
    from flexsat.design.describe import describe_design

    problem = StructureProblem(mixed(True), SHAPES, every_variable(), RESPONSES)
    x = problem.x0 * 1.01
    features = describe_design(problem, x)
    f = features["elastic frequencies"].values
    assert f.size == 6 and np.all(np.diff(f) > 0)
    got = problem.responses(x)
    for k in (1, 2, 3, 4):
        assert f[k - 1] == pytest.approx(got[f"frequency_hz_{k}"][0], rel=1e-10)
    assert features["structural mass"].values[0] == pytest.approx(got["mass"][0], rel=1e-14)
