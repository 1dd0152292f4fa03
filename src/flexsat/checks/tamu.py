"""TAMU hub + four appendages (issue #2): Junkins, Pollock & Rahman 1990, Att. 1-3.

Checked:

- the rigid 40° maneuver times T of the smoothed bang-bang reference (Att. 3 Eq. 16,
  evaluated: the paper gives the law, not a table of T), as :mod:`flexsat.cases.tamu` builds them;
- the numbers the paper reads off its experiments (Att. 3 §V; Att. 2 Fig. 9), against
  the embedded default scenario (``flexsat run``) plus Law I with g2 = 0 (Att. 3 Fig. 9), same
  hardware, noise and seed as ``tests/test_default_scenario.py``.

Not checked, on purpose: Law I's settling time. The paper gives it as "about 12 seconds" (Att. 2)
and "over 12 seconds" (Att. 3) without a settling band; with the scenario's 0.5° band bearing
friction holds Law I outside the band to the end of the 15 s run, so there is no number to
compare (docs/tamu.md). "Much lower peak vibration" and "≈ 100 % reduction" are qualitative and
stay in the tests.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any

from flexsat.checks.core import Check

if TYPE_CHECKING:
    from flexsat.cases.tamu import TamuCase

SOURCE = "Junkins, Pollock & Rahman 1990"


@lru_cache(maxsize=1)
def _case() -> TamuCase:
    from flexsat.cases import tamu

    return tamu()


def _maneuver_time(alpha: float) -> float:
    return float(_case().reference(alpha=alpha).end_time)


@lru_cache(maxsize=1)
def _experiment() -> dict[str, dict[str, Any]]:
    """Metrics of the default scenario's runs (Law I, Law II) and of Law I with g2 = 0."""
    from importlib import resources

    import yaml

    from flexsat.scenarios import DEFAULT_SCENARIO, load_scenario, run_scenario

    data = yaml.safe_load(resources.files("flexsat.cases").joinpath(DEFAULT_SCENARIO).read_text())
    data["runs"].append(
        {
            "label": "Law I, g2 = 0",
            "law": "lyapunov_regulator",
            "gains": {"g1": "600 ozf*in/rad", "g2": 0},
        }
    )
    result = run_scenario(load_scenario(yaml.safe_dump(data)))
    return {row["run"]: row for row in result.metrics_records()}


def _metric(run: str, name: str) -> float:
    value = _experiment()[run][name]
    if value is None:
        raise ValueError(f"{run}: {name} is undefined (not reached within the run)")
    return value


_T_SOURCE = f"{SOURCE}, Att. 3 Eq. 16, evaluated"  # the law, tabulated by the developers

# Experimental readings: "≈ 1.5°", "~10°", "−34°", "6 seconds" are read off single hardware runs
# with bearing friction, sensor noise and random torques, and the model's hub inertia is not
# published (50 oz-in-s² estimate, docs/tamu.md; 10 … 200 oz-in-s² moves Law II's overshoot from
# 1.0° to 2.4°). Tolerance ±25 %: the issues' band for comparing a model with unpublished inputs
# against published values (issue #3, EPS modes), not tuned to the result.
_EXPERIMENT_RTOL = 0.25
_SCENARIO = "default scenario (flexsat run), 0.5° settling band"

CHECKS: list[Check] = [
    # T is exact given Eq. 16; the table prints 4 decimals: half a unit, 5e-5 s
    Check(
        "tamu",
        "maneuver time T, 40°, 400 oz-in, α = 0",
        _T_SOURCE,
        3.8544,
        "s",
        lambda: _maneuver_time(0.0),
        atol=5e-5,
    ),
    Check(
        "tamu",
        "maneuver time T, 40°, 400 oz-in, α = 0.1",
        _T_SOURCE,
        4.2986,
        "s",
        lambda: _maneuver_time(0.1),
        atol=5e-5,
    ),
    Check(
        "tamu",
        "maneuver time T, 40°, 400 oz-in, α = 0.2",
        _T_SOURCE,
        4.9109,
        "s",
        lambda: _maneuver_time(0.2),
        atol=5e-5,
    ),
    Check(
        "tamu",
        "Law II overshoot (α = 0.2, g1 = 3000, g2 = 800)",
        f'{SOURCE}, Att. 3 §V "≈ 1.5°"',
        1.5,
        "deg",
        lambda: _metric("Law II", "overshoot_deg"),
        rtol=_EXPERIMENT_RTOL,
        note=_SCENARIO,
    ),
    Check(
        "tamu",
        "Law II settling time",
        f'{SOURCE}, Att. 3 §V "6 seconds"',
        6.0,
        "s",
        lambda: _metric("Law II", "settling_time_s"),
        rtol=_EXPERIMENT_RTOL,
        note=_SCENARIO,
    ),
    Check(
        "tamu",
        "Law I overshoot (g1 = 600, g2 = 800)",
        f'{SOURCE}, Att. 2 Fig. 9 "~10°", Att. 3 Fig. 10',
        10.0,
        "deg",
        lambda: _metric("Law I", "overshoot_deg"),
        rtol=_EXPERIMENT_RTOL,
        note=_SCENARIO,
    ),
    Check(
        "tamu",
        "Law I overshoot, g2 = 0",
        f'{SOURCE}, Att. 3 Fig. 9 "−34°"',
        34.0,
        "deg",
        lambda: _metric("Law I, g2 = 0", "overshoot_deg"),
        rtol=_EXPERIMENT_RTOL,
        note=_SCENARIO,
    ),
]
