"""Every published number the code base reproduces, recomputed live: ``flexsat validate``.

One module per topic holds a list ``CHECKS`` of :class:`Check` (case, quantity, source, the
value as printed, a ``compute`` callable, a tolerance justified in a comment). Values are never
stored: :func:`run_checks` calls each ``compute`` and compares. Checks that need the same
expensive model share it through a :func:`functools.lru_cache` builder inside their module, and
import the case modules inside ``compute``, so a broken case fails its own checks, not the table.

Adding a check is one entry in a module's ``CHECKS``::

    Check("nps", "PD rate gain kτ", "Hailey, Sortun & Agrawal c. 1992, after Eq. 24", 6.6773,
          "N m s/rad", lambda: float(_case().pd_gains().kd), atol=5e-5)  # half a unit, last digit

or, for a printed column, :func:`series`. A published number that is an erratum, or that the
model deviates from for a documented reason, carries a :class:`Discrepancy` (the value computed
instead and a standalone explanation). A new topic module is one more name in
:data:`MODULES`.

Other packages add checks through the ``flexsat.checks`` entry-point group (docs/plugins.md):
each entry point names a :class:`Check` or a list of them, which :func:`all_checks` runs after
the built-in ones, in entry-point name order.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable

from flexsat.checks.core import COLUMNS, STATUSES, Check, CheckResult, Discrepancy, evaluate, series
from flexsat.input_checks import FieldError

#: the topic modules of :mod:`flexsat.checks`, in table order (issues #2, #3, #4, then #5)
MODULES = (
    "tamu",
    "structures",
    "tamu_grid",
    "draper_rpl",
    "nps",
    "eps",
    "output_feedback",
    "bainum",
    "identification",
    "star_tracker",
    "tether",
    "cmg",
)


def _import_failure(name: str, exc: Exception) -> Check:
    def reraise() -> float:
        raise exc

    return Check(name, "check module imports", f"flexsat.checks.{name}", 0.0, "", reraise, atol=0)


def _check_plugin_rule(name: str, obj: object) -> str | None:
    """Why a ``flexsat.checks`` entry point is not a check or a list of checks, or None."""
    items = obj if isinstance(obj, list | tuple) else [obj]
    if not items or not all(isinstance(c, Check) for c in items):
        return (
            "not a check: a flexsat.checks entry point names a flexsat.checks.Check or a "
            f"non-empty list of them, got {type(obj).__name__}"
        )
    return None


def plugin_checks() -> list[Check]:
    """The checks of the ``flexsat.checks`` plug-ins, in entry-point name order.

    An entry point that cannot be loaded, is not a :class:`Check` (or a list of them) or takes
    the name of a built-in topic module (:data:`MODULES`) is left out and reported
    (:func:`flexsat.plugins.broken_plugins`).
    """
    from flexsat.plugins import entry_point_objects

    reserved = {name: f"the built-in checks flexsat.checks.{name}" for name in MODULES}
    checks: list[Check] = []
    for obj in entry_point_objects("flexsat.checks", _check_plugin_rule, reserved).values():
        checks.extend(obj if isinstance(obj, list | tuple) else [obj])
    return checks


def builtin_checks() -> list[Check]:
    """The checks of the topic modules (:data:`MODULES`), in table order. A topic module that
    fails to import shows up as one failing check carrying the error."""
    checks: list[Check] = []
    for name in MODULES:
        try:
            module = importlib.import_module(f"flexsat.checks.{name}")
        except Exception as exc:  # noqa: BLE001 -- reported as a failing check
            checks.append(_import_failure(name, exc))
            continue
        checks.extend(module.CHECKS)
    return checks


def all_checks() -> list[Check]:
    """Every registered check: the built-in ones (:func:`builtin_checks`), then the plug-ins'
    (:func:`plugin_checks`)."""
    return builtin_checks() + plugin_checks()


def case_names(checks: Iterable[Check] | None = None) -> list[str]:
    """The case names, in table order, without repeats."""
    return list(dict.fromkeys(c.case for c in (all_checks() if checks is None else checks)))


def select_checks(
    select: str | Iterable[str] | None = None, checks: Iterable[Check] | None = None
) -> list[Check]:
    """The checks of the named case(s) (all when ``select`` is None or empty).

    Raises
    ------
    ValueError
        For a case name with no checks, listing the known ones.
    """
    checks = all_checks() if checks is None else list(checks)
    if select is None:
        return checks
    names = [select] if isinstance(select, str) else list(select)
    if not names:
        return checks
    known = case_names(checks)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise FieldError("case", f"no checks for {', '.join(map(repr, unknown))}; known: {known}")
    return [c for c in checks if c.case in names]


def run_checks(
    select: str | Iterable[str] | None = None, checks: Iterable[Check] | None = None
) -> list[CheckResult]:
    """Compute every selected check live and compare it with its published value.

    Parameters
    ----------
    select : str or iterable of str, optional
        Case name(s) to run; all cases when None.
    checks : iterable of Check, optional
        The checks to choose from (default: :func:`all_checks`).

    Returns
    -------
    list of CheckResult
        In table order. A check whose computation raises is a failed result with the message;
        no exception escapes.
    """
    return [evaluate(c) for c in select_checks(select, checks)]


__all__ = [
    "COLUMNS",
    "MODULES",
    "STATUSES",
    "Check",
    "CheckResult",
    "Discrepancy",
    "all_checks",
    "builtin_checks",
    "case_names",
    "evaluate",
    "plugin_checks",
    "run_checks",
    "select_checks",
    "series",
]
