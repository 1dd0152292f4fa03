"""Report of ``kind: design`` (flexsat.report.design_problem; named ``..._report`` beside
tests/scenarios/test_design_problem.py, as pytest needs distinct basenames): the history is
the optimiser's own path ending at the reported optimum, the active-set table is exactly the KKT
report's with its multipliers (checked against the sensitivity of the optimum to the bound),
the starting and final designs' modes, gains and poles equal an independent computation, and
the page holds its sections and opens offline as one file."""

from __future__ import annotations

import dataclasses
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import xarray as xr
import yaml

from design_documents import HUB_BOOM
from flexsat.cases.tamu_codesign import TamuCodesign
from flexsat.design.describe import sorted_poles
from flexsat.design.reference_problems import CantileverTube, HubBoomCodesign
from flexsat.report.design_problem import VIOLATION_FLOOR, active_rows, plots
from flexsat.report.page import write_report
from flexsat.scenarios.documents import load_scenario
from flexsat.scenarios.runner import run_scenario
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

DOC = {
    **HUB_BOOM,
    "pareto": {"secondary": "mass", "points": 3, "starts": 1, "store": "front.zarr"},
}


def _run(doc: dict, folder: Path):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "design.yaml"
    path.write_text(yaml.safe_dump(doc))
    return run_scenario(load_scenario(path))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("design")
    result = _run(DOC, folder)
    return result, write_report(result, folder / "report")


