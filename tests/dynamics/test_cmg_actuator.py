"""A rigid spacecraft with a CMG pyramid as its actuator (issue 14 part 2; Vadali, Oh & Walker,
Eq. 3–7, 17): the steering law delivers the commanded torque (Iω̇ + ω×Iω = τ_c), ḣ = h_r C σ̇
is the derivative of h(σ) along the motion, the total angular momentum is conserved with no
external torque (through the simulation core, fourth order), the gimbal-rate limit scales the
torque without turning it, the pseudo-inverse refuses a singular set and the SR inverse passes
it, and singularity passages are reported and classified."""

import numpy as np
import pytest

from flexsat.control.base import Controller
from flexsat.dynamics import cmg
from flexsat.dynamics.cmg_actuator import CmgSpacecraft
from flexsat.sim import SimConfig, simulate

EPS = np.finfo(float).eps
J = np.array([[100.0, 2.0, -1.0], [2.0, 120.0, 3.0], [-1.0, 3.0, 80.0]])  # kg m², products on


class RateDamping(Controller):
    """τ_c = −k ω: a law that reads the rate and writes the commanded torque."""

    reads = ("rate",)
    writes = ("torque",)

    def __init__(self, k):
        self.k = k

    def __call__(self, t, y, state):
        return -self.k * y["rate"], state


class ConstantTorque(Controller):
    reads = ("rate",)
    writes = ("torque",)

    def __init__(self, torque):
        self.torque = np.asarray(torque, float)

    def __call__(self, t, y, state):
        return np.broadcast_to(self.torque, np.shape(y["rate"])).copy(), state


def _state(plant, sigma):
    return plant.state_from(
        rate=[0.02, -0.03, 0.015], euler123=[0.1, 0.2, -0.1], gimbal_angles=sigma
    )


def test_steering_delivers_the_commanded_torque_with_gyroscopic_coupling():
    plant = CmgSpacecraft(J, "2 N*m*s", steering="pi")
    rng = np.random.default_rng(14)
    x = np.stack([_state(plant, rng.uniform(-np.pi, np.pi, 4)) for _ in range(5)])
    x[:, 4:7] = rng.normal(scale=0.1, size=(5, 3))
    u = rng.normal(size=(5, 3))
    f = plant.nonlinear_force(x, u)
    w, wdot, sdot = x[:, 4:7], f[:, 4:7], f[:, 7:]
    # Eq. (4) with the steering of Eq. (5)–(7): the body feels exactly τ_c; the solve's
    # round-off is cond(CCᵀ) × eps relative to the largest term
    c = cmg.jacobian(x[:, 7:])
    cond = np.linalg.cond(c @ np.swapaxes(c, -1, -2)).max()
    lhs = wdot @ J.T + np.cross(w, w @ J.T)
    np.testing.assert_allclose(lhs, u, atol=100 * cond * EPS * (1 + np.abs(u).max()))
    # ḣ = h_r C σ̇ is the derivative of h(σ) along σ̇: central differences, step 1e-6
    # (truncation step² |h'''| ~ 1e-12, round-off eps |h| / step ~ 1e-10)
    step = 1e-6
    fd = (
        plant.cmg_momentum(np.concatenate([x[:, :7], x[:, 7:] + step * sdot], -1))
        - plant.cmg_momentum(np.concatenate([x[:, :7], x[:, 7:] - step * sdot], -1))
    ) / (2 * step)
    hdot = 2.0 * np.einsum("cij,cj->ci", c, sdot)
    np.testing.assert_allclose(fd, hdot, atol=1e-8 * (1 + np.abs(hdot).max()))
    # and the torque on the body is −ḣ − ω × h
    h = plant.cmg_momentum(x)
    np.testing.assert_allclose(lhs, -hdot - np.cross(w, h), atol=100 * cond * EPS * 10)


def test_total_angular_momentum_is_conserved_through_the_simulation_core():
    # the command is an internal torque: C(β)ᵀ(Iω + h) stays constant whatever the law does.
    # RKMK4 at h = 20 ms over 20 s, started from the stored [1, 1, 1] preferred set (gain stays
    # >= 0.31): measured 1.8e-11 N m s, 1.1e-12 at 10 ms (the fourth order's 16×), of |H| = 4.1
    plant = CmgSpacecraft(J, 1.0, steering="pi")
    x0 = _state(plant, cmg.preferred_set([1.0, 1.0, 1.0]))
    cfg = SimConfig(duration=20.0, control_rate=10.0, substeps=5)
    run = simulate(plant, RateDamping(5.0), cfg, n_cases=1, initial_state=x0, record_states=True)
    X = run.dataset["state"].values[0]
    H = plant.momentum(X)
    assert np.abs(H - H[0]).max() <= 1e-10 * np.linalg.norm(H[0])
    assert np.abs(np.linalg.norm(X[:, :4], axis=1) - 1).max() <= 1e-12
    # the body's momentum went into the cluster: the rates fall (k = 5 N m s, I ~ 100 kg m²)
    assert np.linalg.norm(X[-1, 4:7]) < 0.5 * np.linalg.norm(X[0, 4:7])
    assert {"gimbal_angles", "cmg_momentum", "gain"} <= set(run.dataset.data_vars)


