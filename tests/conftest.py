import sys
from pathlib import Path

import pytest
import yaml

from flexsat.cases import tamu


@pytest.fixture(autouse=True)
def _fresh_modal_model_cache():
    """Each test starts with an empty in-process modal model cache
    (flexsat.scenarios.modal_cache), so a test counting modal solves, or one injecting a fault
    into a build, does not depend on which tests ran before it in the process."""
    cache = sys.modules.get("flexsat.scenarios.modal_cache")
    if cache is not None:  # not imported yet: nothing cached
        cache.MODAL_MODELS.clear()


@pytest.fixture(autouse=True)
def _numpy_print_options():
    """Each test ends with numpy's print options as it found them: a test importing pyyeti's
    nastran.n2p (which sets the legacy "1.13" options when first imported) must not change how
    a later test in the same worker prints (the tutorial's printed arrays)."""
    import numpy as np

    options = np.get_printoptions()
    yield
    np.set_printoptions(**options)


@pytest.fixture(scope="session")
def tamu_case():
    return tamu()


@pytest.fixture(scope="session")
def tamu_model(tamu_case):
    return tamu_case.model()


IDENTIFICATION_EXAMPLE = (
    Path(__file__).resolve().parents[1] / "examples" / "tamu_grid_identification.yaml"
)


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
    from flexsat.cases.identification_campaign import simulate_records
    from flexsat.cases.tamu_grid import tamu_grid
    from flexsat.scenarios import load_scenario

    sim = load_scenario(yaml.safe_dump(_identification_example(fast=True)))
    records = simulate_records(tamu_grid(motor_mass="0.5 kg"), sim.config())
    (tmp_path / "data").mkdir()
    for name in ("hammer", "wheels", "video"):
        getattr(records, name).to_uff(tmp_path / "data" / f"{name}.uff")
    data = _identification_example()
    for name in ("truth", "sensors", "hammer", "video", "wheels"):
        data.pop(name)
    data["records"] = {
        "hammer": "data/hammer.uff",
        "wheels": "data/wheels.uff",
        "video": "data/video.uff",
        "segment": 1000,
    }
    data["identification"]["torque_constants"] = True
    path = tmp_path / "measured.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture(scope="session")
def recorded_scenario():
    return _recorded_scenario


@pytest.fixture
def fail_opening(monkeypatch):
    """``fail_opening(name, code)``: from then on, opening a file called ``name`` for writing
    inside a temporary report folder (``.<out>.tmp-<id>``) raises ``OSError(code)``, as a full
    disk (ENOSPC), a read-only file system (EROFS), ... would."""
    import builtins
    import errno
    import io
    import os

    real = io.open

    def fail(name: str, code: int = errno.ENOSPC) -> None:
        def guarded(file, mode="r", *args, **kwargs):
            path = Path(os.fsdecode(file)) if isinstance(file, (str, bytes, os.PathLike)) else None
            if (
                path is not None
                and path.name == name
                and ".tmp-" in path.parent.name
                and set(mode) & set("wax+")
            ):
                raise OSError(code, os.strerror(code), str(path))
            return real(file, mode, *args, **kwargs)

        monkeypatch.setattr(io, "open", guarded)  # pathlib
        monkeypatch.setattr(builtins, "open", guarded)  # PIL (matplotlib's PNGs)

    return fail


@pytest.fixture(scope="session")
def schur_error_bound():
    """The Schur method's error bound of a Riccati solution (Laub 1979), n ε (κ(U11) + 3):
    :func:`flexsat.control.lqr.riccati_error_bound`."""
    from flexsat.control.lqr import riccati_error_bound

    return riccati_error_bound


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium for the report pages (tests/report_browser.py)."""
    from report_browser import start_browser

    yield from start_browser()
