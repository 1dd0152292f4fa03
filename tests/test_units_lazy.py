"""Units at the boundary only: below ``cases`` and ``scenarios`` the layers take SI numbers.

The layers below the boundary import no pint themselves (read with :mod:`ast`, nothing is
imported), and a run fed SI numbers never loads it (checked in a fresh interpreter, where no
other test has loaded pint already): :mod:`flexsat.units` imports pint only when a Quantity or
a unit string is actually given. Every unit a call site declares is a coherent SI unit, so the
plain number it passes through unconverted is in that unit.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from flexsat.units import Q_, si_factor

SRC = Path(__file__).resolve().parents[1] / "src" / "flexsat"
BELOW_BOUNDARY = (
    "structures",
    "analysis",
    "dynamics",
    "maneuvers",
    "control",
    "identify",
    "attitude",
    "sim",
    "design",
)
#: calls that take a field's unit, and the position of the unit among their arguments
UNIT_ARGUMENT = {
    "to_si": 1,
    "to_si_array": 1,
    "set_si": 3,
    "require_finite": 2,
    "require_positive": 2,
    "require_positive_scalar": 2,
    "require_nonneg": 2,
}


def _pint_imports(path: Path) -> list[int]:
    lines = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [node.module or ""]
        else:
            continue
        if any(name == "pint" or name.startswith("pint.") for name in names):
            lines.append(node.lineno)
    return lines


@pytest.mark.parametrize("package", BELOW_BOUNDARY)
def test_layers_below_the_boundary_do_not_import_pint(package):
    found = {
        f"{path.relative_to(SRC)}:{line}"
        for path in (SRC / package).rglob("*.py")
        for line in _pint_imports(path)
    }
    assert not found, f"pint imported below the boundary at {sorted(found)}"


def test_an_si_only_run_never_loads_pint():
    """Import every module of every layer below the boundary, build a hub + appendage plant
    and a PD law from SI floats and simulate: flexsat never imports pint nor builds its unit
    registry. (xarray, when pint is installed, imports it itself to recognise pint arrays as it
    builds the result Dataset: the importer of record is reported and must be xarray's, never
    a flexsat module.) The same script given one unit string loads pint from flexsat.units,
    so the check can fail.
    """
    script = textwrap.dedent(
        """
        import sys, traceback

        importer = []

        class Watch:
            def find_spec(self, name, path=None, target=None):
                if name == "pint" and not importer:
                    frames = traceback.extract_stack()[:-1]
                    outside = [f for f in frames if "importlib" not in f.filename]
                    importer.append(outside[-1].filename)
                return None

        sys.meta_path.insert(0, Watch())
        import importlib, pkgutil
        import numpy as np
        from flexsat import units

        for name in sys.argv[2:]:  # every module of every layer below the boundary
            package = importlib.import_module(f"flexsat.{name}")
            for info in pkgutil.walk_packages(package.__path__, f"flexsat.{name}."):
                importlib.import_module(info.name)
        from flexsat.control.pd import PD
        from flexsat.dynamics.hub_appendage import HubAppendage, HubAppendageParams
        from flexsat.sim.engine import SimConfig, simulate

        length = sys.argv[1] if sys.argv[1] != "si" else 1.0
        params = HubAppendageParams(0.35, 2, 0.1, length, 20.0, 1.2, damping=0.01)
        result = simulate(
            HubAppendage(params, n_modes=3), PD(1.0, 1.0, target=0.1), SimConfig(duration=1.0)
        )
        assert np.isfinite(result.dataset.theta.values).all()
        print(units._registry.cache_info().currsize, importer[0] if importer else "none")
        """
    )

    def run(length: str) -> tuple[str, str]:
        done = subprocess.run(
            [sys.executable, "-c", script, length, *BELOW_BOUNDARY],
            capture_output=True,
            text=True,
            check=False,
            env={"PYTHONPATH": str(SRC.parent), "OMP_NUM_THREADS": "1", "PATH": ""},
        )
        assert done.returncode == 0, done.stderr
        registries, importer = done.stdout.split()
        return registries, importer

    registries, importer = run("si")
    assert registries == "0"
    assert importer == "none" or f"{Path('xarray', '')}" in importer, importer
    assert "flexsat" not in importer
    registries, importer = run("100 cm")
    assert registries == "1"
    assert importer.endswith(str(Path("flexsat", "units.py")))


def _declared_units() -> dict[str, list[str]]:
    """Every literal unit string a conversion or check call declares, with where."""
    found: dict[str, list[str]] = {}
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Call):
                continue
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if name not in UNIT_ARGUMENT:
                continue
            position = UNIT_ARGUMENT[name]
            unit = node.args[position] if len(node.args) > position else None
            unit = next((k.value for k in node.keywords if k.arg == "unit"), unit)
            if isinstance(unit, ast.Constant) and isinstance(unit.value, str):
                where = f"{path.relative_to(SRC)}:{node.lineno}"
                found.setdefault(unit.value, []).append(where)
    return found


def test_every_declared_unit_is_coherent_si():
    """A plain number passes the boundary unconverted, so a declared unit must be SI (factor 1):
    a field declared in ``"deg"`` would take 40 as 40 rad."""
    declared = _declared_units()
    assert {"s", "rad", "N*m", "kg*m**2", "rad/s", "Hz"} <= set(declared)  # the scan reads
    wrong = {u: where for u, where in declared.items() if si_factor(u) != 1.0}
    assert not wrong, f"units that are not coherent SI: {wrong}"
    assert si_factor("deg") != 1.0 and Q_(1, "kHz").to_base_units().magnitude == 1000.0


def _count_parses(monkeypatch) -> list[tuple[str, str]]:
    """(field, text) of every value that goes through pint's parser from now on."""
    from flexsat import units

    fields: list[tuple[str, str]] = []
    parse = units.parse_quantity

    def counting(text, field="value"):
        fields.append((field, text))
        return parse(text, field)

    monkeypatch.setattr(units, "parse_quantity", counting)
    return fields


