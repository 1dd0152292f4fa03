"""Dependencies point one way: no module imports a layer above its own.

Every module under ``src/flexsat`` is parsed with :mod:`ast` (nothing is imported), and every
``import`` / ``from ... import`` in it -- at module level or inside a function, absolute or
relative -- and every ``importlib.import_module("flexsat....")`` with a literal name is checked
against this table. A *unit* is a sub-package (``structures``) or a top-level module
(``units``); a unit may import units of its own layer or of a lower one, never of a higher one.

=====  ===========================================  ========================================
layer  units                                        what they are
=====  ===========================================  ========================================
0      flexsat (the package root), units,           helpers: SI conversion, input checks,
       input_checks, limits, lazy, text,            resource limits, lazy exports, display
       references, netcdf, plugins, file_locks      text, the bibliography, netCDF writing,
                                                    entry-point plug-ins, file locks
1      structures                                   FE models, modal models, their files
2      analysis                                     Gramians, controllability, placement
3      dynamics                                     plants built from structural models
4      maneuvers, control, identify, attitude       torque shapes, control laws,
                                                    system identification, star trackers
5      sim                                          the simulation engine
6      design, testing                              sweeps, Monte Carlo, optimisation;
                                                    conformance checks of plants and laws
7      cases, catalog                               the published benchmark systems
8      report, mode_plot                            report writer, figures, plots
9      scenarios                                    scenario kinds: a case, a plant, a law
10     checks                                       ``flexsat validate``: results vs papers
11     cli                                          the command line
12     __main__                                     ``python -m flexsat``
=====  ===========================================  ========================================

In particular nothing below ``cases`` imports ``cases``, ``catalog``, ``scenarios``,
``report``, ``checks`` or ``cli``. Units of one layer may import each other; the unit graph
must stay free of cycles. A new sub-package or top-level module must be added to the table
(:data:`LAYERS`), and docs/design.md ("Layers") says the same.

``catalog`` imports the case builders by name on first use (``importlib`` with an f-string
module name, which this test cannot read): that is the catalogue's job, and ``catalog`` sits
in the layer of ``cases``.
"""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "flexsat"

LAYERS = (
    (
        "flexsat",
        "units",
        "input_checks",
        "limits",
        "lazy",
        "text",
        "references",
        "netcdf",
        "plugins",
        "file_locks",
    ),
    ("structures",),
    ("analysis",),
    ("dynamics",),
    ("maneuvers", "control", "identify", "attitude"),
    ("sim",),
    ("design", "testing"),
    ("cases", "catalog"),
    ("report", "mode_plot"),
    ("scenarios",),
    ("checks",),
    ("cli",),
    ("__main__",),
)
RANK = {unit: rank for rank, units in enumerate(LAYERS) for unit in units}
TOP = ("cases", "catalog", "scenarios", "report", "checks", "cli", "__main__")


def module_name(path: Path) -> str:
    """``src/flexsat/a/b.py`` -> ``flexsat.a.b``; a package's ``__init__.py`` -> the package."""
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def unit_of(name: str) -> str:
    """The unit of a dotted name inside the package: ``flexsat.cases.eps`` -> ``cases``;
    ``flexsat.__version__`` (an attribute of the package root) -> ``flexsat``."""
    parts = name.split(".")
    if len(parts) == 1:
        return "flexsat"
    first = parts[1]
    if (SRC / first).is_dir() or (SRC / f"{first}.py").is_file():
        return first
    return "flexsat"


def imported_names(tree: ast.AST, module: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, dotted name) of every flexsat import anywhere in ``tree`` of ``module``."""
    package = module.split(".") if is_package else module.split(".")[:-1]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                stem = ".".join(base + ([node.module] if node.module else []))
            else:
                stem = node.module
            # ``from flexsat import cases`` imports the unit ``cases``: name each alias
            found += [(node.lineno, f"{stem}.{alias.name}") for alias in node.names]
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            found.append((node.lineno, node.args[0].value))
    return [
        (line, name) for line, name in found if name == "flexsat" or name.startswith("flexsat.")
    ]


def imports_of(path: Path) -> list[tuple[int, str]]:
    return imported_names(
        ast.parse(path.read_text(), str(path)), module_name(path), path.name == "__init__.py"
    )


MODULES = sorted(SRC.rglob("*.py"))


def test_every_unit_is_in_the_table():
    units = {unit_of(module_name(p)) for p in MODULES}
    assert units - set(RANK) == set(), "add the new units to LAYERS (and to docs/design.md)"
    assert set(RANK) - units == set(), "LAYERS names units that no longer exist"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC.parent)))
def test_no_module_imports_a_higher_layer(path):
    unit = unit_of(module_name(path))
    upward = [
        f"line {line}: {name} (layer {RANK[unit_of(name)]})"
        for line, name in imports_of(path)
        if RANK[unit_of(name)] > RANK[unit]
    ]
    assert upward == [], (
        f"{module_name(path)} (unit {unit}, layer {RANK[unit]}) imports a "
        f"higher layer: {upward}; move the code up or the dependency down"
    )


def test_nothing_below_cases_imports_the_top():
    """The issue's rule in its own words: checked on the table itself."""
    below = {unit for unit, rank in RANK.items() if rank < RANK["cases"]}
    offenders = [
        (module_name(p), line, name)
        for p in MODULES
        if unit_of(module_name(p)) in below
        for line, name in imports_of(p)
        if unit_of(name) in TOP
    ]
    assert offenders == []
    assert all(RANK[u] >= RANK["cases"] for u in TOP)


def test_the_unit_graph_has_no_cycle():
    graph: dict[str, set[str]] = {unit: set() for unit in RANK}
    for path in MODULES:
        unit = unit_of(module_name(path))
        graph[unit] |= {unit_of(name) for _, name in imports_of(path)} - {unit}
    # depth-first search for a back edge
    state: dict[str, int] = {}

    def visit(unit: str, trail: tuple[str, ...]) -> None:
        state[unit] = 1
        for nxt in sorted(graph[unit]):
            assert state.get(nxt) != 1, f"import cycle: {' -> '.join(trail + (unit, nxt))}"
            if nxt not in state:
                visit(nxt, trail + (unit,))
        state[unit] = 2

    for unit in sorted(graph):
        if unit not in state:
            visit(unit, ())


def test_the_scan_sees_every_kind_of_import():
    """The checks above are only as good as this scan: lazy imports inside functions, relative
    imports, ``from flexsat import X`` and ``importlib.import_module`` are all found."""
    source = textwrap.dedent("""
        import numpy
        from flexsat.units import to_si
        from flexsat import cases
        def f():
            from flexsat.scenarios import load
            import flexsat.report.publish
        class C:
            def g(self):
                from ..checks import core
                from . import beam
                return importlib.import_module("flexsat.cli")
    """)
    found = imported_names(ast.parse(source), "flexsat.structures.fem", is_package=False)
    assert [(line, unit_of(name)) for line, name in found] == [
        (3, "units"),
        (4, "cases"),
        (6, "scenarios"),
        (7, "report"),
        (10, "checks"),
        (11, "structures"),
        (12, "cli"),
    ]
