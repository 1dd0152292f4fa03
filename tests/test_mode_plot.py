import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flexsat.cases import CASES, tamu, tamu_grid
from flexsat.cli import app
from flexsat.mode_plot import plot_case_modes

runner = CliRunner()


@pytest.mark.parametrize("name", sorted(CASES))
def test_modes_json_works_for_every_case(name):
    """Issue #3: `flexsat modes CASE --json` has `frequencies_hz` (ascending) for every case."""
    result = runner.invoke(app, ["modes", name, "-n", "3", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    f = np.asarray(data["frequencies_hz"])
    assert f.shape == (3,) and np.all(np.diff(f) >= -1e-9 * f.max()) and np.all(f >= 0)
    if "descriptions" in data:
        assert len(data["descriptions"]) == 3


def _is_png(path):
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_draws_mode_shapes_of_a_finite_element_case(tmp_path):
    path = plot_case_modes(tamu_grid(), 4, tmp_path / "grid.png", "grid")
    assert _is_png(path)


def test_plot_draws_frequencies_of_a_case_without_a_mesh(tmp_path):
    path = plot_case_modes(tamu(n_modes=4), 4, tmp_path / "tamu.png", "tamu")
    assert _is_png(path)


def test_cli_plot_option_and_its_errors(tmp_path):
    result = runner.invoke(app, ["modes", "nps", "-n", "2", "--plot", str(tmp_path / "n.png")])
    assert result.exit_code == 0, result.output
    assert _is_png(tmp_path / "n.png")
    result = runner.invoke(app, ["modes", "nps", "--plot", str(tmp_path / "nodir" / "n.png")])
    assert result.exit_code == 2 and "--plot: cannot write" in result.output
