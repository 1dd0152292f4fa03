"""Public API typed: every public parameter and return annotated (issue 20, deliverable 8).

Every module under ``src/flexsat`` is parsed with :mod:`ast` (nothing is imported). A *public
callable* is a module-level function, or a method of a module-level class, whose name and
whose class's name do not start with an underscore (``__init__``, ``__call__`` and the other
dunders count: they are how a class is used), in a module whose own name does not start with
an underscore. Nested functions are implementation details and are not counted. Each public
callable contributes its parameters (positional, keyword-only, ``*args`` and ``**kwargs``;
the implicit ``self`` / ``cls`` of a method excluded) and its return to the count; a parameter
or return counts as annotated when it carries any annotation.

``python tests/test_annotations.py`` prints the coverage per package (a *package* is a
sub-package such as ``structures``, or ``flexsat`` for the top-level modules), and with
``--missing PACKAGE`` the unannotated slots of that package.

:data:`COMPLETE` lists the packages and modules whose coverage is 100 %; the test fails as
soon as someone adds an unannotated public parameter or return there. Grow the list as
packages are completed; never shrink it.
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "flexsat"

# packages (a directory under src/flexsat) and single modules (a path relative to src/flexsat)
# whose every public parameter and return is annotated
COMPLETE = (
    "analysis",
    "attitude",
    "cases",
    "checks",
    "control",
    "dynamics",
    "identify",
    "maneuvers",
    "scenarios",
    "structures",
    "testing",
    "cases/__init__.py",
    "cases/agrawal_bang.py",
    "cases/agrawal_bang_ppf.py",
    "cases/bainum.py",
    "cases/bainum_control.py",
    "cases/bainum_three_mass.py",
    "cases/beams.py",
    "cases/draper_rpl.py",
    "cases/eps.py",
    "cases/eps_placement.py",
    "cases/identification_campaign.py",
    "cases/inputs.py",
    "cases/nps.py",
    "cases/space_station_cmg.py",
    "cases/structure_plants.py",
    "cases/tamu.py",
    "cases/tamu_grid.py",
    "cases/tamu_trade.py",
    "cases/tether.py",
    "catalog.py",
    "cli.py",
    "design/monte_carlo_statistics.py",
    "design/parameter_space.py",
    "design/slew_shaping.py",
    "design/slew_weights.py",
    "design/trade_surfaces.py",
    "input_checks.py",
    "lazy.py",
    "limits.py",
    "netcdf.py",
    "plugins.py",
    "references.py",
    "report/__init__.py",
    "report/batch.py",
    "report/identification.py",
    "report/maneuver.py",
    "report/page.py",
    "report/ppf.py",
    "report/publish.py",
    "report/simulation.py",
    "report/slew.py",
    "report/star_tracker.py",
    "report/tether.py",
    "scenarios/__init__.py",
    "scenarios/batch.py",
    "scenarios/datasets.py",
    "scenarios/documents.py",
    "scenarios/errors.py",
    "scenarios/fields.py",
    "scenarios/identification.py",
    "scenarios/kind.py",
    "scenarios/laws.py",
    "scenarios/maneuver.py",
    "scenarios/maneuver_kind.py",
    "scenarios/ppf.py",
    "scenarios/registry.py",
    "scenarios/runner.py",
    "scenarios/simulation.py",
    "scenarios/simulation_laws.py",
    "scenarios/simulation_plants.py",
    "scenarios/slew.py",
    "scenarios/star_tracker.py",
    "scenarios/tether.py",
    "sim/__init__.py",
    "sim/actuators.py",
    "sim/channels.py",
    "sim/config.py",
    "sim/continuous.py",
    "sim/disturbances.py",
    "sim/engine.py",
    "sim/instruments.py",
    "sim/integrators.py",
    "sim/metrics.py",
    "sim/open_loop.py",
    "sim/recording.py",
    "sim/sensors.py",
    "sim/slew_goals.py",
    "sim/star_sensor.py",
    "sim/step.py",
    "sim/vibration_test.py",
    "text.py",
    "units.py",
)


@dataclass(frozen=True)
class Slot:
    """One public parameter or return: where it is and whether it is annotated."""

    module: str
    callable: str
    name: str  # the parameter's name, or "return"
    line: int
    annotated: bool


def package_of(path: Path) -> str:
    """``src/flexsat/sim/engine.py`` -> ``sim``; ``src/flexsat/units.py`` -> ``flexsat``."""
    parts = path.relative_to(SRC).parts
    return parts[0] if len(parts) > 1 else "flexsat"


def _function_slots(
    module: str, owner: str, node: ast.FunctionDef | ast.AsyncFunctionDef, is_method: bool
) -> list[Slot]:
    args = node.args
    positional = args.posonlyargs + args.args
    is_static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in node.decorator_list)
    if is_method and not is_static and positional:
        positional = positional[1:]  # self / cls
    params = positional + args.kwonlyargs
    params += [a for a in (args.vararg, args.kwarg) if a is not None]
    name = f"{owner}.{node.name}" if owner else node.name
    slots = [Slot(module, name, p.arg, p.lineno, p.annotation is not None) for p in params]
    slots.append(Slot(module, name, "return", node.lineno, node.returns is not None))
    return slots


def _is_public(name: str) -> bool:
    return not name.startswith("_") or (name.startswith("__") and name.endswith("__"))


def tree_slots(tree: ast.Module, module: str) -> list[Slot]:
    """The public parameter and return slots of one parsed module."""
    slots: list[Slot] = []
    functions = (ast.FunctionDef, ast.AsyncFunctionDef)
    for node in tree.body:
        if isinstance(node, functions) and not node.name.startswith("_"):
            slots += _function_slots(module, "", node, is_method=False)
        elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            for item in node.body:
                if isinstance(item, functions) and _is_public(item.name):
                    slots += _function_slots(module, node.name, item, is_method=True)
    return slots


def public_slots(path: Path) -> list[Slot]:
    """The public parameter and return slots of one module (empty for a private module)."""
    if path.stem.startswith("_") and path.stem != "__init__":
        return []
    return tree_slots(ast.parse(path.read_text(), str(path)), str(path.relative_to(SRC)))


MODULES = sorted(SRC.rglob("*.py"))


def coverage() -> dict[str, tuple[int, int, int, int]]:
    """Per package: (annotated parameters, parameters, annotated returns, returns)."""
    table: dict[str, list[int]] = {}
    for path in MODULES:
        row = table.setdefault(package_of(path), [0, 0, 0, 0])
        for slot in public_slots(path):
            offset = 2 if slot.name == "return" else 0
            row[offset] += slot.annotated
            row[offset + 1] += 1
    return {package: (a, b, c, d) for package, (a, b, c, d) in sorted(table.items())}


def _complete_paths() -> list[Path]:
    paths: list[Path] = []
    for entry in COMPLETE:
        target = SRC / entry
        paths += sorted(target.rglob("*.py")) if target.is_dir() else [target]
    return paths


def test_the_complete_list_names_existing_modules():
    missing = [entry for entry in COMPLETE if not (SRC / entry).exists()]
    assert missing == [], f"COMPLETE names modules that no longer exist: {missing}"


@pytest.mark.parametrize("path", _complete_paths(), ids=lambda p: str(p.relative_to(SRC)))
def test_every_public_parameter_and_return_is_annotated(path):
    unannotated = [
        f"line {s.line}: {s.callable}({s.name})"
        if s.name != "return"
        else f"line {s.line}: {s.callable} -> ?"
        for s in public_slots(path)
        if not s.annotated
    ]
    assert unannotated == [], f"{path.relative_to(SRC)}: annotate {unannotated}"


def test_the_count_sees_what_it_should():
    """The scan is only as good as its rules: ``self`` and nested functions are not counted,
    private names are skipped, static methods keep their first parameter, and ``*args``,
    ``**kwargs``, keyword-only parameters and the return are each one slot."""
    source = (
        "def f(a: int, b, *args, c: float = 1.0, **kw) -> int:\n"
        "    def inner(x): return x\n"
        "    return 0\n"
        "def _private(x): pass\n"
        "class A:\n"
        "    def __init__(self, n: int): pass\n"
        "    def _helper(self, y): pass\n"
        "    @staticmethod\n"
        "    def s(z): pass\n"
        "class _B:\n"
        "    def m(self, q): pass\n"
    )
    found = tree_slots(ast.parse(source), "probe")
    seen = {(s.callable, s.name): s.annotated for s in found}
    assert seen == {
        ("f", "a"): True,
        ("f", "b"): False,
        ("f", "c"): True,
        ("f", "args"): False,
        ("f", "kw"): False,
        ("f", "return"): True,
        ("A.__init__", "n"): True,
        ("A.__init__", "return"): False,
        ("A.s", "z"): False,
        ("A.s", "return"): False,
    }


def main(argv: list[str]) -> None:
    if argv[:1] == ["--missing"]:
        wanted = set(argv[1:])
        for path in MODULES:
            if package_of(path) in wanted:
                for s in public_slots(path):
                    if not s.annotated:
                        print(f"{s.module}:{s.line}: {s.callable} {s.name}")
        return
    total = [0, 0, 0, 0]
    print(f"{'package':<14} {'parameters':>18} {'returns':>18}")
    for package, row in coverage().items():
        total = [t + r for t, r in zip(total, row)]
        a, b, c, d = row
        print(
            f"{package:<14} {a:>5}/{b:<5} {100 * a / max(b, 1):5.1f} % "
            f"{c:>5}/{d:<5} {100 * c / max(d, 1):5.1f} %"
        )
    a, b, c, d = total
    print(
        f"{'all':<14} {a:>5}/{b:<5} {100 * a / max(b, 1):5.1f} % "
        f"{c:>5}/{d:<5} {100 * c / max(d, 1):5.1f} %"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