def test_gimbal_rate_limit_scales_the_torque_without_turning_it():
    limit = 0.05
    free = CmgSpacecraft(J, 1.0)
    limited = CmgSpacecraft(J, 1.0, gimbal_rate_limit=f"{np.rad2deg(limit)} deg/s")
    x = _state(free, np.deg2rad([10.0, -20.0, 30.0, 5.0]))
    u = np.array([0.3, -0.2, 0.1])
    r_free, r_lim = free.gimbal_rates(x, u), limited.gimbal_rates(x, u)
    assert np.abs(r_free).max() > limit
    assert np.abs(r_lim).max() == pytest.approx(limit, rel=1e-12)
    np.testing.assert_allclose(r_lim, r_free * limit / np.abs(r_free).max(), rtol=1e-12)
    # under the limit the command passes unchanged
    np.testing.assert_allclose(
        limited.gimbal_rates(x, 1e-3 * u), free.gimbal_rates(x, 1e-3 * u), rtol=1e-14
    )


def test_pseudo_inverse_refuses_a_singular_set_and_sr_passes_it_and_events_are_reported():
    saturated = np.deg2rad([-90.0, 180.0, 90.0, 0.0])  # V2: the +x envelope
    pi = CmgSpacecraft(J, 1.0, steering="pi")
    with pytest.raises(ValueError, match="steering='pi'.*steering='sr'"):
        pi.gimbal_rates(pi.state_from(gimbal_angles=saturated), [0.0, 0.0, 1.0])
    # V3 on the spacecraft: from zero gimbals the demand ḣ = +x (torque −x on the body, 0.5 N m)
    # reaches the internal singularity at |h| = 2cosδ h_r = 1.1546 N m s, i.e. t = 2.31 s;
    # the SR inverse carries the gimbals through it and the passage is reported as internal
    sr = CmgSpacecraft(J, 1.0, steering="sr", alpha=1e-3, gimbal_rate_limit=2.0)
    cfg = SimConfig(duration=4.0, control_rate=20.0, substeps=4)
    run = simulate(
        sr,
        ConstantTorque([-0.5, 0.0, 0.0]),
        cfg,
        n_cases=1,
        initial_state=sr.initial_state(1)[0],
        record_states=True,
    )
    X, t = run.dataset["state"].values[0], run.dataset.time.values
    events = sr.singularity_events(t, X, threshold=1e-3)
    assert len(events) == 1 and events[0].internal
    # the gain falls as (1 − |h|/1.1546): below 1e-3 within ~0.1 s of 2.31 s; the SR inverse
    # stalls the momentum near there, so the least gain comes a little later
    assert events[0].time == pytest.approx(2.0 * np.cos(cmg.SKEW) / 0.5, abs=0.15)
    assert all(np.isfinite(X).ravel())


def test_from_the_preferred_set_the_same_demand_ends_in_an_external_singularity():
    # the stored +x set (V4) under ḣ = +x at 0.5 N m s/s on the spacecraft: no internal
    # singularity; the gain falls below 1e-3 only at saturation, (2cosδ + 2)/0.5 = 6.31 s
    # (the body's small rates, |ω| <= 0.03 rad/s here, add ω × h, which the steering absorbs)
    sr = CmgSpacecraft(J, 1.0, steering="sr", alpha=1e-3, gimbal_rate_limit=2.0)
    x0 = sr.state_from(gimbal_angles=cmg.preferred_set([1.0, 0.0, 0.0]))
    cfg = SimConfig(duration=9.0, control_rate=20.0, substeps=4)
    run = simulate(
        sr, ConstantTorque([-0.5, 0.0, 0.0]), cfg, n_cases=1, initial_state=x0, record_states=True
    )
    X, t = run.dataset["state"].values[0], run.dataset.time.values
    events = sr.singularity_events(t, X, threshold=1e-3)
    assert len(events) == 1 and not events[0].internal
    assert events[0].time == pytest.approx((2 * np.cos(cmg.SKEW) + 2) / 0.5, abs=0.1)
    # the SR inverse holds the momentum on the envelope along x (it cannot give more)
    assert sr.cmg_momentum(X[-1])[0] == pytest.approx(cmg.envelope([1.0, 0.0, 0.0])[0], abs=1e-3)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(rotor_momentum=0.0), "rotor_momentum: must be one finite value > 0"),
        (dict(gimbal_rate_limit=0.0), "gimbal_rate_limit: must be > 0"),
        (dict(gimbal_rate_limit="-1 deg/s"), "gimbal_rate_limit: must be > 0"),
        (dict(steering="newton"), "steering: must be one of"),
        (dict(steering="sr", alpha=0.0), "alpha: the singularity-robust inverse needs alpha > 0"),
        (dict(skew="54.74 furlong"), "skew"),
        (dict(inertia=np.diag([1.0, 1.0, 3.0])), "inertia: principal moments"),
    ],
)
def test_bad_configuration_is_named(kwargs, message):
    args = dict(inertia=J, rotor_momentum=1.0) | kwargs
    with pytest.raises(ValueError, match=message):
        CmgSpacecraft(**args)


def test_bad_initial_gimbal_angles_are_named():
    plant = CmgSpacecraft(J, 1.0)
    with pytest.raises(ValueError, match="gimbal_angles: 4 finite angles"):
        plant.state_from(gimbal_angles=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="threshold: must be > 0"):
        plant.singularity_events([0.0], plant.initial_state(1), threshold=0.0)
