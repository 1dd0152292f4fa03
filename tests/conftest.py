from pathlib import Path

import pytest
import yaml

from flexsat.cases import tamu


@pytest.fixture(scope="session")
def tamu_case():
    return tamu()


@pytest.fixture(scope="session")
def tamu_model(tamu_case):
    return tamu_case.model()


IDENTIFICATION_EXAMPLE = (Path(__file__).resolve().parents[1] / "examples"
                          / "tamu_grid_identification.yaml")


def _identification_example(fast=False, **changes) -> dict:
    """The example identification scenario as a dict; ``a__b=v`` sets ``data[a][b] = v``;
    ``fast`` shortens it for tests (2 minutes of reaction-wheel data)."""
    data = yaml.safe_load(IDENTIFICATION_EXAMPLE.read_text())
    for path, value in changes.items():
        node = data
        keys = path.split("__")
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value
    if fast:
        data["wheels"].update(duration="120 s", segment=1000)
    return data


@pytest.fixture(scope="session")
def identification_example():
    return _identification_example