def _forbid_registry(monkeypatch) -> None:
    """From now on, any use of pint by flexsat.units fails the test."""
    from flexsat import units

    def refuse():
        raise AssertionError("a plain SI number reached the unit registry")

    monkeypatch.setattr(units, "_registry", refuse)


def test_a_number_from_a_case_file_is_converted_once_on_its_way_to_the_kernel(monkeypatch):
    """``hub_inertia`` read as published is converted by the case (cases/inputs.py); the
    dynamics layer (HubAppendageParams) takes the SI float the case hands it and passes it
    through without touching pint (before, it looked its unit up again)."""
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.hub_appendage import HubAppendageParams

    parsed = _count_parses(monkeypatch)
    case = tamu(hub_inertia="30 ozf*in*s**2")
    # (the builder also reads the published default once, for its reference inertia)
    assert parsed.count(("hub_inertia", "30 ozf*in*s**2")) == 1
    expected = 30 * 0.028349523125 * 9.80665 * 0.0254  # ozf·in·s² in kg·m²: all exact factors
    assert case.hub_inertia == pytest.approx(expected, rel=1e-15)
    _forbid_registry(monkeypatch)
    params = case.params
    assert isinstance(params, HubAppendageParams) and params.hub_inertia == case.hub_inertia


def test_a_duration_from_a_scenario_is_converted_once_on_its_way_to_the_engine(monkeypatch):
    """``duration: "15 s"`` is converted by the scenario field; SimConfig takes the float."""
    from flexsat.scenarios.maneuver import SimulationSpec

    parsed = _count_parses(monkeypatch)
    spec = SimulationSpec(duration="1.5 min", control_rate="75 Hz", settling_band="0.5 deg")
    assert parsed.count(("duration", "1.5 min")) == 1 and spec.duration == 90.0
    _forbid_registry(monkeypatch)
    config = spec.build()
    assert config.duration == 90.0 and config.control_rate == 75.0
