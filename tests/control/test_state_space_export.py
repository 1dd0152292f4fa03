"""Laws and plants as labelled python-control systems (issue 24): the discrete export is the
law that runs (its own commands reproduced), the continuous one the design; a TAMU hub plant's
Bode has its poles and zeros at the published exact frequencies; a three-axis AttitudeLQG loop
on a rigid spacecraft has its loop-at-input singular values and disk margins."""

import math

import numpy as np
import pytest

import control as ct
from flexsat.analysis.frequency_domain import build_loop, frequency_response
from flexsat.analysis.loop_modes import closed_loop_poles
from flexsat.analysis.margins import disk_margins, loop_margins
from flexsat.control import AttitudeLQG, LQGController
from flexsat.control.attitude_laws import QuaternionPD
from flexsat.control.linear_form import run_linear_law
from flexsat.control.lqg import zoh
from flexsat.control.pd import PD
from flexsat.control.ppf import PPFBank, PPFController
from flexsat.control.state_space_export import continuous_law, discrete_law
from flexsat.dynamics import RigidSpacecraft, linearize_attitude
from flexsat.dynamics.linear_model import plant_state_space
from flexsat.input_checks import FieldError

EPS = np.finfo(float).eps


def test_pd_exports_its_gain_with_labels_and_a_delay_of_d_samples():
    law = PD(3.0, 4.0)
    K = continuous_law(law)
    assert K.input_labels == ["theta", "theta_dot"] and K.output_labels == ["torque"]
    assert np.array_equal(K.D, [[-3.0, -4.0]]) and K.nstates == 0
    dt, d = 0.02, 3
    Kd = discrete_law(law, dt, delay=d)
    assert Kd.dt == dt and Kd.nstates == d
    w = np.linspace(0.1, math.pi / dt, 7)
    r = frequency_response(Kd, omega_rad_s=w).values[:, 0, :]
    want = np.array([-3.0, -4.0])[None, :] * np.exp(-1j * w * dt * d)[:, None]
    assert np.allclose(r, want, rtol=0, atol=10 * EPS * 4)


def ppf_law(dt=0.01):
    bank = PPFBank(omega_f=np.array([[5.0], [12.0]]), zeta_f=0.2)
    return PPFController(bank, [0.3, 0.5], dt=dt)


def test_ppf_discrete_export_is_the_zoh_of_the_continuous_and_runs_as_the_law():
    """The compensator discretised by the law (ZOH) equals python-control's c2d of the
    continuous export (same exponential, round-off), and the exported discrete system driven
    by a random measurement sequence gives exactly the law's own commands (run_linear_law)."""
    law = ppf_law()
    Kc, Kd = continuous_law(law), discrete_law(law, 0.01)
    assert Kc.input_labels == ["y1", "y2"] and Kd.output_labels == ["u1", "u2"]
    ref = ct.c2d(Kc, 0.01, "zoh")
    for a, b in zip((Kd.A, Kd.B, Kd.C, Kd.D), (ref.A, ref.B, ref.C, ref.D)):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-14)
    Y = np.random.default_rng(0).standard_normal((200, 1, 2))
    U = run_linear_law(law.linear_form(0.01, np.arange(200) * 0.01, 1), Y)[:, 0]
    resp = ct.forced_response(Kd, T=np.arange(200) * 0.01, U=Y[:, 0].T)
    assert np.allclose(resp.outputs.T, U, rtol=1e-12, atol=1e-12)


def hub():
    """θ'' = u/J, measured (θ, θ')."""
    return ct.ss(
        [[0, 1], [0, 0]],
        [[0], [0.5]],
        np.eye(2),
        0,
        states=["theta", "theta_dot"],
        inputs=["torque"],
        outputs=["theta", "theta_dot"],
        name="hub",
    )


