"""The benchmark cases by name: where each comes from and what it is, without loading it.

``flexsat cases`` lists this catalogue and ``flexsat run`` / ``flexsat modes`` look a name up in
it before anything heavy is imported: a :class:`CaseInfo` holds the module and function of its
builder, which :attr:`CaseInfo.builder` imports on first use. :mod:`flexsat.cases` re-exports
the built-in catalogue (:data:`CASES`) with the builders themselves.

Other packages add cases through the ``flexsat.cases`` entry-point group
(:mod:`flexsat.plugins`, docs/plugins.md): :func:`all_cases` is the built-ins followed by the
plug-ins, and :func:`get_case` looks a name up in it. The entry points are read on the first
call, not on import.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class CaseInfo:
    """A case: its ``name``, the ``module`` (dotted, absolute) and the ``function`` in it that
    builds the case, its ``source`` (short citation and where in it, or a reference; see
    :func:`flexsat.references.cite`) and a one-line ``description``."""

    name: str
    module: str
    function: str
    source: str
    description: str

    @property
    def builder(self) -> Callable[..., Any]:
        """The builder, imported on first use (with its numerical dependencies)."""
        builder: Callable[..., Any] = getattr(importlib.import_module(self.module), self.function)
        return builder


_BEAMS = "Blevins, Formulas for Natural Frequency and Mode Shape (1979), Table 8-1"

CASES: dict[str, CaseInfo] = {
    info.name: info
    for info in (
        CaseInfo(
            "tamu",
            "flexsat.cases.tamu",
            "tamu",
            "Junkins, Pollock & Rahman 1990, Att. 3 Table 1 and §V",
            "Texas A&M rigid hub with four flexible appendages and tip masses, single-axis slews",
        ),
        CaseInfo(
            "tamu_grid",
            "flexsat.cases.tamu_grid",
            "tamu_grid",
            "Junkins, Pollock & Rahman 1990, Att. 4 Table 1, Att. 6 Tables 1-2, Att. 8 Fig. 4",
            "Texas A&M 5 ft x 5 ft aluminium grid hanging in a vertical plane, "
            "plate-grid elements, optional gravity stiffening",
        ),
        CaseInfo(
            "draper_rpl",
            "flexsat.cases.draper_rpl",
            "draper_rpl",
            "Junkins, Pollock & Rahman 1990, Att. 5 Table 3, Eqs. 50-59, Table 4",
            "Draper/RPL hub with four appendages, Ritz model with comparison functions (Table 4)",
        ),
        CaseInfo(
            "eps",
            "flexsat.cases.eps",
            "eps",
            "EPS slew study c. 1989, 'Model Development' (EPS model), "
            "'Actuator Placement' (node numbers)",
            "Earth Pointing Satellite: 25 m graphite truss with 15 m and 7.5 m antennas",
        ),
        CaseInfo(
            "nps",
            "flexsat.cases.nps",
            "nps",
            "Hailey, Sortun & Agrawal c. 1992 (NPS FSS), 'Experimental Setup', "
            "'Proportional - Derivative Control'",
            "NPS Flexible Spacecraft Simulator: hub with a cantilevered astromast and "
            "reflector, hybrid coordinates",
        ),
        CaseInfo(
            "agrawal_bang",
            "flexsat.cases.agrawal_bang",
            "agrawal_bang",
            "Agrawal & Bang 1996, §4",
            "Agrawal-Bang two-beam L structure with three collocated piezoelectric pairs",
        ),
        CaseInfo(
            "bainum",
            "flexsat.cases.bainum",
            "bainum",
            "Bainum & Reddy 1979 (NASA CR-158684), Ch. II-IV, App. A",
            "Bainum & Reddy free-free beam in orbit: pitch + bending with gravity gradient, "
            "point-force actuators (controllability, decoupling, per-mode LQR)",
        ),
        CaseInfo(
            "cantilever_beam",
            "flexsat.cases.beams",
            "cantilever_beam",
            _BEAMS,
            "uniform cantilever, 3-D frame elements, against the exact beta L",
        ),
        CaseInfo(
            "free_free_beam",
            "flexsat.cases.beams",
            "free_free_beam",
            _BEAMS,
            "uniform free-free beam, 3-D frame elements, six rigid modes",
        ),
        CaseInfo(
            "nafems_fv2",
            "flexsat.cases.beams",
            "nafems_fv2",
            "NAFEMS R0015 Selected Benchmarks for Natural Frequency Analysis (1987), test FV2",
            "NAFEMS FV2 pin-ended double cross, in-plane frame vibration",
        ),
    )
}


def _case_plugin_rule(name: str, obj: Any) -> str | None:
    """Why a ``flexsat.cases`` entry point is not a case, or None."""
    module = importlib.import_module(getattr(obj, "__module__", None) or "builtins")
    if not callable(obj) or getattr(module, getattr(obj, "__qualname__", ""), None) is not obj:
        return f"not a case builder: {obj!r} is not a class or function defined in its module"
    texts = {field: getattr(obj, field, None) for field in ("source", "description")}
    for field, text in texts.items():
        if not isinstance(text, str) or not text.strip():
            return f"{field}: a case builder needs a non-empty string attribute {field!r}"
    if "\n" in str(texts["description"]):
        return "description: one line (a row of `flexsat cases`)"
    return None


def all_cases() -> dict[str, CaseInfo]:
    """The built-in cases (:data:`CASES`), then those of the ``flexsat.cases`` plug-ins.

    A plug-in is a case builder -- a class or function called with the case's keyword
    overrides -- with string attributes ``source`` and ``description``; the entry point's name
    is the case's name. One that cannot be loaded, is not such a builder or takes a built-in
    name is left out and reported (:func:`flexsat.plugins.broken_plugins`).
    """
    from flexsat.plugins import entry_point_objects

    reserved = {
        name: f"the built-in case {name!r} ({info.module}:{info.function})"
        for name, info in CASES.items()
    }
    plugins = entry_point_objects("flexsat.cases", _case_plugin_rule, reserved)
    return CASES | {
        name: CaseInfo(name, obj.__module__, obj.__qualname__, obj.source, obj.description)
        for name, obj in plugins.items()
    }


def get_case(name: str) -> CaseInfo:
    """The catalogue entry of ``name`` (a built-in case or a plug-in's, :func:`all_cases`).

    Raises
    ------
    ValueError
        For an unknown name, listing the known ones.
    """
    if name in CASES:  # the built-ins need no entry point read
        return CASES[name]
    cases = all_cases()
    try:
        return cases[name]
    except KeyError:
        from flexsat.input_checks import FieldError  # numpy: loaded for the refusal only

        raise FieldError("case", f"unknown case {name!r}; known: {sorted(cases)}") from None


__all__ = ["CASES", "CaseInfo", "all_cases", "get_case"]
