from pathlib import Path

import numpy as np
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


def _recorded_scenario(tmp_path):
    """A measured-data scenario: the example's tests simulated, written to UFF 58 files next to
    the scenario file, and a scenario with ``records`` pointing at them."""
    from flexsat.cases.tamu_grid import tamu_grid
    from flexsat.identify.campaign import simulate_records
    from flexsat.scenario import load_scenario

    sim = load_scenario(yaml.safe_dump(_identification_example(fast=True)))
    records = simulate_records(tamu_grid(motor_mass="0.5 kg"), sim.config())
    (tmp_path / "data").mkdir()
    for name in ("hammer", "wheels", "video"):
        getattr(records, name).to_uff(tmp_path / "data" / f"{name}.uff")
    data = _identification_example()
    for name in ("truth", "sensors", "hammer", "video", "wheels"):
        data.pop(name)
    data["records"] = {"hammer": "data/hammer.uff", "wheels": "data/wheels.uff",
                       "video": "data/video.uff", "segment": 1000}
    data["identification"]["torque_constants"] = True
    path = tmp_path / "measured.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture(scope="session")
def recorded_scenario():
    return _recorded_scenario

def _schur_error_bound(S) -> float:
    """Relative error bound of a Riccati solution from the Schur method, and of its residual.

    The method computes an orthonormal basis [U11; U21] of the stable invariant subspace to
    round-off (~ n eps) and returns S = U21 U11^-1: the error is amplified by the condition
    number of U11 (Laub 1979; Petkov, Christov & Konstantinov, "Numerical Methods for Linear
    Control Systems", 1991), which follows from S itself: the basis is [I; S] (I + S^2)^-1/2,
    so kappa(U11) = sqrt(1 + s_max^2) / sqrt(1 + s_min^2).  The relative residual (rho_c, rho_d
    of :mod:`flexsat.control.lqr`) adds its own evaluation round-off, <= 3 n eps of the terms
    (three products of inner length <= n in the quadratic term):
    n eps (kappa(U11) + 3).  This is the spread python-control's solution shows as well.
    """
    s = np.linalg.svd(np.asarray(S, dtype=float), compute_uv=False)
    return len(s) * np.finfo(float).eps * (np.hypot(1.0, s[0]) / np.hypot(1.0, s[-1]) + 3.0)


@pytest.fixture(scope="session")
def schur_error_bound():
    return _schur_error_bound
