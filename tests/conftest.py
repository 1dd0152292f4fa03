import pytest

from flexsat.cases import tamu


@pytest.fixture(scope="session")
def tamu_case():
    return tamu()


@pytest.fixture(scope="session")
def tamu_model(tamu_case):
    return tamu_case.model()
