"""Shared pieces of the perturbation-feedback tests (seed 003 F8-F12): a rigid three-axis
nominal slew, the rebuilt EPS plants and a small flexible model whose modes couple to the
rigid rotation."""

import pytest

from eigenaxis_slew import EigenaxisSlew
from modal_models import coupled_modal


@pytest.fixture(scope="session")
def eigenaxis_slew():
    """The class :class:`EigenaxisSlew` (a nominal factory)."""
    return EigenaxisSlew


@pytest.fixture(scope="session")
def coupled_model():
    """:func:`coupled_modal`: forces and outputs at nodes 1-3."""
    return coupled_modal()


@pytest.fixture(scope="session")
def eps_case():
    from flexsat.cases.eps import eps

    return eps()


@pytest.fixture(scope="session")
def eps_truth_plant(eps_case):
    """The paper's simulation model: 45 elastic modes, torquers at the CG node loading them,
    the final 7 forces, the rim displacements."""
    return eps_case.plant(n_modes=45)


@pytest.fixture(scope="session")
def eps_design_plant(eps_truth_plant):
    """The paper's controller model: the first 10 of the truth model's modes, from the same
    modal model (a separate 10-mode eigen-solution may rotate the repeated antenna pairs)."""
    return eps_truth_plant.reduced(10)
