"""Simulation-core benchmarks of issue #10: the compiled closed-loop kernel
(flexsat.sim.kernels) against python-control's ``forced_response`` and Basilisk.

Run with ``python benchmarks/bench_core.py`` (``--write`` also updates docs/performance.md,
``--no-basilisk`` skips (d)). A plain script, never collected as a test. Every ratio comes from
timings taken side by side in one run, each the best of N calls.

(a) Single TAMU maneuver, 10 modes per appendage, 15 s at 75 Hz, Control Law I
    u = −g1 (θ − θ_f) − g2 θ' − g3 M_root (root torque linear in x and the held input): the
    kernel called with the plant's matrices, against python-control's ``forced_response`` of
    the same discrete closed loop (state [x; w_prev], so the root-torque feedthrough of the
    held input is exact); checked to agree. Also with friction and noise (the TAMU hardware
    settings: bearing friction, 0.01° encoder + least-squares rate, 5 oz-in random torque).
(b) 1,000 cases (g1 dispersed ±20 %), friction and noise: µs per case-step, serial and
    parallel, and memory per case (the kernel's per-case inputs and records).
(c) 100 modes per appendage: the kernel in modal coordinates (ModalPropagator, O(n) per step)
    against ``forced_response`` of the 203-state closed loop.
(d) Basilisk: a hub with four hinged rigid panels (hingedRigidBodyStateEffector, torsional
    spring each) under MRP PD (mrpFeedback), dynamics and control at 75 Hz (RK4), against the
    kernel on the same vehicle linearised about rest (3 rotations, 3 translations, 4 hinges).
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import re
import sys
import textwrap
import time
from pathlib import Path

# one BLAS thread, set before numpy loads: on a shared 2-core machine OpenBLAS threads spin
# against the other jobs (the 100-mode modal set-up took 20 s with them, 0.03 s without), and
# every baseline here works on small matrices, fastest single-threaded
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import control  # noqa: E402
from bench_tamu import best_of  # noqa: E402  (one timing helper for every benchmark)
from flexsat.cases.tamu import tamu  # noqa: E402
from flexsat.sim.engine import stable_substeps  # noqa: E402
from flexsat.sim.integrators import (  # noqa: E402
    ExponentialStepper,
    ModalPropagator,
    modal_coordinates,
    phi_products,
)
from flexsat.sim.kernels import (  # noqa: E402
    ARGUMENTS,
    Loop,
    allocate_records,
    closed_loop,
    closed_loop_parallel,
)
from flexsat.sim.sensors import least_squares_derivative_weights  # noqa: E402
from flexsat.units import to_si  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "performance.md"
SECTION = "## Simulation core (issue #10)"

DURATION, RATE = 15.0, 75.0
G1 = to_si("600 ozf*in/rad", "N*m/rad")  # Law I gains of cases/tamu_default.yaml
G2 = to_si("800 ozf*in*s/rad", "N*m*s/rad")
G3 = 1.0  # root-torque feedback on, so the feedthrough path is exercised
BOUND = 1e12


# ------------------------------------------------------------------------------------------
# TAMU closed loop as kernel arrays


def no_rows(n, m):
    """The kernel's output-row and energy arguments when it records neither (the kernel-only
    benchmarks time the loop with its state record, as before the in-loop records)."""
    return dict(
        Co=np.zeros((1, 0, n)), Do=np.zeros((1, 0, m)), Dof=np.zeros((1, 0)), Q=np.zeros((0, n, n))
    )


def measurement_matrices(plant):
    """(C, D, Df) with [θ, θ', M_root] = C x + D w + Df f: the plant's outputs are linear in
    x, the hub torque w and the friction torque f; read off on unit vectors."""
    n = plant.nx
    names = ("theta", "theta_dot", "root_torque")

    def out(x, u, f):
        o = plant.outputs(
            x[None], np.array([u]), np.multiply.outer(np.array([f]), plant.torque_input)
        )
        return np.array([o[k][0] for k in names])

    C = np.column_stack([out(np.eye(n)[j], 0.0, 0.0) for j in range(n)])
    return C, out(np.zeros(n), 1.0, 0.0)[:, None], out(np.zeros(n), 0.0, 1.0)


def tamu_problem(
    n_modes=10, friction=False, noise=False, n_cases=1, modal=False, dispersion=0.0, seed=0
):
    """Kernel arguments for Law I on the TAMU plant (dense or modal propagation)."""
    case = tamu(n_modes=n_modes)
    plant = case.model()
    cfg = case.sim_config(DURATION, friction=friction, noise=noise)
    dt, n_t = cfg.dt, cfg.n_steps + 1
    A, Bu, Bf = plant.state_space
    n, ndof = plant.nx, plant.ndof
    fr = cfg.friction
    substeps = stable_substeps(plant, fr, dt, cfg.substeps) if fr.active else 1
    bf = Bf[:, :1] if fr.active else None
    C, D, Df = measurement_matrices(plant)
    rate = np.zeros(n)
    rate[ndof] = 1.0
    T = Tinv = np.eye(n)
    if modal:
        T, Tinv, omega, zeta = modal_coordinates(
            plant.mass_matrix, plant.stiffness_matrix, plant.damping_matrix
        )
        prop = ModalPropagator.build(
            omega, zeta, Tinv @ Bu, dt, substeps, None if bf is None else Tinv @ bf
        )
        E, P1u = prop.E, prop.P1u
        P1f, P2f = (None, None) if bf is None else (prop.P1f[:, 0], prop.P2f[:, 0])
    else:
        st = ExponentialStepper.build(A, Bu, bf, dt, substeps)
        E, P1u = st.Et.T.copy(), st.P1u.T  # (m, n) stored transposed -> the kernel's (n, m)
        P1f, P2f = (None, None) if bf is None else (st.P1f[0], st.P2f[0])
    s = cfg.sensors
    sensor = np.zeros((1, 3, 4))
    sensor[0, :, 3] = np.inf
    sensor[0, 0, 0] = s.encoder_resolution
    fir = s.rate == "ls_filter"
    std = cfg.random_torque.std
    rng_noise = np.empty((n_cases, n_t, 1))
    for c in range(n_cases):  # one stream per case seed
        rng_noise[c] = np.random.default_rng(seed + c).standard_normal((n_t, 1))
    g1 = G1 * (1 + dispersion * np.linspace(-1, 1, n_cases))
    Dk = np.zeros((1, n_cases, 1, 3))
    Dk[0, :, 0, 0], Dk[0, :, 0, 1], Dk[0, :, 0, 2] = -g1, -G2, -G3
    theta_f = case.angle
    x0 = np.zeros((n_cases, n))
    args = dict(
        x0=x0 @ Tinv.T,
        E=E[None].copy(),
        block_diagonal=modal,
        P1u=P1u[None].copy(),
        P1f=np.zeros((0, n)) if P1f is None else P1f[None].copy(),
        P2f=np.zeros((0, n)) if P2f is None else P2f[None].copy(),
        Cr=(rate @ T)[None],
        fric=np.array([[fr.coulomb, fr.viscous, fr.smoothing]]),
        substeps=substeps,
        imp_k=np.zeros(0, np.int64),
        imp_dx=np.zeros((0, 1, n)),
        Cm=(C @ T)[None],
        Dm=D[None],
        Dmf=Df[None],
        sensor=sensor,
        sensor_slot=np.array([-1, -1, -1]),
        fir_src=0 if fir else -1,
        fir_dst=1,
        fir_w=least_squares_derivative_weights(s.rate_window, s.rate_order, dt)
        if fir
        else np.zeros(0),
        Ak=np.zeros((1, 1, 0, 0)),
        Bk=np.zeros((1, 1, 0, 3)),
        Ck=np.zeros((1, 1, 1, 0)),
        Dk=Dk,
        y_ref=np.tile([theta_f, 0.0, 0.0], (n_t, 1, 1)),
        u_ff=np.zeros((n_t, 1, 1)),
        K0=np.zeros((0, 0, 3)),
        act=np.array(
            [
                [
                    [
                        cfg.actuator.saturation if (friction or noise) else np.inf,
                        cfg.actuator.torque_constant_ratio,
                    ]
                ]
            ]
        ),
        dist_std=np.array([[std]]),
        dist_slot=np.array([0 if std > 0 else -1]),
        noise=rng_noise,
        bound=BOUND,
        **no_rows(n, 1),
    )
    return args, dict(
        plant=plant, T=T, A=A, Bu=Bu, C=C, D=D, dt=dt, n_t=n_t, theta_f=theta_f, substeps=substeps
    )


def run_kernel(args, parallel=False, record_states=False, rec=None):
    """One kernel call; ``rec``: caller-provided record arrays (reused: no allocation)."""
    n_t, (nc, n) = args["y_ref"].shape[0], args["x0"].shape
    if rec is None:
        rec = allocate_records(n_t, nc, n, 1, 3, record_states)
    (closed_loop_parallel if parallel else closed_loop)(Loop(*(args[k] for k in ARGUMENTS)), rec)
    return rec


def python_control_loop(info):
    """The same linear discrete closed loop for ``forced_response``: state s = [x; w_prev],
    w_k = K s_k + g1 θ_f, x_{k+1} = Φ x_k + Γ w_k."""
    A, Bu, C, D, dt = info["A"], info["Bu"], info["C"], info["D"], info["dt"]
    n = A.shape[0]
    Phi, Gam, _ = phi_products(A, dt, Bu[:, None])
    gains = np.array([-G1, -G2, -G3])
    Kx, Kw = gains @ C, float(gains @ D[:, 0])
    Acl = np.zeros((n + 1, n + 1))
    Acl[:n, :n] = Phi + Gam @ Kx[None]
    Acl[:n, n] = Gam[:, 0] * Kw
    Acl[n, :n], Acl[n, n] = Kx, Kw
    Bcl = np.concatenate([Gam[:, 0] * G1, [G1]])[:, None]
    sys_cl = control.ss(Acl, Bcl, np.eye(n + 1), np.zeros((n + 1, 1)), dt)
    t = dt * np.arange(info["n_t"])
    u = np.full((1, t.size), info["theta_f"])

    def run():
        return control.forced_response(sys_cl, T=t, U=u, X0=np.zeros(n + 1)).states

    return run


# ------------------------------------------------------------------------------------------
def bench_single(repeat):
    rows = {}
    args, info = tamu_problem(10)
    run_kernel(args, record_states=True)  # compile (cached on disk after the first run)
    t_k, _, rec = best_of(lambda: run_kernel(args, record_states=True), repeat)
    pc = python_control_loop(info)
    t_pc, _, states = best_of(pc, max(3, repeat // 5))
    steps = info["n_t"] - 1
    states = np.asarray(states)
    agree = float(np.abs(rec[0][0].T - states[:-1]).max() / np.abs(states[:-1]).max())
    argsm, infom = tamu_problem(10, modal=True)
    run_kernel(argsm)
    t_km, _, recm = best_of(lambda: run_kernel(argsm), repeat)
    argsf, infof = tamu_problem(10, friction=True, noise=True)
    t_kf, _, _ = best_of(lambda: run_kernel(argsf), repeat)
    argsfm, _ = tamu_problem(10, friction=True, noise=True, modal=True)
    t_kfm, _, _ = best_of(lambda: run_kernel(argsfm), repeat)
    rows["a"] = dict(
        kernel=t_k / steps,
        kernel_modal=t_km / steps,
        pc=t_pc / steps,
        full=t_kf / steps,
        full_modal=t_kfm / steps,
        agree=agree,
        substeps=infof["substeps"],
        n=info["plant"].nx,
    )
    return rows


def bench_batch(repeat, n_cases=1000):
    # modal propagation: the O(n) step (22 states here)
    args, info = tamu_problem(
        10, friction=True, noise=True, n_cases=n_cases, dispersion=0.2, modal=True
    )
    steps = info["n_t"] - 1
    n_t, n = info["n_t"], info["plant"].nx
    # the engine passes its own record arrays: time the loop on reused ones (fresh memory
    # costs its first-touch page faults, reported separately)
    rec_s = allocate_records(n_t, n_cases, n, 1, 3, False)
    rec_p = allocate_records(n_t, n_cases, n, 1, 3, False)
    run_kernel(args, parallel=True, rec=rec_p)
    t_ser, _, _ = best_of(lambda: run_kernel(args, rec=rec_s), repeat)
    cpu = []  # CPU time of the serial loop: its cost without the other jobs on a shared machine
    for _ in range(repeat):
        c0 = time.thread_time()
        run_kernel(args, rec=rec_s)
        cpu.append(time.thread_time() - c0)
    t_par, _, _ = best_of(lambda: run_kernel(args, parallel=True, rec=rec_p), repeat)
    same = all(np.array_equal(a, b) for a, b in zip(rec_s, rec_p))
    # the arrays with a case axis: noise streams, initial states, gains, and the records
    per_case = sum(args[k].nbytes for k in ("noise", "x0", "Dk")) + sum(r.nbytes for r in rec_s)
    linear, _ = tamu_problem(10, n_cases=n_cases, dispersion=0.2, modal=True)
    t_lin, _, _ = best_of(lambda: run_kernel(linear, rec=rec_s), repeat)
    t_lin_par, _, _ = best_of(lambda: run_kernel(linear, parallel=True, rec=rec_p), repeat)
    t_lin_fresh, _, _ = best_of(lambda: run_kernel(linear), repeat)
    cpu_lin = []
    for _ in range(repeat):
        c0 = time.thread_time()
        run_kernel(linear, rec=rec_s)
        cpu_lin.append(time.thread_time() - c0)
    big, _ = tamu_problem(10, n_cases=10 * n_cases, dispersion=0.2, modal=True)
    rec_big = allocate_records(n_t, 10 * n_cases, n, 1, 3, False)
    run_kernel(big, rec=rec_big)
    t_big, _, _ = best_of(lambda: run_kernel(big, rec=rec_big), 2)
    return dict(
        serial=t_ser / (steps * n_cases),
        parallel=t_par / (steps * n_cases),
        big=t_big / (steps * 10 * n_cases),
        serial_cpu=min(cpu) / (steps * n_cases),
        linear_cpu=min(cpu_lin) / (steps * n_cases),
        linear_parallel=t_lin_par / (steps * n_cases),
        linear_fresh=t_lin_fresh / (steps * n_cases),
        linear=t_lin / (steps * n_cases),
        memory=per_case / n_cases,
        same=same,
        threads=int(os.environ.get("NUMBA_NUM_THREADS", os.cpu_count())),
    )


def bench_modes(repeat, n_modes=100):
    args, info = tamu_problem(n_modes, modal=True)
    run_kernel(args, record_states=True)
    t_m, _, rec = best_of(lambda: run_kernel(args, record_states=True), repeat)
    dense, _ = tamu_problem(n_modes)
    t_d, _, _ = best_of(lambda: run_kernel(dense), max(3, repeat // 5))
    pc = python_control_loop(info)
    t_pc, _, states = best_of(pc, 3)
    steps = info["n_t"] - 1
    plant = info["plant"]
    A, Bu = info["A"], info["Bu"]

    def modal_setup():
        T, Tinv, omega, zeta = modal_coordinates(
            plant.mass_matrix, plant.stiffness_matrix, plant.damping_matrix
        )
        return ModalPropagator.build(omega, zeta, Tinv @ Bu, info["dt"])

    t_set_m, _, _ = best_of(modal_setup, 3)
    t_set_d, _, _ = best_of(lambda: phi_products(A, info["dt"], Bu[:, None]), 3)
    x = rec[0][0] @ info["T"].T
    states = np.asarray(states)
    agree = float(np.abs(x.T - states[:-1]).max() / np.abs(states[:-1]).max())
    return dict(
        modal=t_m / steps,
        dense=t_d / steps,
        pc=t_pc / steps,
        agree=agree,
        n=info["plant"].nx,
        setup_modal=t_set_m,
        setup_dense=t_set_d,
    )


# ------------------------------------------------------------------------------------------
# (d) four hinged panels: one vehicle description for Basilisk and for the linear model
HUB_MASS, HUB_INERTIA = 750.0, np.diag([900.0, 800.0, 600.0])
PANEL_MASS, PANEL_D, PANEL_K, PANEL_C = 100.0, 1.5, 100.0, 0.5
PANEL_INERTIA = np.diag([100.0, 50.0, 50.0])  # about the panel's center of mass, panel frame
#: hinge point in the body frame and dcm_HB (body to hinge frame); the panel's center of mass
#: sits at r_H − d ĥ1 and it turns about ĥ2
PANELS = (
    ((0.5, 0.0, 1.0), ((-1, 0, 0), (0, -1, 0), (0, 0, 1))),
    ((-0.5, 0.0, 1.0), ((1, 0, 0), (0, 1, 0), (0, 0, 1))),
    ((0.0, 0.5, 1.0), ((0, -1, 0), (1, 0, 0), (0, 0, 1))),
    ((0.0, -0.5, 1.0), ((0, 1, 0), (-1, 0, 0), (0, 0, 1))),
)
MRP_K, MRP_P = 3.5, 30.0  # mrpFeedback gains: L = −K σ − P ω (Ki < 0: no integral term)
SIGMA0 = np.array([0.01, -0.02, 0.015])


def panels_linear_model():
    """Hub + 4 hinged panels linearised about rest: q = [r (3), φ (3), θ_1..4],
    M = Σ Jᵀ diag(m, I) J over the bodies (J their rest velocity Jacobians), K, C on the
    hinges; input the body torque on the hub (3)."""

    def skew(v):
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    nq = 10
    M = np.zeros((nq, nq))
    J = np.zeros((6, nq))
    J[:3, :3], J[3:, 3:6] = np.eye(3), np.eye(3)
    M += J.T @ np.diag(np.r_[np.full(3, HUB_MASS), 0, 0, 0]) @ J
    M[3:6, 3:6] += HUB_INERTIA
    for i, (r_h, dcm) in enumerate(PANELS):
        dcm = np.array(dcm, float)
        h1, h2 = dcm[0], dcm[1]  # hinge-frame axes in the body frame
        rho = np.array(r_h) - PANEL_D * h1
        J = np.zeros((6, nq))
        J[:3, :3] = np.eye(3)
        J[:3, 3:6] = -skew(rho)
        J[:3, 6 + i] = np.cross(h2, -PANEL_D * h1)
        J[3:, 3:6] = np.eye(3)
        J[3:, 6 + i] = h2
        Ip = dcm.T @ PANEL_INERTIA @ dcm
        W = np.zeros((6, 6))
        W[:3, :3], W[3:, 3:] = PANEL_MASS * np.eye(3), Ip
        M += J.T @ W @ J
    K = np.diag(np.r_[np.zeros(6), np.full(4, PANEL_K)])
    Cd = np.diag(np.r_[np.zeros(6), np.full(4, PANEL_C)])
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((nq, nq)), np.eye(nq)], [-Minv @ K, -Minv @ Cd]])
    Bq = np.zeros((nq, 3))
    Bq[3:6] = np.eye(3)
    return A, np.vstack([np.zeros((nq, 3)), Minv @ Bq])


def panels_problem():
    A, B = panels_linear_model()
    n, dt = A.shape[0], 1 / RATE
    n_t = int(round(DURATION * RATE)) + 1
    E, P1, _ = phi_products(A, dt, B)
    Cm = np.zeros((1, 6, n))
    Cm[0, :3, 3:6] = 0.25 * np.eye(3)  # σ ≈ φ/4 for a small rotation
    Cm[0, 3:, 13:16] = np.eye(3)  # ω
    Dk = np.zeros((1, 1, 3, 6))
    Dk[0, 0, :, :3], Dk[0, 0, :, 3:] = -MRP_K * np.eye(3), -MRP_P * np.eye(3)
    x0 = np.zeros((1, n))
    x0[0, 3:6] = 4 * SIGMA0
    args = dict(
        x0=x0,
        E=E[None],
        block_diagonal=False,
        P1u=P1[None],
        P1f=np.zeros((0, n)),
        P2f=np.zeros((0, n)),
        Cr=np.zeros((0, n)),
        fric=np.zeros((1, 3)),
        substeps=1,
        imp_k=np.zeros(0, np.int64),
        imp_dx=np.zeros((0, 1, n)),
        Cm=Cm,
        Dm=np.zeros((1, 6, 3)),
        Dmf=np.zeros((1, 6)),
        sensor=np.tile([0.0, 0.0, 0.0, np.inf], (1, 6, 1)),
        sensor_slot=np.full(6, -1),
        fir_src=-1,
        fir_dst=0,
        fir_w=np.zeros(0),
        Ak=np.zeros((1, 1, 0, 0)),
        Bk=np.zeros((1, 1, 0, 6)),
        Ck=np.zeros((1, 1, 3, 0)),
        Dk=Dk,
        y_ref=np.zeros((n_t, 1, 6)),
        u_ff=np.zeros((n_t, 1, 3)),
        K0=np.zeros((0, 0, 6)),
        act=np.tile([np.inf, 1.0], (1, 3, 1)),
        dist_std=np.zeros((1, 3)),
        dist_slot=np.full(3, -1),
        noise=np.zeros((1, n_t, 1)),
        bound=BOUND,
        **no_rows(n, 3),
    )
    return args, n_t


def run_panels_kernel(args, n_t):
    rec = allocate_records(n_t, 1, args["x0"].shape[1], 3, 6, False)
    closed_loop(Loop(*(args[k] for k in ARGUMENTS)), rec)
    return rec


def basilisk_run(record: bool):
    """Basilisk scenario: spacecraft hub + 4 hingedRigidBodyStateEffector, simpleNav,
    inertial3D + attTrackingError, mrpFeedback, extForceTorque; one task at 75 Hz."""
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import attTrackingError, inertial3D, mrpFeedback
    from Basilisk.simulation import (
        extForceTorque,
        hingedRigidBodyStateEffector,
        simpleNav,
        spacecraft,
    )
    from Basilisk.utilities import SimulationBaseClass, macros

    sim = SimulationBaseClass.SimBaseClass()
    proc = sim.CreateNewProcess("proc")
    proc.addTask(sim.CreateNewTask("task", macros.sec2nano(1 / RATE)))
    sc = spacecraft.Spacecraft()
    sc.hub.mHub = HUB_MASS
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = HUB_INERTIA.tolist()
    sc.hub.sigma_BNInit = [[s] for s in SIGMA0]
    sc.hub.omega_BN_BInit = [[0.0], [0.0], [0.0]]
    panels = []
    for r_h, dcm in PANELS:
        p = hingedRigidBodyStateEffector.HingedRigidBodyStateEffector()
        p.mass, p.d, p.k, p.c = PANEL_MASS, PANEL_D, PANEL_K, PANEL_C
        p.IPntS_S = PANEL_INERTIA.tolist()
        p.r_HB_B = [[v] for v in r_h]
        p.dcm_HB = [list(map(float, row)) for row in dcm]
        p.thetaInit, p.thetaDotInit = 0.0, 0.0
        sc.addStateEffector(p)
        panels.append(p)
    sim.AddModelToTask("task", sc)
    ext = extForceTorque.ExtForceTorque()
    sc.addDynamicEffector(ext)
    sim.AddModelToTask("task", ext)
    nav = simpleNav.SimpleNav()
    nav.scStateInMsg.subscribeTo(sc.scStateOutMsg)
    sim.AddModelToTask("task", nav)
    ref = inertial3D.inertial3D()
    ref.sigma_R0N = [0.0, 0.0, 0.0]
    sim.AddModelToTask("task", ref)
    err = attTrackingError.attTrackingError()
    err.attNavInMsg.subscribeTo(nav.attOutMsg)
    err.attRefInMsg.subscribeTo(ref.attRefOutMsg)
    sim.AddModelToTask("task", err)
    ctl = mrpFeedback.mrpFeedback()
    ctl.guidInMsg.subscribeTo(err.attGuidOutMsg)
    veh = messaging.VehicleConfigMsgPayload()
    veh.ISCPntB_B = HUB_INERTIA.ravel().tolist()
    veh_msg = messaging.VehicleConfigMsg().write(veh)
    ctl.vehConfigInMsg.subscribeTo(veh_msg)
    ctl.K, ctl.Ki, ctl.P = MRP_K, -1.0, MRP_P
    sim.AddModelToTask("task", ctl)
    ext.cmdTorqueInMsg.subscribeTo(ctl.cmdTorqueOutMsg)
    rec = None
    if record:
        rec = sc.scStateOutMsg.recorder()
        sim.AddModelToTask("task", rec)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(DURATION))
    t0 = time.perf_counter()
    sim.ExecuteSimulation()
    wall = time.perf_counter() - t0
    return wall, (None if rec is None else np.array(rec.sigma_BN))


def bench_basilisk(repeat):
    args, n_t = panels_problem()
    run_panels_kernel(args, n_t)
    t_k, _, rec = best_of(lambda: run_panels_kernel(args, n_t), repeat)
    steps = n_t - 1
    walls = [basilisk_run(False)[0] for _ in range(max(3, repeat // 10))]
    _, sigma = basilisk_run(True)
    # σ ≈ φ/4 recorded as Y[0, :, :3]; Basilisk records after each step: compare the shared
    # samples (a check that the two vehicles are the same, to the linearisation error)
    ours = rec[1][0, :, :3]
    k = min(len(sigma), len(ours))
    diff = np.abs(sigma[:k] - ours[:k]).max() / np.abs(SIGMA0).max()
    return dict(kernel=t_k / steps, bsk=min(walls) / steps, diff=diff)


# ------------------------------------------------------------------------------------------
def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numba

    return (
        f"{cpu}, {os.cpu_count()} cores (shared); OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS')}; Python {platform.python_version()}, "
        f"numpy {np.__version__}, numba {numba.__version__}, python-control "
        f"{control.__version__}"
    )


def report(a, b, c, d, repeat) -> str:
    us = 1e6
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [
        SECTION,
        "",
        f"Measured {_dt.date.today()} on {machine()}, load average {load:.1f} during the "
        f"run; `python benchmarks/bench_core.py` "
        f"(best of {repeat}; the ratios from the same run). Kernel: "
        "`flexsat.sim.kernels.closed_loop` (numba), called with the plant's matrices and "
        "the law in its linear form; per control step = loop time / 1,125 steps "
        "(15 s at 75 Hz), the propagator set-up excluded on both sides.",
        "",
        "| benchmark | flexsat kernel | baseline | ratio | budget |",
        "|---|---|---|---|---|",
    ]
    lines.append(
        f"| (a) TAMU Law I, {a['n']} states, linear | {a['kernel'] * us:.2f} µs/step "
        f"(modal: {a['kernel_modal'] * us:.2f}) | python-control `forced_response` "
        f"{a['pc'] * us:.2f} µs/step | {a['pc'] / a['kernel']:.1f}× | ≤ 5 µs, ≥ 1× |"
    )
    lines.append(
        f"| (a) same, friction ({a['substeps']} substeps) + encoder + LS rate + random "
        f"torque | {a['full'] * us:.2f} µs/step (modal: {a['full_modal'] * us:.2f}) "
        f"| — | — | ≤ 10 µs |"
    )
    lines.append(
        f"| (b) 1,000 cases, modal, linear | {b['linear'] * us:.3f} µs/case-step serial "
        f"(CPU {b['linear_cpu'] * us:.3f}), {b['linear_parallel'] * us:.3f} on "
        f"{b['threads']} threads | engine today 0.5 | "
        f"{0.5 / (b['linear_parallel'] * us):.1f}× | ≤ 0.1 µs |"
    )
    lines.append(
        f"| (b) same, records freshly allocated | {b['linear_fresh'] * us:.3f} "
        f"µs/case-step serial | — | — | — |"
    )
    lines.append(
        f"| (b) 10,000 cases, modal, linear | {b['big'] * us:.3f} µs/case-step serial "
        f"| 1,000 cases: {b['linear'] * us:.3f} | {b['big'] / b['linear']:.2f} | "
        f"linear scaling |"
    )
    lines.append(
        f"| (b) 1,000 cases, modal, friction + noise | {b['serial'] * us:.3f} "
        f"µs/case-step serial (CPU {b['serial_cpu'] * us:.3f}), "
        f"{b['parallel'] * us:.3f} on {b['threads']} threads | — | — | — |"
    )
    lines.append(
        f"| (b) memory per case (inputs + default records) | "
        f"{b['memory'] / 1e3:.0f} kB | engine today 320 kB | — | ≤ 150 kB |"
    )
    lines.append(
        f"| (c) 100 modes per appendage, {c['n']} states | {c['modal'] * us:.2f} µs/step "
        f"modal (dense {c['dense'] * us:.1f}) | `forced_response` "
        f"{c['pc'] * us:.1f} µs/step | {c['pc'] / c['modal']:.1f}× | ≥ 3× |"
    )
    if d is not None:
        lines.append(
            f"| (d) hub + 4 hinged panels, MRP PD, 75 Hz | {d['kernel'] * us:.2f} µs/step "
            f"| Basilisk {d['bsk'] * us:.1f} µs/step | {d['bsk'] / d['kernel']:.0f}× "
            f"| ≥ 5× |"
        )
    budgets = [
        ("(a) ≤ 5 µs per step", a["kernel"] * us <= 5),
        ("(a) ≥ 1× python-control", a["pc"] / a["kernel"] >= 1),
        ("(a) ≤ 10 µs with friction and noise", a["full"] * us <= 10),
        ("(b) ≤ 0.1 µs per case-step", min(b["linear"], b["linear_parallel"]) * us <= 0.1),
        ("(b) ≤ 150 kB per case", b["memory"] <= 150e3),
        ("(c) ≥ 3× python-control", c["pc"] / c["modal"] >= 3),
    ]
    if d is not None:
        budgets.append(("(d) ≥ 5× Basilisk", d["bsk"] / d["kernel"] >= 5))
    met = [name for name, ok in budgets if ok]
    missed = [name for name, ok in budgets if not ok]
    lines += [
        "",
        "Budgets of the issue met: "
        + "; ".join(met)
        + "."
        + ("" if not missed else " Missed: " + "; ".join(missed) + "."),
    ]
    lines += [
        "",
        f"Checks in the same run: (a) kernel and `forced_response` states agree to "
        f"{a['agree']:.1e} relative; (b) parallel records bit-identical to serial: "
        f"{b['same']}; (c) modal kernel vs `forced_response` of the physical closed "
        f"loop: {c['agree']:.1e} relative over the 1,125 steps. Set-up at 100 modes "
        f"(excluded above): modal coordinates + block propagators "
        f"{c['setup_modal'] * 1e3:.0f} ms, the dense exponential "
        f"{c['setup_dense'] * 1e3:.0f} ms; set-up included, one 100-mode maneuver "
        f"costs {(c['modal'] * 1125 + c['setup_modal']) * 1e3:.0f} ms modal against "
        f"{(c['pc'] * 1125 + c['setup_dense']) * 1e3:.0f} ms for `forced_response` "
        f"(ratio {(c['pc'] * 1125 + c['setup_dense']) / (c['modal'] * 1125 + c['setup_modal']):.2f}): "  # noqa: E501
        "the modal set-up pays off once per plant, over a batch or repeated runs."
        + (
            ""
            if d is None
            else f" (d) Basilisk's σ_BN and the linear model's σ ≈ φ/4 differ by "
            f"{d['diff']:.1e} of the initial |σ| over the 15 s (linearisation, MRP "
            "kinematics and RK4 against the exact step)."
        ),
        "",
        "Memory per case (b): the per-case kernel inputs (noise stream, gains) and the "
        "default records (measurements, command, applied input, disturbance, friction "
        "at every sample); states are not recorded by default (outputs and energies are "
        "products of recorded measurements or of an optional state record after the "
        "loop).",
        "",
    ]
    # prose paragraphs wrapped like the rest of docs/performance.md; tables stay one row a line
    return "\n".join(ln if ln.startswith(("|", "#")) else textwrap.fill(ln, 95) for ln in lines)


def write_doc(text: str):
    doc = DOC.read_text()
    pattern = re.compile(re.escape(SECTION) + r".*?(?=\n## |\Z)", re.S)
    doc = pattern.sub(text.rstrip() + "\n", doc) if SECTION in doc else doc.rstrip() + "\n\n" + text
    DOC.write_text(doc)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--write", action="store_true", help="update docs/performance.md")
    ap.add_argument("--no-basilisk", action="store_true")
    a = ap.parse_args(argv)
    single = bench_single(a.repeat)["a"]
    batch = bench_batch(max(3, a.repeat // 4))
    modes = bench_modes(a.repeat)
    bsk = None if a.no_basilisk else bench_basilisk(a.repeat)
    text = report(single, batch, modes, bsk, a.repeat)
    print(text)
    if a.write:
        write_doc(text)


if __name__ == "__main__":
    main()