def _strict_json(text: str):
    def refuse(token):
        raise ValueError(f"non-JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_the_history_is_the_optimisers_path_and_ends_at_the_optimum(written):
    result, out = written
    problem = result.configured.problem()
    records = {r["run"]: r for r in _strict_json((out / "metrics.json").read_text())}
    ds = xr.open_dataset(out / "results.nc")
    x0 = problem.x0
    for r in result.optima:
        h = r.history
        assert [e.iteration for e in h] == list(range(len(h)))
        np.testing.assert_array_equal(h[0].x, x0)  # every optimiser starts at the start
        np.testing.assert_array_equal(h[-1].x, r.x)  # and ends at the reported optimum
        assert h[-1].objective == r.objective
        for e in h:
            # each entry is the problem evaluated at its design (the same deterministic
            # function of the same bits, so equal exactly), its violation recomputed here
            ev = problem.evaluate(e.x)
            assert e.objective == ev.objective
            g = ev.constraints / problem.constraint_scale
            bounds = np.concatenate([problem.lower - e.x, e.x - problem.upper]) / np.tile(
                problem.scale, 2
            )
            expected = max(0.0, g.max(initial=0.0), bounds.max())
            assert e.max_violation == pytest.approx(expected, rel=1e-12, abs=1e-15)
        stored = records[f"optimum ({r.method})"]["history"]
        assert stored["objective"] == [e.objective for e in h]
        assert stored["max_violation"] == [e.max_violation for e in h]
        assert stored["x"]["D"] == [float(e.x[1]) for e in h]
        scaled = r.objective / problem.objective.scale
        assert stored["scaled_objective"][-1] == pytest.approx(scaled, rel=1e-15)
        row = ds["history_objective"].sel(run=f"optimum ({r.method})").values
        np.testing.assert_array_equal(row[: len(h)], stored["objective"])
        assert np.isnan(row[len(h) :]).all()
        assert int(ds["history_length"].sel(run=f"optimum ({r.method})")) == len(h)
    assert records["start"]["x_t"] == x0[0] and records["start"]["x_D"] == x0[1]


def test_the_history_figures_draw_each_optimisers_path(written):
    result, _ = written
    objective, violation, design = plots(result)
    problem = result.configured.problem()
    for curve, r in zip(objective.curves, result.optima):
        assert curve.run == f"optimum ({r.method})"
        np.testing.assert_allclose(
            curve.y, [e.objective / problem.objective.scale for e in r.history], rtol=1e-15
        )
    assert violation.log_y and min(c.y.min() for c in violation.curves) >= VIOLATION_FLOOR
    # the wall ends on its lower bound: 0 on the normalised axis, to within the KKT check's
    # activity threshold (1e-6 · scale = 1e-9 m, over the 2.5 mm range: 4e-7)
    wall = [c for c in design.curves if c.label.startswith("t (")]
    lo, hi = problem.lower[0], problem.upper[0]
    for curve, r in zip(wall, result.optima):
        assert curve.y[-1] == (r.x[0] - lo) / (hi - lo)
        assert 0 <= curve.y[-1] <= 1e-9 / (hi - lo)


class _Tables(HTMLParser):
    """Every <table> of a page as a list of rows of cell texts."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[list[list[str]]] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _tables(out: Path) -> list[list[list[str]]]:
    parser = _Tables()
    parser.feed((out / "index.html").read_text())
    return parser.tables


def test_the_active_set_table_is_the_kkt_reports_active_set_with_its_multipliers(written):
    result, out = written
    (table,) = [t for t in _tables(out) if t[0][:2] == ["optimiser", "active"]]
    shown = {(row[0], row[1]): float(row[4]) for row in table[1:]}
    expected = {
        (f"optimum ({r.method})", name): r.kkt.multipliers[name]
        for r in result.optima
        for name in r.kkt.active
    }
    assert shown.keys() == expected.keys()
    for key, value in shown.items():
        assert value == pytest.approx(expected[key], rel=1e-5)  # 6 significant digits shown
        assert value >= 0  # minimisation convention
    assert ("optimum (slsqp)", "mass <= 0.3") in shown
    (kkt,) = [t for t in _tables(out) if t[0][:2] == ["optimiser", "KKT residual"]]
    for row, r in zip(kkt[1:], result.optima):
        assert float(row[1]) == pytest.approx(r.kkt.residual, rel=1e-5)
        assert float(row[4]) == pytest.approx(r.kkt.dual, rel=1e-5, abs=1e-300)


def test_the_mass_multiplier_is_the_optimums_sensitivity_to_the_mass_cap(written, tmp_path):
    """λ of "mass <= ε" = −df*/dε (the sensitivity theorem, Nocedal & Wright 2006 §12.8),
    checked by a central difference of two optima at ε ± 0.1 g. The truncation is O(h²): the
    relative difference measured 9.3e-4 at ± 1 g and 9.3e-6 at ± 0.1 g; the optima's own error
    (~1e-12 of f* over a difference of 2e-4 of it) is far below, so 1e-4 holds."""
    result, _ = written
    (slsqp, *_) = result.optima
    (row,) = [r for r in active_rows(result.configured.problem(), slsqp) if r[1] == "mass <= 0.3"]
    lam = float(row[4])
    f = {}
    for cap in ("299.9", "300.1"):
        doc = dict(DOC, optimizer={"method": "slsqp"}, pareto=None)
        doc["constraints"] = [DOC["constraints"][0], {"response": "mass", "max": f"{cap} g"}]
        doc = {k: v for k, v in doc.items() if v is not None}
        f[cap] = _run(doc, tmp_path / str(cap)).optima[0].objective
    assert lam == pytest.approx(-(f["300.1"] - f["299.9"]) / 0.2e-3, rel=1e-4)


def _hub_modal_plant(problem: HubBoomCodesign, t: float, D: float):
    """The hub-boom modal plant built here from scipy's dense eigen-solution of the FE
    matrices (its own normalisation and signs): A, B, Q and the initial state."""
    asm = problem.structure(t, D).assemble()
    K, M = asm.K.toarray(), asm.M.toarray()
    w2, V = sla.eigh(K, M)  # mass-normalised; the pinned half-model has one rigid mode
    n = problem.elastic_modes + 1
    omega = np.sqrt(np.clip(w2[:n], 0.0, None))
    omega[0] = 0.0
    phi = V[:, :n]
    hub, tip = asm.index(0, "rz"), asm.index(problem.elements, "uy")
    zeta = np.full(n, problem.damping)
    zeta[0] = 0.0
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(omega**2), -np.diag(2 * zeta * omega)]])
    B = np.concatenate([np.zeros(n), phi[hub]])[:, None]
    z = np.zeros(n)
    C = np.array(
        [
            np.concatenate([phi[hub], z]),
            np.concatenate([z, phi[hub]]),
            np.concatenate([phi[tip] - problem.length * phi[hub], z]),
        ]
    )
    Q = C.T @ np.diag(problem.weights) @ C
    # the rigid mode's coordinate for a hub angle θ0 with the boom undeformed: η0 = θ0 / φ0[hub]
    x0 = np.zeros(2 * n)
    x0[0] = problem.initial_angle / phi[hub, 0]
    return omega, A, B, Q, x0


@pytest.mark.numerics
def test_the_hub_boom_start_and_final_designs_equal_an_independent_computation(written):
    """Frequencies from scipy's dense eigh of the FE matrices, the LQ gain and poles from
    scipy's CARE on a plant built here. The two computations differ by round-off only: over four
    designs across the bounds the frequencies agreed to 6e-11, the poles to 3e-12 of the
    largest, the gain's magnitudes (signs follow the eigenvectors') to 3.5e-10 and the cost
    J = x0ᵀ P x0 to 3.7e-10 (the Riccati solutions' own error); the tolerances leave 15-30×."""
    result, _ = written
    problem = result.configured.reference
    assert isinstance(problem, HubBoomCodesign)
    from flexsat.report.design_problem import described

    features = described(result)
    points = {"start": result.optima[0].history[0].x}
    points.update({f"optimum ({r.method})": r.x for r in result.optima})
    for label, x in points.items():
        f = features[label]
        omega, A, B, Q, x0 = _hub_modal_plant(problem, *x)
        np.testing.assert_allclose(
            f["elastic frequencies"].values, omega[1:] / (2 * np.pi), rtol=1e-9
        )
        R = np.array([[problem.control_weight]])
        P = sla.solve_continuous_are(A, B, Q, R)
        K = np.linalg.solve(R, B.T @ P)
        poles = sorted_poles(np.linalg.eigvals(A - B @ K))
        shown = f["closed-loop poles"].values
        np.testing.assert_allclose(shown, poles, rtol=0, atol=1e-10 * np.abs(poles).max())
        np.testing.assert_allclose(np.abs(f["LQ gain"].values), np.abs(K[0]), rtol=1e-8)
        cost = problem.responses(np.asarray(x))["lq_cost"][0]
        assert x0 @ P @ x0 == pytest.approx(cost, rel=1e-8)
    # the report shows them: the first elastic frequency is the frequency_hz response
    final = result.optima[0]
    assert features[f"optimum ({final.method})"]["elastic frequencies"].values[0] == (
        pytest.approx(result.configured.responses(final.x)["frequency_hz"][0], rel=1e-12)
    )


def test_the_tube_frequency_equals_a_converged_fe_model():
    """The closed-form Euler–Bernoulli ω₁ against 40 planar beam elements: the FE error falls
    as h⁴ (measured 8.6e-7, 5.4e-8, 3.5e-9 at 10, 20, 40 elements), so 1e-8 holds."""
    tube = CantileverTube()
    t, D = 2e-3, 40e-3
    n = 40
    s = Structure("tube")
    for i in range(n + 1):
        s.add_node(i, (tube.length * i / n, 0.0, 0.0))
    for i in range(n):
        s.add_beam2d(i, i + 1, Material(tube.youngs_modulus, tube.density), Section.tube(D, t))
    s.clamp(0)
    fe = s.assemble().modes(1).frequencies_hz[0]
    shown = tube.describe(np.array([t, D]))["first bending frequency"].values[0]
    assert shown == pytest.approx(fe, rel=1e-8)


def test_the_tamu_appendage_frequencies_equal_an_fe_model_and_the_gains_are_the_design():
    """Law II's gains and α are the design's own; the appendage frequencies (transcendental
    clamped-beam-with-tip-mass equation) against 120 planar beam elements with the tip mass and
    its rotary inertia: the FE error falls as h⁴ (mode 3: 2.1e-6, 1.3e-7, 8.4e-9 at 30, 60,
    120 elements), so 2e-8 holds."""
    problem = TamuCodesign()
    x = np.array([1.3, 20.0, 6.0, 0.15])
    f = problem.describe(x)
    assert f["g1"].values[0] == x[1] and f["g2"].values[0] == x[2]
    assert f["alpha"].values[0] == x[3]
    p = problem.case.params
    st = problem.structure(np.array([x[0]]))
    n = 120
    s = Structure("appendage")
    for i in range(n + 1):
        s.add_node(i, (p.length * i / n, 0.0, 0.0))
    strip = Material(float(st["EI"][0]), float(st["rho"][0]))  # E·I = EI, ρ·A = line density
    for i in range(n):
        s.add_beam2d(i, i + 1, strip, Section.general(1.0, 1.0, 1.0, 1.0))
    s.add_mass(n, float(st["tip_mass"][0]), inertia=(0.0, 0.0, float(p.tip_inertia)))
    s.clamp(0)
    for i in range(1, n + 1):  # bending only: E·A = EI here, so the axial modes are spurious
        s.clamp(i, ("ux",))
    s.clamp(n, ("uz", "rx", "ry"))  # the tip inertia activates rotations out of the plane
    fe = s.assemble().modes(3).frequencies_hz
    np.testing.assert_allclose(f["appendage frequencies"].values, fe, rtol=2e-8)
    total = st["rho"][0] * p.length + st["tip_mass"][0]
    assert total == pytest.approx(problem.appendage_mass, rel=1e-14)


def test_the_tamu_law_ii_poles_equal_an_fe_hub_with_its_appendage(monkeypatch):
    """Law II's closed-loop poles (hybrid-coordinate model, 10 cantilever modes) against a
    planar FE half-model: the hub's share of the inertia on a pinned node, a rigid link to the
    appendage root at the hub radius, 80 beam elements and the tip mass, the law's share
    g/n of the feedback on the hub rotation, poles of the pencil (A, E) by QZ (no inverse of
    the nearly singular FE mass). Both undamped (the FE model has no modal damping). The
    lowest three pole pairs differ by 4e-7, 7e-8, 6e-7 at 80 elements, as at 40: the assumed
    modes' truncation, not the FE's; 2e-6 holds."""
    from flexsat.cases.tamu import tamu

    problem = TamuCodesign()
    monkeypatch.setattr(problem, "_case", tamu(n_modes=10, damping=0.0))
    x = np.array([1.3, 20.0, 6.0, 0.15])
    shown = problem.describe(x)["closed-loop poles"].values
    p = problem.case.params
    st = problem.structure(np.array([x[0]]))
    n, share = 80, p.n_appendages
    s = Structure("hub with one appendage")
    s.add_node(0, (0.0, 0.0, 0.0))
    for i in range(n + 1):
        s.add_node(i + 1, (p.hub_radius + p.length * i / n, 0.0, 0.0))
    strip = Material(float(st["EI"][0]), float(st["rho"][0]))
    for i in range(n):
        s.add_beam2d(i + 1, i + 2, strip, Section.general(1.0, 1.0, 1.0, 1.0))
    s.add_mass(0, 0.0, inertia=(0.0, 0.0, p.hub_inertia / share))
    s.add_mass(n + 1, float(st["tip_mass"][0]))
    s.add_rigid_link(0, [1])
    for i in [0, *range(2, n + 2)]:
        s.clamp(i, ("ux",))
    s.clamp(0, ("uy", "uz", "rx", "ry"))
    asm = s.assemble()
    M, K = asm.M.toarray(), asm.K.toarray()
    e = np.zeros(M.shape[0])
    e[asm.index(0, "rz")] = 1.0
    N = M.shape[0]
    A = np.block(
        [
            [np.zeros((N, N)), np.eye(N)],
            [-(K + x[1] / share * np.outer(e, e)), -x[2] / share * np.outer(e, e)],
        ]
    )
    E = np.block([[np.eye(N), np.zeros((N, N))], [np.zeros((N, N)), M]])
    fe = sla.eigvals(A, E)
    # the tip mass's out-of-plane translation is a free, decoupled dof: its poles are 0
    fe = fe[np.isfinite(fe) & (np.abs(fe) > 1e-6) & (fe.imag > 0)]
    fe = fe[np.argsort(fe.imag)][:3]
    upper = shown[shown.imag > 0]
    upper = upper[np.argsort(upper.imag)][:3]
    np.testing.assert_allclose(upper, fe, rtol=2e-6)
    assert np.all(shown.real < 0)  # Law II stabilises the linear model


def test_the_page_holds_every_section(written):
    result, out = written
    page = (out / "index.html").read_text()
    for heading in (
        "Optimum",
        "Active set and KKT residuals",
        "Starting design beside the final design",
        "Structure",
        "Controller",
        "Pareto front",
        "Figures",
    ):
        assert re.search(f"<h[23]>{re.escape(heading)}", page), heading
    for title in ("Objective along the iterations", "Design variables along the iterations"):
        assert title in page
    assert 'src="data:image/png;base64,' in page  # the front, embedded
    (comparison,) = [t for t in _tables(out) if t[0] == ["", "unit", "start", *_labels(result)]][:1]
    assert comparison[1][0] == "variable t"


def _labels(result):
    return [f"optimum ({r.method})" for r in result.optima]


def test_a_problem_that_does_not_describe_its_designs_says_so(tmp_path):
    class Plain:  # the protocol's two methods only
        def __init__(self, inner):
            self.inner = inner

        def responses(self, x):
            return self.inner.responses(x)

        def problem(self):
            return self.inner.problem()

    doc = {
        "kind": "design",
        "name": "tube",
        "problem": "cantilever_tube",
        "objective": "mass",
        "constraints": [{"response": "omega", "min": "20 Hz"}],
    }
    result = _run(doc, tmp_path)
    plain_reference = Plain(result.configured.reference)
    configured = dataclasses.replace(result.configured, reference=plain_reference)
    plain = dataclasses.replace(result, configured=configured)
    out = write_report(plain, tmp_path / "report")
    assert "does not describe its designs" in (out / "index.html").read_text()
    records = _strict_json((out / "metrics.json").read_text())
    assert records[0]["described"] == {} and records[0]["history"]["iteration"][0] == 0
    # with describe, the tube's frequency is beside the start
    page = (write_report(result, tmp_path / "with") / "index.html").read_text()
    assert "first bending frequency" in page


def test_the_report_opens_offline_alone(written, tmp_path, browser):
    from report_browser import open_offline

    _, out = written
    page, refused, text = open_offline(browser, out / "index.html", tmp_path / "alone")
    try:
        assert refused == []
        assert "Starting design beside the final design" in text
        assert page.locator("canvas").count() >= 3  # the three history figures
    finally:
        page.context.close()
