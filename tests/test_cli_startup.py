"""What a user meets first: ``flexsat --version``, ``python -m flexsat``, a fast ``--help`` and
``cases``, the typing marker and the licence."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import flexsat

ROOT = Path(__file__).resolve().parents[1]
SRC = Path(flexsat.__file__).resolve().parent
#: what `--help` and `cases` must not load: the numerical stack that made them take 2.5 s
HEAVY = (
    "numpy",
    "scipy",
    "matplotlib",
    "xarray",
    "pint",
    "control",
    "h5py",
    "flexsat.cases",
    "flexsat.sim",
    "flexsat.scenarios",
    "flexsat.checks",
)


def _python(*args: str, code: str | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(SRC.parent)}
    argv = [sys.executable, *(("-c", code) if code else ()), *args]
    return subprocess.run(argv, capture_output=True, text=True, env=env, timeout=120)


@pytest.mark.parametrize("argv", [["--help"], ["cases"], ["cases", "--json"], ["--version"]])
def test_light_commands_import_no_numerical_stack(argv):
    """Measured by the modules loaded, not by a wall-clock limit (benchmarks/bench_cli.py times
    them)."""
    code = (
        "import sys\nfrom flexsat.cli import app\n"
        "try:\n    app(sys.argv[1:], prog_name='flexsat')\nexcept SystemExit:\n    pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)"
    )
    done = _python(*argv, code=code)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]", done.stderr


def test_version_comes_from_the_package_metadata():
    from importlib.metadata import PackageNotFoundError, version

    try:
        expected = version("flexsat")
    except PackageNotFoundError:  # a bare source tree
        expected = flexsat.__version__
    done = _python("-m", "flexsat", "--version")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[:2] == ["flexsat", expected]


def test_python_dash_m_flexsat_is_the_command_line():
    done = _python("-m", "flexsat", "cases", "--json")
    assert done.returncode == 0, done.stderr
    assert "tamu" in {row["case"] for row in json.loads(done.stdout)}
    usage = _python("-m", "flexsat", "--help")
    assert usage.returncode == 0 and "Usage: flexsat" in usage.stdout


def test_typing_marker_ships_in_the_package():
    """pyproject's package-data names py.typed: it must exist inside the package."""
    assert (SRC / "py.typed").is_file()
    assert '"py.typed"' in (ROOT / "pyproject.toml").read_text()


def test_licence_is_the_declared_bsd_3_clause():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "the flexsat developers" in text
    assert "Neither the name of the copyright holder" in text  # the third clause