def test_lqg_discrete_export_closes_the_loop_of_the_law():
    """The sampled loop of the exported LQG law has the eigenvalues of the law's own
    sampled-data closed-loop matrix (LQGController.closed_loop_matrix), to round-off; the
    continuous export is the textbook (A − BK − LC, L, −K)."""
    A, B, C = np.array([[0, 1], [0, 0.0]]), np.array([[0], [0.5]]), np.eye(2)
    law = LQGController.design((A, B, C), np.diag([10.0, 1.0]), 0.1, 1.0, 1e-3 * np.eye(2), 0.05)
    Kc = continuous_law(law)
    assert np.allclose(Kc.A, A - B @ law.K - law.L @ C, atol=1e-14)
    loop = build_loop(hub(), discrete_law(law, 0.05), "torque")
    got = np.sort_complex(loop.poles)
    want = np.sort_complex(np.linalg.eigvals(law.closed_loop_matrix()))
    assert np.allclose(got, want, atol=1e-10)
    assert loop.stable
    # the continuous design's loop: the separation principle's eigenvalues
    cont = build_loop(hub(), Kc, "torque")
    assert np.allclose(
        np.sort_complex(cont.poles),
        np.sort_complex(np.linalg.eigvals(law.continuous_closed_loop())),
        atol=1e-10,
    )


def test_nonlinear_and_discrete_laws_refused_by_name():
    with pytest.raises(FieldError, match="QuaternionPD is nonlinear"):
        discrete_law(QuaternionPD(1.0, 1.0), 0.1)
    with pytest.raises(FieldError, match="QuaternionPD has no continuous form"):
        continuous_law(QuaternionPD(1.0, 1.0))
    with pytest.raises(FieldError, match="kp: has 2 cases"):
        discrete_law(PD([1.0, 2.0], 1.0), 0.1)
    with pytest.raises(FieldError, match="dt"):
        discrete_law(PD(1.0, 1.0), -0.1)
    with pytest.raises(FieldError, match="Controller"):
        continuous_law(ct.ss([], [], [], [[1.0]]))


def test_tamu_hub_bode_poles_and_zeros_at_the_published_frequencies():
    """TAMU hub + four appendages (docs/tamu.md, exact distributed-parameter values): torque →
    θ has its resonances at the hub-free frequencies 3.4054, 10.7613, 27.2821, 54.4188 Hz and its
    antiresonances at the hub-clamped 0.7489, 8.2025, 25.782, 53.346 Hz (a collocated
    transfer's zeros are the constrained structure's frequencies). Tolerance: the printed
    digits and the 10-mode Galerkin error (< 2e-5 relative for these modes)."""
    from flexsat.cases.tamu import tamu

    P = plant_state_space(tamu().model(), outputs=["theta"])
    poles = np.linalg.eigvals(P.A)
    zeros = ct.zeros(P)
    pole_hz = np.sort(np.abs(poles[poles.imag > 0]))[:4] / (2 * math.pi)
    zero_hz = np.sort(np.abs(zeros[zeros.imag > 0]))[:4] / (2 * math.pi)
    assert pole_hz == pytest.approx([3.4054, 10.7613, 27.2821, 54.4188], rel=1e-4)
    assert zero_hz == pytest.approx([0.7489, 8.2025, 25.782, 53.346], rel=1e-4)
    # on the Bode magnitude: a peak near each pole, a notch near each zero (±0.5 % windows; a
    # ζ = 0.005 resonance beside a zero peaks within 0.2 % of |p|)
    for f, kind in [(f, "peak") for f in pole_hz] + [(f, "notch") for f in zero_hz]:
        w = 2 * math.pi * f * np.linspace(0.995, 1.005, 2001)
        mag = np.abs(frequency_response(P, omega_rad_s=w).values[:, 0, 0])
        k = np.argmax(mag) if kind == "peak" else np.argmin(mag)
        assert 0 < k < len(w) - 1, f"no {kind} near {f:.4f} Hz"
        assert w[k] / (2 * math.pi) == pytest.approx(f, rel=2e-3)


def test_plant_export_refusals():
    from flexsat.cases.tamu import tamu

    plant = tamu().model()
    with pytest.raises(FieldError, match="'pitch' is not an output"):
        plant_state_space(plant, outputs=["pitch"])
    with pytest.raises(FieldError, match="states"):
        plant_state_space(plant, states=["a"])


