"""Conformance checks for plug-in plants and control laws (like scikit-learn's
``check_estimator``).

:func:`check_plant` runs every check of :mod:`flexsat.testing.plant_checks` on a
:class:`~flexsat.dynamics.plant.Plant`, :func:`check_controller` those of
:mod:`flexsat.testing.law_checks` on a :class:`~flexsat.control.base.Controller` and the plant
it is written for; each raises an AssertionError ``"<class> fails <check>: <why>"`` at the first
failure. :func:`plant_checks` / :func:`controller_checks` list the checks (each a callable
:class:`Check` with its name and, when it does not apply by the subject's declaration, a
``skip`` reason) and :func:`parametrize_with_checks` makes them one pytest test each.
docs/conformance.md ("Checking your plant or law") shows how.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Plant
from flexsat.testing.checks import Check, run_checks
from flexsat.testing.law_checks import LAW_CHECKS, controller_checks
from flexsat.testing.plant_checks import PLANT_CHECKS, plant_checks

if TYPE_CHECKING:
    import pytest


def check_plant(plant: Plant, **options: Any) -> list[Check]:
    """Run every conformance check of ``plant``; return the checks skipped by its declarations.

    Parameters
    ----------
    plant : Plant
    **options
        ``state_scale``, ``input_scale``, ``seed`` of :func:`plant_checks`.

    Raises
    ------
    AssertionError
        Naming the plant's class, the failing check and why.
    """
    return run_checks(plant_checks(plant, **options))


def check_controller(law: Controller, plant: Plant, **options: Any) -> list[Check]:
    """Run every conformance check of ``law`` on ``plant``; return the skipped checks.

    Parameters
    ----------
    law : Controller
    plant : Plant
        The plant the law is written for.
    **options
        ``state_scale``, ``seed`` of :func:`controller_checks`.

    Raises
    ------
    AssertionError
        Naming the law's class, the failing check and why.
    """
    return run_checks(controller_checks(law, plant, **options))


def parametrize_with_checks(
    plants: Iterable[Plant] = (), laws: Iterable[tuple[Controller, Plant]] = ()
) -> pytest.MarkDecorator:
    """A ``pytest.mark.parametrize`` over the checks of ``plants`` and of ``laws`` (pairs
    ``(law, plant)``): one test per check, with argument ``check`` (call it), a check that
    does not apply marked skipped with its reason.

    Examples
    --------
    >>> @parametrize_with_checks(plants=[MyPlant()], laws=[(MyLaw(), MyPlant())])
    ... def test_conformance(check):
    ...     check()
    """
    import pytest  # a test-time dependency only

    checks = [c for p in plants for c in plant_checks(p)]
    checks += [c for law, plant in laws for c in controller_checks(law, plant)]
    params = [
        pytest.param(c, id=str(c), marks=() if c.skip is None else pytest.mark.skip(reason=c.skip))
        for c in checks
    ]
    return pytest.mark.parametrize("check", params)


__all__ = [
    "LAW_CHECKS",
    "PLANT_CHECKS",
    "Check",
    "check_controller",
    "check_plant",
    "controller_checks",
    "parametrize_with_checks",
    "plant_checks",
]
