"""Readable metric names (flexsat.report.display): the units agree with the ones the
simulation records for its metrics (an independent table), suffixes are read longest first,
and a name without a unit suffix takes the dataset's unit."""

from __future__ import annotations

import pytest

from flexsat.report.display import METRICS, UNIT_SUFFIXES, metric_label, metric_name
from flexsat.sim.metrics import METRIC_UNITS


@pytest.mark.parametrize("name", sorted(METRIC_UNITS))
def test_units_agree_with_the_simulation_metrics_units(name):
    assert metric_name(name).unit == METRIC_UNITS[name]


@pytest.mark.parametrize(
    "name, unit, label",
    [
        ("peak_gimbal_rate_rad_s", None, "Peak gimbal rate (rad/s)"),  # not "rad_s" read as s
        ("peak_rate_deg_s", None, "Peak rate (deg/s)"),
        ("error_std_x_arcsec", None, "Error std x (arcsec)"),
        ("peak_momentum_ft_lb_s", None, "Peak momentum (ft lb s)"),
        ("rms_torque", "N m", "RMS torque (N m)"),  # the dataset's unit, abbreviation upper
        ("peak_torque_Nm", "ignored", "Peak torque (N m)"),  # the name's own unit wins
        ("singular", None, "Singular"),
        ("s", None, "S"),  # a bare suffix is a name, not a unit
        ("min_triplets", "", "Min triplets"),
    ],
)
def test_names_are_read_by_the_rules(name, unit, label):
    assert metric_label(name, unit) == label


def test_suffixes_are_tried_longest_first():
    lengths = [len(suffix) for suffix, _ in UNIT_SUFFIXES]
    assert lengths == sorted(lengths, reverse=True)


def test_every_listed_name_is_written_out():
    for name, shown in METRICS.items():
        assert shown.name[0].isupper() and "_" not in shown.name, name
        assert shown.label == (f"{shown.name} ({shown.unit})" if shown.unit else shown.name)