def test_three_axis_attitude_lqg_loop_at_input():
    """AttitudeLQG on a rigid spacecraft (J with products of inertia), MRP errors, 10 Hz:
    the sampled loop at the plant input is 3 × 3; its closed-loop poles are those of the law's
    sampled-data loop (z-plane); σ̄ of L falls through 1 once per axis; loop-at-a-time disk
    margins exceed the multiloop one, which guarantees a simultaneous ±gain and phase
    variation on the three torques; each axis broken alone has finite classical margins."""
    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    lin = linearize_attitude(RigidSpacecraft(J), "mrp")
    Q = np.diag([1600.0] * 3 + [10.0] * 3)
    law = AttitudeLQG.design(
        lin, Q, 1e-3 * np.eye(3), np.eye(3), np.diag([1e-6] * 3 + [1e-4] * 3), 0.1
    )
    P = lin.to_statespace("rigid")
    loop = build_loop(P, discrete_law(law, 0.1), "input")
    assert loop.transfer.input_labels == ["torque[0]", "torque[1]", "torque[2]"]
    Phi, Gam = zoh(lin.A, lin.B, 0.1)
    Pe, Gu, Gy = law.estimator
    M = np.block([[Phi, -Gam @ law.K], [Gy @ lin.C, Pe - Gu @ law.K]])
    assert np.allclose(
        np.sort_complex(loop.poles), np.sort_complex(np.linalg.eigvals(M)), atol=1e-10
    )
    w = np.geomspace(1e-3, math.pi / 0.1, 400)
    sv = frequency_response(loop.transfer, omega_rad_s=w).singular_values()
    assert sv.shape == (400, 3) and np.all(sv[0] > 1) and np.all(sv[-1] < 1)
    per_channel, multi = disk_margins(loop)
    assert len(per_channel) == 3 and all(d.alpha >= multi.alpha * (1 - 1e-9) for d in per_channel)
    assert 0 < multi.alpha < 2 and multi.gain_range[0] < 1 < multi.gain_range[1]
    for axis in range(3):
        m = loop_margins(build_loop(P, discrete_law(law, 0.1), f"torque[{axis}]"))
        assert 0 < m.phase_margin_deg < 90 and m.gain_margin > 1
    modes = {p.mode for p in closed_loop_poles(loop)}
    assert {"sigma[0]", "rate_error[0]"} & modes


def test_tamu_open_loop_poles_belong_to_the_cantilever_coordinates_in_order():
    """With a law of negligible gain the closed loop is the plant: the rigid pole is θ's, and
    the k-th elastic pair is carried (participation > 0.9) by the k-th cantilever coordinate
    q[k] — the hub-free modes of a light hub are each close to one clamped shape."""
    from flexsat.analysis.loop_modes import damping_table
    from flexsat.cases.tamu import tamu

    n = 10
    states = ["theta"] + [f"q[{i}]" for i in range(n)] + ["theta_dot"]
    states += [f"q_dot[{i}]" for i in range(n)]
    P = plant_state_space(tamu().model(), states=states)
    K = ct.ss([], [], [], [[-1e-9, -1e-9]], inputs=["theta", "theta_dot"], outputs=["torque"])
    poles = [p for p in closed_loop_poles(build_loop(P, K, "torque")) if p.pole.imag >= 0]
    assert poles[0].mode == "theta"
    elastic = [p for p in poles if p.natural_frequency_rad_s > 1.0]
    assert [p.mode for p in elastic] == [f"q[{i}]" for i in range(n)]
    assert all(p.participation > 0.9 and p.plant_share == pytest.approx(1.0) for p in elastic)
    assert "q[3]" in damping_table(poles)
    with pytest.raises(FieldError, match="modes.*'nope'"):
        closed_loop_poles(build_loop(P, K, "torque"), modes={"m": ["nope"]})


def test_loop_figure_draws_the_computed_response():
    """The helper's Bode magnitude line is |L| at the frequencies asked (in Hz on the axis)."""
    from flexsat.analysis.frequency_plots import loop_figure

    loop = build_loop(hub(), discrete_law(PD(3.0, 4.0), 0.05, delay=1), "torque")
    w = np.geomspace(0.01, math.pi / 0.05, 50)
    fig = loop_figure(loop, omega_rad_s=w, frequency_unit="Hz", title="hub")
    ax = fig.axes[0]
    x, y = ax.lines[0].get_data()
    assert np.allclose(x, w / (2 * math.pi))
    assert np.allclose(y, np.abs(frequency_response(loop.transfer, omega_rad_s=w).values[:, 0, 0]))
    assert "Hz" in fig.axes[2].get_xlabel()
    with pytest.raises(FieldError, match="frequency_unit"):
        loop_figure(loop, frequency_unit="rpm")
    with pytest.raises(FieldError, match="delay"):
        build_loop(hub(), discrete_law(PD(3.0, 4.0), 0.05), "torque", delay=-1)
