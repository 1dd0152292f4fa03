"""The control laws a maneuver run names (flexsat.scenarios.laws): each builds its controller from
the run's gains and what the case gives (slew angle, inertias, appendage count, plant, control
period), so the controller's own rules are checked against that case."""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np
import pytest

from flexsat.scenarios.laws import MANEUVER_LAWS, CaseContext
from flexsat.scenarios.maneuver import GainsSpec, ReferenceSpec, RunSpec

LQG = {
    "rigid_weight": 1,
    "mode_weights": 0.1,
    "control_weight": 7,
    "sensor_noise": [1e-7, 5e-6],
    "process_noise": 0.1,
}


@pytest.fixture(scope="module")
def ctx(tamu_case, tamu_model):
    return CaseContext(
        angle=math.radians(40),
        reference_inertia=tamu_case.reference_inertia,
        appendage_inertia=tamu_model.appendage_inertia,
        n_appendages=int(tamu_model.n_appendages),
        plant=tamu_model,
        dt=1 / 75,
    )


def build(ctx, shape=None, **run):
    """The controller of the run given by ``run`` (RunSpec keywords), tracking the torque
    ``shape`` built from its reference."""
    run = RunSpec(label="run", **run)
    return MANEUVER_LAWS[run.law].build(run, ctx, shape)


def test_the_law_table_matches_the_schema():
    assert set(MANEUVER_LAWS) == set(typing.get_args(RunSpec.model_fields["law"].annotation))
    for law in MANEUVER_LAWS.values():
        assert set(law.required) <= set(law.gains) <= set(GainsSpec.model_fields)


def test_regulator_takes_the_slew_and_the_cases_appendage_count(ctx):
    law = build(ctx, law="lyapunov_regulator", gains={"g1": 2.0, "g2": 3.0, "g3": -3.0})
    assert (float(law.g1), float(law.g2), float(law.g3)) == (2.0, 3.0, -3.0)
    assert float(law.target) == pytest.approx(math.radians(40))
    # g3 > -n_appendages (Att. 3 Eq. 11): -3 is admissible with four appendages, not with two
    with pytest.raises(ValueError, match=r"^g3: must be > -2 \(= -n_appendages\)"):
        build(
            dataclasses.replace(ctx, n_appendages=2),
            law="lyapunov_regulator",
            gains={"g1": 2.0, "g2": 3.0, "g3": -3.0},
        )


def test_tracker_follows_its_reference_with_the_cases_appendage_inertia(ctx):
    spec = ReferenceSpec(shape="smooth_bang_bang", u_max=1.0, alpha=0.2)
    reference = spec.build(ctx.angle, ctx.reference_inertia)
    law = build(
        ctx,
        reference,
        law="lyapunov_tracker",
        gains={"g1": 2.0, "g2": 3.0},
        reference=spec.model_dump(exclude_none=True),
    )
    assert law.reference is reference
    assert float(law.appendage_inertia) == ctx.appendage_inertia
    assert float(law.target) == pytest.approx(ctx.angle)  # where the reference ends


def test_pd_poles_place_the_rigid_poles_with_the_reference_inertia(ctx):
    inertia = 2.5
    law = build(
        dataclasses.replace(ctx, reference_inertia=inertia),
        law="pd",
        poles={"natural_frequency": "0.06 Hz", "damping_ratio": 0.9},
    )
    wn = 2 * np.pi * 0.06
    # I θ'' = -kp θ - kd θ': s² + (kd/I) s + kp/I = s² + 2ζω s + ω²
    assert float(law.kp) == pytest.approx(inertia * wn**2, rel=1e-12)
    assert float(law.kd) == pytest.approx(2 * 0.9 * wn * inertia, rel=1e-12)
    assert float(law.target) == pytest.approx(ctx.angle)


def test_pd_gains_and_feedforward_pass_through(ctx):
    law = build(ctx, law="pd", gains={"kp": 4.0, "kd": 6.0}, feedforward=False)
    assert (float(law.kp), float(law.kd), law.feedforward) == (4.0, 6.0, False)
    assert build(ctx, law="pd", gains={"kp": 4.0, "kd": 6.0}).feedforward is True


def test_lqg_position_gain_is_the_integrator_value(ctx):
    """The θ channel is a pure integrator: the LQR position gain is √(R_xx(θ) / R_uu) = √(1/7)
    whatever the modes (as for the NPS case); the Riccati solve's
    round-off is ~1e-14 here."""
    law = build(ctx, law="lqg", lqg=LQG)
    n = ctx.plant.ndof
    assert law.K.shape == (1, 2 * n)
    assert law.K[0, 0] == pytest.approx(math.sqrt(1 / 7), rel=1e-8)
    assert float(law.target) == pytest.approx(ctx.angle)


def test_lqg_needs_one_mode_weight_or_one_per_mode(ctx):
    k = ctx.plant.ndof - 1
    with pytest.raises(ValueError) as info:
        build(ctx, law="lqg", lqg=dict(LQG, mode_weights=[0.5, 0.1]))
    assert str(info.value) == f"lqg.mode_weights: give one weight or one per mode ({k}), got 2"
    per_mode = build(ctx, law="lqg", lqg=dict(LQG, mode_weights=[0.1] * k))
    assert per_mode.K == pytest.approx(build(ctx, law="lqg", lqg=LQG).K, rel=1e-12)


def test_lqg_refinements(ctx):
    """``weighted`` keeps the regulator and recomputes the filter (Eq. 52); ``truncated`` also
    zeroes the regulator gains of the modes beyond ``keep_modes`` (Eq. 53)."""
    full = build(ctx, law="lqg", lqg=LQG)
    weighted = build(ctx, law="lqg", lqg=dict(LQG, refine="weighted"))
    assert weighted.K == pytest.approx(full.K, rel=1e-12)
    assert not np.allclose(weighted.L, full.L)
    truncated = build(ctx, law="lqg", lqg=dict(LQG, refine="truncated", keep_modes=1))
    n = ctx.plant.ndof
    kept = np.zeros(2 * n, bool)
    kept[[0, 1, n, n + 1]] = True  # θ, q_1 and their rates
    assert np.all(truncated.K[0, ~kept] == 0)
    assert truncated.K[0, kept] == pytest.approx(full.K[0, kept], rel=1e-12)
